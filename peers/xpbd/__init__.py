"""Extended position-based dynamics (XPBD; Macklin, Müller & Chentanez 2016) with the
deviatoric and hydrostatic tetrahedral constraints of Macklin & Müller 2021.

Modules: :mod:`.constraints` (the constraints, their gradients and the energy they stand
for, in numpy), :mod:`.energy` (that energy as a mechanical system: the Newton answer XPBD
converges to), :mod:`.kernels` (the compiled substep), :mod:`.solver` (substeps,
iterations, damping, the run to rest). docs/peers.rst describes them.

Examples
--------
>>> from peers.xpbd.solver import XPBDSettings
>>> XPBDSettings().iteration
'gauss-seidel'
"""

from .energy import StableNeoHookean
from .solver import XPBD, XPBDSettings

__all__ = ["XPBD", "StableNeoHookean", "XPBDSettings"]

"""Vertex Block Descent (VBD; Chen, Macklin, Yang & Kavan 2024): implicit-Euler substeps
minimised by Gauss–Seidel sweeps of per-vertex 3 x 3 Newton steps over a vertex colouring,
with the stable neo-Hookean energy of :mod:`peers.xpbd` or linear elasticity.

Modules: :mod:`.energy` (the energies and their vertex Hessian blocks, in numpy),
:mod:`.colouring` (vertex colouring and incidence in colour order), :mod:`.kernels` (the
compiled frame), :mod:`.solver` (settings, frames, the run to rest). docs/peers.rst
describes them.

Examples
--------
>>> from peers.vbd import VBDSettings
>>> VBDSettings().init
'adaptive'
"""

from .solver import VBD, VBDSettings

__all__ = ["VBD", "VBDSettings"]

"""Projective Dynamics (Bouaziz, Martin, Liu, Kavan & Pauly 2014): local projections of every
tet's deformation gradient and one prefactorised global solve, with its ARAP-like energy, and
its quasi-Newton form for neo-Hookean (Liu, Bouaziz & Kavan 2017).

Modules: :mod:`.energy` (the energies, their projections and a mechanical system of each,
in numpy), :mod:`.kernels` (the compiled local step), :mod:`.solver` (the global matrix,
local/global and L-BFGS iterations, frames, the run to rest). docs/peers.rst describes them.

Examples
--------
>>> from peers.pd import PDSettings
>>> PDSettings().energy, PDSettings(energy="neo-hookean").history
('arap', 5)
"""

from .solver import PD, PDSettings

__all__ = ["PD", "PDSettings"]

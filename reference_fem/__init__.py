"""reference_fem: the scikit-fem reference on the spring model's own mesh.

Linear elasticity (isotropic and transversely isotropic) and compressible neo-Hookean
hyperelasticity (coupled, or uncoupled with a choice of ``U(J)``), P1 or P2 tets on the
scene's vertices, Newton with line search and adaptive load stepping, SuperLU or
AMG-preconditioned Krylov solves.

Modules, one idea each:

- ``materials``: per-element Voigt matrices grouped by frame.
- ``hyperelastic``: neo-Hookean energy, stress and tangent; ``laws/``: the tissue laws
  (with an optional active fibre tension); ``point_fibres``: rule-based fibres at the P2
  quadrature points.
- ``space``: P1/P2 shape-function gradients and quadrature on the scene mesh.
- ``assembly``: einsum element arrays and 3x3-block sparse assembly.
- ``loads``: consistent load vectors, follower pressure and its stiffness.
- ``constraints``: prescribed displacements, reactions, the rigid-motion check.
- ``newton``: the adapter to the core Newton (line search, adaptive load stepping).
- ``law_names``: law names and :func:`~reference_fem.law_names.parse_law`.
- ``problem``: :class:`FemProblem` (residual, tangent, energy, post-processing);
  ``mixed``: the Taylor–Hood u-p problem; ``mini``: the P1-bubble/P1 u-p problem;
  ``nodal_volume``: P1 with nodal volumes; ``nodal_strain``: nodal volumes and nodal-averaged
  strain; ``volumetric_split``: a law as element part
  plus ``U(J)``.
- ``solver``: :func:`solve` (scene in, Result out).
- ``explicit``, ``explicit_kernels``, ``explicit_anisotropic``, ``dynamics``: explicit P1 FEM
  (isotropic and anisotropic compiled kernels) and time integration.
- ``dynamics_implicit``, ``dynamics_terms``: the dynamic reference (P2 and P2/P1 mixed,
  Newmark trapezoidal or generalised-α, consistent mass, Rayleigh damping).
- ``scenes``: verification scenes built in code; ``bench``: the speed benchmark;
  ``bench_formulations``: one Newton iteration per formulation, interleaved.

Public API
----------
solve(scene, order=None, law=None, verbose=False) -> FemSolution
bench(n_tets=100_000) -> dict
material_matrix(material, frames) -> (m, 6, 6) Voigt stiffness
element_stiffness_p1(points, tets, Cmat) -> (m, 12, 12)
dynamics_implicit.run(scene, t_end, dt, order=2, formulation=None, probes=None) -> DynamicResult
dynamics_error.estimate_error(scene, t_end, dt) -> ErrorEstimate

Examples
--------
>>> import numpy as np
>>> law = NeoHookean(mu=1.0, lam=2.0)
>>> float(abs(law.stress(np.eye(3))).max())  # stress free at rest
0.0
"""

from springfem.materials.laws.neo_hookean import NeoHookean

from . import options as _options  # noqa: F401  (registers the [fem] scene section)
from .assembly import element_stiffness_p1
from .bench import bench
from .materials import material_matrix
from .problem import FemProblem
from .solver import FemSolution, solve

__all__ = [
    "FemProblem",
    "FemSolution",
    "NeoHookean",
    "bench",
    "element_stiffness_p1",
    "material_matrix",
    "solve",
]

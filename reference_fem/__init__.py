"""reference_fem: the scikit-fem reference on the spring model's own mesh.

Linear elasticity (isotropic and transversely isotropic) and compressible neo-Hookean
hyperelasticity, P1 or P2 tets on the scene's vertices, Newton with adaptive load stepping,
SuperLU or AMG-preconditioned Krylov solves.

Public API
----------
solve(scene, order=None, law=None, verbose=False) -> FemSolution
bench(n_tets=100_000) -> dict
material_matrix(material, frames) -> (m, 6, 6) Voigt stiffness
element_stiffness_p1(points, tets, Cmat) -> (m, 12, 12)
"""

from .assembly import element_stiffness_p1
from .bench import bench
from .hyperelastic import NeoHookean
from .materials import material_matrix
from .solver import FemProblem, FemSolution, solve

__all__ = [
    "FemProblem",
    "FemSolution",
    "NeoHookean",
    "bench",
    "element_stiffness_p1",
    "material_matrix",
    "solve",
]

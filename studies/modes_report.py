"""``springfem inspect --modes``: the zero-energy modes of each model's tangent at rest.

A stable discretisation has exactly as many near-zero eigenvalues of its free-DOF tangent
as the rigid motions the constraints leave free: six for a free body, none when clamped
(:mod:`springfem.mechanics.modes`). The expected count is computed, not assumed: it is
``6 - rank`` of the rigid-body modes restricted to the fixed DOFs. Any eigenvalue near zero
beyond that is a spurious mode (an hourglass or a loose element volume mode).

Examples
--------
A free block: the exact spring element and P1 each show the six rigid motions, nothing more.

>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [1, 1, 1],
...     "divisions": [2, 2, 2], "split": "delaunay"},
...     "material": {"law": "linear", "E": 1e3, "nu": 0.3},
...     "spring": {"volume": "axes", "torsion": "energy", "calibration": "exact"}})
>>> [(r.model, r.count, r.expected) for r in scene_modes(scene)]
[('spring', 6, 6), ('fem', 6, 6)]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from springfem.mechanics import rigid_body_modes, zero_modes
from springfem.scene import Scene


@dataclass(frozen=True)
class ModeCount:
    """The near-zero eigenvalues of one model's free-DOF tangent at rest.

    Attributes
    ----------
    model
        ``spring`` or ``fem``.
    count
        Near-zero eigenvalues found.
    expected
        The rigid motions the constraints leave free.
    dofs
        Free DOFs of the tangent.
    """

    model: str
    count: int
    expected: int
    dofs: int

    @property
    def spurious(self) -> int:
        """Near-zero eigenvalues beyond the free rigid motions."""
        return max(self.count - self.expected, 0)

    @property
    def line(self) -> str:
        """One line: the count, the expectation and the verdict."""
        verdict = "no spurious modes" if self.spurious == 0 else f"{self.spurious} SPURIOUS modes"
        return (
            f"modes ({self.model}, tangent at rest, {self.dofs} free DOFs): {self.count} "
            f"near-zero eigenvalues, {self.expected} expected (free rigid motions): {verdict}"
        )


def _expected(points: np.ndarray, fixed: np.ndarray) -> int:
    R = rigid_body_modes(points)
    if fixed.size == 0:
        return 6
    return 6 - int(np.linalg.matrix_rank(R[fixed], tol=1e-9 * float(np.abs(R).max())))


def scene_modes(scene: Scene, models: tuple[str, ...] = ("spring", "fem")) -> list[ModeCount]:
    """The mode count of each model's tangent at rest (P1 for the FEM; the spring model's
    analytic tangent, or for its non-conservative laws the finite-difference tangent the
    solvers use).

    Parameters
    ----------
    scene
        The scene (its ``[spring]`` and ``[fem]`` options are used).
    models
        ``spring`` and/or ``fem``.

    Returns
    -------
    list of ModeCount
    """
    out = []
    n = scene.mesh.n_points
    if "spring" in models:
        from springfem.mechanics.system import free_dofs
        from springmodel.model import SpringModel

        model = SpringModel(scene)
        free = free_dofs(model)
        K = model.stiffness(model.x0)
        if K is None:  # a non-conservative law: the solvers' finite-difference tangent
            from springfem.mechanics import fd_jacobian

            K = fd_jacobian(lambda x: model.forces(x, None), model.x0, scene.mesh.tets)
        fixed = np.setdiff1d(np.arange(3 * n), free)
        Kf = K.tocsr()[free][:, free]
        out.append(ModeCount("spring", zero_modes(Kf).count, _expected(model.x0, fixed), len(free)))
    if "fem" in models:
        from reference_fem.solver import make_problem

        problem = make_problem(scene, order=1)
        u0 = np.zeros(problem.n_dofs)
        K = problem.residual_tangent(u0, 1.0)[1].tocsr()
        free = np.flatnonzero(problem.free)
        fixed = np.flatnonzero(~problem.free)
        Kf = K[free][:, free]
        pts = scene.mesh.points
        out.append(ModeCount("fem", zero_modes(Kf).count, _expected(pts, fixed), len(free)))
    return out

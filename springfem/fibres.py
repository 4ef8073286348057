"""Rule-based myocardial fibres: a helix angle varying through the wall.

The transmural depth ``d`` (0 on the endocardium, 1 on the epicardium) is the solution of
Laplace's equation ``div grad d = 0`` with ``d = 0`` on ``endo`` and ``d = 1`` on ``epi``
(P2, scikit-fem; natural boundary elsewhere, e.g. the base), and its gradient is taken at
each element's barycentre (P2 rather than P1: a P1 gradient is constant per element and
off by O(h / R) in direction, tens of degrees on a coarse wall). Per element, with the
transmural direction ``t = grad d / |grad d|``, the circumferential direction
``c = axis x t`` (normalised) and the longitudinal ``l = t x c`` (towards the base for a
ventricle whose long axis is ``axis``), the fibre is ``f = cos(a) c + sin(a) l`` with the
helix angle ``a = endo_angle + (epi_angle - endo_angle) d``; the sheet is transmural
(``t``) and the normal ``f x t``. Frames are rows (fiber, sheet, normal), as in
:mod:`springfem.axes`.

Examples
--------
>>> from springfem.ellipsoid import ellipsoid_mesh
>>> m = ellipsoid_mesh(size=4.0)
>>> frames, depth = rule_based_frames(m, endo_angle=60.0, epi_angle=-60.0)
>>> frames.shape == (m.n_tets, 3, 3), bool(0 <= depth.min() and depth.max() <= 1)
(True, True)
"""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as sla
import skfem
from skfem.models.poisson import laplace

from .axes import orthonormal_frame
from .errors import InputError
from .mesh import TetMesh


def _facet_keys(tris: np.ndarray, n: int) -> np.ndarray:
    """One integer per triangle, independent of its vertex order."""
    t = np.sort(np.asarray(tris, dtype=np.int64), axis=1)
    return (t[:, 0] * n + t[:, 1]) * n + t[:, 2]


def _laplace(mesh: TetMesh, endo: str, epi: str):
    """P2 solution (scikit-fem basis, dof vector) of the transmural Laplace problem."""
    for name in (endo, epi):
        if name not in mesh.facet_sets:
            have = ", ".join(sorted(mesh.facet_sets)) or "none"
            raise InputError(f"rule-based fibres need facet region {name!r} (mesh has: {have})")
    inner = np.unique(mesh.facet_sets[endo])
    outer = np.unique(mesh.facet_sets[epi])
    if np.intersect1d(inner, outer).size:
        raise InputError(f"facet regions {endo!r} and {epi!r} share nodes")
    sk = skfem.MeshTet(np.ascontiguousarray(mesh.points.T), np.ascontiguousarray(mesh.tets.T))
    basis = skfem.Basis(sk, skfem.ElementTetP2(), intorder=2)
    A = laplace.assemble(basis).tocsr()
    x = np.zeros(basis.N)
    fixed = np.zeros(basis.N, dtype=bool)
    n = mesh.n_points
    all_keys = _facet_keys(sk.facets.T, n)
    for name, value in ((endo, 0.0), (epi, 1.0)):
        ids = np.flatnonzero(np.isin(all_keys, _facet_keys(mesh.facet_sets[name], n)))
        dofs = basis.get_dofs(ids).flatten()
        x[dofs] = value
        fixed[dofs] = True
    free = np.flatnonzero(~fixed)
    x[free] = sla.spsolve(A[free][:, free].tocsc(), -A[free][:, fixed] @ x[fixed])
    return sk, x


def transmural_depth(mesh: TetMesh, endo: str = "endo", epi: str = "epi") -> np.ndarray:
    """Vertex values ``(n_points,)`` of Laplace's solution, 0 on ``endo``, 1 on ``epi``.

    Parameters
    ----------
    mesh
        A mesh with facet sets ``endo`` and ``epi`` (names may be changed).
    endo, epi
        The facet-set names of the two surfaces.

    Returns
    -------
    numpy.ndarray
        The depth at the mesh vertices (P2 vertex DOFs come first).
    """
    return _laplace(mesh, endo, epi)[1][: mesh.n_points]


def rule_based_frames(
    mesh: TetMesh,
    endo_angle: float = 60.0,
    epi_angle: float = -60.0,
    axis=(0.0, 0.0, 1.0),
    endo: str = "endo",
    epi: str = "epi",
) -> tuple[np.ndarray, np.ndarray]:
    """Per-element (fiber, sheet, normal) frames and the elements' transmural depth.

    Parameters
    ----------
    mesh
        A ventricle mesh with facet sets ``endo`` and ``epi``.
    endo_angle, epi_angle
        Helix angle in degrees on the endocardium and the epicardium (linear in depth).
    axis
        The long axis, apex to base.
    endo, epi
        Facet-set names.

    Returns
    -------
    frames, depth
        ``(m, 3, 3)`` frames and ``(m,)`` depth at the element barycentres.
    """
    sk, x = _laplace(mesh, endo, epi)
    centre = skfem.Basis(sk, skfem.ElementTetP2(), intorder=1)  # one point: the barycentre
    frames, depth = _frames_at(centre, x, endo_angle, epi_angle, axis)
    return frames[:, 0], depth[:, 0]


def rule_based_point_frames(
    mesh: TetMesh,
    intorder: int,
    endo_angle: float = 60.0,
    epi_angle: float = -60.0,
    axis=(0.0, 0.0, 1.0),
    endo: str = "endo",
    epi: str = "epi",
) -> np.ndarray:
    """The frames of :func:`rule_based_frames` at each element's quadrature points.

    A fibre per quadrature point follows the helix through a wall that is only one or two
    elements thick, which one fibre per element cannot
    (docs/verification.rst#land-problem-3-fibres).

    Parameters
    ----------
    mesh
        A ventricle mesh with facet sets ``endo`` and ``epi``.
    intorder
        Order of the scikit-fem tetrahedron quadrature (the FEM space's ``intorder``).
    endo_angle, epi_angle, axis, endo, epi
        As for :func:`rule_based_frames`.

    Returns
    -------
    numpy.ndarray
        ``(m, nq, 3, 3)`` frames (rows: fiber, sheet, normal) at the quadrature points.

    Examples
    --------
    >>> from springfem.ellipsoid import ellipsoid_mesh
    >>> m = ellipsoid_mesh(size=6.0)
    >>> q = rule_based_point_frames(m, intorder=2, endo_angle=-90.0, epi_angle=90.0)
    >>> q.shape == (m.n_tets, 4, 3, 3)
    True
    """
    sk, x = _laplace(mesh, endo, epi)
    basis = skfem.Basis(sk, skfem.ElementTetP2(), intorder=intorder)
    return _frames_at(basis, x, endo_angle, epi_angle, axis)[0]


def _frames_at(basis, x: np.ndarray, endo_angle: float, epi_angle: float, axis):
    """Frames ``(m, nq, 3, 3)`` and depth ``(m, nq)`` at the quadrature points of ``basis``."""
    field = basis.interpolate(x)
    grad = np.asarray(field.grad)  # (3, m, nq)
    m, nq = grad.shape[1:]
    g = grad.transpose(1, 2, 0).reshape(-1, 3)
    depth = np.asarray(field).reshape(-1)
    norm = np.linalg.norm(g, axis=1)
    if not (norm > 0).all():
        raise InputError("rule-based fibres: the transmural depth is flat in some elements")
    t = g / norm[:, None]
    k = np.asarray(axis, dtype=float)
    k = k / np.linalg.norm(k)
    c = np.cross(k, t)
    # at the apex t is (nearly) parallel to the axis: any direction normal to t will do
    weak = np.linalg.norm(c, axis=1) < 1e-6
    if weak.any():
        other = np.array([1.0, 0.0, 0.0]) if abs(k[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        c[weak] = np.cross(other, t[weak])
    c /= np.linalg.norm(c, axis=1, keepdims=True)
    ell = np.cross(t, c)
    a = np.radians(endo_angle + (epi_angle - endo_angle) * depth)[:, None]
    f = np.cos(a) * c + np.sin(a) * ell
    return orthonormal_frame(f, t).reshape(m, nq, 3, 3), depth.reshape(m, nq)

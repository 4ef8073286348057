"""The truncated-ellipsoid left ventricle of Land et al. 2015 (problems 2 and 3), by gmsh.

The wall lies between two confocal-free ellipsoids of revolution about the z axis,
``(x^2 + y^2) / r_short^2 + z^2 / r_long^2 = 1``: endocardium ``r_short = 7``,
``r_long = 17`` mm, epicardium 10 and 20 mm, cut by the base plane ``z = 5`` mm (the apex
points to -z). gmsh's OpenCASCADE kernel builds the solid (scaled spheres, a difference, a
cut by the half space below the base) and meshes it with linear tets of size about
``size``; the three boundary surfaces become the facet regions ``endo``, ``epi`` and
``base``.

Examples
--------
>>> m = ellipsoid_mesh(size=3.0)
>>> sorted(m.facet_sets), bool(m.points[:, 2].max() <= 5.0 + 1e-9)
(['base', 'endo', 'epi'], True)
>>> bool(abs(m.volumes().sum() / wall_volume() - 1) < 0.05)  # faceted: a little less
True
"""

from __future__ import annotations

import math

import numpy as np

from .errors import InputError
from .mesh import TetMesh, validate_mesh

#: Land et al. 2015 geometry, mm.
ENDO = (7.0, 17.0)
EPI = (10.0, 20.0)
BASE_Z = 5.0
#: Growth of the element size with the distance from the long axis (``axis_size``).
AXIS_GRADING = 0.4


def _cap_volume(r_short: float, r_long: float, base_z: float) -> float:
    """Volume of ``(x^2+y^2)/a^2 + z^2/c^2 <= 1`` below the plane ``z = base_z``."""
    z0 = max(-r_long, min(r_long, base_z))
    # int_{-c}^{z0} pi a^2 (1 - z^2 / c^2) dz
    return math.pi * r_short**2 * ((z0 + r_long) - (z0**3 + r_long**3) / (3 * r_long**2))


def wall_volume(endo=ENDO, epi=EPI, base_z: float = BASE_Z) -> float:
    """Exact volume of the truncated ellipsoidal wall (epicardial minus endocardial cap).

    Parameters
    ----------
    endo, epi
        ``(r_short, r_long)`` of the endocardial and epicardial ellipsoids (mm).
    base_z
        Height of the base plane (mm).

    Returns
    -------
    float
        Volume (mm^3).

    Examples
    --------
    >>> import math
    >>> math.isclose(wall_volume((1.0, 1.0), (2.0, 2.0), 2.0), 4 / 3 * math.pi * 7)
    True
    """
    return _cap_volume(epi[0], epi[1], base_z) - _cap_volume(endo[0], endo[1], base_z)


def cavity_volume(endo=ENDO, base_z: float = BASE_Z) -> float:
    """Exact volume enclosed by the endocardium and the base plane.

    Parameters
    ----------
    endo
        ``(r_short, r_long)`` of the endocardial ellipsoid (mm).
    base_z
        Height of the base plane (mm).

    Returns
    -------
    float
        Volume (mm^3).

    Examples
    --------
    >>> import math
    >>> math.isclose(cavity_volume((1.0, 1.0), 0.0), 2 / 3 * math.pi)  # half a unit ball
    True
    """
    return _cap_volume(endo[0], endo[1], base_z)


def ellipsoid_mesh(
    size: float = 2.0,
    endo: tuple[float, float] = ENDO,
    epi: tuple[float, float] = EPI,
    base_z: float = BASE_Z,
    axis_size: float | None = None,
) -> TetMesh:
    """Tet mesh of the truncated ellipsoidal ventricle wall.

    Parameters
    ----------
    size
        Target element size (gmsh ``Mesh.MeshSizeMax``), in the units of the radii.
    endo, epi
        ``(r_short, r_long)`` of the endocardial and epicardial ellipsoids.
    base_z
        Height of the base plane; it must cut both ellipsoids above their centres' apex.
    axis_size
        Element size on the long axis (``None``: uniform ``size``): the size grows as
        ``min(size, axis_size + AXIS_GRADING * rho)`` with the distance ``rho`` from the
        axis, which the wall crosses only at the apex. Land's problem-3 fibre field is
        singular on the axis (docs/verification.rst#land-problem-3-fibres).

    Returns
    -------
    TetMesh
        With facet sets ``endo``, ``epi`` and ``base``.

    Raises
    ------
    InputError
        Radii or base plane that give no wall, or a size that is not positive.
    """
    (a_in, c_in), (a_out, c_out) = endo, epi
    if not (0 < a_in < a_out and 0 < c_in < c_out):
        raise InputError(
            f"ellipsoid: endo radii {tuple(endo)} must lie inside epi radii {tuple(epi)}"
        )
    if not -c_in < base_z < c_in:
        raise InputError(f"ellipsoid: base_z = {base_z} must lie within (-{c_in}, {c_in})")
    if not (size > 0 and math.isfinite(size)):
        raise InputError(f"ellipsoid: size must be positive, got {size}")
    if size < 1e-3 * c_out:
        raise InputError(f"ellipsoid: size {size} would give far too many tets")
    if axis_size is not None and not (1e-3 * c_out <= axis_size <= size):
        raise InputError(f"ellipsoid: axis_size must lie in [{1e-3 * c_out:g}, size = {size:g}]")
    import gmsh

    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("ventricle")
        occ = gmsh.model.occ
        outer = occ.addSphere(0, 0, 0, 1.0)
        occ.dilate([(3, outer)], 0, 0, 0, a_out, a_out, c_out)
        inner = occ.addSphere(0, 0, 0, 1.0)
        occ.dilate([(3, inner)], 0, 0, 0, a_in, a_in, c_in)
        wall, _ = occ.cut([(3, outer)], [(3, inner)])
        big = 4.0 * c_out
        box = occ.addBox(-big, -big, -big, 2 * big, 2 * big, big + base_z)
        solid, _ = occ.intersect(wall, [(3, box)])
        occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.option.setNumber("Mesh.MeshSizeMin", 0.1 * min(size, axis_size or size))
        if axis_size is not None:
            field = gmsh.model.mesh.field
            f = field.add("MathEval")
            field.setString(
                f, "F", f"min({size!r}, {axis_size!r} + {AXIS_GRADING!r} * sqrt(x * x + y * y))"
            )
            field.setAsBackgroundMesh(f)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
        gmsh.model.mesh.generate(3)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        points = coords.reshape(-1, 3)
        index = np.zeros(int(tags.max()) + 1, dtype=np.int64)
        index[tags.astype(np.int64)] = np.arange(len(tags))
        blocks = []
        for dim, tag in solid:
            _, _, nodes = gmsh.model.mesh.getElements(dim, tag)
            blocks.append(np.asarray(nodes[0], dtype=np.int64).reshape(-1, 4))
        tets = index[np.concatenate(blocks)]
        facets: dict[str, list[np.ndarray]] = {"endo": [], "epi": [], "base": []}
        for _, tag in gmsh.model.getEntities(2):
            _, _, nodes = gmsh.model.mesh.getElements(2, tag)
            tri = index[np.asarray(nodes[0], dtype=np.int64).reshape(-1, 3)]
            c = points[tri].mean(axis=1).mean(axis=0)
            name = _surface_name(points[np.unique(tri)], endo, epi, base_z)
            if name is None:
                raise InputError(f"ellipsoid: unrecognised boundary surface near {c.tolist()}")
            facets[name].append(tri)
    finally:
        gmsh.finalize()
    used = np.unique(tets)
    renumber = np.full(len(points), -1, dtype=np.int64)
    renumber[used] = np.arange(len(used))
    mesh = TetMesh(
        points=np.ascontiguousarray(points[used]),
        tets=renumber[tets],
        facet_sets={k: renumber[np.concatenate(v)] for k, v in facets.items() if v},
        source=f"ellipsoid(size={size:g}, endo={tuple(endo)}, epi={tuple(epi)}, base_z={base_z}"
        + ("" if axis_size is None else f", axis_size={axis_size:g}")
        + ")",
    )
    return validate_mesh(mesh, "ellipsoid")


def _surface_name(x: np.ndarray, endo, epi, base_z: float) -> str | None:
    """Which surface the nodes ``x`` lie on: the base plane, endo or epi ellipsoid."""
    scale = max(epi)
    if np.abs(x[:, 2] - base_z).max() <= 1e-6 * scale:
        return "base"
    for name, (a, c) in (("endo", endo), ("epi", epi)):
        level = (x[:, 0] ** 2 + x[:, 1] ** 2) / a**2 + x[:, 2] ** 2 / c**2
        if np.abs(level - 1.0).max() <= 1e-6:
            return name
    return None


def project_to_ellipsoid(x: np.ndarray, radii, base_z: float = BASE_Z) -> np.ndarray:
    """Points moved onto the ellipsoid ``(x^2 + y^2) / a^2 + z^2 / c^2 = 1``.

    A point at the base plane's height (within 1e-9 of ``base_z``, e.g. the midpoint of an
    edge of the basal ring) moves radially in that plane, so that it stays on both
    surfaces; every other point moves along the ray from the centre in the scaled
    coordinates ``(x / a, y / a, z / c)``.

    Parameters
    ----------
    x
        ``(k, 3)`` points near the surface.
    radii
        ``(a, c)``: the short and long radius (mm).
    base_z
        Height of the base plane (mm).

    Returns
    -------
    numpy.ndarray
        ``(k, 3)`` points on the ellipsoid.

    Examples
    --------
    >>> p = project_to_ellipsoid(np.array([[3.0, 0.0, -8.0], [6.0, 0.0, 5.0]]), (7.0, 17.0))
    >>> lev = (p[:, 0] ** 2 + p[:, 1] ** 2) / 49 + p[:, 2] ** 2 / 289
    >>> np.allclose(lev, 1.0), float(p[1, 2])
    (True, 5.0)
    """
    a, c = (float(r) for r in radii)
    x = np.array(x, dtype=float, copy=True)
    rho2 = (x[:, 0] ** 2 + x[:, 1] ** 2) / a**2
    level = rho2 + x[:, 2] ** 2 / c**2
    ring = np.abs(x[:, 2] - base_z) <= 1e-9 * max(a, c)
    s = 1.0 / np.sqrt(level)
    x[~ring] *= s[~ring, None]
    ring_scale = np.sqrt((1.0 - base_z**2 / c**2) / np.maximum(rho2[ring], 1e-300))
    x[ring, :2] *= ring_scale[:, None]
    return x


def curved_edge_nodes(mesh: TetMesh, edges: np.ndarray, endo=ENDO, epi=EPI,
                      base_z: float = BASE_Z) -> np.ndarray:  # fmt: skip
    """The P2 edge nodes of an ellipsoid mesh with its curved walls: isoparametric geometry.

    Each edge's node is its midpoint, except on the edges of the ``endo`` and ``epi``
    facets, whose nodes move onto the true ellipsoid (:func:`project_to_ellipsoid`), so that
    the quadratic map of each boundary tet follows the wall to ``O(h^3)`` instead of the
    faceted ``O(h^2)`` (docs/verification.rst#land-problem-3-fibres).

    Parameters
    ----------
    mesh
        A mesh of :func:`ellipsoid_mesh` (its ``endo`` and ``epi`` facet sets).
    edges
        ``(n_edges, 2)`` vertex pairs, in the P2 space's edge order.
    endo, epi, base_z
        The geometry the mesh was built with (mm).

    Returns
    -------
    numpy.ndarray
        ``(n_edges, 3)`` edge-node positions.

    Examples
    --------
    >>> m = ellipsoid_mesh(size=6.0)
    >>> e = np.unique(np.sort(m.tets[:, [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]]
    ...               .reshape(-1, 2), axis=1), axis=0)
    >>> moved = np.linalg.norm(curved_edge_nodes(m, e) - m.points[e].mean(axis=1), axis=1)
    >>> bool(moved.max() > 0.1), bool((moved > 0).sum() < len(e))
    (True, True)
    """
    edges = np.asarray(edges, dtype=np.int64)
    x = np.asarray(mesh.points, dtype=float)
    nodes = 0.5 * (x[edges[:, 0]] + x[edges[:, 1]])
    n = len(x)
    keys = edges.min(axis=1) * n + edges.max(axis=1)
    for name, radii in (("endo", endo), ("epi", epi)):
        tri = mesh.facet_sets.get(name)
        if tri is None or len(tri) == 0:
            raise InputError(f'curved geometry needs the ellipsoid mesh\'s "{name}" facets')
        fe = np.asarray(tri, dtype=np.int64)[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2)
        on = np.isin(keys, np.unique(fe.min(axis=1) * n + fe.max(axis=1)))
        nodes[on] = project_to_ellipsoid(nodes[on], radii, base_z)
    return nodes

"""Scenes built in code: verification problems that no bundled TOML file describes.

:func:`make_scene` assembles a :class:`~springfem.scene.Scene` from a mesh and short
specs (regions as in scene files: box-face names, mesh sets, ``{"box": ...}``,
``{"point": ...}``). :func:`thick_cylinder_scene` maps a box mesh to a quarter of a thick
cylinder (Lamé's problem in plane strain); :func:`bench_scene` is the speed benchmark.

Examples
--------
>>> s = thick_cylinder_scene(1.0, 2.0, pressure=1.0, divisions=(2, 4, 1))
>>> s.mesh.n_tets, sorted(b.region.name for b in s.boundaries)
(48, ['x_min', 'y_min', 'z_max', 'z_min'])
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from springfem.axes import uniform_frames
from springfem.errors import InputError
from springfem.mesh import TetMesh, boundary_facets, box_mesh
from springfem.regions import locate_points, resolve_region
from springfem.scene import Boundary, Load, Material, Probe, Scene

from .options import FemOptions

_AXES = {"x": 0, "y": 1, "z": 2}


def make_scene(
    mesh: TetMesh,
    material: Material,
    boundaries: Sequence[tuple] = (),
    loads: Sequence[tuple] = (),
    probes: dict[str, Sequence[float]] | None = None,
    frames: np.ndarray | None = None,
    fem: FemOptions | None = None,
    name: str = "scene",
) -> Scene:
    """A scene from a mesh and specs.

    Parameters
    ----------
    boundaries
        ``(region, "xyz", displacement)`` tuples (``displacement`` optional, default 0).
    loads
        ``(type, value, region)`` tuples (``region`` omitted for gravity).
    probes
        Name -> point; each must lie in the mesh.
    frames
        ``(m, 3, 3)`` element frames (default: the global axes).
    """
    bnd = []
    for spec in boundaries:
        region, comps = spec[0], spec[1]
        value = np.zeros(3) if len(spec) < 3 else np.asarray(spec[2], dtype=float)
        idx = tuple(sorted(_AXES[c] for c in comps))
        bnd.append(Boundary(resolve_region(mesh, region), idx, value))
    lds = []
    for spec in loads:
        kind, value = spec[0], spec[1]
        region = resolve_region(mesh, spec[2]) if len(spec) > 2 else None
        value = np.atleast_1d(np.asarray(value, dtype=float))
        lds.append(Load(kind, value, region))
    prb = []
    for pname, point in (probes or {}).items():
        point = np.asarray(point, dtype=float)
        tet, bary = locate_points(mesh.points, mesh.tets, point[None])
        if tet[0] < 0:
            raise InputError(f"probe {pname!r} at {point.tolist()} is outside the mesh")
        prb.append(Probe(pname, point, int(tet[0]), bary[0]))
    if frames is None:
        frames = uniform_frames(mesh.n_tets, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    return Scene(
        name=name,
        mesh=mesh,
        material=material,
        frames=np.asarray(frames, dtype=float),
        boundaries=bnd,
        loads=lds,
        probes=prb,
        options={"fem": fem or FemOptions()},
    )


def thick_cylinder_mesh(
    inner: float, outer: float, divisions: tuple[int, int, int], height: float | None = None
) -> TetMesh:
    """Quarter of a thick-walled cylinder (``0 <= theta <= pi/2``), axis along z.

    A box mesh in ``(r, theta, z)`` is mapped by ``(r cos theta, r sin theta, z)``
    (positive Jacobian ``r``, so orientation is kept). The inner and outer surfaces are the
    facet sets ``inner`` and ``outer``.
    """
    nr, nt, nz = divisions
    height = 0.2 * inner if height is None else height
    box = box_mesh((outer - inner, np.pi / 2, height), (nr, nt, nz), origin=(inner, 0.0, 0.0))
    r, th, z = box.points.T
    points = np.column_stack([r * np.cos(th), r * np.sin(th), z])
    points[np.isclose(th, np.pi / 2), 0] = 0.0  # exactly on the symmetry plane x = 0
    bf = boundary_facets(box.tets)
    tol = 1e-12 * outer
    sets = {
        "inner": bf[(np.abs(r[bf] - inner) < tol).all(axis=1)],
        "outer": bf[(np.abs(r[bf] - outer) < tol).all(axis=1)],
    }
    desc = f"quarter cylinder r {inner}..{outer}, divisions {list(divisions)}"
    return TetMesh(points=points, tets=box.tets.copy(), facet_sets=sets, source=desc)


def thick_cylinder_scene(
    inner: float,
    outer: float,
    pressure: float,
    divisions: tuple[int, int, int] = (4, 12, 1),
    E: float = 1000.0,
    nu: float = 0.3,
    law: str = "linear",
    order: int = 2,
) -> Scene:
    """Lamé's problem: internal ``pressure`` on a quarter cylinder in plane strain.

    Symmetry planes ``x = 0`` and ``y = 0`` slide (``ux = 0``, ``uy = 0``); ``uz = 0`` on
    both end faces gives plane strain.
    """
    mesh = thick_cylinder_mesh(inner, outer, divisions)
    return make_scene(
        mesh,
        Material(law, E=E, nu=nu),
        boundaries=[("x_min", "x"), ("y_min", "y"), ("z_min", "z"), ("z_max", "z")],
        loads=[("pressure", pressure, "inner")],
        fem=FemOptions(order=order),
        name="thick-cylinder",
    )


def bench_scene(n_tets: int = 100_000, linear_solver: str = "amg") -> Scene:
    """A 2:1:1 block of about ``n_tets`` tets, clamped at ``x_min``, pulled down at ``x_max``."""
    k = max(1, round((n_tets / 12.0) ** (1.0 / 3.0)))
    mesh = box_mesh((2.0, 1.0, 1.0), (2 * k, k, k))
    return make_scene(
        mesh,
        Material("linear", E=1.0e4, nu=0.3),
        boundaries=[("x_min", "xyz")],
        loads=[("traction", [0.0, 0.0, -1.0], "x_max")],
        probes={"tip": [2.0, 0.5, 0.5]},
        fem=FemOptions(order=1, linear_solver=linear_solver),
        name=f"bench-{mesh.n_tets}",
    )

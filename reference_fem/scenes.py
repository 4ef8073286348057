"""Scenes built in code: verification problems that no bundled TOML file describes.

Each builds the scene's table as a dict and passes it to
:func:`springfem.scene.scene_from_dict`, the one way scenes are made.
:func:`thick_cylinder_scene` maps a box mesh to a quarter of a thick cylinder (Lamé's
problem in plane strain); :func:`bench_scene` is the speed benchmark.

Examples
--------
>>> s = thick_cylinder_scene(1.0, 2.0, pressure=1.0, divisions=(2, 4, 1))
>>> s.mesh.n_tets, sorted(b.region.name for b in s.boundaries)
(48, ['x_min', 'y_min', 'z_max', 'z_min'])
"""

from __future__ import annotations

import numpy as np

from springfem.mesh import TetMesh, boundary_facets, box_mesh
from springfem.scene import Scene, scene_from_dict

from . import options as _options  # noqa: F401  (registers the [fem] section)


def thick_cylinder_mesh(
    inner: float, outer: float, divisions: tuple[int, int, int], height: float | None = None
) -> TetMesh:
    """Quarter of a thick-walled cylinder (``0 <= theta <= pi/2``), axis along z.

    A box mesh in ``(r, theta, z)`` is mapped by ``(r cos theta, r sin theta, z)``
    (positive Jacobian ``r``, so orientation is kept).

    Parameters
    ----------
    inner, outer
        Inner and outer radius.
    divisions
        Hexahedra along ``r``, ``theta`` and ``z``.
    height
        Length along the axis (default ``0.2 inner``).

    Returns
    -------
    TetMesh
        With the inner and outer surfaces as the facet sets ``inner`` and ``outer``.
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

    Parameters
    ----------
    inner, outer
        Inner and outer radius.
    pressure
        Internal pressure (Pa).
    divisions
        Hexahedra along ``r``, ``theta`` and ``z`` (see :func:`thick_cylinder_mesh`).
    E, nu, law
        The material.
    order
        FEM element order (the scene's ``[fem] order``).

    Returns
    -------
    Scene
    """
    slide = [("x_min", "x"), ("y_min", "y"), ("z_min", "z"), ("z_max", "z")]
    return scene_from_dict(
        {
            "name": "thick-cylinder",
            "mesh": thick_cylinder_mesh(inner, outer, divisions),
            "material": {"law": law, "E": E, "nu": nu},
            "boundary": [{"region": r, "fix": [c]} for r, c in slide],
            "load": [{"type": "pressure", "value": pressure, "region": "inner"}],
            "fem": {"order": order},
        }
    )


def bench_scene(n_tets: int = 100_000, linear_solver: str = "amg") -> Scene:
    """A 2:1:1 block of about ``n_tets`` tets, clamped at ``x_min``, pulled down at ``x_max``.

    Parameters
    ----------
    n_tets
        Wanted number of tets (the block has ``12 k^3``, ``k`` the nearest integer).
    linear_solver
        The FEM's ``[fem] linear_solver``.

    Returns
    -------
    Scene
        Named ``bench-<tets>``, with a probe ``tip`` at the middle of the loaded end, and
        the specification's spring element (``[spring] element = "seed"``): the bench
        measures the kernels of the specification (a new scene's default is the exact
        element).

    Examples
    --------
    >>> s = bench_scene(100)
    >>> s.name, s.probes[0].name
    ('bench-96', 'tip')
    """
    k = max(1, round((n_tets / 12.0) ** (1.0 / 3.0)))
    return scene_from_dict(
        {
            "name": f"bench-{12 * k**3}",
            "mesh": {"generator": "box", "size": [2.0, 1.0, 1.0], "divisions": [2 * k, k, k]},
            "material": {"law": "linear", "E": 1.0e4, "nu": 0.3},
            "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
            "load": [{"type": "traction", "value": [0.0, 0.0, -1.0], "region": "x_max"}],
            "probe": [{"name": "tip", "point": [2.0, 0.5, 0.5]}],
            "fem": {"order": 1, "linear_solver": linear_solver},
            "spring": {"element": "seed"},
        }
    )

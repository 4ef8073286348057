"""The exact spring variants and the extra meshes of the accuracy study.

*Exact variants* (issue 10, DESIGN §4b): the axis-volume spring (``volume = "axes"``) with
energy torsion and the closed-form ``calibration = "exact"``; for a transversely isotropic
material also the Poisson-coupling springs (``coupling = true``). Their small-strain element
equals the P1 element on any tet, so their error against linear P1 on the same mesh is only
geometric nonlinearity (the spring model is solved at finite strain); against the
finite-strain P1 (neo-Hookean) it is the model error proper.

*Extra meshes*: the cantilever on an unstructured mesh (a Delaunay triangulation of a
jittered grid, :func:`jittered_box`) and on elongated cells (2:1:1).

Examples
--------
>>> m = jittered_box((1.0, 1.0, 1.0), (3, 3, 3), seed=0)
>>> round(float(m.volumes().sum()), 12), bool((m.volumes() > 0).all())
(1.0, True)
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from springfem.mesh import TetMesh, tet_volumes
from springfem.scene import Scene

#: Spring options of the exact variant (coupling added for anisotropic materials).
EXACT = {"volume": "axes", "torsion": "energy", "calibration": "exact"}

#: The variant's label in tables and findings.
EXACT_LABEL = "exact (axis-volume + energy torsion + exact calibration)"

MIN_VOLUME = 1e-6  # a Delaunay tet below this fraction of a grid cell is flat (dropped)


def exact_options(scene: Scene):
    """The scene's spring options with the exact element switched on.

    Parameters
    ----------
    scene
        The scene (its material decides whether coupling springs are needed).

    Returns
    -------
    springmodel.options.SpringOptions
    """
    from springmodel.options import SpringOptions

    coupling = scene.material.law == "transverse-linear"
    return dataclasses.replace(SpringOptions.of(scene), coupling=coupling, **EXACT)


def jittered_box(
    size: tuple[float, float, float],
    divisions: tuple[int, int, int],
    jitter: float = 0.3,
    seed: int = 0,
) -> TetMesh:
    """An unstructured box mesh: Delaunay tets of a grid whose nodes moved at random.

    Interior nodes move by up to ``jitter`` of a cell along each axis; nodes on a face move
    only within it, so the box (and its ``x_min`` … ``z_max`` faces) is kept exactly.

    Parameters
    ----------
    size
        Box edge lengths (m).
    divisions
        Grid cells per axis.
    jitter
        Largest move as a fraction of the cell (below 0.5 keeps the nodes ordered).
    seed
        Random seed (the mesh is a function of the arguments).

    Returns
    -------
    TetMesh
        Positively oriented tets.
    """
    from scipy.spatial import Delaunay

    rng = np.random.default_rng(seed)
    axes = [np.linspace(0.0, s, n + 1) for s, n in zip(size, divisions, strict=True)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    h = np.asarray(size, float) / np.asarray(divisions, float)
    move = rng.uniform(-jitter, jitter, grid.shape) * h
    on_face = np.isclose(grid, 0.0) | np.isclose(grid, np.asarray(size, float))
    pts = grid + np.where(on_face, 0.0, move)
    tets = Delaunay(pts).simplices.astype(np.int64)
    vol = tet_volumes(pts, tets)
    keep = np.abs(vol) > MIN_VOLUME * float(np.prod(h))
    tets, vol = tets[keep], vol[keep]
    tets[vol < 0] = tets[vol < 0][:, [0, 2, 1, 3]]
    return TetMesh(pts, tets, source=f"jittered Delaunay box {list(divisions)} seed {seed}")


def variant_errors(cmp_errors, u_spring: np.ndarray, refs: dict[str, np.ndarray]) -> dict[str, Any]:
    """Relative L2 and max errors of ``u_spring`` against each reference field.

    Parameters
    ----------
    cmp_errors
        The error function ``(u, u_ref) -> {"rel_l2": ..., "rel_max": ...}``.
    u_spring
        The variant's vertex displacements.
    refs
        Reference name -> vertex displacements.

    Returns
    -------
    dict
        Reference name -> error dict.
    """
    return {name: cmp_errors(u_spring, u) for name, u in refs.items()}

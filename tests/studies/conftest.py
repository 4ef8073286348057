"""Fixtures of the studies tests: a scene table written as a TOML file for the CLI."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
from support.toml import to_toml


def scene_toml(data: dict) -> str:
    """The TOML text of a scene table, checked to round-trip."""
    text = to_toml(data)
    if tomllib.loads(text) != data:  # the writer must round-trip what it was given
        raise AssertionError("scene table does not round-trip through TOML")
    return text


@pytest.fixture
def scene_file(tmp_path):
    """``scene_file(table, name="scene.toml")``: write a scene table as TOML, return its path."""

    def write(data: dict, name: str = "scene.toml"):
        path = tmp_path / name
        path.write_text(scene_toml(data), encoding="utf-8")
        return path

    return write


# ------------------------------------------------------- the spring model's linear answer


def dk_p1_displacement(scene, options=None):
    """Small-strain displacement ``(n, 3)`` of the spring model, computed independently of
    its force kernel: P1 FEM assembled with each element's effective spring matrix ``D_k``
    in place of the material matrix (docs/theory.rst#the-effective-small-strain-matrix-d-k: the
    linearised spring model *is* this FEM).

    Valid for the energy forms (axial, torsion ``energy``, volume ``gradient``). Loads and
    prescribed displacements are the scene's at load factor 1, taken at the rest state.
    """
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    from reference_fem import element_stiffness_p1
    from springmodel.element_energy import effective_matrix
    from springmodel.model import SpringModel

    model = SpringModel(scene, options, parallel=False)
    el = model.elements
    D = effective_matrix(el, el.k_axial, el.k_torsion, el.k_volume)
    points, tets = scene.mesh.points, scene.mesh.tets
    Ke = element_stiffness_p1(points, tets, D)
    dofs = (3 * tets[:, :, None] + np.arange(3)).reshape(len(tets), 12)
    n = 3 * len(points)
    rows = np.repeat(dofs, 12, axis=1).ravel()
    cols = np.tile(dofs, (1, 12)).ravel()
    K = sp.csr_matrix((Ke.ravel(), (rows, cols)), shape=(n, n))
    f = model.external(model.x0, 1.0).ravel()
    fixed = np.asarray(model.fixed_dofs, dtype=np.int64)
    u = np.zeros(n)
    u[fixed] = model.prescribed(1.0) - model.x0.ravel()[fixed]
    free = np.setdiff1d(np.arange(n), fixed)
    rhs = f[free] - K[free][:, fixed] @ u[fixed]
    u[free] = spla.spsolve(K[free][:, free].tocsc(), rhs)
    return u.reshape(-1, 3)


def scaled_loads(data: dict, factor: float) -> dict:
    """A copy of a scene table with every load value multiplied by ``factor``."""
    import copy

    out = copy.deepcopy(data)
    for load in out.get("load", []):
        load["value"] = [factor * float(v) for v in load["value"]]
    return out


@pytest.fixture(scope="session")
def dk_reference():
    """The helpers :func:`dk_p1_displacement` and :func:`scaled_loads`."""
    return dk_p1_displacement, scaled_loads

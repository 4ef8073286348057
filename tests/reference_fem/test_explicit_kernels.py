"""Explicit FEM kernels (reference_fem.explicit_kernels) against numpy and finite differences.

The oracle is a vectorised numpy P1 evaluation written here from the formulas (``F`` from
the shape gradients of :func:`reference_fem.space.p1_gradients`, the first Piola stress,
``f_a = -V P grad N_a``), on a jittered non-cubic five-tet box with a padded last block.
float64 agrees to 1e-12 relative (round-off of reordered sums and FMA, ~1e-15 measured).
"""

from __future__ import annotations

import numpy as np
import pytest

from reference_fem.explicit_kernels import BLOCK, fem_kernel, fem_layout
from reference_fem.space import p1_gradients
from springfem.mesh import box_mesh

MU, LAM = 384.6, 576.9


@pytest.fixture(scope="module")
def mesh_state():
    mesh = box_mesh((1.0, 0.8, 0.6), (3, 3, 2), split="five")
    rng = np.random.default_rng(3)
    points = mesh.points + 0.04 * rng.standard_normal(mesh.points.shape)
    x = points + 0.03 * rng.standard_normal(points.shape)
    assert mesh.n_tets % BLOCK != 0
    return points, np.asarray(mesh.tets), x


def oracle(points, tets, x, law):
    G, V = p1_gradients(points, tets)
    X = x[tets]
    F = np.einsum("kac,kad->kcd", X, G)  # sum_a x_a (x) grad N_a
    if law == "neo-hookean":
        J = np.linalg.det(F)
        FinvT = np.linalg.inv(F).transpose(0, 2, 1)
        P = MU * (F - FinvT) + LAM * np.log(J)[:, None, None] * FinvT
    else:
        eps = 0.5 * (F + F.transpose(0, 2, 1)) - np.eye(3)
        P = 2 * MU * eps + LAM * np.trace(eps, axis1=1, axis2=2)[:, None, None] * np.eye(3)
    fe = -V[:, None, None] * np.einsum("kcd,kad->kac", P, G)
    f = np.zeros_like(x)
    np.add.at(f, tets, fe)
    return f


def run(points, tets, x, law, precision, parallel=False):
    T, K = fem_layout(tets, points, precision)
    serial, par = fem_kernel(law, precision)
    out = np.full_like(x, np.nan)
    if parallel:
        from springfem.blocks import chunks

        ptr = chunks(T.shape[0])
        buf = np.zeros((ptr.size - 1, x.shape[0], 3))
        bad = par(x, T, K, tets.shape[0], MU, LAM, ptr, buf, out)
    else:
        bad = serial(x, T, K, tets.shape[0], MU, LAM, out)
    return out, bad


def rel(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


#: Each compiled variant costs seconds on a cold numba cache. The parallel driver
#: (springfem.blocks) is the same code for every law: the default run checks it with
#: neo-Hookean (also compiled by ``springfem bench step``); linear in parallel runs with -m slow.
SLOW = pytest.mark.slow


@pytest.mark.parametrize(
    ("law", "parallel"),
    [("neo-hookean", False), ("linear", False), ("neo-hookean", True),
     pytest.param("linear", True, marks=SLOW)],
)  # fmt: skip
def test_float64_matches_oracle(mesh_state, law, parallel):
    points, tets, x = mesh_state
    f, bad = run(points, tets, x, law, "float64", parallel)
    assert bad == 0
    assert rel(f, oracle(points, tets, x, law)) < 1e-12


@pytest.mark.parametrize(
    ("law", "precision", "tol"),
    # each precision and each law once by default (the precision is a compile-time type,
    # independent of the law's arithmetic); the other two pairs with -m slow
    [("linear", "mixed", 1e-5), ("neo-hookean", "float32", 1e-4),
     pytest.param("neo-hookean", "mixed", 1e-5, marks=SLOW),
     pytest.param("linear", "float32", 1e-4, marks=SLOW)],
)  # fmt: skip
def test_reduced_precision(mesh_state, law, precision, tol):
    # float32 rounding (1.2e-7 relative) of the constants (mixed) and of every operation
    # (float32), amplified by the cancellation F - I at this ~5 % strain: bound ~1e-7 x 100
    points, tets, x = mesh_state
    f, _ = run(points, tets, x, law, precision)
    assert 1e-10 < rel(f, oracle(points, tets, x, law)) < tol


def test_inverted_elements_counted_and_left_out(mesh_state):
    points, tets, x = mesh_state
    y = x.copy()
    k = tets.shape[0] - 1  # an element of the padded last block: counted once
    a, b = tets[k, 0], tets[k, 1]
    y[a], y[b] = x[b], x[a]  # swap two vertices: J < 0
    J = np.linalg.det(y[tets[:, 1:]] - y[tets[:, :1]])
    n_inverted = int(np.sum(J <= 0))
    f, bad = run(points, tets, y, "neo-hookean", "float64")
    assert bad == n_inverted >= 1 and np.isfinite(f).all()
    ok = J > 0
    expected = oracle(points, tets[ok], y, "neo-hookean")
    assert rel(f, expected) < 1e-12
    _, bad_lin = run(points, tets, y, "linear", "float64")
    assert bad_lin == n_inverted


def test_bad_arguments():
    with pytest.raises(ValueError, match="law"):
        fem_kernel("mooney", "float64")
    with pytest.raises(ValueError, match="precision"):
        fem_kernel("linear", "float16")


def test_precision_scene_key():
    from reference_fem.options import FemOptions, parse_fem_options
    from springfem.errors import SceneError
    from springfem.scene import TableReader

    o = parse_fem_options(TableReader({"precision": "float32"}, "fem", "s.toml"))
    assert o.precision == "float32" and FemOptions().precision == "float64"
    with pytest.raises(SceneError, match="precision"):
        parse_fem_options(TableReader({"precision": "half"}, "fem", "s.toml"))

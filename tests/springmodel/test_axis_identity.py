"""The fast-kernel identity of docs/theory.rst#the-fast-kernel-identity: axis differences of ``C^k``
are shape gradients.

``G[k,i,l] = C[k,i,2l] - C[k,i,2l+1] = grad N_i . zeta_l^0``, on irregular tets with random
axes; distributing ``+-g`` through ``C`` equals distributing ``g`` through ``G``. It is what
lets the kernels (:mod:`springmodel.fastkernels`) skip the six intersection points.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from springfem.mesh import box_mesh
from springmodel import springs
from springmodel.elements import build_spring_elements
from springmodel.intersections import shape_gradients
from springmodel.options import SpringOptions

MATERIAL = {"law": "linear", "E": 1.0e3, "nu": 0.3}


@pytest.fixture(scope="module")
def mesh_state():
    """A perturbed 3x3x2 five-tet box (irregular tets), random axes."""
    mesh = box_mesh((1.0, 1.3, 0.7), (3, 3, 2), split="five")
    rng = np.random.default_rng(0)
    points = mesh.points + 0.04 * rng.standard_normal(mesh.points.shape)
    frames = Rotation.random(mesh.n_tets, random_state=1).as_matrix()
    el = build_spring_elements(points, mesh.tets, frames, SpringOptions(), MATERIAL)
    x = points + 0.15 * rng.standard_normal(points.shape)
    return points, el, x, None


def test_axis_gradient_identity(mesh_state):
    # G[k,i,l] = C[k,i,2l] - C[k,i,2l+1] = grad N_i . zeta_l^0
    # (docs/theory.rst#the-fast-kernel-identity), on irregular tets
    # with random axes; and distributing +-g through C equals distributing g through G
    points, el, x, _ = mesh_state
    grad = shape_gradients(points, el.tets)
    np.testing.assert_allclose(el.G, np.einsum("kic,klc->kil", grad, el.zeta0), rtol=0, atol=1e-13)
    g = np.random.default_rng(2).standard_normal((el.n_elements, 3, 3))
    fq = np.zeros((el.n_elements, 6, 3))
    fq[:, 0::2], fq[:, 1::2] = g, -g
    via_C = np.einsum("kij,kjc->kic", el.C, fq)
    via_G = np.einsum("kil,klc->kic", el.G, g)
    np.testing.assert_allclose(via_C, via_G, rtol=0, atol=1e-13 * np.abs(g).max())
    zeta_C = springs.intersection_points(x, el)
    zeta_G = np.einsum("kil,kic->klc", el.G, x[el.tets])
    np.testing.assert_allclose(zeta_C[:, 0::2] - zeta_C[:, 1::2], zeta_G, atol=1e-13)

"""Fused kernel (springmodel.kernels) against the numpy oracle (springmodel.springs).

The oracle goes through the six intersection points and ``C^k``; the kernel uses the axis
gradients ``G``. Agreement to 1e-12 relative (round-off of differently ordered sums) for
every variant, serial and parallel, plus the identity that makes the kernel legitimate.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from springfem.mesh import box_mesh
from springmodel import springs
from springmodel.elements import build_spring_elements
from springmodel.intersections import shape_gradients
from springmodel.kernels import ForceKernel, element_colouring
from springmodel.options import SpringOptions

MATERIAL = {"law": "linear", "E": 1.0e3, "nu": 0.3}
MODES = [(False, "colour"), (True, "colour"), (True, "buffer")]


@pytest.fixture(scope="module")
def mesh_state():
    """A perturbed 3x3x2 five-tet box (irregular tets), random axes, random constants."""
    mesh = box_mesh((1.0, 1.3, 0.7), (3, 3, 2), split="five")
    rng = np.random.default_rng(0)
    points = mesh.points + 0.04 * rng.standard_normal(mesh.points.shape)
    frames = Rotation.random(mesh.n_tets, random_state=1).as_matrix()
    el = build_spring_elements(points, mesh.tets, frames, SpringOptions(), MATERIAL)
    el.k_axial = el.k_axial * rng.uniform(0.5, 2, el.k_axial.shape)
    el.k_torsion = el.k_torsion * rng.uniform(0.5, 2, el.k_torsion.shape)
    el.k_volume = el.k_volume * rng.uniform(0.5, 2, el.k_volume.shape)
    x = points + 0.15 * rng.standard_normal(points.shape)
    v = rng.standard_normal(points.shape)
    return points, el, x, v


def variants():
    axial = ("linear", "quadratic", "cubic", "stress-scaled")
    torsion = ("off", "angle", "cosine", "cubic", "energy")
    for a, t in itertools.product(axial, torsion):
        yield SpringOptions(
            axial=a,
            axial_coefficients=(0.6, 0.4),
            torsion=t,
            torsion_cubic=1.3,
            axial_damping=0.2,
            volume_damping=0.3,
        )
    for form, damping in itertools.product(("gradient", "spec"), (0.0, 0.5)):
        yield SpringOptions(torsion="energy", volume_form=form, volume_damping=damping)
    yield SpringOptions(torsion="cosine", volume=False)


def rel(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


@pytest.mark.parametrize(
    "options",
    list(variants()),
    ids=lambda o: f"{o.axial}-{o.torsion}-{o.volume and o.volume_form}-{o.volume_damping}",
)
@pytest.mark.parametrize(("parallel", "scatter"), [(False, "colour"), (True, "buffer")])
def test_kernel_matches_oracle(mesh_state, options, parallel, scatter):
    _, el, x, v = mesh_state
    expected = springs.internal_forces(x, v, el, options)
    kernel = ForceKernel(el, options, parallel=parallel, scatter=scatter)
    assert rel(kernel.forces(x, v), expected) < 1e-12
    # without velocities: no damping, in both
    assert rel(kernel.forces(x), springs.internal_forces(x, None, el, options)) < 1e-12


@pytest.mark.parametrize(
    "options",
    [
        SpringOptions(axial="stress-scaled", torsion="angle", volume_form="spec"),
        SpringOptions(axial="cubic", axial_coefficients=(0.5, 0.5), torsion="energy"),
        SpringOptions(torsion="cubic", torsion_cubic=2.0, axial_damping=0.3, volume_damping=0.2),
    ],
    ids=["stress-angle-spec", "cubic-energy-gradient", "damped-cubic"],
)
def test_colour_scatter_matches_oracle(mesh_state, options):
    # the colour driver runs the same element code as the others: a few variants suffice
    _, el, x, v = mesh_state
    kernel = ForceKernel(el, options, parallel=True, scatter="colour")
    assert kernel.n_colours > 1
    assert rel(kernel.forces(x, v), springs.internal_forces(x, v, el, options)) < 1e-12


@pytest.mark.parametrize(("parallel", "scatter"), MODES)
def test_kernel_is_deterministic_and_writes_out(mesh_state, parallel, scatter):
    _, el, x, v = mesh_state
    options = SpringOptions(torsion="energy", volume_damping=0.1)
    kernel = ForceKernel(el, options, parallel=parallel, scatter=scatter)
    out = np.full_like(x, np.nan)
    first = kernel.forces(x, v, out=out).copy()
    assert np.shares_memory(kernel.forces(x, v, out=out), out)
    for _ in range(3):
        np.testing.assert_array_equal(kernel.forces(x, v), first)  # bit-identical


def test_parallel_colour_equals_serial_order_of_colours(mesh_state):
    # colour mode sums at each node in colour order whatever the thread count, so parallel
    # equals a serial pass over the colour-ordered elements exactly
    _, el, x, _ = mesh_state
    options = SpringOptions(torsion="cosine")
    par = ForceKernel(el, options, parallel=True, scatter="colour")
    ser = ForceKernel(el, options, parallel=False)
    ser._tets, ser._G, ser._P = par._tets, par._G, par._P  # serial pass in colour order
    np.testing.assert_array_equal(par.forces(x), ser.forces(x))


def test_colouring_is_valid():
    mesh = box_mesh((1.0, 1.0, 1.0), (4, 3, 3), split="six")
    colour = element_colouring(mesh.tets, mesh.n_points)
    assert colour.min() == 0
    for c in range(colour.max() + 1):
        nodes = mesh.tets[colour == c].ravel()
        assert nodes.size == np.unique(nodes).size  # no node shared within a colour
    # greedy bound: at most (number of elements touching a tet's nodes) colours
    valence = np.bincount(mesh.tets.ravel())
    assert colour.max() + 1 <= 4 * valence.max()


def test_axis_gradient_identity(mesh_state):
    # G[k,i,l] = C[k,i,2l] - C[k,i,2l+1] = grad N_i . zeta_l^0 (DESIGN §4), on irregular tets
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


def test_volume_stiffness_update_and_energy(mesh_state):
    _, el, x, _ = mesh_state
    options = SpringOptions(torsion="energy")
    kernel = ForceKernel(el, options, parallel=True)
    k_new = el.k_volume * np.linspace(0.5, 3.0, el.n_elements)
    kernel.set_volume_stiffness(k_new)
    el_new = el.with_volume_stiffness(k_new)
    assert rel(kernel.forces(x), springs.internal_forces(x, None, el_new, options)) < 1e-12
    assert kernel.energy(x) == pytest.approx(springs.spring_energy(x, el_new, options)[1])

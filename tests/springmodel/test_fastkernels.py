"""Specialised spring kernels (springmodel.fastkernels) against the numpy oracle (springs).

The oracle goes through the six intersection points and ``C^k``; the kernels use the axis
gradients ``G / l0`` on a blocked layout. In float64 they agree to 1e-12 relative (round-off
of differently ordered sums and FMA contraction, ~1e-15 measured) on a jittered, non-cubic
five-tet box with random axes and random constants. The reduced precisions are held to
what their rounding allows (see each test). Every variant compiles its own kernel (several
seconds each), so the full sweep is ``slow``; the default run covers each law once.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from springfem.blocks import BLOCK, block_layout
from springfem.mesh import box_mesh
from springmodel import springs
from springmodel.elements import build_spring_elements
from springmodel.fastkernels import Variant
from springmodel.options import SpringOptions
from springmodel.spring_kernel import SpringKernel, needs_c0, variant_of

MATERIAL = {"law": "linear", "E": 1.0e3, "nu": 0.3}


@pytest.fixture(scope="module")
def mesh_state():
    """A perturbed 3x3x2 five-tet box (irregular tets; 90 tets: 5 full blocks and a partial
    one), random axes, random constants, a large random deformation and velocities."""
    mesh = box_mesh((1.0, 1.3, 0.7), (3, 3, 2), split="five")
    rng = np.random.default_rng(0)
    points = mesh.points + 0.04 * rng.standard_normal(mesh.points.shape)
    frames = Rotation.random(mesh.n_tets, random_state=1).as_matrix()
    el = build_spring_elements(points, mesh.tets, frames, SpringOptions(), MATERIAL)
    el.k_axial = el.k_axial * rng.uniform(0.5, 2, el.k_axial.shape)
    el.k_torsion = el.k_torsion * rng.uniform(0.5, 2, el.k_torsion.shape)
    el.k_volume = el.k_volume * rng.uniform(0.5, 2, el.k_volume.shape)
    el.k_axis_volume = rng.uniform(100.0, 300.0, el.n_elements)  # not calibrated: random
    el.k_coupling = rng.uniform(-20.0, 50.0, (el.n_elements, 3))
    x = points + 0.15 * rng.standard_normal(points.shape)
    v = rng.standard_normal(points.shape)
    assert el.n_elements % BLOCK != 0  # the padded last block is exercised
    return points, el, x, v


@pytest.fixture(scope="module")
def skewed(mesh_state):
    """The same elements with non-zero rest cosines (as non-orthogonal axes would give):
    the kernels must then read ``c0`` (and ``alpha0``)."""
    _, el, x, v = mesh_state
    rng = np.random.default_rng(5)
    c0 = rng.uniform(-0.3, 0.3, el.c0.shape)
    from dataclasses import replace

    return replace(el, c0=c0, alpha0=np.arccos(c0)), x, v


def rel(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


def all_variants():
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
    for vol, coupling in itertools.product(("quadratic", "log", "simo-taylor"), (False, True)):
        yield SpringOptions(
            torsion="energy", volume="axes", volumetric=vol, coupling=coupling, volume_damping=0.3
        )


FAST = [
    SpringOptions(),  # the seed variant: linear, cosine, gradient
    SpringOptions(
        axial="cubic",
        axial_coefficients=(0.6, 0.4),
        torsion="energy",
        axial_damping=0.2,
        volume_damping=0.3,
    ),
    SpringOptions(axial="stress-scaled", torsion="angle", volume_form="spec"),
    SpringOptions(
        axial="quadratic",
        axial_coefficients=(0.6, 0.4),
        torsion="cubic",
        torsion_cubic=1.3,
        volume=False,
    ),
    SpringOptions(
        torsion="energy",
        volume="axes",
        volumetric="simo-taylor",
        coupling=True,
        volume_damping=0.3,
    ),
]


def label(o):
    vol = o.volume_form if o.volume is True else ("axes-" + o.volumetric if o.volume else "off")
    return f"{o.axial}-{o.torsion}-{vol}-{o.coupling}-{o.volume_damping}"


def check(el, x, v, options, parallel=False, tol=1e-12):
    kernel = SpringKernel(el, options, parallel=parallel)
    assert rel(kernel.forces(x, v), springs.internal_forces(x, v, el, options)) < tol
    # without velocities: no damping, in both
    assert rel(kernel.forces(x), springs.internal_forces(x, None, el, options)) < tol


@pytest.mark.parametrize("options", FAST, ids=label)
def test_kernel_matches_oracle(mesh_state, options):
    _, el, x, v = mesh_state
    check(el, x, v, options)


@pytest.mark.slow
@pytest.mark.parametrize("options", list(all_variants()), ids=label)
def test_every_variant_matches_oracle(mesh_state, options):
    points, el, x, v = mesh_state
    if options.axis_volume and options.volumetric == "log":
        # U = kappa/2 ln(J)^2 is undefined for inverted elements, which the large random
        # deformation has (both backends give NaN there): a fifth of it inverts none
        x = points + 0.2 * (x - points)
        assert np.isfinite(springs.internal_forces(x, v, el, options)).all()
    check(el, x, v, options)


@pytest.mark.parametrize(
    "torsion",
    # cosine by default: the seed variant with rest cosines, which the accuracy study's
    # unstructured meshes compile anyway; the other two laws with -m slow
    [
        "cosine",
        pytest.param("energy", marks=pytest.mark.slow),
        pytest.param("angle", marks=pytest.mark.slow),
    ],
)
def test_rest_cosines_are_read_when_not_zero(skewed, torsion):
    el, x, v = skewed
    options = SpringOptions(torsion=torsion)
    assert variant_of(el, options).c0 == (torsion != "angle")  # angle reads alpha0
    check(el, x, v, options)


def test_parallel_matches_oracle_and_is_deterministic(mesh_state):
    _, el, x, v = mesh_state
    options = FAST[1]
    kernel = SpringKernel(el, options, parallel=True)
    assert kernel.parallel
    first = kernel.forces(x, v).copy()
    assert rel(first, springs.internal_forces(x, v, el, options)) < 1e-12
    out = np.full_like(x, np.nan)
    assert np.shares_memory(kernel.forces(x, v, out=out), out)
    for _ in range(3):
        np.testing.assert_array_equal(kernel.forces(x, v), first)  # bit-identical


@pytest.mark.parametrize(("precision", "tol"), [("mixed", 1e-5), ("float32", 1e-4)])
def test_reduced_precision(mesh_state, precision, tol):
    # mixed: constants rounded to float32 (relative 6e-8 each), arithmetic in float64;
    # float32: also the edge vectors and every operation (~1e-7 relative each), with
    # cancellation in dL = sum|xi| - L0 and |zeta|/l0 - 1 at this ~15 % strain: the bound is
    # the float32 epsilon (1.2e-7) times a cancellation factor of at most ~100.
    _, el, x, v = mesh_state
    for options in FAST[:1]:
        kernel = SpringKernel(el, options, precision=precision)
        err = rel(kernel.forces(x, v), springs.internal_forces(x, v, el, options))
        assert 1e-10 < err < tol  # really rounded, and no worse than its rounding allows


def test_volume_stiffness_update_and_energy(mesh_state):
    _, el, x, _ = mesh_state
    options = SpringOptions(torsion="energy")
    kernel = SpringKernel(el, options)
    k_new = el.k_volume * np.linspace(0.5, 3.0, el.n_elements)
    kernel.set_volume_stiffness(k_new)
    el_new = el.with_volume_stiffness(k_new)
    assert rel(kernel.forces(x), springs.internal_forces(x, None, el_new, options)) < 1e-12
    assert kernel.energy(x) == pytest.approx(springs.spring_energy(x, el_new, options)[1])


def test_compact_constants(mesh_state):
    # orthonormal frames: c0 is round-off (docs/theory.rst#axis-vectors-are-parallel-to-the-frame)
    # and is not stored; the seed variant
    # reads 9 + 3 + 6 + 2 constants and 4 int32 ids
    _, el, _, _ = mesh_state
    assert not needs_c0(el)
    kernel = SpringKernel(el, SpringOptions())
    assert kernel.bytes_per_element == 20 * 8 + 16
    assert SpringKernel(el, SpringOptions(), precision="mixed").bytes_per_element == 20 * 4 + 16
    assert len(Variant(torsion="energy").columns()) == 9 + 3 + 3 + 2


def test_block_layout_round_trip():
    rng = np.random.default_rng(1)
    m = 3 * BLOCK + 5
    tets = rng.integers(0, 100, (m, 4))
    cols = rng.standard_normal((7, m))
    T, K = block_layout(tets, cols, np.float64)
    back = T.reshape(-1, 4, BLOCK).transpose(0, 2, 1).reshape(-1, 4)[:m]
    np.testing.assert_array_equal(back, tets)
    kb = K.reshape(-1, 7, BLOCK).transpose(1, 0, 2).reshape(7, -1)[:, :m]
    np.testing.assert_array_equal(kb, cols)


def test_bad_options(mesh_state):
    _, el, _, _ = mesh_state
    with pytest.raises(ValueError, match="precision"):
        SpringKernel(el, SpringOptions(), precision="float16")


def test_precision_scene_key():
    from springfem.errors import SceneError
    from springfem.scene import TableReader
    from springmodel.options import parse_spring_options

    o = parse_spring_options(TableReader({"precision": "mixed"}, "spring", "s.toml"))
    assert o.precision == "mixed" and SpringOptions().precision == "float64"
    with pytest.raises(SceneError, match="precision"):
        parse_spring_options(TableReader({"precision": "half"}, "spring", "s.toml"))

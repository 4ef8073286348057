"""Tests of springfem.axes: per-element orthonormal anisotropy frames.

References: scipy's Rotation for Rodrigues' formula, the defining properties of a proper
orthonormal frame (F F^T = I, det F = +1, F[2] = F[0] x F[1]), and angles measured with
atan2. Tolerances of 1e-14 to 1e-15 are a few eps: every quantity here is O(1).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial.transform import Rotation

from springfem.axes import (
    cell_frames,
    helix_frames,
    orthonormal_frame,
    rotation_matrix,
    uniform_frames,
)


def assert_proper_frames(F: np.ndarray, atol: float = 1e-14) -> None:
    """Rows orthonormal, right-handed (normal = fiber x sheet, det = +1)."""
    F = F.reshape(-1, 3, 3)
    eye = np.broadcast_to(np.eye(3), F.shape)
    np.testing.assert_allclose(F @ F.transpose(0, 2, 1), eye, rtol=0, atol=atol)
    np.testing.assert_allclose(np.linalg.det(F), 1.0, rtol=0, atol=atol)
    np.testing.assert_allclose(np.cross(F[:, 0], F[:, 1]), F[:, 2], rtol=0, atol=atol)


def signed_angle_deg(u: np.ndarray, v: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Angle from ``u`` to ``v`` about ``axis`` (right-hand rule), in degrees."""
    axis = axis / np.linalg.norm(axis)
    return np.degrees(np.arctan2(np.cross(u, v) @ axis, (u * v).sum(axis=-1)))


# ---------------------------------------------------------------------- rotation_matrix
def test_rotation_matrix_matches_scipy():
    rng = np.random.default_rng(0)
    for _ in range(50):
        axis, angle = rng.normal(size=3), rng.uniform(-7, 7)
        expect = Rotation.from_rotvec(angle * axis / np.linalg.norm(axis)).as_matrix()
        np.testing.assert_allclose(rotation_matrix(axis, angle), expect, atol=1e-14)


def test_rotation_matrix_vectorised_over_angles():
    angles = np.linspace(-np.pi, np.pi, 7)
    R = rotation_matrix([0.0, 0.0, 2.0], angles)
    assert R.shape == (7, 3, 3)
    np.testing.assert_allclose(R[:, 0, 0], np.cos(angles), atol=1e-15)
    np.testing.assert_allclose(R[:, 1, 0], np.sin(angles), atol=1e-15)
    assert_proper_frames(R)


@pytest.mark.parametrize("axis", [[0.0, 0.0, 0.0], [1.0, 0.0], [np.nan, 1.0, 0.0]])
def test_rotation_matrix_rejects_bad_axis(axis):
    with pytest.raises(ValueError, match="rotation axis"):
        rotation_matrix(axis, 0.3)


# ---------------------------------------------------------------------- orthonormal_frame
def test_orthonormal_frame_by_hand():
    F = orthonormal_frame([0.0, 0.0, 3.0], [2.0, 0.0, 5.0])
    np.testing.assert_allclose(F, [[0, 0, 1], [1, 0, 0], [0, 1, 0]], atol=1e-15)


def _frame_properties(fiber, sheet):
    nf, ns = np.linalg.norm(fiber), np.linalg.norm(sheet)
    assume(nf > 1e-6 and ns > 1e-6 and np.linalg.norm(np.cross(fiber, sheet)) > 1e-5 * nf * ns)
    F = orthonormal_frame(fiber, sheet)
    assert_proper_frames(F)
    np.testing.assert_allclose(F[0], fiber / nf, atol=1e-15)  # fiber kept, normalised
    assert F[1] @ sheet > 0  # sheet keeps its side of the fiber ...
    assert abs(F[2] @ sheet) <= 1e-13 * ns  # ... and stays in the fiber-sheet plane


@pytest.mark.parametrize(  # a fifth of the search by default, all of it under -m slow
    "n_examples",
    [pytest.param(60, id="quick"), pytest.param(300, id="full", marks=pytest.mark.slow)],
)
def test_orthonormal_frame_properties(n_examples):
    vectors = arrays(np.float64, 3, elements=st.floats(-100, 100))
    cases = given(fiber=vectors, sheet=vectors)
    settings(max_examples=n_examples, deadline=None)(cases(_frame_properties))()


def test_orthonormal_frame_close_to_parallel_is_still_orthonormal():
    # angles just above the tolerance (sin = 1e-6) are accepted; one Gram-Schmidt pass would
    # leave F[0] . F[1] ~ eps / angle ~ 1e-10, the frame must be orthonormal to round-off
    rng = np.random.default_rng(5)
    fib = rng.normal(size=(200, 3))
    perp = np.cross(fib, rng.normal(size=(200, 3)))
    angle = 2e-6
    R = Rotation.from_rotvec(angle * perp / np.linalg.norm(perp, axis=1, keepdims=True))
    sheet = R.apply(fib) * rng.uniform(0.1, 10.0, size=(200, 1))
    F = orthonormal_frame(fib, sheet)
    assert_proper_frames(F)
    # the sheet axis is the in-plane perpendicular direction, to ~ eps / angle
    expect = np.cross(perp, fib)
    expect /= np.linalg.norm(expect, axis=1, keepdims=True)
    np.testing.assert_allclose(F[:, 1], expect, atol=1e-9)


def test_orthonormal_frame_broadcasts():
    rng = np.random.default_rng(1)
    fib = rng.normal(size=(4, 5, 3))
    F = orthonormal_frame(fib, [0.3, 0.1, 1.0])
    assert F.shape == (4, 5, 3, 3)
    assert_proper_frames(F)
    np.testing.assert_allclose(F[2, 3], orthonormal_frame(fib[2, 3], [0.3, 0.1, 1.0]))


@pytest.mark.parametrize(
    ("fiber", "sheet", "match"),
    [
        ([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], "fiber vector is zero"),
        ([1.0, np.inf, 0.0], [0.0, 1.0, 0.0], "fiber vector is zero or not finite"),
        ([1.0, 0.0, 0.0], [0.0, 0.0, 0.0], "sheet vector is zero or parallel"),
        ([1.0, 0.0, 0.0], [2.0, 0.0, 0.0], "parallel"),
        ([1.0, 0.0, 0.0], [-3.0, 0.0, 0.0], "parallel"),
        ([1.0, 0.0, 0.0], [1.0, 1e-9, 0.0], "parallel"),  # nearly parallel
        ([1.0, 0.0, 0.0], [1.0, np.nan, 0.0], "parallel"),
        ([1.0, 0.0], [0.0, 1.0], "3 components"),
    ],
)
def test_orthonormal_frame_rejects(fiber, sheet, match):
    with pytest.raises(ValueError, match=match):
        orthonormal_frame(fiber, sheet)


def test_orthonormal_frame_names_bad_elements():
    fib = np.tile([1.0, 0.0, 0.0], (6, 1))
    sheet = np.tile([0.0, 1.0, 0.0], (6, 1))
    sheet[[1, 4]] = [5.0, 0.0, 0.0]
    with pytest.raises(ValueError, match=r"at elements 1, 4$"):
        orthonormal_frame(fib, sheet)


# ---------------------------------------------------------------------- uniform_frames
def test_uniform_frames():
    F = uniform_frames(10, [1.0, 1.0, 0.0], [0.0, 0.0, 1.0])
    assert F.shape == (10, 3, 3) and F.flags.writeable and F.flags.c_contiguous
    assert_proper_frames(F)
    s = np.sqrt(0.5)
    np.testing.assert_allclose(F, np.broadcast_to([[s, s, 0], [0, 0, 1], [s, -s, 0]], F.shape))
    F[0, 0] = 0.0  # a real array, not a broadcast view
    assert F[1, 0, 0] == pytest.approx(s)
    with pytest.raises(ValueError, match="parallel"):
        uniform_frames(3, [0.0, 1.0, 0.0], [0.0, -2.0, 0.0])


# ---------------------------------------------------------------------- helix_frames
def wall_centers(n: int = 41) -> np.ndarray:
    rng = np.random.default_rng(2)
    c = rng.uniform(-1, 1, size=(n, 3))
    c[:, 0] = np.linspace(0.0, 1.0, n)  # transmural coordinate x from endo (0) to epi (1)
    return c


def test_helix_angle_at_both_ends_and_linear_between():
    c = wall_centers()
    # fiber circumferential (y), sheet transmural (x): the helix turns about x
    F = helix_frames(c, [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], "x", (0.0, 1.0), (60.0, -60.0))
    assert F.shape == (len(c), 3, 3)
    assert_proper_frames(F)
    angle = signed_angle_deg(np.array([0.0, 1.0, 0.0]), F[:, 0], np.array([1.0, 0.0, 0.0]))
    assert angle[0] == pytest.approx(60.0, abs=1e-12)
    assert angle[-1] == pytest.approx(-60.0, abs=1e-12)
    np.testing.assert_allclose(angle, 60.0 - 120.0 * c[:, 0], atol=1e-12)
    # the fiber stays in the planes of constant depth, the transmural sheet is unchanged
    np.testing.assert_allclose(F[:, 0, 0], 0.0, atol=1e-15)
    np.testing.assert_allclose(F[:, 1], np.tile([1.0, 0.0, 0.0], (len(c), 1)), atol=1e-15)


def test_helix_reversed_range_and_clamping():
    c = np.array([[-1.0, 0, 0], [0.0, 0, 0], [2.0, 0, 0], [4.0, 0, 0], [9.0, 0, 0]])
    # range given from high to low coordinate; angles clamp outside it
    F = helix_frames(c, [0.0, 0.0, 1.0], [0.0, 1.0, 0.0], 0, (4.0, 0.0), (-30.0, 90.0))
    angle = signed_angle_deg(np.array([0.0, 0.0, 1.0]), F[:, 0], np.array([1.0, 0.0, 0.0]))
    np.testing.assert_allclose(angle, [90.0, 90.0, 30.0, -30.0, -30.0], atol=1e-12)


def test_helix_about_explicit_vector_matches_rodrigues():
    c = wall_centers(9)
    fiber, sheet = np.array([1.0, 0.2, 0.0]), np.array([0.0, 1.0, 0.5])
    about = np.array([0.3, -0.4, 1.0])
    F = helix_frames(c, fiber, sheet, "x", (0.0, 1.0), (10.0, 100.0), about=about)
    assert_proper_frames(F)
    base = orthonormal_frame(fiber, sheet)
    for k in range(len(c)):
        R = Rotation.from_rotvec(
            np.radians(10.0 + 90.0 * c[k, 0]) * about / np.linalg.norm(about)
        ).as_matrix()
        np.testing.assert_allclose(F[k], base @ R.T, atol=1e-14)


def test_helix_about_by_name_equals_about_by_vector():
    c = wall_centers(5)
    args = (c, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], "y", (-1.0, 1.0), (20.0, -20.0))
    np.testing.assert_allclose(
        helix_frames(*args, about="z"), helix_frames(*args, about=[0.0, 0.0, 7.0]), atol=1e-15
    )
    np.testing.assert_allclose(helix_frames(*args, about=2), helix_frames(*args, about="z"))


def test_helix_errors():
    c = wall_centers(5)
    with pytest.raises(ValueError, match="parallel to the rotation axis"):
        # default about = the coordinate axis x, and the fiber is along x: it cannot turn
        helix_frames(c, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], "x", (0.0, 1.0), (60.0, -60.0))
    with pytest.raises(ValueError, match="two different finite coordinates"):
        helix_frames(c, [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], "x", (1.0, 1.0), (60.0, -60.0))
    with pytest.raises(ValueError, match="'x', 'y', 'z'"):
        helix_frames(c, [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], "r", (0.0, 1.0), (60.0, -60.0))
    with pytest.raises(ValueError, match="non-zero 3-vector"):
        helix_frames(c, [0.0, 1.0, 0.0], [1, 0, 0], "x", (0, 1), (60, -60), about=[0, 0, 0])
    with pytest.raises(ValueError, match="parallel"):
        helix_frames(c, [0.0, 1.0, 0.0], [0.0, 2.0, 0.0], "x", (0.0, 1.0), (60.0, -60.0))


# ---------------------------------------------------------------------- cell_frames
def test_cell_frames_with_sheets_are_rowwise_frames():
    rng = np.random.default_rng(3)
    fib, sheet = rng.normal(size=(2, 50, 3))
    F = cell_frames(fib, sheet)
    assert_proper_frames(F)
    for k in (0, 17, 49):
        np.testing.assert_allclose(F[k], orthonormal_frame(fib[k], sheet[k]), atol=1e-15)


def test_cell_frames_without_sheets_are_deterministic_and_local():
    rng = np.random.default_rng(4)
    fib = rng.normal(size=(200, 3)) * rng.uniform(0.01, 100, size=(200, 1))
    fib[:3] = [[0.0, 0.0, 2.0], [1.0, 1.0, 1.0], [0.0, -1.0, 0.0]]  # axis-aligned, ties
    F = cell_frames(fib)
    assert_proper_frames(F)
    np.testing.assert_allclose(F[:, 0], fib / np.linalg.norm(fib, axis=1, keepdims=True))
    perm = rng.permutation(len(fib))
    np.testing.assert_array_equal(cell_frames(fib[perm]), F[perm])  # depends on the cell only
    # the sheet comes from the coordinate axis least aligned with the fiber: for these
    # fibers that is x (index 0, first on ties), so the sheet lies in the x-fiber plane
    np.testing.assert_allclose(F[:3, 2] @ np.array([1.0, 0.0, 0.0]), 0.0, atol=1e-15)


def test_cell_frames_errors_name_cells():
    fib = np.tile([0.0, 0.0, 1.0], (5, 1))
    fib[3] = 0.0
    with pytest.raises(ValueError, match="fiber vector is zero or not finite at elements 3$"):
        cell_frames(fib)
    with pytest.raises(ValueError, match=r"shape \(m, 3\)"):
        cell_frames(np.ones((5, 2)))
    with pytest.raises(ValueError, match=r"sheet vectors must have shape \(5, 3\)"):
        cell_frames(np.ones((5, 3)), np.ones((4, 3)))
    sheet = np.tile([0.0, 1.0, 0.0], (5, 1))
    sheet[2] = [0.0, 0.0, -1.0]
    fib[3] = [1.0, 0.0, 0.0]
    with pytest.raises(ValueError, match="parallel to the fiber at elements 2$"):
        cell_frames(fib, sheet)

"""springfem.testing.check_model catches what it claims to catch: toy models, each the core's
linear P1 (springfem.testing.LinearP1) with one defect, fail the check that defect breaks
and pass the others; the reference itself passes every check it is held to."""

from __future__ import annotations

import numpy as np
import pytest

from springfem.model_api import SystemModel
from springfem.scene import scene_from_dict
from springfem.testing import LinearP1, check_model, rotation, scaled_scene


@pytest.fixture(scope="module")
def scene():
    """A jittered Delaunay box (45 nodes), clamped at x_min, a traction at x_max."""
    return scene_from_dict({
        "name": "toybox",
        "mesh": {"generator": "box", "size": [0.04, 0.02, 0.02], "divisions": [4, 2, 2],
                 "split": "delaunay"},
        "material": {"law": "linear", "E": 1e4, "nu": 0.3, "density": 1000.0},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        "load": [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, -10.0]}],
    })  # fmt: skip


class Anchored(LinearP1):
    """Each node also tied to its rest position: a force under rigid motion."""

    def forces(self, x, v=None, scale=1.0):
        return super().forces(x, v, scale) - 1e-2 * self.K.diagonal().reshape(-1, 3) * (x - self.x0)

    def energy(self, x, scale=1.0):
        d = (np.asarray(x) - self.x0).ravel()
        return super().energy(x, scale) + 0.5e-2 * float(self.K.diagonal() @ d**2)

    def stiffness(self, x, scale=1.0):
        return self.K + 1e-2 * type(self.K)(np.diag(self.K.diagonal()))


class Cubic(LinearP1):
    """P1 plus quartic edge springs of the edge's displacement ``d = u_i - u_j`` (energy
    ``c |d|^4 / 4``): blind to translations, nonlinear, yet not objective."""

    def __init__(self, scene):
        super().__init__(scene)
        pairs = [(a, b) for a in range(4) for b in range(a)]
        self.edges = np.unique(np.sort(np.concatenate([self.tets[:, p] for p in pairs])), axis=0)
        self.c = float(self.K.diagonal().mean()) / np.ptp(self.x0) ** 2 * 1e2

    def _d(self, x):
        u = np.asarray(x) - self.x0
        return u[self.edges[:, 0]] - u[self.edges[:, 1]]

    def forces(self, x, v=None, scale=1.0):
        d = self._d(x)
        g = self.c * (d * d).sum(axis=1, keepdims=True) * d  # dW/dd
        f = super().forces(x, v, scale)
        np.add.at(f, self.edges[:, 0], -g)
        np.add.at(f, self.edges[:, 1], g)
        return f

    def energy(self, x, scale=1.0):
        w = (self._d(x) ** 2).sum(axis=1) ** 2
        return super().energy(x, scale) + 0.25 * self.c * float(w.sum())

    def stiffness(self, x, scale=1.0):
        d = self._d(x)
        H = self.c * ((d * d).sum(1)[:, None, None] * np.eye(3) + 2 * d[:, :, None] * d[:, None])
        K = self.K.toarray()
        for (i, j), h in zip(self.edges, H, strict=True):
            for a, b, sign in ((i, i, 1), (j, j, 1), (i, j, -1), (j, i, -1)):
                K[3 * a : 3 * a + 3, 3 * b : 3 * b + 3] += sign * h
        return type(self.K)(K)


class HalfEnergy(LinearP1):
    """The energy reported is half the forces' potential."""

    def energy(self, x, scale=1.0):
        return 0.5 * super().energy(x, scale)


class Flipped(LinearP1):
    def stiffness(self, x, scale=1.0):
        return -self.K


class Stiffer(LinearP1):
    """Ten per cent stiffer than the scene's law."""

    def __init__(self, scene):
        super().__init__(scene)
        self.K = 1.1 * self.K


class Crashing(LinearP1):
    def forces(self, x, v=None, scale=1.0):
        raise RuntimeError("kernel fault")


def model(cls, name="toy"):
    return SystemModel(name, name, cls)


def test_the_reference_passes_everything_it_is_held_to(scene):
    report = check_model(model(LinearP1), scene, small_strain="exact", rotation="infinitesimal")
    assert report.passed, str(report)
    assert [c.name for c in report.checks if c.status == "skipped"] == ["finite rotation"]
    assert report.checks[0].value < 1e-8 and report.checks[0].tolerance == 1e-8


@pytest.mark.parametrize(
    ("cls", "failed"),
    [
        (Anchored, {"translation", "infinitesimal rotation", "small strain"}),
        (Cubic, {"finite rotation"}),
        (HalfEnergy, {"energy gradient", "explicit energy"}),
        # the tangent at rest and the stable step come from the tangent too
        (Flipped, {"tangent", "small strain", "explicit energy"}),
        (Stiffer, {"small strain"}),
    ],
)
def test_each_defect_fails_its_check(scene, cls, failed):
    report = check_model(model(cls), scene, small_strain="exact", strict=False)
    assert {c.name for c in report.failures} == failed, str(report)
    with pytest.raises(AssertionError, match=f"model toy fails {len(failed)} check"):
        check_model(model(cls), scene, small_strain="exact")


def test_a_crash_is_a_failure_naming_the_exception(scene):
    report = check_model(model(Crashing), scene, strict=False)
    assert report.status("translation") == "failed"
    assert "RuntimeError: kernel fault" in report.checks[0].message


def test_an_approximate_tangent_is_measured_not_failed(scene):
    report = check_model(model(Flipped), scene, tangent="approximate", strict=False)
    assert report.status("tangent") == "skipped"
    assert report.checks[4].value == pytest.approx(2.0, rel=1e-6)  # K d = -(-K d): off by 2


def test_claims_come_from_the_model(scene):
    m = model(Stiffer)
    m.claims = {"small_strain": "exact"}  # type: ignore[attr-defined]
    assert check_model(m, scene, strict=False).status("small strain") == "failed"
    m.claims = {"small_strain": "limit", "small_strain_tol": 0.2}  # type: ignore[attr-defined]
    report = check_model(m, scene, strict=False)
    assert report.status("small strain") == "passed"
    assert report.checks[5].value == pytest.approx(1 - 1 / 1.1, rel=1e-6)  # u = u_P1 / 1.1


def test_a_model_that_does_not_apply_or_has_no_system_is_skipped(scene):
    no_system = SystemModel("none", "none", lambda s: None)
    report = check_model(no_system, scene)
    assert {c.status for c in report.checks} == {"skipped"}
    assert "no mechanical system" in report.checks[0].message
    refuses = SystemModel("refuses", "refuses", LinearP1, applies=lambda s: "not this one")
    report = check_model(refuses, scene)
    assert all(c.message == "does not apply: not this one" for c in report.checks)


def test_scaled_scene_scales_loads_and_prescribed_displacements(scene):
    small = scaled_scene(scene, 1e-3)
    np.testing.assert_allclose(small.loads[0].value, 1e-3 * scene.loads[0].value)
    assert scene.loads[0].value[2] == -10.0  # the original is unchanged


def test_rotation_is_orthonormal_and_turns_about_its_axis():
    w = np.array([0.3, -1.2, 0.5])
    R = rotation(w)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(R @ w, w, atol=1e-15)
    assert np.linalg.det(R) == pytest.approx(1.0)

"""Cases of the anisotropy study: the settings, the rotated-fibre blocks, which scenes it
runs on, one solve, and the measures read off the displacements."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from springfem.mesh import displacement_gradients
from springfem.scene import Scene

from .. import models
from ..scenes import StudyScene, case_scene

STUDY, VERSION = "anisotropy", 2

#: The spring model with the scene's options on the analytic and on the per-element
#: least-squares calibration; ``spring-exact`` adds the Poisson-coupling springs.
SPRING_ANALYTIC = models.spring_variant(
    "spring-analytic", "spring model, analytic calibration", calibration="analytic"
)
SPRING_NNLS = models.spring_variant(
    "spring-nnls", "spring model, nnls calibration", calibration="nnls"
)
#: The models compared; errors are measured against the references P2 (total) and P1 on the
#: same mesh (model error).
MODELS = ("spring-analytic", "spring-nnls", "spring-exact", "P1", "P2")
REFERENCES = ("P2", "P1")
MARKERS = dict(zip(MODELS, "os*x+"))
#: Laws with a fibre: what the study needs.
ANISOTROPIC = ("transverse-linear", "guccione", "holzapfel-ogden")


@dataclass(frozen=True)
class Settings:
    """Fibre angles and mesh of the bundled rotated blocks.

    Parameters
    ----------
    angles
        Fibre angles θ (degrees) in the x-y plane; 0 and 90 give the anisotropy ratio.
    n
        Divisions per side of the block.
    """

    angles: tuple[float, ...] = tuple(float(a) for a in np.arange(0.0, 90.1, 7.5))
    n: int = 6

    @classmethod
    def full(cls) -> Settings:
        """Every 7.5° on a 6³ block."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """0, 30, 60, 90° on a 3³ block."""
        return cls(angles=(0.0, 30.0, 60.0, 90.0), n=3)


def fibre_block(angle: float, n: int) -> StudyScene:
    """The bundled ``stretch-fiber`` block on ``n³`` hexahedra with its fibre at ``angle``
    degrees from x in the x-y plane (fibre ``(cos θ, sin θ, 0)``, sheet
    ``(-sin θ, cos θ, 0)``), pulled along x; its reference is the off-axis formula.

    Examples
    --------
    >>> fibre_block(90.0, 2).table["axes"]["sheet"][0]
    -1.0
    """
    th = np.radians(angle)
    c, s = float(np.cos(th)), float(np.sin(th))
    sets = {"mesh.divisions": [n] * 3, "axes.fiber": [c, s, 0.0], "axes.sheet": [-s, c, 0.0]}
    label = f"stretch-fiber {angle:g}°"
    return StudyScene.bundled("stretch-fiber", sets, label=label, analytic="off-axis")


def bundled_scenes(settings: Settings) -> list[StudyScene]:
    """The rotated blocks of the settings' angles."""
    return [fibre_block(a, settings.n) for a in settings.angles]


def refusal(scene: StudyScene) -> str | None:
    """Why the study cannot run on ``scene`` (``None``: it can).

    Examples
    --------
    >>> refusal(StudyScene("ball", {"material": {"law": "linear"}})).split(":")[0]
    'scene ball has isotropic material (law linear)'
    """
    law = str(scene.table.get("material", {}).get("law", "linear"))
    if law not in ANISOTROPIC:
        return (
            f"scene {scene.label} has isotropic material (law {law}): anisotropy needs a "
            f"fibre-reinforced law ({', '.join(ANISOTROPIC)}) with its fibre direction from "
            "[axes]"
        )
    if "axes" not in scene.table:
        return (
            f"scene {scene.label} has no [axes] section (its fibre would be the default x "
            "axis): anisotropy needs the fibre direction stated (uniform, helix, rule-based "
            "or cells)"
        )
    return None


def grid(scenes: list[StudyScene]) -> list[dict[str, Any]]:
    """One case per scene and model."""
    return [s.case(STUDY, VERSION, model=m) for s in scenes for m in MODELS]


def solve_case(case: dict[str, Any]) -> dict[str, Any]:
    """Vertex displacements of one model on one scene: ``status``, ``u``, ``message``."""
    got = models.run(case_scene(case), case["model"])
    if not got.ok:
        return {"status": got.status, "message": got.message[:200]}
    return {"status": "ok", "u": np.asarray(got.u)}


# ----------------------------------------------------------------------------- measures


def affine_fit(points: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Small-strain tensor ``(3, 3)`` of the least-squares affine fit ``u ≈ A X + b`` of the
    displacements ``u`` at ``points``.
    """
    X = np.column_stack([points, np.ones(len(points))])
    coef, *_ = np.linalg.lstsq(X, u, rcond=None)
    A = coef[:3].T  # A[i, j] = du_i / dX_j
    return 0.5 * (A + A.T)


def stretch_measures(scene: Scene, u: np.ndarray) -> dict[str, float]:
    """The block's response to its pull along x: ``E_eff = σ / ε_xx`` (``ε_xx``: mean x
    displacement of the ``x_max`` vertices over the length), ``eps_xx``, and ``gamma_xy``,
    ``eps_fit_xx`` of the affine fit.
    """
    pts = scene.mesh.points
    L = float(pts[:, 0].max() - pts[:, 0].min())
    face = np.isclose(pts[:, 0], pts[:, 0].max())
    eps_xx = float(u[face, 0].mean() / L)
    eps = affine_fit(pts, u)
    sigma = float(scene.loads[0].value[0])
    return {
        "E_eff": sigma / eps_xx,
        "eps_xx": eps_xx,
        "gamma_xy": float(2.0 * eps[0, 1]),
        "eps_fit_xx": float(eps[0, 0]),
    }


def vertex_fibres(tets: np.ndarray, frames: np.ndarray, n_points: int) -> np.ndarray:
    """Fibre direction per vertex (unit, sign arbitrary): principal eigenvector of ``sum f f^T``
    over its tets (``frames`` row 0).

    Examples
    --------
    >>> fr = np.tile(np.eye(3), (2, 1, 1)); fr[1, 0] *= -1  # the same fibre, opposite signs
    >>> np.abs(vertex_fibres(np.array([[0, 1, 2, 3], [1, 2, 3, 4]]), fr, 5)).round(6)[1]
    array([1., 0., 0.])
    """
    f = frames[:, 0, :]
    T = np.zeros((n_points, 3, 3))
    for j in range(tets.shape[1]):
        np.add.at(T, tets[:, j], f[:, :, None] * f[:, None, :])
    return np.linalg.eigh(T)[1][:, :, -1]


def _axis_strains(scene: Scene, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Per tet: the fibre strain ``f·εf``, the mean cross-fibre normal strain, and the L2
    norm of the strain tensors."""
    m = scene.mesh
    G = displacement_gradients(m.points, m.tets, u)
    eps = 0.5 * (G + np.transpose(G, (0, 2, 1)))
    proj = np.einsum("kli,kij,klj->kl", scene.frames, eps, scene.frames)
    return proj[:, 0], 0.5 * (proj[:, 1] + proj[:, 2]), float(np.linalg.norm(eps))


def split_errors(scene: Scene, u: np.ndarray, u_ref: np.ndarray) -> dict[str, float]:
    """Fibre / cross-fibre split of the displacement and strain error of ``u`` vs ``u_ref``.

    At every vertex the error ``e = u - u_ref`` splits into ``e·f`` and ``e - (e·f) f``
    (``f``: :func:`vertex_fibres`), each relative to ``||u_ref||`` (they add in quadrature
    to the total): ``fibre``, ``cross``, ``total``. The strains are those of the P1
    interpolation per tet, and the errors of the fibre strain and of the mean cross-fibre
    normal strain (``strain_fibre``, ``strain_cross``) are relative to the L2 norm of the
    reference's strain tensors (a projected strain may vanish where the tensor does not:
    under a pull at an angle to the fibre, the cross-fibre mean changes sign).
    """
    m = scene.mesh
    f = vertex_fibres(m.tets, scene.frames, m.n_points)
    e = u - u_ref
    ef = np.sum(e * f, axis=1)
    ec = e - ef[:, None] * f
    norm = np.linalg.norm(u_ref)
    (mf, mc, _), (rf, rc, strain) = _axis_strains(scene, u), _axis_strains(scene, u_ref)
    return {
        "fibre": float(np.linalg.norm(ef) / norm),
        "cross": float(np.linalg.norm(ec) / norm),
        "total": float(np.linalg.norm(e) / norm),
        "strain_fibre": float(np.linalg.norm(mf - rf) / strain),
        "strain_cross": float(np.linalg.norm(mc - rc) / strain),
    }

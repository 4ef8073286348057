"""Cases of the anisotropy study: the rotated-fiber scene, the off-axis formula, one
modulus measurement, the settings."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from springfem.errors import SolverError
from springfem.scene import Material, Scene, scene_from_dict
from springmodel.options import SpringOptions

from ..compare import bundled_scene

#: Models compared: label -> (kind, setting).
MODELS: dict[str, tuple[str, Any]] = {
    "spring (analytic cal.)": ("spring", "analytic"),
    "spring (nnls cal.)": ("spring", "nnls"),
    # the exact element of issue 10 with Poisson coupling (transversely isotropic material)
    "spring (exact + coupling)": ("spring", "exact"),
    "FEM P1": ("fem", 1),
    "FEM P2": ("fem", 2),
}
MARKERS = {
    "spring (analytic cal.)": "o",
    "spring (nnls cal.)": "s",
    "spring (exact + coupling)": "*",
    "FEM P1": "x",
    "FEM P2": "+",
}
#: Spring options of the exact calibration: axis-volume, energy torsion, coupling springs.
EXACT = {"volume": "axes", "torsion": "energy", "coupling": True}


# ------------------------------------------------------------------------------ scene


def fiber_table(angle_deg: float, n: int = 6) -> dict[str, Any]:
    """The table of ``stretch-fiber`` with the fiber at ``angle_deg`` in the x-y plane on an
    ``n³`` box.

    Parameters
    ----------
    angle_deg
        Fiber angle from x, in degrees.
    n
        Divisions per side.

    Returns
    -------
    dict
        The table for :func:`springfem.scene.scene_from_dict`.

    Examples
    --------
    >>> fiber_table(90.0, 2)["axes"]["sheet"][0]
    -1.0
    """
    data = bundled_scene("stretch-fiber", (n, n, n))
    th = np.radians(angle_deg)
    c, s = float(np.cos(th)), float(np.sin(th))
    data["axes"]["fiber"] = [c, s, 0.0]
    data["axes"]["sheet"] = [-s, c, 0.0]
    return data


def fiber_scene(angle_deg: float, n: int = 6) -> Scene:
    """The scene of :func:`fiber_table`.

    Parameters
    ----------
    angle_deg, n
        As for :func:`fiber_table`.

    Returns
    -------
    Scene
    """
    return scene_from_dict(fiber_table(angle_deg, n))


def applied_stress(scene: Scene) -> float:
    """The x traction on ``x_max`` (Pa)."""
    return float(scene.loads[0].value[0])


# --------------------------------------------------------------------------- analytic


def compliance_voigt(mat: Material) -> np.ndarray:
    """6×6 compliance (Voigt xx, yy, zz, yz, xz, xy; engineering shear) in the material frame
    (axis 0 = fiber), as the FEM reference builds it."""
    from springfem.materials import transverse_compliance

    return transverse_compliance(
        mat.E_fiber, mat.E_cross, mat.nu_fiber_cross, mat.nu_cross, mat.G_fiber
    )


_VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))


def off_axis_strain(mat: Material, angle_deg: float, stress: float) -> np.ndarray:
    """Strain tensor (3×3) of uniaxial stress ``stress`` along x with the fiber at θ."""
    S = compliance_voigt(mat)
    S4 = np.zeros((3, 3, 3, 3))
    for a, (i, j) in enumerate(_VOIGT):
        for b, (k, l) in enumerate(_VOIGT):
            w = (0.5 if i != j else 1.0) * (0.5 if k != l else 1.0)
            for p, q in {(i, j), (j, i)}:
                for r, t in {(k, l), (l, k)}:
                    S4[p, q, r, t] = S[a, b] * w
    th = np.radians(angle_deg)
    R = np.array([[np.cos(th), -np.sin(th), 0.0], [np.sin(th), np.cos(th), 0.0], [0, 0, 1.0]])
    # material frame axes are the columns of R: S_global = R R S4 R^T R^T
    Sg = np.einsum("ia,jb,kc,ld,abcd->ijkl", R, R, R, R, S4)
    sigma = np.zeros((3, 3))
    sigma[0, 0] = stress
    return np.einsum("ijkl,kl->ij", Sg, sigma)


def off_axis_modulus(mat: Material, angle_deg: float) -> float:
    """``E(θ)`` of the off-axis formula."""
    th = np.radians(angle_deg)
    c2, s2 = np.cos(th) ** 2, np.sin(th) ** 2
    inv = (
        c2**2 / mat.E_fiber
        + s2**2 / mat.E_cross
        + (1.0 / mat.G_fiber - 2.0 * mat.nu_fiber_cross / mat.E_fiber) * s2 * c2
    )
    return float(1.0 / inv)


# ------------------------------------------------------------------------------ cases


def affine_fit(points: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Small-strain tensor of the least-squares affine fit ``u ≈ A X + b``."""
    X = np.column_stack([points, np.ones(len(points))])
    coef, *_ = np.linalg.lstsq(X, u, rcond=None)
    A = coef[:3].T  # A[i, j] = du_i / dX_j
    return 0.5 * (A + A.T)


def modulus_case(case: dict[str, Any]) -> dict[str, Any]:
    """Effective modulus of one model at one fiber angle.

    ``case``: ``angle`` (degrees), ``n`` (divisions per side), ``model`` (``spring`` or
    ``fem``), ``calibration`` (spring) or ``order`` (FEM). Returns ``E_eff``,
    ``eps_xx`` (mean x strain of the ``x_max`` face), ``gamma_xy``/``eps_fit`` (affine fit),
    ``status`` and, on failure, ``message``.
    """
    scene = fiber_scene(case["angle"], case["n"])
    try:
        if case["model"] == "spring":
            from springmodel.model import solve_spring

            extra = EXACT if case["calibration"] == "exact" else {}
            opts = replace(SpringOptions.of(scene), calibration=case["calibration"], **extra)
            u = solve_spring(scene, opts, parallel=False).u
        else:
            import reference_fem

            u = reference_fem.solve(scene, order=case["order"]).u_vertices
    except SolverError as exc:
        return {"status": "fails", "message": str(exc)[:200], "E_eff": float("nan")}
    pts = scene.mesh.points
    L = float(pts[:, 0].max() - pts[:, 0].min())
    face = np.isclose(pts[:, 0], pts[:, 0].max())
    eps_xx = float(u[face, 0].mean() / L)
    eps = affine_fit(pts, u)
    return {
        "status": "ok",
        "E_eff": applied_stress(scene) / eps_xx,
        "eps_xx": eps_xx,
        "gamma_xy": float(2.0 * eps[0, 1]),
        "eps_fit_xx": float(eps[0, 0]),
    }


@dataclass(frozen=True)
class Settings:
    """Fiber angles and mesh of the anisotropy study.

    Parameters
    ----------
    angles
        Fiber angles θ (degrees); 0 and 90 give the anisotropy ratio.
    n
        Divisions per side of the cube.
    scene, scene_path
        A user scene table and its file (``study anisotropy --scene``; see :mod:`.scene`).
    """

    angles: tuple[float, ...] = tuple(float(a) for a in np.arange(0.0, 90.1, 7.5))
    n: int = 6
    scene: dict | None = None
    scene_path: str | None = None

    @classmethod
    def full(cls) -> Settings:
        """Every 7.5° on a 6³ cube."""
        return cls()

    @classmethod
    def for_scene(cls, table: dict, path: str | None = None, quick: bool = False) -> Settings:
        """The fibre / cross-fibre error split on a user scene (see :mod:`.scene`).

        Parameters
        ----------
        table
            The scene table.
        path
            The scene file.
        quick
            Unused (the user's mesh is the mesh).

        Returns
        -------
        Settings

        Raises
        ------
        InputError
            If the scene's material is isotropic (the message says what is needed).
        """
        from springfem.errors import InputError

        from .scene import refusal

        why = refusal(table, path)
        if why is not None:
            raise InputError(f"study anisotropy cannot run on --scene: {why}")
        return cls(scene=table, scene_path=path)

    @classmethod
    def quick(cls) -> Settings:
        """0, 30, 60, 90° on a 3³ cube."""
        return cls(angles=(0.0, 30.0, 60.0, 90.0), n=3)

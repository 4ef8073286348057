"""Study ``anisotropy``: effective modulus of a transversely isotropic block against fiber angle.

The bundled ``stretch-fiber`` scene (a cube of transversely isotropic material, E_f = 30 kPa,
E_c = 10 kPa, G_f = 5 kPa, ν_fc = 0.3, ν_c = 0.4) with its fiber rotated by θ in the x-y plane
(fiber ``(cos θ, sin θ, 0)``, sheet ``(-sin θ, cos θ, 0)``) and pulled along x by a uniform
traction σ on ``x_max``. The scene's boundary conditions only remove rigid motion: the
``x_min`` face is held in x alone (it slides in y and z), the origin is pinned in y and z and
the corner ``(0, L, 0)`` in z. A homogeneous strain with any shear is compatible with them
(the body rotates rigidly so that ``x_min`` stays at x = 0), so the state is uniaxial
stress, the coupled shear ``γ_xy`` is free, and the off-axis formula

    1/E(θ) = cos⁴θ/E_f + sin⁴θ/E_c + (1/G_f − 2ν_fc/E_f) sin²θ cos²θ

is exact for the continuum and for P1/P2 (a homogeneous field is in both spaces).

Measured: ``E_eff = σ / ε_xx`` with ``ε_xx`` the mean x displacement of the ``x_max`` nodes
over L, for the spring model (analytic and nnls calibration), FEM P1 and P2; and the shear
coupling ``γ_xy / ε_xx`` from a least-squares affine fit of the nodal displacements,
against the rotated compliance.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pandas as pd

from springfem.errors import SolverError
from springfem.scene import Material, Scene, parse_scene
from springmodel.options import SpringOptions

from .cli import SCENES
from .registry import Figure, StudyContext, StudyOutput, Table, study
from .tables import save_figure, write_table

#: Models compared: label -> (kind, setting).
MODELS: dict[str, tuple[str, Any]] = {
    "spring (analytic cal.)": ("spring", "analytic"),
    "spring (nnls cal.)": ("spring", "nnls"),
    "FEM P1": ("fem", 1),
    "FEM P2": ("fem", 2),
}
MARKERS = {"spring (analytic cal.)": "o", "spring (nnls cal.)": "s", "FEM P1": "x", "FEM P2": "+"}


# ------------------------------------------------------------------------------ scene


def fiber_scene(angle_deg: float, n: int = 6) -> Scene:
    """``stretch-fiber`` with the fiber at ``angle_deg`` in the x-y plane on an ``n³`` box."""
    text = (SCENES / "stretch-fiber.toml").read_text()
    th = np.radians(angle_deg)
    c, s = float(np.cos(th)), float(np.sin(th))
    text = re.sub(r"(?m)^fiber = \[.*\]", f"fiber = [{c!r}, {s!r}, 0.0]", text)
    text = re.sub(r"(?m)^sheet = \[.*\]", f"sheet = [{-s!r}, {c!r}, 0.0]", text)
    text = re.sub(r"(?m)^divisions = \[.*\]", f"divisions = [{n}, {n}, {n}]", text)
    return parse_scene(text)


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

            opts = replace(SpringOptions.of(scene), calibration=case["calibration"])
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


# -------------------------------------------------------------------------------- run


@dataclass(frozen=True)
class Settings:
    """Fiber angles and mesh of the anisotropy study.

    Parameters
    ----------
    angles
        Fiber angles θ (degrees); 0 and 90 give the anisotropy ratio.
    n
        Divisions per side of the cube.
    """

    angles: tuple[float, ...] = tuple(float(a) for a in np.arange(0.0, 90.1, 7.5))
    n: int = 6

    @classmethod
    def full(cls) -> Settings:
        """Every 7.5° on a 6³ cube."""
        return cls()

    @classmethod
    def quick(cls) -> Settings:
        """0, 30, 60, 90° on a 3³ cube."""
        return cls(angles=(0.0, 30.0, 60.0, 90.0), n=3)


@study("anisotropy", Settings)
def run(ctx: StudyContext, settings: Settings) -> StudyOutput:
    """Run the anisotropy study (see the module docstring).

    Parameters
    ----------
    ctx
        Output folder, cache and preset.
    settings
        Angles and mesh.

    Returns
    -------
    StudyOutput
        Findings, modulus and ratio tables, the modulus figure, headline errors.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    angles = list(settings.angles)
    n = settings.n
    out = StudyOutput(name=ctx.name, title="Anisotropy: effective modulus against fiber angle")
    scene0 = fiber_scene(0.0, n)
    mat = scene0.material
    sigma = applied_stress(scene0)

    cases = []
    for label, (kind, setting) in MODELS.items():
        for a in angles:
            c = {"angle": a, "n": n, "model": kind}
            c["calibration" if kind == "spring" else "order"] = setting
            cases.append((label, c))
    res = ctx.cache.run([c for _, c in cases], modulus_case, ctx.progress, "angles")
    rows = []
    for (label, c), r in zip(cases, res):
        a = c["angle"]
        E_an = off_axis_modulus(mat, a)
        eps_an = off_axis_strain(mat, a, sigma)
        g_an = 2.0 * eps_an[0, 1] / eps_an[0, 0]
        rows.append(
            {
                "model": label,
                "angle": a,
                "E_eff": r["E_eff"],
                "E_analytic": E_an,
                "rel_error": r["E_eff"] / E_an - 1.0,
                "gamma_xy/eps_xx": r.get("gamma_xy", np.nan) / r.get("eps_xx", np.nan),
                "gamma_xy/eps_xx analytic": g_an,
                "status": r["status"],
            }
        )
    df = pd.DataFrame(rows)

    # ---- wide table: E_eff per model and angle
    wide = df.pivot(index="angle", columns="model", values="E_eff")[list(MODELS)]
    wide.insert(0, "analytic", [off_axis_modulus(mat, a) for a in wide.index])
    for label in MODELS:
        if label.startswith("spring"):
            wide[f"{label} error"] = wide[label] / wide["analytic"] - 1.0
    wide = wide.reset_index().rename(columns={"angle": "θ (deg)"})
    out.tables.append(
        Table(
            write_table(wide, ctx.path("modulus")),
            f"Effective modulus E_eff = σ/ε_xx (Pa) against fiber angle θ on the {n}³×6-tet "
            f"cube (σ = {sigma:g} Pa): off-axis formula, spring model (analytic and nnls "
            "calibration), FEM P1 and P2, and the spring model's relative error.",
        )
    )

    # ---- anisotropy ratio
    def E_at(label: str, a: float) -> float:
        g = df[(df.model == label) & (df.angle == a)]
        return float(g.E_eff.iloc[0]) if len(g) else float("nan")

    ratio_an = off_axis_modulus(mat, 0.0) / off_axis_modulus(mat, 90.0)
    rrows = [
        {
            "model": "analytic",
            "E(0°)": mat.E_fiber,
            "E(90°)": mat.E_cross,
            "E(0)/E(90)": ratio_an,
            "ratio error": 0.0,
        }
    ]
    for label in MODELS:
        e0, e90 = E_at(label, 0.0), E_at(label, 90.0)
        rrows.append(
            {
                "model": label,
                "E(0°)": e0,
                "E(90°)": e90,
                "E(0)/E(90)": e0 / e90,
                "ratio error": (e0 / e90) / ratio_an - 1.0,
            }
        )
    ratios = pd.DataFrame(rrows)
    out.tables.append(
        Table(
            write_table(ratios, ctx.path("anisotropy_ratio")),
            "Stiffness along (0°) and across (90°) the fibers and the anisotropy ratio "
            "E(0)/E(90) of each model against the analytic E_f/E_c.",
        )
    )
    spring_err = {
        label: float(np.nanmax(np.abs(df[df.model == label].rel_error))) for label in MODELS
    }
    worst_angle = {
        label: float(df[df.model == label].set_index("angle").rel_error.abs().idxmax())
        for label in MODELS
        if df[df.model == label].rel_error.notna().any()
    }

    # ---- figure
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    th = np.linspace(0.0, 90.0, 181)
    axes[0].plot(
        th,
        [off_axis_modulus(mat, a) / 1e3 for a in th],
        "k-",
        lw=1.2,
        label="analytic (off-axis formula)",
    )
    g_an = [2 * (e := off_axis_strain(mat, a, sigma))[0, 1] / e[0, 0] for a in th]
    axes[2].plot(th, g_an, "k-", lw=1.2, label="analytic (rotated compliance)")
    for label in MODELS:
        g = df[df.model == label].sort_values("angle")
        kw = {
            "marker": MARKERS[label],
            "ls": "none",
            "label": label,
            "ms": 7,
            "mfc": "none" if MARKERS[label] in "os" else None,
        }
        axes[0].plot(g.angle, g.E_eff / 1e3, **kw)
        axes[1].plot(g.angle, 100 * g.rel_error, **{**kw, "ls": "-", "lw": 0.8})
        axes[2].plot(g.angle, g["gamma_xy/eps_xx"], **kw)
    axes[0].set_ylabel("E_eff = σ / ε_xx (kPa)")
    axes[0].set_title("effective modulus along x")
    axes[1].set_ylabel("E_eff / E_analytic − 1 (%)")
    axes[1].set_title("error against the off-axis formula")
    axes[1].axhline(0.0, color="k", lw=0.8)
    axes[2].set_ylabel("γ_xy / ε_xx")
    axes[2].set_title("shear coupling (free: only rigid motion removed)")
    for a in axes:
        a.set_xlabel("fiber angle θ (deg)")
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
    sa, sn = "spring (analytic cal.)", "spring (nnls cal.)"
    out.figures.append(
        Figure(
            save_figure(fig, ctx.path("modulus_vs_angle.png")),
            f"Effective modulus, its error and the shear coupling against fiber angle "
            f"({n}³×6 tets). FEM P1 and P2 reproduce the off-axis formula to "
            f"{max(spring_err['FEM P1'], spring_err['FEM P2']):.1e} (a homogeneous field is "
            f"exact for both); the spring model deviates by up to "
            f"{spring_err[sa]:.1%} (analytic calibration, worst at {worst_angle.get(sa, 0):g}°)"
            f" and {spring_err[sn]:.1%} (nnls, worst at {worst_angle.get(sn, 0):g}°).",
        )
    )

    r = ratios.set_index("model")
    out.findings.append(
        f"Anisotropy ratio E(0)/E(90): analytic {ratio_an:.3g}; spring model "
        f"{r.loc[sa, 'E(0)/E(90)']:.3g} (analytic calibration, {r.loc[sa, 'ratio error']:+.1%})"
        f" and {r.loc[sn, 'E(0)/E(90)']:.3g} (nnls, {r.loc[sn, 'ratio error']:+.1%}); FEM P1 "
        f"{r.loc['FEM P1', 'E(0)/E(90)']:.4g}, P2 {r.loc['FEM P2', 'E(0)/E(90)']:.4g}."
    )
    out.findings.append(
        f"Along the fibers the spring model (analytic calibration) gives "
        f"E(0°) = {r.loc[sa, 'E(0°)']:.4g} Pa ({r.loc[sa, 'E(0°)'] / mat.E_fiber - 1:+.1%} "
        f"of E_f), across E(90°) = {r.loc[sa, 'E(90°)']:.4g} Pa "
        f"({r.loc[sa, 'E(90°)'] / mat.E_cross - 1:+.1%} of E_c); off-axis it is off by up to "
        f"{spring_err[sa]:.1%} (at {worst_angle.get(sa, 0):g}°). The nnls calibration is "
        f"off by up to {spring_err[sn]:.1%}."
    )
    gs = df[df.model == sa]
    gamma_err = float(np.nanmax(np.abs(gs["gamma_xy/eps_xx"] - gs["gamma_xy/eps_xx analytic"])))
    gmax = float(np.nanmax(np.abs(gs["gamma_xy/eps_xx analytic"])))
    g0 = gs.set_index("angle")["gamma_xy/eps_xx"]
    spurious = ", ".join(f"{g0.loc[a]:.2f} at {a:g}°" for a in (0.0, 90.0) if a in g0.index)
    out.findings.append(
        f"The boundary conditions remove only rigid motion, so the off-axis shear develops "
        f"freely: analytic |γ_xy/ε_xx| reaches {gmax:.2f} and FEM matches it; the spring "
        f"model (analytic calibration) deviates by up to {gamma_err:.2f}, including a "
        f"spurious coupling where the material has none ({spurious}): the six-tet split's "
        "anisotropic radial tensor couples the volume springs to shear."
    )
    out.headline["ratio_analytic"] = round(ratio_an, 4)
    out.headline["ratio_spring_analytic_cal"] = round(float(r.loc[sa, "E(0)/E(90)"]), 4)
    out.headline["ratio_spring_nnls_cal"] = round(float(r.loc[sn, "E(0)/E(90)"]), 4)
    out.headline["ratio_fem_p1"] = round(float(r.loc["FEM P1", "E(0)/E(90)"]), 4)
    out.headline["max_rel_error_spring_analytic_cal"] = round(spring_err[sa], 4)
    out.headline["max_rel_error_spring_nnls_cal"] = round(spring_err[sn], 4)
    out.headline["max_rel_error_fem_p1"] = round(spring_err["FEM P1"], 6)
    return out

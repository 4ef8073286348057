"""The ``tissue`` study's homogeneous deformations: each spring element against its law.

Every node of a jittered Delaunay cube is moved by ``x = F X`` for a deformation ``F``
given in the fibre frame (fibre at 30° in the x–y plane, sheet tilted 20° out of it):
stretches of 1.3 along and across the fibre, simple shears of 0.3 in the fibre–sheet,
fibre–normal and sheet–normal planes, and a stretch with a shear. Under a homogeneous
deformation P1 FEM is exact, so its nodal forces are the law's first Piola stress
integrated over each node's patch; the measure is the spring element's nodal-force error
against them (relative, max norm). The tissue element (``spring-tissue``: Green torsion and
the law's own stiffening, docs/tissue.rst#the-tissue-element-on-the-green-strain) equals the
law in every case; the stiffened element equals it only under frame-aligned stretches.

Examples
--------
>>> F = deformations()["shear 0.3 f-s"]
>>> R = frame()
>>> bool(abs((R @ F @ R.T)[0, 1] - 0.3) < 1e-12)  # the shear, read in the frame
True
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from springfem.mesh import box_mesh
from springfem.scene import scene_from_dict

from .. import models
from ..registry import StudyContext, Table

#: Land's problem-1/3 Guccione constants (kPa) with a volumetric penalty the spring model
#: can carry (kappa = 50 C: nearly incompressible, Poisson's ratio near 0.5 at rest).
GUCCIONE = {"law": "guccione", "C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0, "kappa": 100.0}
#: Holzapfel & Ogden's (2009) fit to myocardium shear data (kPa), with a penalty
#: kappa = 1000 kPa (nearly incompressible against the fibre's small-strain 4 a_f = 74 kPa).
HOLZAPFEL_OGDEN = {"law": "holzapfel-ogden", "a": 0.059, "b": 8.023, "a_f": 18.472,
                   "b_f": 16.026, "a_s": 2.481, "b_s": 11.120, "a_fs": 0.216, "b_fs": 11.436,
                   "kappa": 1000.0}  # fmt: skip
#: The stress-stretch cube's laws by name.
STRETCH_LAWS = {"guccione": GUCCIONE, "holzapfel-ogden": HOLZAPFEL_OGDEN}

#: The spring elements measured: the tissue element and today's stiffened one.
HOMOGENEOUS_MODELS = ("spring-tissue", "spring-stiffened")


def frame() -> np.ndarray:
    """Rows fibre, sheet, normal: the fibre at 30° in the x–y plane, the sheet tilted 20°."""
    c, s, t = np.cos(np.radians(30.0)), np.sin(np.radians(30.0)), np.radians(20.0)
    fiber = np.array([c, s, 0.0])
    sheet = np.array([-s * np.cos(t), c * np.cos(t), np.sin(t)])
    return np.array([fiber, sheet, np.cross(fiber, sheet)])


def deformations() -> dict[str, np.ndarray]:
    """The deformation gradients (global frame) by name; their frame components are named."""
    R = frame()

    def in_frame(G: np.ndarray) -> np.ndarray:
        return R.T @ G @ R

    def shear(a: int, b: int, stretch=(1.0, 1.0, 1.0)) -> np.ndarray:
        G = np.diag(stretch)
        G[a, b] = 0.3
        return in_frame(G)

    return {
        "stretch 1.3 along the fibre": in_frame(np.diag([1.3, 1.0, 1.0])),
        "stretch 1.3 across the fibre": in_frame(np.diag([1.0, 1.3, 1.0])),
        "shear 0.3 f-s": shear(0, 1),
        "shear 0.3 f-n": shear(0, 2),
        "shear 0.3 s-n": shear(1, 2),
        "stretch 1.3 + shear 0.3 f-s": shear(0, 1, (1.3, 1.0, 1.0)),
    }


def homogeneous_cases(version: int) -> list[dict]:
    """One case per law, deformation and spring element (JSON-able, for the cache)."""
    return [
        {"study": "tissue-homogeneous", "version": version, "law": law, "deformation": d,
         "model": m}
        for law in STRETCH_LAWS
        for d in deformations()
        for m in HOMOGENEOUS_MODELS
    ]  # fmt: skip


def _scene(law: str):
    R = frame()
    return scene_from_dict(
        {
            "name": f"tissue-homogeneous-{law}",
            "units": "mm-kPa",
            "mesh": box_mesh((1.0, 1.0, 1.0), (3, 3, 3), split="delaunay", seed=3),
            "material": dict(STRETCH_LAWS[law]),
            "axes": {"fiber": R[0].tolist(), "sheet": R[1].tolist()},
        }
    )


def homogeneous_case(case: dict) -> dict:
    """``force_error`` of one spring element under one deformation, and ``error`` ("")."""
    from reference_fem import FemProblem

    scene = _scene(case["law"])
    F = deformations()[case["deformation"]]
    X = scene.mesh.points
    x = X @ F.T
    fem_scene, _, law = models.get("P1").fem_settings(scene)
    f_fem = FemProblem(fem_scene, 1, law).internal_force((x - X).ravel())[0].reshape(-1, 3)
    try:
        f = models.get(case["model"]).system(scene).forces(x, None)  # -dW/dx
    except Exception as exc:  # a model that refuses the law: its row says why
        return {"force_error": math.nan, "error": str(exc).splitlines()[0][:200]}
    err = np.abs(f + f_fem).max() / np.abs(f_fem).max()
    return {"force_error": float(err), "error": ""}


def homogeneous_frame(cases: list[dict], results: list[dict]) -> pd.DataFrame:
    """Rows law × deformation, a force-error column per spring element."""
    rows = [{**{k: c[k] for k in ("law", "deformation", "model")}, **r}
            for c, r in zip(cases, results)]  # fmt: skip
    df = pd.DataFrame(rows)
    wide = df.pivot_table(index=["law", "deformation"], columns="model", values="force_error",
                          sort=False)  # fmt: skip
    wide.columns.name = None
    return wide.reset_index()


def homogeneous_findings(df: pd.DataFrame) -> tuple[list[str], dict[str, float]]:
    """One line per spring element: its worst error under shear and under stretch."""
    text, head = [], {}
    shear = df.deformation.str.contains("shear")
    for model in HOMOGENEOUS_MODELS:
        if model not in df:
            continue
        worst_shear, worst_stretch = df[model][shear].max(), df[model][~shear].max()
        text.append(
            f"Homogeneous deformations (jittered cube, fibre at 30°), {model}: nodal forces "
            f"{100 * worst_shear:.2g}% off its law's P1 at worst under a shear of 0.3, "
            f"{100 * worst_stretch:.2g}% under a stretch of 1.3."
        )
        head[f"homogeneous_shear_error_{model}"] = float(worst_shear)
    return text, head


def homogeneous_table(ctx: StudyContext, df: pd.DataFrame) -> Table:
    """Write the homogeneous cases' table (CSV + Markdown)."""
    return ctx.table(df, "homogeneous", "Nodal-force error (relative, max norm) of each spring "
                     "element against P1 FEM of its law, which is exact here, with x = F X "
                     "imposed on every node of a jittered Delaunay cube; F in the fibre frame "
                     "(fibre at 30 deg in x-y, sheet tilted 20 deg), Land's Guccione and "
                     "Holzapfel-Ogden's 2009 fit.")  # fmt: skip

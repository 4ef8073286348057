"""Tables of the accuracy study: errors per scene and the main probe displacements."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from ..compare import COMPONENTS
from .cases import ERROR_KINDS, EXACT_KINDS, nan_float


def error_table(res: dict[str, dict]) -> pd.DataFrame:
    """Model, total and discretisation errors (L2, max) and volume changes, one row per scene
    of ``res`` (scene name -> :func:`~.cases.work` result), with the exact variant's columns
    (``exact_model`` = vs linear P1, ``exact_model_nh`` = vs P1 neo-Hookean) when run.
    """
    rows = []
    for name in res:
        r = res[name]
        row: dict[str, Any] = {
            "scene": name,
            "tets": r["tets"],
            "reference": r["reference"],
            "same-mesh P1": r["p1"],
            "max strain (ref)": nan_float(r["strain_ref"]),
        }
        for kind in ERROR_KINDS:
            e = r["errors"][kind]
            row[f"{kind} err L2"] = nan_float(e.get("rel_l2"))
            row[f"{kind} err max"] = nan_float(e.get("rel_max"))
        for kind in EXACT_KINDS:
            if kind in r["errors"]:
                row[f"{kind.replace('_', ' ')} err L2"] = nan_float(r["errors"][kind].get("rel_l2"))
        for key, e in r["errors"].items():  # the plug-in models (springfem.model_api)
            kind, _, peer = key.partition(":")
            if kind == "peer_total":
                row[f"{peer} total err L2"] = nan_float(e.get("rel_l2"))
            elif kind == "peer_model_nh":
                row[f"{peer} vs P1-NH err L2"] = nan_float(e.get("rel_l2"))
        row["spring volume change"] = nan_float(r["volume"].get("spring"))
        if "spring-exact" in r["volume"]:
            row["exact volume change"] = nan_float(r["volume"]["spring-exact"])
        row["ref volume change"] = nan_float(r["volume"].get(r["reference"]))
        rows.append(row)
    return pd.DataFrame(rows)


def probe_table(
    res: dict[str, dict], refs: dict[str, tuple | None], lateral: dict[str, int | None]
) -> pd.DataFrame:
    """The main probe component per scene: analytic value, spring, P1, reference, ratios.

    ``refs``: scene name -> its closed-form reference (:func:`studies.analytic.reference`);
    ``lateral``: scene name -> the transverse (Poisson) component shown beside it, if any.
    """
    prow = []
    for name in res:
        r = res[name]
        ref = r["reference"]
        an = refs[name]
        if not an and not r["probes"][ref]:
            continue  # a user scene without probes
        probe = an[0] if an else next(iter(r["probes"][ref]))
        comp = an[1] if an else int(np.argmax(np.abs(r["probes"][ref][probe])))

        def value(m: str, r=r, probe=probe, comp=comp) -> float:
            return nan_float(r["probes"].get(m, {}).get(probe, [None] * 3)[comp])

        row = {
            "scene": name,
            "probe": f"{probe} u{COMPONENTS[comp]}",
            "analytic (m)": an[2] if an else float("nan"),
            "analytic source": an[3] if an else "",
            "spring (m)": value("spring"),
            "P1 (m)": value(r["p1"]),
            "reference (m)": value(ref),
        }
        if "spring-exact" in r["probes"]:
            row["exact (m)"] = value("spring-exact")
        row["spring / ref − 1"] = row["spring (m)"] / row["reference (m)"] - 1
        if "spring-exact" in r["probes"]:
            row["exact / ref − 1"] = row["exact (m)"] / row["reference (m)"] - 1
        row["P1 / ref − 1"] = row["P1 (m)"] / row["reference (m)"] - 1
        for key in r["errors"]:  # the plug-in models
            kind, _, peer = key.partition(":")
            if kind == "peer_total":
                row[f"{peer} (m)"] = value(peer)
                row[f"{peer} / ref − 1"] = row[f"{peer} (m)"] / row["reference (m)"] - 1
        row["ref / analytic − 1"] = (
            row["reference (m)"] / row["analytic (m)"] - 1 if an else float("nan")
        )
        row["spring / analytic − 1"] = row["spring (m)"] / row["analytic (m)"] - 1 if an else np.nan
        # lateral (Poisson) response at the same probe, for the stretches
        lat = lateral[name]
        if lat is not None:
            ls = nan_float(r["probes"]["spring"][probe][lat])
            lr = nan_float(r["probes"][ref][probe][lat])
            row["lateral spring / ref − 1"] = ls / lr - 1
        else:
            row["lateral spring / ref − 1"] = float("nan")
        prow.append(row)
    return pd.DataFrame(prow)

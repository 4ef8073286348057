"""Projective Dynamics as plug-in models (:mod:`springfem.model_api`): ``pd`` (local/global
iterations of its ARAP-like energy) and ``pd-nh`` (quasi-Newton iterations of neo-Hookean),
each the run to rest of :class:`peers.pd.PD` (:class:`peers.rest_model.RestModel`).

Examples
--------
>>> PDModel().law, PDNHModel().law, PDNHModel().settings["energy"]
('arap', 'neo-hookean', 'neo-hookean')
>>> PDNHModel().with_settings(iterations=4).label
'PD quasi-Newton neo-Hookean (40 substeps x 4)'
"""

from __future__ import annotations

from typing import Any

from springfem.scene import Scene

from ..rest_model import RestModel
from .solver import PD, PDSettings, why_not


def _arap(scene: Scene) -> str | None:
    return why_not(scene, "arap")


def _neo_hookean(scene: Scene) -> str | None:
    return why_not(scene, "neo-hookean")


class PDModel(RestModel):
    """PD with its ARAP-like energy (settings: :class:`peers.pd.PDSettings`)."""

    Settings = PDSettings
    Solver = PD
    why_not = staticmethod(_arap)
    law = "arap"
    default_name = "pd"

    def make_label(self) -> str:
        s = self.settings
        return f"PD ARAP + volume ({s['substeps']} substeps x {s['iterations']})"


class PDNHModel(RestModel):
    """PD's quasi-Newton form for neo-Hookean (settings: :class:`peers.pd.PDSettings`,
    ``energy`` fixed to ``neo-hookean``)."""

    Settings = PDSettings
    Solver = PD
    why_not = staticmethod(_neo_hookean)
    law = "neo-hookean"
    default_name = "pd-nh"

    def __init__(self, name: str | None = None, label: str | None = None, default: bool = True,
                 **settings: Any):  # fmt: skip
        super().__init__(name, label, default, **{**settings, "energy": "neo-hookean"})

    def make_label(self) -> str:
        s = self.settings
        return f"PD quasi-Newton neo-Hookean ({s['substeps']} substeps x {s['iterations']})"


__all__ = ["PDModel", "PDNHModel"]

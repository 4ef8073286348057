"""Vertex Block Descent as a plug-in model (:mod:`springfem.model_api`): its static answer is
the run to rest of :class:`peers.vbd.VBD` (:class:`peers.rest_model.RestModel`).

Examples
--------
>>> VBDModel().settings["iterations"], VBDModel().law
(2, 'stable-neo-hookean')
>>> VBDModel().with_settings(substeps=20).label
'VBD stable neo-Hookean (20 substeps x 2)'
"""

from __future__ import annotations

from ..rest_model import RestModel
from .solver import VBD, VBDSettings, why_not


class VBDModel(RestModel):
    """VBD as a plug-in: :meth:`solve` runs to rest (settings: :class:`peers.vbd.VBDSettings`).

    The result's law is ``stable-neo-hookean`` (what a ``neo-hookean`` scene becomes; a
    ``linear`` scene is solved with linear elasticity, :mod:`peers.vbd.energy`).
    """

    Settings = VBDSettings
    Solver = VBD
    why_not = staticmethod(why_not)
    law = "stable-neo-hookean"
    default_name = "vbd"

    def make_label(self) -> str:
        s = self.settings
        return f"VBD stable neo-Hookean ({s['substeps']} substeps x {s['iterations']})"


__all__ = ["VBDModel"]

"""Co-rotational P1 as models of the plug-in API (:mod:`springfem.model_api`).

``corotational``
    Newton with the consistent tangent (a default model: the studies and the verdict
    weigh it where it applies);
``corotational-warped``
    the same forces, Newton with the warped stiffness ``R K R^T`` (asked for by name only:
    ``--models corotational-warped``; docs/plugins.rst measures both).

The entry point ``corotational = "corotational.plugin:models"`` of group
``springfem.models`` (``pyproject.toml``) registers them.

Examples
--------
>>> [m.name for m in models()], models()[0].settings
(['corotational', 'corotational-warped'], {'tangent': 'consistent'})
"""

from __future__ import annotations

from functools import cache

from springfem.model_api import SystemModel
from springfem.scene import Scene

from .system import Corotational, why_not


def build(scene: Scene, tangent: str = "consistent") -> Corotational:
    """The co-rotational system of ``scene`` (what :class:`SystemModel` builds)."""
    return Corotational(scene, tangent=tangent)  # type: ignore[arg-type]


@cache
def models() -> tuple[SystemModel, ...]:
    """The two co-rotational models (one object each per process).

    Returns
    -------
    tuple of SystemModel
    """
    return (
        SystemModel(
            "corotational", "co-rotational P1 (consistent tangent)", build,
            law="corotational-linear", applies=why_not, tangent="consistent",
        ),
        SystemModel(
            "corotational-warped", "co-rotational P1 (warped stiffness)", build,
            law="corotational-linear", applies=why_not, default=False, tangent="warped",
        ),
    )  # fmt: skip

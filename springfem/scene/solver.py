"""The ``[solver]`` scene section: settings both models share (today: the kernel precision).

``[solver] precision = "float64" | "mixed" | "float32"`` sets the force-kernel precision of
the spring model and of the explicit FEM alike (``mixed``: float32 constants, float64
arithmetic); a model section's own ``precision`` key (``[spring]``/``[fem]``) overrides it
for that model.

Examples
--------
>>> SolverOptions.of_table({"precision": "mixed"})
SolverOptions(precision='mixed')
>>> SolverOptions.of_table({"precison": "mixed"})
Traceback (most recent call last):
...
springfem.errors.SceneError: <scene>: solver.precison: unknown key; did you mean 'precision'?
"""

from __future__ import annotations

from dataclasses import dataclass

from .reader import TableReader

PRECISIONS = ("float64", "mixed", "float32")


@dataclass(frozen=True)
class SolverOptions:
    """Settings of a scene's ``[solver]`` section.

    Attributes
    ----------
    precision
        Force-kernel precision for both models, or ``None`` (each model's own default).
    """

    precision: str | None = None

    @classmethod
    def of(cls, scene) -> SolverOptions:
        """The ``[solver]`` options of ``scene`` (defaults when the section is absent)."""
        return scene.section("solver", parse_solver)

    @classmethod
    def of_table(cls, table: dict, file: str = "<scene>") -> SolverOptions:
        """Parse a plain ``[solver]`` table (see :func:`parse_solver`)."""
        return parse_solver(TableReader(table, "solver", file))


def parse_solver(r: TableReader) -> SolverOptions:
    """Validate a scene's ``[solver]`` table.

    Parameters
    ----------
    r
        Reader over the table.

    Returns
    -------
    SolverOptions
    """
    precision = r.get("precision", "str", default=None, choices=PRECISIONS)
    r.finish()
    return SolverOptions(precision)


def model_precision(scene, section: str, own: str) -> str:
    """The precision a model runs at: its own section's key, else ``[solver]``, else ``own``.

    Parameters
    ----------
    scene
        The scene.
    section
        The model's section name (``spring`` or ``fem``).
    own
        The model's parsed ``precision`` (its default when the key is absent).

    Returns
    -------
    str
        ``float64``, ``mixed`` or ``float32``.
    """
    if "precision" in (scene.raw.get(section) or {}):
        return own
    return SolverOptions.of(scene).precision or own

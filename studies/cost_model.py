"""What a model's static solve will cost on a scene: seconds and peak memory, before it runs.

The verdict plans with it (:mod:`studies.verdict_plan`): which models fit the time and the
memory there is, in which order to solve them, and what a model left out would have needed.

A model's cost follows a power law in the mesh's size, ``a (tets / 10⁴)^b`` seconds and
``c (tets / 10⁴)^d`` bytes of peak resident memory, measured on this machine's kind on a
family of gmsh organ meshes (neo-Hookean, ν = 0.49, gravity) by ``springfem bench scale``.
The laws come from, in order:

1. this machine's own calibration, ``<cache>/cost_laws.json`` (``springfem bench scale
   --cost-laws <cache>/cost_laws.json``; ``<cache>`` is ``$XDG_CACHE_HOME/springfem`` or
   ``~/.cache/springfem``), or the file ``$SPRINGFEM_COST_LAWS`` names;
2. the shipped defaults, ``studies/cost_laws.json``.

A model the laws do not name is priced as the nearest one they do (:func:`kin`), and the
prediction says so. A tissue law's Newton solve takes more steps than neo-Hookean's, a
small-strain law fewer (:data:`LAW_FACTOR`). The prediction is refined as solves finish
(:meth:`SolveCosts.observe`): the median ratio of measured to predicted time of the
models solved so far on this scene scales the rest, since the scene, its load and the
machine's load move every model alike.

Examples
--------
>>> laws = {"P1-NH": Law(time=(0.5, 1.0), memory=(2e8, 1.0))}
>>> costs = SolveCosts(laws, tets=20_000, law="neo-hookean")
>>> p = costs.predict("P1-NH")
>>> round(p.seconds, 3), round(p.bytes / 1e6), p.source
(1.0, 400, 'measured law')
>>> costs.observe("P1-NH", 2.0)  # twice as slow here: the rest is scaled alike
>>> round(costs.predict("P1-NH").seconds, 3)
2.0
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from springfem.materials.laws import TISSUE_LAWS

#: The shipped laws (measured by ``springfem bench scale`` on this project's machines).
SHIPPED = Path(__file__).with_name("cost_laws.json")
#: Mesh size the laws are written in: tets / UNIT.
UNIT = 1.0e4
#: Newton steps of a law against neo-Hookean's (the laws are measured on neo-Hookean); every
#: tissue law of the table takes :data:`TISSUE_FACTOR`.
LAW_FACTOR = {"linear": 0.5, "transverse-linear": 0.5}
TISSUE_FACTOR = 1.5
#: Models whose time does not depend on the law's Newton steps (one linear solve).
LINEAR_SOLVES = ("P1", "P2")
#: Solves shorter than this do not refine the prediction (fixed costs dominate them).
MIN_OBSERVED = 0.3
#: The refinement factor stays within this range.
REFINE_RANGE = (0.2, 5.0)


@dataclass(frozen=True)
class Law:
    """A model's measured cost laws: ``(a, b)`` for ``a (tets / UNIT)^b``.

    Attributes
    ----------
    time
        Static solve, seconds.
    memory
        Peak resident memory of the process during the solve, bytes.
    step
        One explicit step, seconds (``None``: no explicit form).
    """

    time: tuple[float, float]
    memory: tuple[float, float]
    step: tuple[float, float] | None = None

    @staticmethod
    def at(coef: tuple[float, float], tets: float) -> float:
        a, b = coef
        return float(a * (tets / UNIT) ** b)


@dataclass(frozen=True)
class Prediction:
    """A model's predicted static solve.

    Attributes
    ----------
    seconds
        Wall time.
    bytes
        Peak resident memory.
    source
        ``measured law``, ``as <model>`` (priced as a similar model) or ``no law``.
    """

    seconds: float
    bytes: float
    source: str


def cache_dir() -> Path:
    """The user's cache folder of springfem."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "springfem"


def laws_file() -> Path:
    """The laws in use: ``$SPRINGFEM_COST_LAWS``, this machine's calibration, the shipped."""
    named = os.environ.get("SPRINGFEM_COST_LAWS")
    if named:
        return Path(named)
    own = cache_dir() / "cost_laws.json"
    return own if own.is_file() else SHIPPED


def read_laws(path: str | os.PathLike | None = None) -> dict[str, Law]:
    """The cost laws of a ``springfem bench scale --cost-laws`` file (empty if unreadable).

    Parameters
    ----------
    path
        The file (default :func:`laws_file`).

    Returns
    -------
    dict
        Model name -> :class:`Law`.
    """
    path = Path(path) if path is not None else laws_file()
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        out = {}
        for name, law in data.get("laws", {}).items():
            step = law.get("step")
            out[name] = Law(
                time=(float(law["time"][0]), float(law["time"][1])),
                memory=(float(law["memory"][0]), float(law["memory"][1])),
                step=(float(step[0]), float(step[1])) if step else None,
            )
        return out
    except (OSError, ValueError, KeyError, TypeError, IndexError):
        return {}


def kin(name: str, known: dict[str, Law]) -> str | None:
    """The measured model nearest to ``name`` in cost: itself, else a model of the same
    discretisation (a stabilised spring element as ``spring-stabilised``, a spring element
    as ``spring-exact``, a P2 model as ``P2-NH``, a plug-in as ``corotational``).

    Parameters
    ----------
    name
        The model.
    known
        The measured laws.

    Returns
    -------
    str or None

    Examples
    --------
    >>> known = dict.fromkeys(["spring-exact", "spring-stabilised", "P2-NH"])
    >>> kin("spring-tissue-stabilised", known), kin("spring-tissue", known), kin("P2", known)
    ('spring-stabilised', 'spring-exact', 'P2-NH')
    """
    if name in known:
        return name
    if name.startswith("spring") and name.endswith("stabilised"):
        guesses = ["spring-stabilised", "fem-P1-nodal-strain"]
    elif name.startswith("spring"):
        guesses = ["spring-exact", "spring", "P1-NH"]
    elif "P2" in name or name == "fem":
        guesses = ["P2-NH", "P2", "fem-P2-mixed"]
    elif name.startswith("fem-"):
        guesses = ["fem-P1-nodal-strain", "P1-NH"]
    else:
        guesses = ["corotational", "P1-NH"]
    return next((g for g in guesses if g in known), None)


@dataclass
class SolveCosts:
    """Predicted costs of the models on one scene, refined as its solves finish.

    Parameters
    ----------
    laws
        Model name -> :class:`Law` (:func:`read_laws`).
    tets
        The scene's number of tets.
    law
        The scene's material law.
    """

    laws: dict[str, Law]
    tets: int
    law: str = "neo-hookean"
    ratios: list[float] = field(default_factory=list)

    def factor(self) -> float:
        """The refinement: the median measured/predicted time of the solves so far."""
        if not self.ratios:
            return 1.0
        f = float(np.exp(np.median(np.log(self.ratios))))
        return float(np.clip(f, *REFINE_RANGE))

    def _raw(self, name: str) -> tuple[float, float, str] | None:
        like = kin(name, self.laws)
        if like is None:
            return None
        law = self.laws[like]
        seconds = Law.at(law.time, self.tets)
        if name not in LINEAR_SOLVES:
            tissue = TISSUE_FACTOR if self.law in TISSUE_LAWS else 1.0
            seconds *= LAW_FACTOR.get(self.law, tissue)
        source = "measured law" if like == name else f"as {like}"
        return seconds, Law.at(law.memory, self.tets), source

    def predict(self, name: str) -> Prediction:
        """The predicted static solve of model ``name`` on this scene.

        Parameters
        ----------
        name
            The model.

        Returns
        -------
        Prediction
            NaN seconds and bytes with source ``no law`` when nothing prices it.
        """
        raw = self._raw(name)
        if raw is None:
            return Prediction(math.nan, math.nan, "no law")
        seconds, nbytes, source = raw
        return Prediction(seconds * self.factor(), nbytes, source)

    def step(self, name: str) -> float:
        """Predicted seconds of one explicit step of ``name`` (NaN: not known)."""
        like = kin(name, self.laws)
        law = self.laws.get(like) if like else None
        if law is None or law.step is None:
            return math.nan
        return Law.at(law.step, self.tets) * self.factor()

    def observe(self, name: str, seconds: float) -> None:
        """Record that ``name``'s solve took ``seconds`` here (refines the rest).

        Parameters
        ----------
        name
            The model.
        seconds
            Its measured wall time.
        """
        raw = self._raw(name)
        if raw is None or not math.isfinite(seconds) or seconds < MIN_OBSERVED:
            return
        if raw[0] > 0:
            self.ratios.append(seconds / raw[0])


def gigabytes(nbytes: float) -> str:
    """``1.2 GB``, ``350 MB``: a memory figure in words.

    Examples
    --------
    >>> gigabytes(1.234e9), gigabytes(3.5e8), gigabytes(float("nan"))
    ('1.2 GB', '350 MB', '? GB')
    """
    if not math.isfinite(nbytes):
        return "? GB"
    return f"{nbytes / 1e9:.1f} GB" if nbytes >= 1e9 else f"{nbytes / 1e6:.0f} MB"

"""What :func:`springfem.testing.check_model` returns: one :class:`Check` per check, in a
:class:`ModelReport`.

Examples
--------
>>> report = ModelReport("toy", "box", [Check("translation", "failed", "max |f| = 1 > 1e-08",
...                                            1.0, 1e-8), Check("tangent", "skipped", "no K")])
>>> report.passed, report.status("tangent")
(False, 'skipped')
>>> report.raise_on_failure()
Traceback (most recent call last):
AssertionError: model toy fails 1 check on scene box: translation: max |f| = 1 > 1e-08
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

Status = Literal["passed", "skipped", "failed"]


@dataclass
class Check:
    """One check's outcome.

    Attributes
    ----------
    name
        ``translation``, ``rotation``, ``energy gradient``, ``tangent``, ``small strain``,
        ``explicit energy``.
    status
        ``passed``, ``skipped`` or ``failed``.
    message
        What was measured against what (passed, failed) or why not (skipped).
    value, tolerance
        The measured relative error and its bound (``None`` when skipped).
    """

    name: str
    status: Status
    message: str
    value: float | None = None
    tolerance: float | None = None

    def line(self) -> str:
        """One line: ``name: status: message``."""
        return f"{self.name}: {self.status}: {self.message}"


@dataclass
class ModelReport:
    """What :func:`check_model` found, one :class:`Check` per check in a fixed order.

    Attributes
    ----------
    model, scene
        The names checked.
    checks
        Translation, rotation (infinitesimal), rotation (finite), energy gradient,
        tangent, small strain, explicit energy.
    """

    model: str
    scene: str
    checks: list[Check] = field(default_factory=list)

    @property
    def failures(self) -> list[Check]:
        """The failed checks."""
        return [c for c in self.checks if c.status == "failed"]

    @property
    def passed(self) -> bool:
        """No check failed (skipped ones do not count)."""
        return not self.failures

    def status(self, name: str) -> Status:
        """The status of the check ``name`` (the first of that name)."""
        return next(c.status for c in self.checks if c.name == name)

    def __str__(self) -> str:
        head = f"model {self.model} on scene {self.scene}:"
        return "\n".join([head] + ["  " + c.line() for c in self.checks])

    def raise_on_failure(self) -> None:
        """Raise ``AssertionError`` listing the failures (nothing when none)."""
        if self.failures:
            n = len(self.failures)
            lines = "; ".join(c.line().replace(": failed:", ":", 1) for c in self.failures)
            raise AssertionError(
                f"model {self.model} fails {n} check{'s' * (n > 1)} on scene {self.scene}: {lines}"
            )

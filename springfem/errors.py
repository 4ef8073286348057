"""Typed errors shared by both models and the CLI (exit codes of DESIGN §6)."""

from __future__ import annotations


class SpringFemError(Exception):
    """Base class of the errors the CLI turns into one clear line."""

    exit_code = 1


class InputError(SpringFemError, ValueError):
    """Bad input: a scene key, a mesh file, a region or a probe (exit code 2)."""

    exit_code = 2


class SceneError(InputError):
    """A scene file is malformed: names the file and the key."""


class MeshError(InputError):
    """A mesh is unusable: names the file and the element or node ids."""


class SolverError(SpringFemError, RuntimeError):
    """A solve failed: diverged, blew up, singular (exit code 3).

    Parameters
    ----------
    message
        What failed, where and when (step, iteration, element).
    state
        The last good state, if any (e.g. a displacement array), so callers can write it.
    """

    exit_code = 3

    def __init__(self, message: str, state: object | None = None):
        super().__init__(message)
        self.state = state

"""The runnable examples of the runner, every study package and its modules (cases, ...)."""

import doctest
import importlib
import pkgutil

import pytest

import studies.runner  # noqa: F401  (registers every study)
from studies.registry import REGISTRY


def _modules():
    yield studies.runner
    for spec in REGISTRY.values():
        pkg = importlib.import_module(spec.run.__module__)
        yield pkg
        for info in pkgutil.iter_modules(getattr(pkg, "__path__", [])):
            yield importlib.import_module(f"{pkg.__name__}.{info.name}")


@pytest.mark.parametrize("module", list(_modules()), ids=lambda m: m.__name__)
def test_doctests(module):
    assert doctest.testmod(module).failed == 0

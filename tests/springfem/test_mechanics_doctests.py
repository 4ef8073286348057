"""The docstring examples of every module of springfem.mechanics run (and pass)."""

import doctest
import importlib
import pkgutil

import pytest

import springfem.mechanics

MODULES = ["springfem.mechanics"] + [
    f"springfem.mechanics.{m.name}" for m in pkgutil.iter_modules(springfem.mechanics.__path__)
]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0, f"{name} has no docstring example"
    assert result.failed == 0

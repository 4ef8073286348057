"""The docstring examples of every spring-model module run and pass
(docs/verification.rst#docstring-examples: examples
double as tests). Each module, the package itself included, has at least one, but for the
compiled helpers that have no public API of their own."""

import doctest
import importlib
import pkgutil

import pytest

import springmodel

MODULES = ["springmodel"] + sorted(
    m.name for m in pkgutil.walk_packages(springmodel.__path__, "springmodel.")
)
#: Compiled helpers with no public API of their own (their callers' docstrings show them).
COMPILED_ONLY = {"springmodel.hessian_numba"}


def test_the_modules_are_found():
    assert {"springmodel.springs", "springmodel.model", "springmodel.fastkernels"} <= set(MODULES)


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0
    assert result.attempted > 0 or name in COMPILED_ONLY, f"{name} has no docstring example"

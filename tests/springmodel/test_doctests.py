"""The docstring examples of every spring-model module run and pass (DESIGN §7: examples
double as tests). Each module, the package itself included, has at least one."""

import doctest
import importlib
import pkgutil

import pytest

import springmodel

MODULES = ["springmodel"] + sorted(
    m.name for m in pkgutil.walk_packages(springmodel.__path__, "springmodel.")
)


def test_the_modules_are_found():
    assert {"springmodel.springs", "springmodel.model", "springmodel.fastkernels"} <= set(MODULES)


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0
    assert result.attempted > 0, f"{name} has no docstring example"

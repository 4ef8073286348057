"""The docstring examples of every core module run and pass
(docs/verification.rst#docstring-examples: examples double
as tests). Each public module has at least one. ``springfem.mechanics`` is checked by its
own tests."""

import doctest
import importlib
import pkgutil

import pytest

import springfem

MODULES = ["springfem"] + sorted(
    m.name
    for m in pkgutil.walk_packages(springfem.__path__, "springfem.")
    if not m.name.startswith("springfem.mechanics")
)


def test_the_modules_are_found():
    assert {"springfem.errors", "springfem.mesh.io", "springfem.scene.build"} <= set(MODULES)


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0
    assert result.attempted > 0, f"{name} has no docstring example"

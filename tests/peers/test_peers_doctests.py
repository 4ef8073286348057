"""The docstring examples of every ``peers`` module run and pass; each module has one."""

import doctest
import importlib
import pkgutil

import pytest

import peers

MODULES = ["peers"] + sorted(m.name for m in pkgutil.walk_packages(peers.__path__, "peers."))


def test_the_modules_are_found():
    assert {"peers.xpbd.kernels", "peers.mass_spring.network", "peers.plugin"} <= set(MODULES)


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0
    assert result.attempted > 0, f"{name} has no docstring example"

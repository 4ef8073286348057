"""Fixtures shared by the core's tests."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))  # mechanics_systems


@pytest.fixture(scope="module")
def stretch_model():
    """The bundled stretch-fiber scene's spring model with energy torsion (conservative)."""
    from mechanics_systems import stretch_fiber_model

    return stretch_fiber_model()

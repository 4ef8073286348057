"""Floating-point warnings are counted, not shown; other warnings still reach the user."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from springfem.warning_count import counted_warnings, summary


def test_runtime_warnings_are_counted_by_message(capsys):
    with counted_warnings() as seen:
        for _ in range(12):
            np.exp(np.array([800.0]))
        np.log(np.array([-1.0]))
    assert seen == {"overflow encountered in exp": 12, "invalid value encountered in log": 1}
    assert capsys.readouterr().err == ""
    assert summary(seen).startswith("13 floating-point warnings while solving: overflow")


def test_other_warnings_pass_through():
    with pytest.warns(UserWarning, match="kept"), counted_warnings() as seen:
        warnings.warn("kept", UserWarning, stacklevel=1)
    assert not seen and summary(seen) is None

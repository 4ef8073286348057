"""Test configuration: off-screen rendering and the Agg backend (pyvista's convention), and
the shared helpers of ``tests/support`` on the import path."""

import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the shared helpers: ``support``
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_WAIT_POLICY", "passive")
# the command line's studies run in this process, where a test's monkeypatches reach them
os.environ.setdefault("SPRINGFEM_WORKERS", "1")

import matplotlib  # noqa: E402

matplotlib.use("Agg")

try:  # pragma: no cover - pyvista is optional for most tests
    import pyvista

    pyvista.OFF_SCREEN = True
except ImportError:  # pragma: no cover
    pass


import signal  # noqa: E402

import pytest  # noqa: E402


@pytest.fixture
def python_sigint():
    """Python's own SIGINT handler for the test (``_thread.interrupt_main`` does nothing
    when an earlier test in the worker left SIGINT ignored or at the OS default)."""
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)

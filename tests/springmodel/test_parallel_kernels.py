"""The parallel spring force driver (springfem.blocks.block_drivers) against the serial one.

The parallel driver once returned wrong forces in whole-suite runs only (garbage in the
last rows, parallel only). The cause was no thread race: every variant's block loop is a
closure of one factory, numba names a compiled function by its qualified name, a counter of
the functions its process had compiled and the argument types, and a cached entry keeps the
counter of the process that wrote it. Two variants cached by two pytest-xdist workers could
carry one symbol; a process that loaded both linked the parallel driver (compiled afresh) to
the definition loaded last and ran the other variant's code on its constants. The serial
driver calls its own dispatcher and was never wrong. :func:`springfem.blocks.compile_named`
gives each variant its own name; the first tests force that collision in one process (the
counter set alike for two closures) and show that unnamed closures run each other's code and
named ones do not.

The stress tests run the parallel kernels many times against the serial result beside other
work; cheap forms by default, every variant at every precision (and the stiffened pass, and
two processes filling one cold numba cache, as two xdist workers do) with ``-m slow``.
"""

from __future__ import annotations

import itertools
import os
import pickle
import subprocess
import sys
import textwrap
import threading
from dataclasses import replace
from pathlib import Path

import numba
import numpy as np
import pytest
from numba import njit
from numba.core import bytecode
from scipy.spatial.transform import Rotation

from springfem.blocks import BLOCK, block_drivers, chunks, compile_named
from springfem.mesh import box_mesh
from springmodel.elements import build_spring_elements
from springmodel.options import GREEN_AXIAL_COEFFICIENTS, SpringOptions
from springmodel.spring_kernel import SpringKernel
from springmodel.stiffening import StiffeningPart

from .test_fastkernels import all_variants

MATERIAL = {"law": "linear", "E": 1.0e3, "nu": 0.3}
PRECISIONS = ("float64", "mixed", "float32")
#: Relative agreement of the parallel and serial passes: the same sums in another order
#: (two chunk buffers added at the end), ~1e-16 in float64 and mixed; float32 arithmetic
#: rounds each element's forces to ~1e-7 before they are summed in float64.
TOL = {"float64": 1e-12, "mixed": 1e-12, "float32": 1e-5}
#: The tissue element of the bundled ventricle (exact, shear torsion, Green axial, log U(J)).
TISSUE = SpringOptions(
    volume="axes", torsion="shear", calibration="exact", coupling=True, axial="cubic",
    axial_coefficients=GREEN_AXIAL_COEFFICIENTS, volumetric="log",
)  # fmt: skip


def needs_threads():
    if numba.get_num_threads() < 2:
        pytest.skip("needs two numba threads")


# --------------------------------------------------------------------------- the cause


def _block_loop(c: float):
    """A block loop of the drivers' signature whose result is proportional to ``c``, large
    enough that LLVM calls it rather than inlining it into the driver (as the kernels)."""

    def run(lo, hi, x, w, T, K, m, p, q, out):
        for b in range(lo, hi):
            s, t, u = 0.0, 0.0, 0.0
            for k in range(20):
                s += np.sin(x[b, 0] + k)
            for k in range(20):
                t += np.cos(x[b, 1] * k + s)
            for k in range(20):
                u += np.exp(-x[b, 2] * k) * np.sin(t + k)
            out[b, 0] += c * s
            out[b, 1] += c * t
            out[b, 2] += c * u
        return 0

    return run


def _drivers_with_one_counter(named: bool, monkeypatch):
    """Block loops of ``c = 1`` and ``c = 2`` compiled with numba's function counter at the
    same value (as two processes that compiled alike give their cached entries), both
    called serially (loaded) before their parallel drivers are compiled."""
    n = 64
    x = np.linspace(0.0, 1.0, 3 * n).reshape(n, 3)
    T, K, w = np.zeros((n, 1), np.int32), np.zeros((n, 1)), np.zeros((1, 3))
    ptr = chunks(n, 2)
    original = bytecode.FunctionIdentity._unique_ids
    runs, results = {}, {}
    for c in (1.0, 2.0):
        monkeypatch.setattr(bytecode.FunctionIdentity, "_unique_ids", itertools.count(10**8))
        py = _block_loop(c)
        name = f"collision_probe_{int(c)}_{named}"
        runs[c] = compile_named(py, name, cache=False) if named else njit(cache=False)(py)
        serial, _ = block_drivers(runs[c])
        ref = np.empty((n, 3))
        serial(x, w, T, K, n, 0.0, 0.0, ref)  # compiles the loop under the set counter
        results[c] = {"serial": ref}
    monkeypatch.setattr(bytecode.FunctionIdentity, "_unique_ids", original)
    for c, run in runs.items():
        _, parallel = block_drivers(run)
        out = np.empty((n, 3))
        parallel(x, w, T, K, n, 0.0, 0.0, ptr, np.zeros((ptr.size - 1, n, 3)), out)
        results[c]["parallel"] = out
    return results


def test_named_block_loops_keep_their_own_code_in_the_parallel_driver(monkeypatch):
    needs_threads()
    res = _drivers_with_one_counter(True, monkeypatch)
    for c in (1.0, 2.0):
        np.testing.assert_array_equal(res[c]["parallel"], res[c]["serial"])
    assert not np.array_equal(res[1.0]["serial"], res[2.0]["serial"])


@pytest.mark.slow
def test_unnamed_block_loops_with_one_counter_run_each_others_code(monkeypatch):
    # the control: the same closures under their shared qualified name; the parallel driver
    # of the first runs the second's code (the definition loaded last). If this stops
    # failing, numba no longer shares such symbols and compile_named's reason is gone.
    needs_threads()
    res = _drivers_with_one_counter(False, monkeypatch)
    np.testing.assert_array_equal(res[1.0]["parallel"], res[2.0]["serial"])
    assert not np.array_equal(res[1.0]["parallel"], res[1.0]["serial"])


def test_a_kernel_name_is_never_given_to_other_code():
    with pytest.raises(ValueError, match="already used"):
        for c in (1.0, 3.0):
            compile_named(_block_loop(c), "reused_kernel_name", cache=False)
    compile_named(_block_loop(1.0), "reused_kernel_name", cache=False)  # same code: fine


# --------------------------------------------------------------------------- stress


@pytest.fixture(scope="module")
def state():
    """A jittered five-tet box (300 tets: a partial last block), random axes, random
    constants, a deformed state and velocities."""
    mesh = box_mesh((1.0, 1.3, 0.7), (5, 4, 3), split="five")
    rng = np.random.default_rng(3)
    points = mesh.points + 0.03 * rng.standard_normal(mesh.points.shape)
    frames = Rotation.random(mesh.n_tets, random_state=4).as_matrix()
    el = build_spring_elements(points, mesh.tets, frames, SpringOptions(), MATERIAL)
    el.k_axis_volume = rng.uniform(100.0, 300.0, el.n_elements)
    el.k_coupling = rng.uniform(-20.0, 50.0, (el.n_elements, 3))
    x = points + 0.02 * rng.standard_normal(points.shape)  # no element inverts
    v = rng.standard_normal(points.shape)
    assert el.n_elements % BLOCK != 0
    return points, el, x, v


class NumpyWork:
    """A background thread multiplying matrices (numpy releases the GIL: the other core is
    busy while the kernels run), as a context manager."""

    def __enter__(self):
        self.stop, self.rounds = threading.Event(), 0
        self.thread = threading.Thread(target=self._work, daemon=True)
        self.thread.start()
        return self

    def _work(self):
        a = np.random.default_rng(0).standard_normal((200, 200))
        while not self.stop.is_set():
            a = np.tanh(a @ a.T / 200.0)
            self.rounds += 1

    def __exit__(self, *exc):
        self.stop.set()
        self.thread.join()


def hammer(kernel: SpringKernel, serial: SpringKernel, x, v, reps: int, tol: float) -> int:
    """``reps`` parallel passes: each bitwise equal to the first, the first equal to the
    serial pass to ``tol`` (relative to the largest force). Returns the passes compared."""
    ref = serial.forces(x, v)
    first = kernel.forces(x, v).copy()
    assert np.abs(first - ref).max() <= tol * np.abs(ref).max()
    out = np.empty_like(first)
    for _ in range(reps):
        np.testing.assert_array_equal(kernel.forces(x, v, out=out), first)
    return reps + 1


@pytest.mark.parametrize(
    ("options", "precision"),
    [(SpringOptions(), "float64"), (TISSUE, "mixed")],
    ids=["seed-float64", "tissue-mixed"],
)
def test_parallel_forces_equal_serial_beside_numpy_work(state, options, precision):
    needs_threads()
    _, el, x, v = state
    par = SpringKernel(el, options, parallel=True, precision=precision)
    ser = SpringKernel(el, options, parallel=False, precision=precision)
    assert par.parallel and par._ptr.size == 3  # two chunks: the parallel path
    with NumpyWork() as work:
        n = hammer(par, ser, x, v, 200, TOL[precision])
    assert n == 201 and work.rounds > 0


def test_same_thread_count_gives_bitwise_identical_forces(state):
    # deterministic for a given thread count: fixed chunks, each summed in mesh order into
    # its own buffer, the buffers added in chunk order; a new kernel gives the same bits
    needs_threads()
    _, el, x, v = state
    o = replace(TISSUE, volume_damping=0.3)
    a = SpringKernel(el, o, parallel=True).forces(x, v)
    b = SpringKernel(el, o, parallel=True).forces(x.copy(), v.copy())
    np.testing.assert_array_equal(a, b)


def test_one_chunk_is_the_serial_pass_bit_for_bit(state):
    # one thread's chunk adds the elements in the serial order into a zeroed buffer, which
    # is copied out: the same bits as the serial pass (two chunks differ by round-off only)
    _, el, x, v = state
    kernel = SpringKernel(el, TISSUE, parallel=True)
    kernel._ptr = chunks(kernel._T.shape[0], 1)
    kernel._buf = np.zeros((1, el.n_points, 3))
    np.testing.assert_array_equal(kernel.forces(x, v), SpringKernel(el, TISSUE).forces(x, v))


def _variants():
    yield from all_variants()
    yield SpringOptions(torsion="shear", volume="axes", coupling=True, volume_damping=0.3)
    yield TISSUE


@pytest.mark.slow
@pytest.mark.parametrize("precision", PRECISIONS)
def test_every_variant_in_parallel_equals_serial_beside_work(state, precision, tmp_path):
    # every law of every part (the kernels compile one loop each), with and without
    # velocities, 300 parallel passes each, beside a numpy thread and a numpy process
    needs_threads()
    points, el, x, v = state
    busy = subprocess.Popen(
        [sys.executable, "-c", "import numpy as np\na = np.ones((300, 300))\nwhile True: a @ a"]
    )
    count = 0
    try:
        with NumpyWork():
            for o in _variants():
                par = SpringKernel(el, o, parallel=True, precision=precision)
                ser = SpringKernel(el, o, parallel=False, precision=precision)
                for vel in (v, None):
                    count += hammer(par, ser, x, vel, 300, TOL[precision])
    finally:
        busy.kill()
        busy.wait()
    assert count == 2 * 301 * len(list(_variants()))


@pytest.mark.slow
def test_stiffened_element_in_parallel_equals_serial(state):
    # the stiffened exact element: the fused kernel (parallel) plus the stiffening pass
    needs_threads()
    _, el, x, _ = state
    o = replace(TISSUE, stiffening="exponential", stiffening_modulus=MATERIAL["E"] / 3)
    part = StiffeningPart(el, o, o.stiffening_modulus)
    par, ser = SpringKernel(el, o, parallel=True), SpringKernel(el, o, parallel=False)
    ref = ser.forces(x) + part.forces(x)
    first = par.forces(x) + part.forces(x)
    assert np.abs(first - ref).max() <= 1e-12 * np.abs(ref).max()
    with NumpyWork():
        for _ in range(300):
            np.testing.assert_array_equal(par.forces(x) + part.forces(x), first)


CHECK = textwrap.dedent(
    """
    import pickle, sys
    import numpy as np
    from springfem.mesh import box_mesh
    from springmodel.elements import build_spring_elements
    from springmodel.options import SpringOptions
    from springmodel.spring_kernel import SpringKernel
    variants, start, step = pickle.load(open(sys.argv[1], "rb")), int(sys.argv[2]), int(sys.argv[3])
    mesh = box_mesh((1.0, 1.3, 0.7), (5, 4, 3), split="five")
    rng = np.random.default_rng(3)
    frames = np.tile(np.eye(3), (mesh.n_tets, 1, 1))
    material = {"law": "linear", "E": 1.0e3, "nu": 0.3}
    el = build_spring_elements(mesh.points, mesh.tets, frames, SpringOptions(), material)
    x = mesh.points + 0.02 * rng.standard_normal(mesh.points.shape)
    v = rng.standard_normal(mesh.points.shape)
    order = variants[start::step]
    for o in order:  # each variant serially first: every block loop is loaded
        SpringKernel(el, o).forces(x, v)
    n = 0
    for o in order:
        par, ser = SpringKernel(el, o, parallel=True), SpringKernel(el, o)
        ref = ser.forces(x, v)
        for _ in range(50):
            f = par.forces(x, v)
            assert np.abs(f - ref).max() <= 1e-12 * np.abs(ref).max(), o
            n += 1
    print("compared", n)
    """
)


@pytest.mark.slow
def test_two_processes_filling_one_cold_cache_then_a_third_loading_it(tmp_path):
    # as two pytest-xdist workers: both compile kernels into one empty numba cache at once
    # (each a different half, in the same order), then a process loads them all from it
    needs_threads()
    root = str(Path(__file__).resolve().parents[2])
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"), NUMBA_NUM_THREADS="2")
    env["PYTHONPATH"] = os.pathsep.join([root, env.get("PYTHONPATH", "")])
    variants = list(_variants())
    path = tmp_path / "variants.pickle"
    path.write_bytes(pickle.dumps(variants))

    def start(begin, step):
        args = [sys.executable, "-c", CHECK, str(path), str(begin), str(step)]
        return subprocess.Popen(args, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True)  # fmt: skip

    workers = [start(0, 2), start(1, 2)]
    for p in workers:
        out, err = p.communicate(timeout=3600)
        assert p.returncode == 0, err[-2000:]
        assert out.startswith("compared")
    last = start(0, 1)
    out, err = last.communicate(timeout=3600)
    assert last.returncode == 0, err[-2000:]
    assert out.split() == ["compared", str(50 * len(variants))]


def test_the_default_is_parallel_from_the_rules_threshold(state, monkeypatch):
    from springmodel import spring_kernel

    _, el, _, _ = state
    many = numba.get_num_threads() > 1
    monkeypatch.setattr(spring_kernel, "PARALLEL_MIN_ELEMENTS", el.n_elements)
    assert SpringKernel(el, SpringOptions()).parallel == many
    monkeypatch.setattr(spring_kernel, "PARALLEL_MIN_ELEMENTS", el.n_elements + 1)
    assert not SpringKernel(el, SpringOptions()).parallel
    assert SpringKernel(el, SpringOptions(), parallel=True).parallel  # forced on

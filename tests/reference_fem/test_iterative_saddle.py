"""The iterative solves of the FEM reference (block-preconditioned GMRES on the P2/P1 saddle
point, AMG-CG on the P2 displacement tangent) against the factorised ones, on the
liver-shaped organ (about 1,500 tets, not a cube, nu = 0.49); the memory limit that sends a
solve from the factorisation to the iterative solver, or refuses it cleanly; and the
factor's memory estimate against the memory the factorisation really takes.

References are independent of the code under test: the direct factorisation (PARDISO or
SuperLU) of the same systems, and the process's resident memory read from ``/proc``."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from reference_fem.solver import make_problem, solve
from springfem.mechanics import memory
from springfem.mechanics import pardiso as _pardiso
from springfem.mechanics.direct import FreeBlock
from springfem.mechanics.limits import solve_limits
from springfem.mechanics.linsolve import LinearSolver
from springfem.mechanics.memory import MemoryLimitExceeded, resident_bytes
from springfem.scene import load_scene


@pytest.fixture(scope="module")
def organ(tmp_path_factory):
    from springfem.mesh.organ import organ_scene

    folder = tmp_path_factory.mktemp("organ")
    path = organ_scene(folder, tets=1500, nu=0.49)
    return path


def scene_file(path, **fem):
    text = path.read_text() + "\n[fem]\n" + "".join(f"{k} = {v}\n" for k, v in fem.items())
    p = path.with_name(f"{path.stem}-{len(list(path.parent.iterdir()))}.toml")
    p.write_text(text)
    return p


def scene_with(path, **fem):
    return load_scene(scene_file(path, **fem))


def test_block_gmres_newton_equals_the_factorised_newton(organ):
    fem = {"order": 2, "formulation": '"mixed"'}
    direct = solve(scene_with(organ, linear_solver='"direct"', **fem))
    it = solve(scene_with(organ, linear_solver='"amg"', **fem))
    assert it.result.info["krylov_solver"] == "gmres+block"
    assert it.result.info["krylov_iterations"] > 0 and "factorizations" not in it.result.info
    assert direct.result.info["krylov_iterations"] == 0
    scale = np.abs(direct.u_vertices).max()
    assert scale > 1.0  # a large deformation (mm): the test is not trivial
    assert np.abs(it.u_vertices - direct.u_vertices).max() <= 1e-6 * scale


def test_amg_cg_p2_equals_the_factorisation(organ):
    direct = solve(scene_with(organ, order=2, linear_solver='"direct"'), law="linear")
    it = solve(scene_with(organ, order=2, linear_solver='"amg"'), law="linear")
    assert it.result.info["krylov_solver"] == "cg+amg"
    scale = np.abs(direct.u_vertices).max()
    assert np.abs(it.u_vertices - direct.u_vertices).max() <= 1e-6 * scale


@pytest.fixture(scope="module")
def tangent(organ):
    problem = make_problem(scene_with(organ, order=2, formulation='"mixed"'))
    x = np.zeros(problem.n_dofs)
    R, K, _, _ = problem.residual_tangent(x, 1.0)
    return problem, K, np.where(problem.free, -R, 0.0)


def test_a_factorisation_over_the_memory_limit_goes_iterative(tangent, monkeypatch):
    problem, K, b = tangent
    x_direct = LinearSolver("direct", saddle_point=True).solve(K, b, problem.free)
    monkeypatch.setattr(memory, "ITERATIVE_BYTES_PER_NNZ", 0.0)  # room for the iterative
    monkeypatch.setattr(memory, "KRYLOV_VECTORS", 1)
    solver = LinearSolver(
        "auto",
        near_nullspace=problem.linear_solver.near_nullspace,
        saddle_point=True,
        schur=problem.schur_diagonal(),
    )
    with solve_limits(max_memory=resident_bytes() + 1e6):  # no room for a factor
        f = solver.factorize(K, problem.free, True)
        x = f.solve(b, 1e-10)
    assert f.kind == "block" and solver.name == "gmres+block"
    assert "memory limit" in solver.reason
    assert np.abs(x - x_direct).max() <= 1e-7 * np.abs(x_direct).max()


def test_a_solve_that_fits_neither_way_is_refused_before_it_starts(tangent):
    problem, K, b = tangent
    solver = LinearSolver("auto", saddle_point=True, schur=problem.schur_diagonal())
    with solve_limits(max_memory=resident_bytes() + 1e6):
        with pytest.raises(MemoryLimitExceeded, match="memory limit"):
            solver.factorize(K, problem.free, True)
    assert solver.stats["factorizations"] == 0 and solver.stats["krylov_iterations"] == 0


def test_the_cli_refuses_a_solve_over_the_memory_limit_in_one_line(organ, monkeypatch, capsys):
    from studies.cli import main

    path = scene_file(organ, order=2, formulation='"mixed"')
    monkeypatch.setenv("SPRINGFEM_MAX_MEMORY", "1M")
    code = main(["solve", str(path), "--model", "fem", "--out", str(path.parent / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 3
    assert [line for line in err if "memory limit" in line]
    assert not [line for line in err if "Traceback" in line]


MEASURE = """
import sys, numpy as np, scipy.sparse as sp
from springfem.mechanics.pardiso import Pardiso
def peak():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) * 1024
A = sp.load_npz(sys.argv[1]).tocsr()
warm = Pardiso(symmetric=True)  # MKL's code pages are resident memory too: load them first
small = sp.csr_matrix(sp.eye(3))
warm.analyse(small)
warm.factor(small.data)
warm.solve(np.ones(3))
warm.release()
handle = Pardiso(symmetric=True)
before = peak()
handle.analyse(A)
estimate = handle.memory
handle.factor(A.data)
print(estimate, peak() - before)
"""


@pytest.mark.skipif(not _pardiso.available(), reason="the estimate is PARDISO's analysis")
def test_the_factor_memory_estimate_is_the_memory_the_factor_takes(tangent, tmp_path):
    import scipy.sparse as sp

    problem, K, _ = tangent
    K = K.tocsr()
    K.sum_duplicates()
    fb = FreeBlock(K, problem.free)
    up = fb.upper_pattern.copy()
    up.data = fb.upper(K.data, True)
    sp.save_npz(tmp_path / "upper.npz", up)
    # a fresh process: its peak resident memory grows by what the factorisation takes
    out = subprocess.run(
        [sys.executable, "-c", MEASURE, str(tmp_path / "upper.npz")],
        capture_output=True, text=True, check=True, timeout=300,
        env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)},
    )  # fmt: skip
    estimate, taken = map(float, out.stdout.split())
    assert taken > 0
    assert 0.5 <= estimate / taken <= 2.0
    law = memory.factor_bytes_law(fb.n)
    assert 0.5 <= law / estimate <= 2.0

"""Reliability: fuzzed scene files and meshes never crash, hang or print more than one line.

Property-based tests (hypothesis) over more than 1000 generated malformed inputs in all
(``-m slow``; the default run draws a fifth of each budget, :data:`QUICK_SHARE`):

* scenes: a valid scene (random law, axes, regions, loads, probes, solver options) with
  one to four random mutations: keys deleted, unknown keys added, values replaced by wrong
  types, NaN, infinities, huge, negative and zero numbers, nested tables, lists of the
  wrong length, empty or far-away regions, probes outside the mesh, mesh files that are
  missing, broken or a directory;
* broken files: the TOML text cut, spliced with random characters, or random bytes;
* meshes: random points and tets (indices out of range, NaN, coincident nodes, repeated
  nodes, zero volume, inverted), mixed with other cell types, through
  :func:`springfem.mesh.mesh_from_meshio` and through files.

The contract (docs/contract.rst#exit-codes): :func:`springfem.scene.parse_scene` either returns a
:class:`Scene` whose arrays are all finite and consistent, or raises an ``InputError``
(exit code 2) with one non-empty line that names the file; never another exception, and
never a hang. The scene cases run in-process (a subprocess per case would cost a second
each); a small sample goes through the ``springfem`` console script for the exit code.
The time bound is a hang detector (a generous alarm per case), not a timing assertion.
"""

from __future__ import annotations

import contextlib
import copy
import io
import math
import os
import signal
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from support.toml import Raw
from support.toml import to_toml as write_toml

from springfem.errors import InputError, MeshError, SceneError
from springfem.mesh import box_mesh, mesh_from_meshio, read_mesh
from springfem.scene import MAX_TETS, Scene, load_scene, parse_scene
from studies.cli import main

ROOT = Path(__file__).resolve().parents[2]

# an overflow or invalid operation while loading would be a silently non-finite value
pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")

#: Seconds one fuzz case may take before it counts as a hang (the slowest valid case takes
#: milliseconds; the bound only has to separate "finished" from "stuck" on a busy machine).
HANG_SECONDS = 30.0
#: Longest acceptable error line: one clear sentence, not a dump of the input.
MAX_MESSAGE = 600

FUZZ = settings(
    deadline=None,  # timing is checked by the hang alarm, not by hypothesis
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    database=None,
    # the same cases on every run, so a CI failure reproduces locally; set
    # SPRINGFEM_FUZZ_RANDOM=1 (and SPRINGFEM_FUZZ_SCALE) for a fresh, deeper search
    derandomize=not os.environ.get("SPRINGFEM_FUZZ_RANDOM"),
)


class Hang(Exception):
    """A fuzz case did not finish within :data:`HANG_SECONDS`."""


@contextlib.contextmanager
def hang_alarm(seconds: float = HANG_SECONDS):
    """Raise :class:`Hang` in the main thread if the block runs longer than ``seconds``."""

    def _fire(signum, frame):
        raise Hang(f"fuzz case still running after {seconds} s")

    old = signal.signal(signal.SIGALRM, _fire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def assert_one_line(msg: str, file: str | None = None) -> None:
    """One clear line: non-empty, no newline, bounded, naming the file when given."""
    assert msg.strip(), "empty error message"
    assert "\n" not in msg and "\r" not in msg, f"multi-line message: {msg!r}"
    assert len(msg) <= MAX_MESSAGE, f"message of {len(msg)} characters: {msg[:200]!r}…"
    assert "Traceback" not in msg
    if file is not None:
        assert file in msg, f"message does not name {file}: {msg!r}"


# ------------------------------------------------------------------ TOML serialisation


def to_toml(scene: dict) -> str:
    """Top-level keys as ``key = value`` lines, every table inline (same data as [table])."""
    return write_toml(scene, inline=True)


# ------------------------------------------------------------------ valid base scenes

MATERIALS = [
    {"law": "linear", "E": 1.0e3, "nu": 0.3, "density": 1000.0},
    {"law": "neo-hookean", "mu": 300.0, "kappa": 3000.0, "formulation": "uncoupled"},
    {"law": "neo-hookean", "E": 1.0e3, "nu": 0.45, "volumetric": "quadratic"},
    {
        "law": "transverse-linear",
        "E_fiber": 3.0e3,
        "E_cross": 1.0e3,
        "G_fiber": 400.0,
        "nu_fiber_cross": 0.3,
        "nu_cross": 0.4,
    },
]
AXES = [
    None,
    {"type": "uniform", "fiber": [1.0, 0.0, 0.0], "sheet": [0.0, 1.0, 0.0]},
    {
        "type": "helix",
        "fiber": [0.0, 1.0, 0.0],
        "sheet": [0.0, 0.0, 1.0],
        "axis": "x",
        "range": [0.0, 1.0],
        "angles": [60.0, -60.0],
    },
    {"type": "cells"},
]
BOUNDARIES = [
    {"region": "x_min", "fix": ["x", "y", "z"]},
    {"region": "x_max", "displacement": [0.01, 0.0, 0.0], "fix": ["x"]},
    {"region": {"box": [[-0.1, -0.1, -0.1], [0.1, 1.0, 1.0]]}, "fix": ["y", "z"]},
    {"region": {"point": [0.0, 0.0, 0.0]}, "displacement": [0.0, 0.0, 0.0]},
]
LOADS = [
    {"type": "traction", "region": "x_max", "value": [0.0, 0.0, -1.0]},
    {"type": "pressure", "region": "z_max", "value": 10.0},
    {"type": "gravity", "value": [0.0, 0.0, -9.81]},
    {"type": "force", "region": "y_max", "value": [0.0, 1.0e-3, 0.0]},
]
PROBES = [
    {"name": "tip", "point": [1.0, 0.25, 0.25]},
    {"name": "mid", "point": [0.5, 0.1, 0.4]},
]
SPRINGS = [
    None,
    {"solver": "explicit", "dt": 1.0e-4, "steps": 10, "mass_damping": 5.0},
    {"torsion": "angle", "volume": False, "calibration": "nnls"},
    {"lms": {"mu": 0.5, "k_min": 0.5, "k_max": 2.0, "rule": "spec"}, "axial": "cubic"},
]
FEMS = [None, {"order": 2, "tol": 1e-8, "load_steps": 2, "linear_solver": "direct"}]


@st.composite
def base_scenes(draw) -> dict:
    """A valid scene dict on a 1 x 0.5 x 0.5 box of at most 12 tets."""
    scene: dict = {"name": draw(st.sampled_from(["fuzz", "beam-1", "Liver (coarse)"]))}
    scene["mesh"] = {
        "generator": "box",
        "size": [1.0, 0.5, 0.5],
        "divisions": [2, 1, 1],
        "split": draw(st.sampled_from(["five", "six", "five-mirrored", "six-mirrored"])),
    }
    scene["material"] = draw(st.sampled_from(MATERIALS))
    for key, choices in (("axes", AXES[:3]), ("spring", SPRINGS), ("fem", FEMS)):
        value = draw(st.sampled_from(choices))
        if value is not None:
            scene[key] = value
    for key, choices in (("boundary", BOUNDARIES), ("load", LOADS), ("probe", PROBES)):
        items = draw(st.lists(st.sampled_from(choices), max_size=2, unique_by=id))
        if items:
            scene[key] = items
    return copy.deepcopy(scene)  # sampled_from hands out shared objects: mutate a copy


# ------------------------------------------------------------------ mutations

SPECIAL_NUMBERS = [
    math.nan,
    math.inf,
    -math.inf,
    0,
    0.0,
    -0.0,
    -1,
    -1.0,
    1e308,
    -1e308,
    5e-324,
    1e-300,
    10**30,
    -(10**30),
    2**63,
    2**63 - 1,
    0.5,
    1,
    3,
]
SPECIAL_STRINGS = [
    "",
    " ",
    "x",
    "x_min",
    "z_max",
    "tag:1",
    "six",
    "linear",
    "neo-hookean",
    "helix",
    "cells",
    "explicit",
    "static",
    "..",
    "../../etc/passwd",
    "/dev/null",
    "nan",
    "1e3",
    "__import__('os').system('false')",
    "é\u2028\t\x00",
]
DATES = [Raw("1979-05-27T07:32:00Z"), Raw("1979-05-27"), Raw("07:32:00")]

_leaf = st.one_of(
    st.sampled_from(SPECIAL_NUMBERS),
    st.sampled_from(SPECIAL_STRINGS),
    st.sampled_from(DATES),
    st.booleans(),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(st.characters(exclude_categories=("Cs",)), max_size=12),
)
weird_values = st.recursive(
    _leaf,
    lambda children: st.one_of(
        st.lists(children, max_size=5),
        st.dictionaries(
            st.sampled_from(["box", "point", "x", "file", "type"]), children, max_size=2
        ),
        st.dictionaries(st.text(max_size=6), children, max_size=3),
    ),
    max_leaves=8,
)
vectors = st.lists(
    st.one_of(st.sampled_from(SPECIAL_NUMBERS), st.floats(-10, 10)), min_size=0, max_size=4
)
regions = st.one_of(
    st.fixed_dictionaries({"box": st.lists(vectors, min_size=0, max_size=3)}),
    st.fixed_dictionaries({"point": vectors}),
    st.builds(lambda: {"box": [[5.0, 5.0, 5.0], [6.0, 6.0, 6.0]]}),  # fresh lists each time
    st.sampled_from(SPECIAL_STRINGS),
)
unknown_keys = st.one_of(
    st.sampled_from(["colour", "E", "size", "region", "mesh", "name", "bogus", "a\nb", "é", ""]),
    st.text(max_size=10),
)


def paths(obj, prefix=()):
    """Every path (tuple of keys and indices) to a node below ``obj``."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield prefix + (k,)
            yield from paths(v, prefix + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield prefix + (i,)
            yield from paths(v, prefix + (i,))


def _parent(obj, path):
    for key in path[:-1]:
        obj = obj[key]
    return obj


def mutate(data, scene: dict, files: dict[str, str]) -> None:
    """Apply one random mutation to ``scene`` in place (``data`` is hypothesis' st.data())."""
    all_paths = [()] + list(paths(scene))
    # a section first, then a node in it: spreads the mutations over the whole scene
    sections = sorted({p[0] for p in all_paths if p}, key=str) or [None]
    section = data.draw(st.sampled_from(sections), label="section")
    inside = [p for p in all_paths if p and p[0] == section] or [()]
    path = data.draw(st.sampled_from(inside + [()]), label="path")
    op = data.draw(
        st.sampled_from(
            ["delete", "replace", "special", "add", "wrap", "vector", "region", "section", "file"]
            + ["number"] * 3
        ),
        label="op",
    )
    if op == "section":  # a whole section replaced, removed or duplicated as a list
        key = data.draw(st.sampled_from(["mesh", "material", "axes", "boundary", "load", "probe"]))
        how = data.draw(st.sampled_from(["drop", "weird", "empty", "list"]))
        if how == "drop":
            scene.pop(key, None)
        elif how == "weird":
            scene[key] = data.draw(weird_values)
        elif how == "empty":
            scene[key] = {} if key in ("mesh", "material", "axes") else []
        else:
            scene[key] = [scene.get(key, {})] * 2
        return
    if op == "file":  # the mesh comes from a file: missing, broken, a directory, or fine
        scene["mesh"] = {"file": data.draw(st.sampled_from(sorted(files.values())))}
        if data.draw(st.booleans()):
            scene["mesh"]["scale"] = data.draw(st.sampled_from(SPECIAL_NUMBERS))
        if data.draw(st.booleans()):
            scene["axes"] = {
                "type": "cells",
                "fiber_data": data.draw(st.sampled_from(["fiber", "q"])),
            }
        return
    if op == "add" or path == ():
        target = _parent(scene, path + ("",)) if path else scene
        if isinstance(target, dict):
            target[data.draw(unknown_keys, label="key")] = data.draw(weird_values)
            return
        op = "replace"
    parent = _parent(scene, path)
    key = path[-1]
    if op == "delete":
        del parent[key]
    elif op == "replace":
        parent[key] = data.draw(weird_values, label="value")
    elif op == "special":
        parent[key] = data.draw(st.sampled_from(SPECIAL_NUMBERS + SPECIAL_STRINGS + DATES))
    elif op == "number":  # a number somewhere in the scene becomes a special one
        numeric = [p for p in all_paths if p and type(_parent(scene, p)[p[-1]]) in (int, float)]
        if numeric:
            where = data.draw(st.sampled_from(numeric), label="number")
            _parent(scene, where)[where[-1]] = data.draw(st.sampled_from(SPECIAL_NUMBERS))
    elif op == "wrap":
        parent[key] = data.draw(st.sampled_from([[parent[key]], {"x": parent[key]}, []]))
    elif op == "vector":
        parent[key] = data.draw(vectors)
    elif op == "region":
        parent[key] = data.draw(regions)


def bound_mesh_size(scene: dict) -> None:
    """Keep generated boxes tiny, except those the loader must refuse before building them.

    Divisions between the fuzz size and the loader's limit would build a real mesh of up to
    ``MAX_TETS`` tets; such a case tests nothing the small ones don't, so it is shrunk.
    """
    mesh = scene.get("mesh")
    if not isinstance(mesh, dict):
        return
    div = mesh.get("divisions")
    if not (isinstance(div, list) and all(type(d) is int and d > 0 for d in div)):
        return
    n = math.prod(div) * 6
    if 200 < n <= 2 * MAX_TETS:
        mesh["divisions"] = [2, 1, 1]


# ------------------------------------------------------------------ the contract


def check_scene(s: Scene) -> None:
    """A scene the loader accepted is usable: finite, consistent arrays and parameters."""
    m = s.mesh
    assert np.isfinite(m.points).all() and m.n_tets > 0
    assert m.tets.min() >= 0 and m.tets.max() < m.n_points
    vol = m.volumes()
    assert np.isfinite(vol).all() and (vol > 0).all()
    F = s.frames
    assert F.shape == (m.n_tets, 3, 3) and np.isfinite(F).all()
    # orthonormal frames to round-off (rows are unit axes)
    np.testing.assert_allclose(
        F @ F.transpose(0, 2, 1), np.broadcast_to(np.eye(3), F.shape), atol=1e-9
    )
    mat = s.material
    assert math.isfinite(mat.density) and mat.density > 0
    if mat.law == "transverse-linear":  # E, nu are an isotropic stand-in, nu in (-1, 1)
        for v in (mat.E_fiber, mat.E_cross, mat.G_fiber):
            assert math.isfinite(v) and v > 0
        assert -1 < mat.nu_cross < 1 and math.isfinite(mat.nu_fiber_cross)
    else:
        for v in (mat.E, mat.nu, mat.mu, mat.kappa, mat.lam):
            assert math.isfinite(v)
        assert mat.E > 0 and mat.mu > 0 and mat.kappa > 0 and -1 < mat.nu < 0.5
    for b in s.boundaries:
        assert b.region.nodes.size > 0 and np.isfinite(b.value).all() and b.components
    for ld in s.loads:
        assert np.isfinite(ld.value).all()
        if ld.type in ("traction", "pressure"):
            assert ld.region.facets.size > 0
    for p in s.probes:
        assert 0 <= p.tet < m.n_tets and np.isfinite(p.bary).all()
        assert abs(p.bary.sum() - 1.0) < 1e-9 and p.bary.min() >= -1e-6


def parse_or_refuse(text: str, file: str = "fuzz.toml") -> Scene | None:
    """Parse ``text``; ``None`` if refused with a good message; fail on anything else."""
    try:
        with hang_alarm():
            scene = parse_scene(text, path=file)
    except InputError as exc:  # SceneError, MeshError: exit code 2
        assert_one_line(str(exc), file)
        return None
    check_scene(scene)
    return scene


@pytest.fixture(scope="module")
def mesh_files(tmp_path_factory) -> dict[str, str]:
    """Mesh files a fuzzed scene may point to: good (with fibers), broken, missing, a folder."""
    d = tmp_path_factory.mktemp("meshes")
    m = box_mesh((1.0, 0.5, 0.5), (2, 1, 1))
    fib = np.tile([1.0, 0.0, 0.0], (m.n_tets, 1))
    meshio.write(
        d / "good.vtu", meshio.Mesh(m.points, [("tetra", m.tets)], cell_data={"fiber": [fib]})
    )
    (d / "broken.vtu").write_text("<VTKFile> this is not a mesh")
    (d / "empty.msh").write_bytes(b"")
    meshio.write(d / "tris.vtu", meshio.Mesh(m.points, [("triangle", m.tets[:, :3])]))
    (d / "folder.vtu").mkdir()
    return {
        "good": str(d / "good.vtu"),
        "broken": str(d / "broken.vtu"),
        "empty": str(d / "empty.msh"),
        "tris": str(d / "tris.vtu"),
        "folder": str(d / "folder.vtu"),
        "missing": str(d / "missing.vtu"),
        "relative": "no/such/mesh.msh",
    }


def scaled(n: int) -> int:
    """``n`` times ``SPRINGFEM_FUZZ_SCALE`` (default 1; raise it for a deeper local fuzz)."""
    return max(1, round(n * float(os.environ.get("SPRINGFEM_FUZZ_SCALE", "1"))))


#: The default run draws this fraction of each budget; ``-m slow`` draws all of it.
QUICK_SHARE = 0.2


def budgets(n: int):
    """Parametrize a fuzz test over its quick share of ``n`` cases and (``-m slow``) all ``n``.

    Both draw from the same derandomized (fixed-seed) search, so a failure of either
    reproduces from its test id.
    """
    return pytest.mark.parametrize(
        "n_examples",
        [
            pytest.param(max(1, round(QUICK_SHARE * scaled(n))), id="quick"),
            pytest.param(scaled(n), id="full", marks=pytest.mark.slow),
        ],
    )


def cases(**strategies):
    """Attach the hypothesis strategies of a fuzz body (run by :func:`fuzz`)."""

    def attach(body):
        body.strategies = strategies
        return body

    return attach


def fuzz(n_examples: int, body, **fixtures) -> None:
    """Run ``body`` on ``n_examples`` cases drawn from its :func:`cases` strategies."""
    settings(FUZZ, max_examples=n_examples)(given(**body.strategies)(body))(**fixtures)


N_SCENES = 700
N_TEXT = 150
N_BYTES = 60
N_MESHES = 150
N_MESH_FILES = 60
N_CLI = 40
#: Generated malformed inputs in all (the issue asks for at least 1000).
N_TOTAL = N_SCENES + N_TEXT + N_BYTES + N_MESHES + N_MESH_FILES + N_CLI


def test_fuzz_budget_is_at_least_1000():
    assert N_TOTAL >= 1000


@cases(data=st.data(), scene=base_scenes())
def _fuzzed_scenes_load_or_fail_with_one_line(mesh_files, data, scene):
    # the unmutated scene is valid: the loader must accept it (so mutations test something)
    if data.draw(st.integers(0, 20), label="keep") == 0:
        assert parse_or_refuse(to_toml(scene)) is not None
        return
    for _ in range(data.draw(st.integers(1, 4), label="n_mutations")):
        mutate(data, scene, mesh_files)
    bound_mesh_size(scene)
    parse_or_refuse(to_toml(scene))


@budgets(N_SCENES)
def test_fuzzed_scenes_load_or_fail_with_one_line(mesh_files, n_examples):
    fuzz(n_examples, _fuzzed_scenes_load_or_fail_with_one_line, mesh_files=mesh_files)


@cases(scene=base_scenes(), data=st.data())
def _broken_toml_text_fails_with_one_line(scene, data):
    text = to_toml(scene)
    cut = data.draw(st.integers(0, len(text)), label="cut")
    how = data.draw(st.sampled_from(["truncate", "splice", "delete", "duplicate"]))
    if how == "truncate":
        text = text[:cut]
    elif how == "splice":
        junk = data.draw(
            st.one_of(
                st.text(st.characters(exclude_categories=("Cs",)), min_size=1, max_size=8),
                st.sampled_from(["[", "]]", "=", '"', "'''", "{", "\n[mesh]\n", "\\", "#", "\x00"]),
            )
        )
        text = text[:cut] + junk + text[cut:]
    elif how == "delete":
        text = text[:cut] + text[cut + data.draw(st.integers(1, 20)) :]
    else:
        text = text + text[cut:]
    parse_or_refuse(text)


@budgets(N_TEXT)
def test_broken_toml_text_fails_with_one_line(n_examples):
    fuzz(n_examples, _broken_toml_text_fails_with_one_line)


@cases(
    payload=st.one_of(
        st.binary(max_size=200),
        st.builds(lambda b: b"\xff\xfe" + b, st.binary(max_size=50)),
        st.builds(lambda b: b'[mesh]\nfile = "x"\n' + b, st.binary(min_size=1, max_size=20)),
    )
)
def _random_bytes_scene_files_fail_with_one_line(tmp_path_factory, payload):
    path = tmp_path_factory.getbasetemp() / "bytes.toml"
    path.write_bytes(payload)
    try:
        with hang_alarm():
            scene = load_scene(path)
    except InputError as exc:
        assert_one_line(str(exc), str(path))
    else:  # random bytes that happen to be a valid scene would need [mesh] and [material]
        check_scene(scene)


@budgets(N_BYTES)
def test_random_bytes_scene_files_fail_with_one_line(tmp_path_factory, n_examples):
    fuzz(
        n_examples, _random_bytes_scene_files_fail_with_one_line, tmp_path_factory=tmp_path_factory
    )


# ------------------------------------------------------------------ meshes

DEFECTS = [
    "invert",
    "nan",
    "huge",
    "coincident",
    "index",
    "repeat",
    "duplicate",
    "flatten",
    "sliver",
    "unused",
    "part",
    "bow-tie",
    "overlap",
    "fold",
    "cells",
    "flat-2d",
    "no-tets",
    "shuffle",
]


@st.composite
def raw_meshes(draw) -> meshio.Mesh:
    """A small valid box mesh with zero to three random defects, as a ``meshio.Mesh``."""
    with np.errstate(all="ignore"):  # defects on NaN or huge nodes: the generator's own
        return _raw_mesh(draw)


def _raw_mesh(draw) -> meshio.Mesh:
    split = draw(st.sampled_from(["five", "six", "five-mirrored", "six-mirrored"]))
    base = box_mesh((1.0, 0.5, 0.5), (draw(st.integers(1, 2)), 1, 1), split)
    pts, tets = base.points.copy(), base.tets.copy()
    cells = []
    rows = st.integers(0, len(tets) - 1)
    defects = draw(st.lists(st.sampled_from(DEFECTS), max_size=3))
    final = [d for d in defects if d in ("index", "flat-2d", "no-tets")]  # applied last
    for defect in [d for d in defects if d not in final]:
        n = len(pts)
        node = draw(st.integers(0, n - 1))
        if defect == "invert":
            k = draw(st.integers(0, len(tets) - 1))
            tets[k] = tets[k][[1, 0, 2, 3]]
        elif defect == "nan":
            pts[node, draw(st.integers(0, 2))] = draw(st.sampled_from([math.nan, math.inf]))
        elif defect == "huge":
            pts[node] *= draw(st.sampled_from([1e150, 1e-150, 1e300]))
        elif defect == "coincident":
            pts = np.vstack([pts, pts[node]])
            tets[draw(rows) % len(tets), draw(st.integers(0, 3))] = n
        elif defect == "repeat":
            k = draw(rows) % len(tets)
            tets[k, 1] = tets[k, 0]
        elif defect == "duplicate":
            tets = np.vstack([tets, tets[draw(rows) % len(tets)][[2, 1, 0, 3]]])
        elif defect == "flatten":
            k = tets[draw(rows) % len(tets)]
            pts[k[3]] = pts[k[:3]].mean(axis=0)
        elif defect == "sliver":
            k = tets[draw(rows) % len(tets)]
            pts[k[3]] = 0.99 * pts[k[:3]].mean(axis=0) + 0.01 * pts[k[3]]
        elif defect == "unused":
            pts = np.vstack([pts, [[5.0, 5.0, 5.0]]])
        elif defect == "part":
            tets = np.vstack([tets, tets + n])
            pts = np.vstack([pts, pts + [3.0, 0.0, 0.0]])
        elif defect == "bow-tie":  # a reflected copy of the first tet through its node 0
            c = pts[tets[0, 0]]
            new = 2 * c - pts[tets[0, 1:]]
            pts = np.vstack([pts, new])
            tets = np.vstack([tets, [[tets[0, 0], n, n + 2, n + 1]]])
        elif defect == "overlap":  # a node inside the body, joined to a boundary face
            pts = np.vstack([pts, [[0.5, 0.25, 0.25]]])
            tets = np.vstack([tets, [[tets[0, 1], tets[0, 2], tets[0, 3], n]]])
        elif defect == "fold":
            k = tets[0]
            pts = np.vstack([pts, [pts[k[:3]].mean(axis=0) + 0.1 * (pts[k[3]] - pts[k[0]])]])
            tets = np.vstack([tets, [[k[0], k[1], k[2], n]]])
        elif defect == "cells":
            kind = draw(
                st.sampled_from(["triangle", "line", "vertex", "quad", "hexahedron", "wedge"])
            )
            k = {"triangle": 3, "line": 2, "vertex": 1, "quad": 4, "hexahedron": 8, "wedge": 6}[
                kind
            ]
            cells.append((kind, np.arange(k)[None] % n))
        elif defect == "shuffle":
            perm = np.random.default_rng(draw(st.integers(0, 99))).permutation(n)
            inv = np.argsort(perm)
            pts, tets = pts[perm], np.where((tets >= 0) & (tets < n), inv[tets % n], tets)
    if "index" in final:
        tets[draw(rows) % len(tets), 0] = draw(st.sampled_from([-1, len(pts), len(pts) + 5]))
    if "flat-2d" in final:
        pts = pts[:, :2]
    if "no-tets" not in final:
        cells.insert(0, ("tetra", tets))
    return meshio.Mesh(pts, cells)


@cases(m=raw_meshes())
def _fuzzed_meshes_are_validated_or_refused_with_ids(m):
    try:
        with hang_alarm():
            mesh = mesh_from_meshio(m, "fuzz.vtu")
    except MeshError as exc:
        assert_one_line(str(exc), "fuzz.vtu")
        return
    assert np.isfinite(mesh.points).all()
    assert mesh.tets.min() >= 0 and mesh.tets.max() < mesh.n_points
    assert (mesh.volumes() > 0).all()
    assert np.unique(mesh.tets.ravel()).size == mesh.n_points  # no unused nodes left
    for note in mesh.notes:
        assert_one_line(note, "fuzz.vtu")


@budgets(N_MESHES)
def test_fuzzed_meshes_are_validated_or_refused_with_ids(n_examples):
    fuzz(n_examples, _fuzzed_meshes_are_validated_or_refused_with_ids)


@cases(
    ext=st.sampled_from(["vtu", "vtk", "msh", "mesh", "inp", "xdmf", "stl", "obj", "bin", ""]),
    payload=st.one_of(
        st.binary(max_size=300),
        st.sampled_from([b"", b"<VTKFile", b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n"]),
    ),
)
def _broken_mesh_files_fail_with_one_line(tmp_path_factory, ext, payload):
    path = (
        tmp_path_factory.getbasetemp() / f"broken.{ext}"
        if ext
        else tmp_path_factory.getbasetemp() / "broken"
    )
    path.write_bytes(payload)
    try:
        with hang_alarm():
            read_mesh(path)
    except MeshError as exc:
        assert_one_line(str(exc), str(path))


@budgets(N_MESH_FILES)
def test_broken_mesh_files_fail_with_one_line(tmp_path_factory, n_examples):
    fuzz(n_examples, _broken_mesh_files_fail_with_one_line, tmp_path_factory=tmp_path_factory)


@cases(data=st.data(), scene=base_scenes())
def _cli_inspect_exits_0_or_2_with_one_line(tmp_path_factory, mesh_files, data, scene):
    """In-process ``springfem inspect``: exit 0, or exit 2 with exactly one stderr line."""
    for _ in range(data.draw(st.integers(0, 3), label="n_mutations")):
        mutate(data, scene, mesh_files)
    bound_mesh_size(scene)
    path = tmp_path_factory.getbasetemp() / "cli.toml"
    path.write_text(to_toml(scene))
    out, err = io.StringIO(), io.StringIO()
    with hang_alarm(), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["inspect", str(path)])
    err = err.getvalue()
    assert code in (0, 2), err
    # notes and one-line warnings (e.g. a locking formulation at nu >= 0.45) may precede
    lines = [ln for ln in err.splitlines() if not ln.startswith(("note: ", "warning: "))]
    if code == 2:
        assert len(lines) == 1 and lines[0].startswith("springfem: error: "), err
        assert_one_line(lines[0])
    else:
        assert lines == [], err


@budgets(N_CLI)
def test_cli_inspect_exits_0_or_2_with_one_line(tmp_path_factory, mesh_files, n_examples):
    fuzz(
        n_examples,
        _cli_inspect_exits_0_or_2_with_one_line,
        tmp_path_factory=tmp_path_factory,
        mesh_files=mesh_files,
    )


# ------------------------------------------------------------------ exit codes


@pytest.mark.parametrize(
    "text, code, needle, real",
    [
        (
            '[mesh]\ngenerator = "box"\nsize = [1.0, 1.0, 1.0]\ndivisions = [1, 1, 1]\n'
            '[material]\nlaw = "linear"\nE = nan\nnu = 0.3\n',
            2,
            "material.E: must be finite",
            False,
        ),
        ("\xff\xfe garbage", 2, "not valid TOML", True),
        (
            'name = "ok"\n[mesh]\ngenerator = "box"\nsize = [1.0, 1.0, 1.0]\n'
            "divisions = [1, 1, 1]\n"
            '[material]\nlaw = "linear"\nE = 1.0\nnu = 0.3\n',
            0,
            "",
            False,
        ),
    ],
    ids=["nan", "bytes", "ok"],
)
def test_console_script_exit_codes(tmp_path, capfd, text, code, needle, real):
    """Exit code and a single stderr line, no traceback. Undecodable bytes go through a real
    process (its stderr encoding); the others through ``main`` in-process (a process costs
    about a second; the real process's exit 2 and 0 are also checked by
    tests/studies/test_cli.py and test_reliability_determinism.py)."""
    path = tmp_path / "s.toml"
    path.write_text(text, encoding="utf-8")
    if real:
        proc = subprocess.run(
            [sys.executable, "-m", "studies.cli", "inspect", str(path)],
            capture_output=True,
            text=True,
            cwd=ROOT,
            timeout=120,
        )
        returncode, stderr = proc.returncode, proc.stderr
    else:
        returncode = main(["inspect", str(path)])
        stderr = capfd.readouterr().err
    assert returncode == code, stderr
    if code:
        assert stderr.count("\n") == 1 and needle in stderr
        assert "Traceback" not in stderr
    else:
        assert stderr == ""


def test_scene_error_is_an_input_error():
    # the CLI maps InputError to exit 2; every loader error must be one
    assert issubclass(SceneError, InputError) and issubclass(MeshError, InputError)


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["solve", "cantilever", "--model", "bogus"], "argument --model: invalid choice"),
        ([], "the following arguments are required: COMMAND"),
        (["solve", "cantilever", "--order", "3"], "argument --order: invalid choice"),
        (["inspect"], "the following arguments are required: scene"),
    ],
)
def test_command_line_misuse_exits_2_with_one_line(capsys, argv, needle):
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("springfem: error: ") and needle in err

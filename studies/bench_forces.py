"""``springfem bench forces --models``: every fast model's force or projection pass on the
organ at several sizes, in tets per second, against a memory-bandwidth floor.

The models are the spring model and explicit P1 neo-Hookean (:data:`IN_HOUSE`) and the
plug-ins weighed by default (:func:`studies.models.plugins`), or those named. A model's
pass is its plug-in's ``kernel_pass(scene)`` where it has one (XPBD: one constraint
iteration over every element), else the internal forces of its explicit form
(``system(scene).internal``). Each runs on the organ of :func:`springfem.mesh.organ.organ_scene`
at a deformed state, on one thread (numba's threads set to 1), timed in interleaved rounds
(:func:`studies.timing.interleaved`), the median of the CPU times reported (on a shared,
loaded machine CPU time is what preemption does not inflate).

The **floor** is the rate at which the machine could merely move the bytes a pass must move:
the STREAM-copy bandwidth (``numpy.copyto`` of a 256 MB array, read plus write bytes, timed
as one more case of the same interleaved rounds, so under the same load) over the bytes per
tet: the element arrays the kernel reads (and writes), and once
per node the positions read and the forces written (:func:`bytes_per_tet`). ``of floor`` is
the measured rate over it: 1 would be a kernel that only waits for memory.

A size is skipped when the resident memory it would need exceeds ``max_memory``: the
growth per tet while the size before was built, once that size had :data:`WARM` tets
(smaller ones carry the compiled kernels' memory), else :data:`PRIOR_BYTES` per tet.

Examples
--------
>>> per_tet({"_K": np.zeros((2, 160)), "_T": np.zeros((2, 64), np.int32)}, ("_K", "_T"), 32)
96.0
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from . import models
from .timing import interleaved, load_average, median, stream_bandwidth

#: Sizes (tets) of the organ meshes, and the in-house fast models.
DEFAULT_SIZES = (1_000, 50_000, 500_000)
IN_HOUSE = ("spring", "P1-NH")
#: The arrays each force kernel reads per element, by the class of the explicit form (a
#: kernel with ``bytes_per_element``, the spring kernel's, says it itself): the blocked
#: explicit FEM (constants and node indices), the co-rotational element (indices, shape
#: gradients, volume) and the edge network (edge ends, rest length, stiffness; per tet:
#: edges over tets).
READS: dict[str, tuple[str, ...]] = {
    "ExplicitFem": ("_K", "_T"),
    "Corotational": ("tets", "G", "V"),
    "MassSpring": ("edges", "rest_length", "k"),
}
#: Per node, once: the positions read and the forces written (bytes).
NODE_BYTES = 2 * 3 * 8
#: Memory estimate: measured growth from sizes of at least WARM tets, else PRIOR_BYTES a tet
#: (all models' systems together at 50k tets: about 2 KB a tet).
WARM, PRIOR_BYTES = 20_000, 4_000
#: The copy of the bandwidth case (bytes).
COPY_BYTES = 256 << 20


def copy_case() -> Callable[[], None]:
    """STREAM copy in numpy (:data:`COPY_BYTES` read and as many written per call)."""
    b = np.ones(COPY_BYTES // 8)
    a = np.empty_like(b)
    return lambda: np.copyto(a, b)


def per_tet(obj: Any, names: tuple[str, ...], m: int) -> float:
    """Bytes of the arrays ``names`` of ``obj`` (a mapping or an object) per tet."""
    get = obj.get if isinstance(obj, dict) else (lambda k: getattr(obj, k))
    return float(sum(np.asarray(get(k)).nbytes for k in names)) / m


def bytes_per_tet(system: Any, m: int, n: int) -> float:
    """What a force pass of ``system`` moves per tet (the module docstring); ``nan`` when
    its kernel is not known here."""
    kernel = getattr(system, "kernel", None)
    own = getattr(kernel, "bytes_per_element", None)
    if own is not None:
        return float(own) + NODE_BYTES * n / m
    names = READS.get(type(system).__name__)
    if names is None:
        return float("nan")
    return per_tet(system, names, m) + NODE_BYTES * n / m


def model_pass(name: str, scene: Any) -> tuple[Callable[[], object], float, str]:
    """``(go, bytes per tet, what)`` of model ``name`` on ``scene`` (the module docstring)."""
    from springfem.errors import InputError

    from .timing import deformed_state

    model = models.get(name)
    plugin = getattr(model, "plugin", None) or model
    if hasattr(plugin, "kernel_pass"):
        go, nbytes = plugin.kernel_pass(scene)
        return go, float(nbytes), "one iteration"
    system = model.system(scene)
    if system is None:
        raise InputError(f"model {name}: no explicit form and no kernel pass")
    x = deformed_state(system.x0)
    internal = getattr(system, "internal", None)
    go = (lambda: internal(x)) if internal is not None else (lambda: system.forces(x, None))
    return go, bytes_per_tet(system, scene.mesh.n_tets, scene.mesh.n_points), "force pass"


def timed_rounds(
    cases: dict[str, Callable[[], object]], rounds: int, count: int
) -> tuple[dict[str, dict[str, list[float]]], float]:
    """Every case once a round (:func:`studies.timing.interleaved`, ``count`` calls a
    timing), then one copy of :func:`copy_case`: the samples and the median copy bandwidth
    (bytes read plus written per CPU second)."""
    import time

    copy = copy_case()
    copy()  # warm-up: the pages of the copy
    samples: dict[str, dict[str, list[float]]] = {}
    seconds = []
    for r in range(rounds):
        got = interleaved(cases, rounds=1, count=count, warmup=0 if r else 1, seed=r)
        for name, kinds in got.items():
            for kind, values in kinds.items():
                samples.setdefault(name, {}).setdefault(kind, []).extend(values)
        t0 = time.process_time()
        copy()
        seconds.append(time.process_time() - t0)
    return samples, 2 * COPY_BYTES / float(np.median(seconds))


def bench_forces(
    sizes: tuple[int, ...] = DEFAULT_SIZES,
    names: list[str] | None = None,
    repeats: int = 7,
    max_memory: float = 4.0e9,
    folder: str | os.PathLike | None = None,
    log: Callable[[str], None] = lambda s: None,
) -> dict[str, Any]:
    """Time every model's pass at every size (the module docstring).

    Parameters
    ----------
    sizes
        Organ sizes in tets (about).
    names
        Models (default: :data:`IN_HOUSE` and the default plug-ins that apply).
    repeats
        Interleaved rounds.
    max_memory
        Bytes of resident memory a size may need (estimated from the size before).
    folder
        Where the organ meshes go (default: a temporary folder).
    log
        Progress lines.

    Returns
    -------
    dict
        ``bandwidth`` (copy, read), ``rows`` (one per size and model), ``skipped``,
        ``load_average`` before and after.
    """
    import numba

    from springfem.errors import InputError
    from springfem.mechanics.memory import resident_bytes
    from springfem.mesh.organ import organ_scene
    from springfem.scene import load_scene

    numba.set_num_threads(1)
    out: dict[str, Any] = {"bandwidth_read": stream_bandwidth(), "bandwidth_copy": {}, "rows": [],
                           "skipped": [], "load_average_before": load_average()}  # fmt: skip
    tmp = tempfile.TemporaryDirectory() if folder is None else None
    where = Path(tmp.name if tmp is not None else folder)  # type: ignore[arg-type]
    per_tet_bytes = float(PRIOR_BYTES)
    for size in sorted(sizes):
        if resident_bytes() + per_tet_bytes * size > max_memory:
            need = per_tet_bytes * size / 1e9
            out["skipped"].append(f"{size} tets: about {need:.1f} GB (limit {max_memory / 1e9:g})")
            log(f"skip {size} tets: about {need:.1f} GB")
            continue
        base = resident_bytes()
        scene = load_scene(organ_scene(where, tets=size))
        m, n = scene.mesh.n_tets, scene.mesh.n_points
        chosen = names or [*IN_HOUSE, *(p for p in models.plugins(scene) if p not in IN_HOUSE)]
        cases, info = {}, {}
        for name in chosen:
            try:
                go, nbytes, what = model_pass(name, scene)
            except InputError as exc:  # neither a kernel pass nor an explicit form
                out["skipped"].append(f"{name} at {m} tets: {exc}")
                continue
            cases[name], info[name] = go, (nbytes, what)
        if m >= WARM:
            per_tet_bytes = max(resident_bytes() - base, 1) / m
        count = max(1, 2_000_000 // m)
        log(f"{m} tets: {', '.join(cases)} ({repeats} rounds of {count} passes)")
        samples, copy = timed_rounds(cases, repeats, count)
        out["bandwidth_copy"][m] = copy
        for name in cases:
            t = median(samples, name, "cpu")
            nbytes, what = info[name]
            rate, floor = m / t, copy / nbytes
            out["rows"].append({"tets": m, "nodes": n, "model": name, "pass": what,
                                "seconds": t, "tets_per_s": rate, "bytes_per_tet": nbytes,
                                "floor_tets_per_s": floor, "of_floor": rate / floor})  # fmt: skip
        del cases, info, scene
    out["load_average_after"] = load_average()
    if tmp is not None:
        tmp.cleanup()
    return out


def markdown(res: dict[str, Any]) -> str:
    """The result as a Markdown table with its bandwidth and load lines."""
    copies = ", ".join(f"{v / 1e9:.1f} GB/s ({m:,} tets)" for m, v in res["bandwidth_copy"].items())
    lines = [
        f"Copy bandwidth {copies}, timed in the rounds; read {res['bandwidth_read'] / 1e9:.1f}"
        f" GB/s; one thread, CPU time; load average {res['load_average_before']} before, "
        f"{res['load_average_after']} after.",
        "",
        "| tets | model | pass | µs / pass | M tets/s | bytes / tet | floor M tets/s | of floor |",
        "| ---: | --- | --- | ---: | ---: | ---: | ---: | ---: |",
    ]
    for r in res["rows"]:
        lines.append(
            f"| {r['tets']:,} | {r['model']} | {r['pass']} | {r['seconds'] * 1e6:,.0f} | "
            f"{r['tets_per_s'] / 1e6:.2f} | {r['bytes_per_tet']:.0f} | "
            f"{r['floor_tets_per_s'] / 1e6:.0f} | {r['of_floor']:.1%} |"
        )
    lines += [f"Skipped: {s}" for s in res["skipped"]]
    return "\n".join(lines)


def csv(res: dict[str, Any]) -> str:
    """The rows as CSV."""
    keys = list(res["rows"][0]) if res["rows"] else []
    return "\n".join([",".join(keys)] + [",".join(str(r[k]) for k in keys) for r in res["rows"]])


__all__ = ["DEFAULT_SIZES", "IN_HOUSE", "bench_forces", "bytes_per_tet", "csv", "markdown"]

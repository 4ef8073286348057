"""Vertex Block Descent and Projective Dynamics on the jittered large-rotation cantilever: how
VBD converges in iterations and substeps (a chart), and each peer's error and cost per
substep at about 1k and 10k tets.

    .venv/bin/python examples/vbd_pd_numbers.py [chart|cost] [--tets 1000 10000]

``chart`` writes ``reports/peers/vbd_convergence.png``: (left) VBD's rest state against the
Newton answer of the same stable neo-Hookean energy, and the frames it takes to come to rest,
for substeps 10-80 and iterations 1-8 (rest_tol 1e-7); (right) the tip after 0.25 s of
undamped motion from rest under the load against a reference run of 320 substeps x 16
iterations (the dynamics VBD converges to as both grow). ``cost`` prints, per mesh, the
rest-state error of VBD (vs its Newton answer), PD (vs P1-NH, a different energy, and its
equilibrium residual) and PD-NH (vs P1-NH, the same energy) at their default settings, and
the median wall time of one substep of each (2 iterations) against one explicit P1
neo-Hookean force pass and one XPBD substep, interleaved rounds in one process
(:func:`studies.timing.interleaved`). A shared machine: ratios from one run.
"""

from __future__ import annotations

import argparse
import time
import tomllib
from importlib import resources
from pathlib import Path

import numpy as np

from peers.pd import PD, PDSettings
from peers.vbd import VBD, VBDSettings
from peers.xpbd import XPBD, StableNeoHookean, XPBDSettings
from springfem.mechanics import static
from springfem.scene import scene_from_dict

OUT = Path(__file__).resolve().parents[1] / "reports" / "peers"


def cantilever(divisions=(20, 2, 2)):
    """The bundled large-rotation cantilever on a jittered Delaunay mesh of ``divisions``."""
    text = resources.files("studies.scenes").joinpath("cantilever-large-rotation.toml")
    table = tomllib.loads(text.read_text())
    table["mesh"] = {**table["mesh"], "split": "delaunay", "divisions": list(divisions)}
    return scene_from_dict(table)


def error(u, ref):
    """Largest nodal distance over the largest reference displacement."""
    return float(np.abs(u - ref).max() / np.abs(ref).max())


def chart() -> Path:
    import matplotlib.pyplot as plt

    scene = cantilever()
    energy = StableNeoHookean(scene)
    newton = static(energy, tol=1e-11).x - energy.x0
    substeps, iterations = (10, 20, 40, 80), (1, 2, 4, 8)
    rest = {}
    for k in iterations:
        for n in substeps:
            t0 = time.perf_counter()
            out = VBD(scene, VBDSettings(substeps=n, iterations=k, rest_tol=1e-7)).solve()
            rest[n, k] = (error(out.u, newton), out.frames, out.converged)
            print(f"rest {n:3d} x {k}: error {rest[n, k][0]:.2e}, {out.frames} frames, "
                  f"{'at rest' if out.converged else 'NOT at rest'}, "
                  f"{time.perf_counter() - t0:.1f} s")  # fmt: skip
    frames = 15

    def tip(n, k):
        x, _ = VBD(scene, VBDSettings(substeps=n, iterations=k, damping=0.0)).run(frames)
        return (x - energy.x0)[:, 2].min()

    ref = tip(320, 16)
    dyn = {(n, k): abs(tip(n, k) - ref) / abs(ref) for k in iterations for n in substeps}
    fig, ax = plt.subplots(1, 3, figsize=(13, 4))
    for k in iterations:
        line = ax[0].loglog(substeps, [rest[n, k][0] for n in substeps], "o-", label=f"{k} it.")
        ax[1].semilogx(substeps, [rest[n, k][1] for n in substeps], "o-", label=f"{k} it.")
        ax[2].loglog(substeps, [dyn[n, k] for n in substeps], "o-", label=f"{k} iterations")
        moving = [n for n in substeps if not rest[n, k][2]]
        for a, i in ((ax[0], 0), (ax[1], 1)):  # no rest within max_frames: a cross
            a.plot(moving, [rest[n, k][i] for n in moving], "x", ms=12, color=line[0].get_color())
    ax[0].set(xlabel="substeps per 1/60 s frame", ylabel="rest state vs Newton (max, relative)",
              title="VBD rest state (x: no rest in 2,000 frames)")  # fmt: skip
    ax[1].set(xlabel="substeps per frame", ylabel="frames to rest", title="cost to rest")
    ax[2].set(xlabel="substeps per frame", ylabel="tip error at 0.25 s vs 320 x 16",
              title="undamped dynamics")  # fmt: skip
    for a in ax:
        a.set_xticks(substeps, [str(n) for n in substeps])
        a.minorticks_off() if a is not ax[1] else None
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=8)
    fig.suptitle(f"VBD, stable neo-Hookean, jittered large-rotation cantilever "
                 f"({scene.mesh.n_tets} tets)")  # fmt: skip
    fig.tight_layout()
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / "vbd_convergence.png"
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")
    return path


def cost(tets: int, rest=("vbd", "pd", "pd-nh")) -> None:
    from reference_fem.explicit import ExplicitFem
    from studies import models
    from studies.timing import interleaved, median

    k = max(2, round((tets / 136) ** (1 / 3)))  # 20k x k x k cells, about 6.8 tets each
    scene = cantilever((20 * k, k, k))
    print(f"\n{scene.mesh.n_tets} tets, {scene.mesh.n_points} nodes")
    newton = p1nh = np.zeros_like(scene.mesh.points)
    if rest:
        energy = StableNeoHookean(scene)
        t0 = time.perf_counter()
        newton = static(energy, tol=1e-10).x - energy.x0
        print(f"  stable-NH Newton {time.perf_counter() - t0:.1f} s")
        t0 = time.perf_counter()
        p1nh = models.run(scene, "P1-NH").u
        print(f"  P1-NH {time.perf_counter() - t0:.1f} s")
    for name, make, ref in (
        ("vbd", lambda: VBD(scene), newton),
        ("pd", lambda: PD(scene), p1nh),
        ("pd-nh", lambda: PD(scene, PDSettings(energy="neo-hookean")), p1nh),
    ):
        if name not in rest:
            continue
        t0 = time.perf_counter()
        out = make().solve()
        print(f"  {name:6s} rest: error {error(out.u, ref):.2e} "
              f"(vs {'its Newton' if name == 'vbd' else 'P1-NH'}), residual {out.residual:.1e}, "
              f"{out.frames} frames, {time.perf_counter() - t0:.1f} s")  # fmt: skip
    # one substep (2 iterations) of each from a deformed state, one explicit force pass
    one = {"vbd": VBD(scene, VBDSettings(substeps=1, dt=1 / 2400, damping=0.0)),
           "pd": PD(scene, PDSettings(substeps=1, dt=1 / 2400, damping=0.0)),
           "pd-nh": PD(scene, PDSettings(energy="neo-hookean", substeps=1, dt=1 / 2400,
                                         damping=0.0))}  # fmt: skip
    states = {}
    for name, s in one.items():
        x, v, vo = s.start()
        a = s.accelerations(x)
        for _ in range(20):
            s.advance(x, v, vo, a)
        states[name] = (x, v, vo, a)
    xp = XPBD(scene, XPBDSettings(substeps=1, dt=1 / 2400, damping=0.0))
    xx, xv = xp.start()
    xa = xp.accelerations(xx)
    fem = ExplicitFem(scene, law="neo-hookean")
    xf = states["vbd"][0].copy()

    def step(name):
        s = one[name]
        x, v, vo, a = states[name]
        return lambda: s.advance(x.copy(), v.copy(), vo.copy(), a)

    cases = {name: step(name) for name in one}
    cases["xpbd"] = lambda: xp.advance(xx.copy(), xv.copy(), xa)
    cases["explicit P1-NH force"] = lambda: fem.forces(xf, None)
    samples = interleaved(cases, rounds=9, warmup=2)
    base = median(samples, "explicit P1-NH force")
    for name in cases:
        t = median(samples, name)
        print(f"  {name:22s} {t * 1e3:8.3f} ms per substep  ({t / base:6.1f} x explicit force)")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("what", choices=("chart", "cost"))
    parser.add_argument("--tets", type=int, nargs="*", default=[1000, 10000])
    parser.add_argument(
        "--rest",
        nargs="*",
        default=["vbd", "pd", "pd-nh"],
        help="the peers whose run to rest is measured (none: costs only)",
    )
    args = parser.parse_args()
    if args.what == "chart":
        chart()
    else:
        for n in args.tets:
            cost(n, tuple(args.rest))


if __name__ == "__main__":
    main()

"""Error and cost metrics shared by the comparison and the studies.

All displacement errors are measured at the mesh vertices (both models have them), so a
spring solution, a P1 and a P2 solution on the same mesh compare node by node.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from springfem.mesh import displacement_gradients
from springfem.scene import Scene


def relative_l2_error(u: np.ndarray, u_ref: np.ndarray) -> float:
    """``||u - u_ref|| / ||u_ref||`` over all vertex displacement components."""
    u, u_ref = np.asarray(u, float).ravel(), np.asarray(u_ref, float).ravel()
    den = np.linalg.norm(u_ref)
    return float(np.linalg.norm(u - u_ref) / den) if den > 0 else float("nan")


def relative_max_error(u: np.ndarray, u_ref: np.ndarray) -> float:
    """Largest nodal error magnitude over the largest reference displacement magnitude."""
    u, u_ref = np.asarray(u, float).reshape(-1, 3), np.asarray(u_ref, float).reshape(-1, 3)
    den = np.linalg.norm(u_ref, axis=1).max()
    err = np.linalg.norm(u - u_ref, axis=1).max()
    return float(err / den) if den > 0 else float("nan")


def max_principal_strain(scene: Scene, u: np.ndarray) -> float:
    """The largest absolute principal Green–Lagrange strain over the P1 elements for the
    vertex field ``u``.

    The Green–Lagrange strain ``E = (H + Hᵀ + HᵀH) / 2`` of a small-strain solution also
    flags large rotations (a rotation by θ gives ``E ≈ θ²/2``), which a linear solution
    cannot represent either.
    """
    H = displacement_gradients(scene.mesh.points, scene.mesh.tets, u)
    E = 0.5 * (H + np.swapaxes(H, 1, 2) + np.swapaxes(H, 1, 2) @ H)
    return float(np.abs(np.linalg.eigvalsh(E)).max())


def nodal_error(u: np.ndarray, u_ref: np.ndarray) -> np.ndarray:
    """Error magnitude per vertex ``(n,)``."""
    return np.linalg.norm(np.asarray(u).reshape(-1, 3) - np.asarray(u_ref).reshape(-1, 3), axis=1)


def probe_error(probes: dict[str, list[float]], ref: dict[str, list[float]]) -> dict[str, float]:
    """Relative error of each probe's displacement vector against the reference."""
    out = {}
    for name, u in probes.items():
        r = np.asarray(ref[name])
        n = np.linalg.norm(r)
        out[name] = float(np.linalg.norm(np.asarray(u) - r) / n) if n > 0 else float("nan")
    return out


def median_time(fn: Callable[[], object], repeats: int = 5, warmup: int = 1) -> float:
    """Median wall time of ``fn()`` over ``repeats`` runs after ``warmup`` runs."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def fitted_rate(h: np.ndarray, err: np.ndarray) -> float:
    """Slope of ``log err`` against ``log h`` (``np.polyfit``), the convergence rate."""
    h, err = np.asarray(h, float), np.asarray(err, float)
    ok = (h > 0) & (err > 0) & np.isfinite(err)
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(h[ok]), np.log(err[ok]), 1)[0])


def observed_order(h: ArrayLike, f: ArrayLike) -> tuple[float, float, str]:
    """Observed order ``p`` and Richardson value ``f0`` of ``f = f0 + C h^p`` through three
    (h, f) pairs (any order), and a note: NaN and the reason when there are not three
    finite values on distinct meshes, when the differences change sign (oscillating), or
    when no order in (0.05, 12) fits (else ``""``).

    Examples
    --------
    >>> h = np.array([4.0, 2.0, 1.0])
    >>> p, f0, note = observed_order(h, 1.0 + 0.5 * h**2)
    >>> round(p, 9), round(f0, 9), note
    (2.0, 1.0, '')
    """
    from scipy.optimize import brentq

    nan = float("nan")
    h, f = np.asarray(h, float), np.asarray(f, float)
    if len(h) != 3 or len(f) != 3:
        return nan, nan, "needs three finite values on distinct meshes"
    order = np.argsort(-h)
    (h1, h2, h3), (f1, f2, f3) = h[order], f[order]
    if not (np.isfinite([f1, f2, f3]).all() and h1 > h2 > h3 > 0):
        return nan, nan, "needs three finite values on distinct meshes"
    if f2 == f3 or (f1 - f2) / (f2 - f3) <= 0:
        return nan, nan, "oscillating"
    r = (f1 - f2) / (f2 - f3)

    def g(p):
        return (h1**p - h2**p) / (h2**p - h3**p) - r

    lo, hi = 0.05, 12.0
    if g(lo) * g(hi) > 0:
        return nan, nan, f"no order in ({lo}, {hi:g}) fits"
    p = brentq(g, lo, hi, xtol=1e-12)
    return float(p), float(f3 - (f2 - f3) / (h2**p - h3**p) * h3**p), ""


def timoshenko_tip_deflection(
    force: float, length: float, width: float, height: float, E: float, nu: float
) -> float:
    """Tip deflection of a cantilever with a rectangular section under an end shear force.

    Euler–Bernoulli bending ``F L^3 / (3 E I)`` plus Timoshenko shear ``F L / (k G A)``
    with the rectangular-section shear coefficient ``k = 10 (1 + nu) / (12 + 11 nu)``.
    """
    inertia = width * height**3 / 12.0
    area = width * height
    G = E / (2.0 * (1.0 + nu))
    k = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)
    return force * length**3 / (3.0 * E * inertia) + force * length / (k * G * area)

"""Spring-force kernels specialised at compile time per variant, on a blocked layout.

:func:`spring_kernel` builds (and caches) one numba kernel per *variant*: the switched-on
parts and laws (:class:`Variant`). The laws are chosen in Python when the kernel is built,
so the compiled loop holds only the arithmetic of that variant: no law codes, no branches.

Layout (:mod:`springfem.blocks`): elements in blocks of :data:`BLOCK`, connectivity int32
and constants lane-major. A block's edge vectors are gathered into a scratch, its lanes
computed in one branch-free loop (LLVM vectorises it: ``error_model='numpy'``, contraction
to FMA allowed; no law codes: the variant's choices are compile-time constants), and its
vertex forces scattered. Each variant's block loop captures only numbers, so numba caches
it on disk (``cache=True``). Compact constants, from the fast-kernel identity
(docs/theory.rst#the-fast-kernel-identity)
``G[i,l] = grad N_i . zeta_l^0``:

* ``G' = G / l0`` (rows of vertices 1..3: ``sum_i G[i] = 0`` gives vertex 0), so
  ``zeta_l / l0_l = sum_{i>0} G'[i,l] (x_i - x_0)`` is the axis stretch vector;
* the axial constant ``k l0^2`` (the force ``f_i = G'[i,l] (l0 s_l) zeta_hat_l``);
* torsion: ``energy`` needs ``k`` only (``l0`` cancels), the force laws ``k_f l0_l`` and
  ``k_f l0_m``; the rest cosines ``c0`` only when they are not zero to round-off (they are
  zero for orthonormal frames, docs/theory.rst#axis-vectors-are-parallel-to-the-frame), the rest
  angles for ``angle``;
* barycentric volume: ``k_s`` and ``sum_j |xi_j^0|``;
* axis volume (``J = det[zeta] / det[zeta^0] = c_J det[zeta / l0]``, ``c_J = l0_0 l0_1 l0_2 /
  det0``): ``c_J``, ``V0 kappa c_J`` (and ``eta V0 c_J`` with damping), its force on axis
  ``l`` being ``-V0 U'(J) c_J (z_m x z_n)`` for the cyclic ``(l, m, n)``, times ``l0_l``;
* Poisson coupling: ``c_lm`` (``l0`` cancels: ``l0_l g_l = -c_lm s_m zeta_hat_l``).

The specification's variant (linear axial, cosine torsion, gradient volume) reads 20 constants per
element (160 B in f64) and 16 B of connectivity, against 256 B before.

Precision (``precision``): ``float64``; ``mixed`` (constants stored in float32, arithmetic
in float64); ``float32`` (constants, gathered positions and arithmetic in float32; forces
accumulated in float64).

Examples
--------
>>> v = Variant(axial="linear", torsion="cosine", volume="gradient")
>>> v.columns()[:3]
('g10', 'g11', 'g12')
>>> len(v.columns())
20
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import numpy as np
from numba import njit

from springfem.blocks import BLOCK, block_drivers, compile_named, variant_id

from .options import ENERGY_TORSION
from .springs.shear import SHEAR_FLOOR

PRECISIONS = ("float64", "mixed", "float32")
_PAIRS = ((0, 1), (0, 2), (1, 2))
_FLAGS = {"error_model": "numpy", "fastmath": {"contract"}}


@dataclass(frozen=True)
class Variant:
    """The compile-time choices of one spring kernel.

    Parameters
    ----------
    axial
        ``linear``, ``quadratic``, ``cubic`` or ``stress-scaled``.
    torsion
        ``off``, ``angle``, ``cosine``, ``cubic``, ``energy`` or ``shear``.
    volume
        ``off``, ``gradient``, ``spec`` (barycentric) or ``axes`` (axis volume).
    volumetric
        ``U(J)`` of the axis volume: ``quadratic``, ``log`` or ``simo-taylor``.
    coupling
        Poisson-coupling springs on.
    damp_axial, damp_volume
        Axial and volume damping coefficients (0 for off).
    b2, b3, bt
        Polynomial axial and cubic torsion coefficients.
    c0
        Whether rest cosines are read (``False``: they are zero to round-off).
    precision
        ``float64``, ``mixed`` or ``float32``.
    """

    axial: str = "linear"
    torsion: str = "cosine"
    volume: str = "gradient"
    volumetric: str = "quadratic"
    coupling: bool = False
    damp_axial: float = 0.0
    damp_volume: float = 0.0
    b2: float = 0.0
    b3: float = 0.0
    bt: float = 0.0
    c0: bool = False
    precision: str = "float64"

    def columns(self) -> tuple[str, ...]:
        """Names of the per-element constants this variant reads, in storage order."""
        cols = [f"g{i}{l}" for i in (1, 2, 3) for l in range(3)]
        cols += [f"ka{l}" for l in range(3)]
        if self.axial == "stress-scaled":
            cols.append("inv6v0")
        if self.damp_axial:
            cols += [f"ca{l}" for l in range(3)]
        if self.torsion in ENERGY_TORSION:
            cols += [f"kt{p}" for p in range(3)]
        elif self.torsion != "off":
            cols += [f"kf{p}{s}" for p in range(3) for s in "lm"]
        if self.torsion == "angle":
            cols += [f"a0{p}" for p in range(3)]
        elif self.torsion != "off" and self.c0:
            cols += [f"c0{p}" for p in range(3)]
        if self.volume in ("gradient", "spec"):
            cols += ["ks", "lsum"]
        elif self.volume == "axes":
            cols += ["kj", "cj"] + (["ej"] if self.damp_volume else [])
        if self.coupling:
            cols += [f"cp{p}" for p in range(3)]
        return tuple(cols)

    @property
    def uses_velocity(self) -> bool:
        return bool(self.damp_axial) or (self.volume != "off" and bool(self.damp_volume))


# --------------------------------------------------------------------------- the factory


_AXIAL = {"linear": 0, "quadratic": 1, "cubic": 1, "stress-scaled": 2}
_TORSION = {"off": 0, "angle": 1, "cosine": 2, "cubic": 3, "energy": 4, "shear": 5}
_VOLUMETRIC = {"quadratic": 0, "log": 1, "simo-taylor": 2}


@njit(cache=True, **_FLAGS)
def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(cache=True, **_FLAGS)
def _dU(law, J, one):
    """``U'(J) / kappa`` of the volumetric energies (quadratic, log, Simo-Taylor)."""
    if law == 0:
        return J - one
    if law == 1:
        return math.log(J) / J
    return (J - one / J) / (one + one)


@njit(cache=True, **_FLAGS)
def _comb(g1, g2, g3, a, b, c):
    return (
        g1 * a[0] + g2 * b[0] + g3 * c[0],
        g1 * a[1] + g2 * b[1] + g3 * c[1],
        g1 * a[2] + g2 * b[2] + g3 * c[2],
    )


@njit(cache=True, **_FLAGS)
def _unit(z):
    n = math.sqrt(z[0] * z[0] + z[1] * z[1] + z[2] * z[2])
    return n, (z[0] / n, z[1] / n, z[2] / n)


@njit(cache=True, **_FLAGS)
def _axpy(s, a, b):
    return (s * a[0] + b[0], s * a[1] + b[1], s * a[2] + b[2])


@njit(cache=True, **_FLAGS)
def _add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@njit(cache=True, **_FLAGS)
def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(cache=True, **_FLAGS)
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True, **_FLAGS)
def _axial(law, lam, k, jac, b2, b3, one):
    """``l0 s``: the axial force magnitude times the rest length."""
    e = lam - one
    if law == 0:
        return -k * e  # eq. 2.35
    if law == 2:
        return -k * e / lam * jac  # E (d/l0) (V/|zeta|)
    return -k * (e + b2 * e * e + b3 * e * e * e)  # eq. 2.36


@njit(cache=True, **_FLAGS)
def _shear_slope(c, c0, one):
    """``dU/dc / k`` of the shear torsion energy (:mod:`springmodel.springs.shear`)."""
    g = max(one - c * c, SHEAR_FLOOR)
    g0 = one - c0 * c0
    s03 = g0 * math.sqrt(g0)
    delta = s03 * (c / math.sqrt(g) - c0 / math.sqrt(g0))
    return delta * s03 / (g * math.sqrt(g))


@njit(cache=True, **_FLAGS)
def _pair(law, ul, um, lam_l, lam_m, k_l, k_m, t0, bt, one):
    """Forces on the + ends of axes ``l`` and ``m`` of one torsion spring, times ``l0``."""
    c = ul[0] * um[0] + ul[1] * um[1] + ul[2] * um[2]  # eq. 2.32
    if law >= 4:  # energy (4) or shear (5): k_l = k_m = k, dc = dU/dc / k
        if law == 4:
            dc = c - t0
        else:
            dc = _shear_slope(c, t0, one)
        sl, sm = -k_l * dc / lam_l, -k_l * dc / lam_m
        return (
            (sl * (um[0] - c * ul[0]), sl * (um[1] - c * ul[1]), sl * (um[2] - c * ul[2])),
            (sm * (ul[0] - c * um[0]), sm * (ul[1] - c * um[1]), sm * (ul[2] - c * um[2])),
        )
    if law == 2:
        s = -(c - t0)  # eqs. 2.44-2.45
    elif law == 3:
        dc = c - t0
        s = -(dc + bt * dc * dc * dc)  # eqs. 2.47-2.50
    else:
        s = math.acos(min(max(c, -one), one)) - t0  # eqs. 2.40-2.41, restoring
    sl, sm = s * k_l, s * k_m
    return (sl * um[0], sl * um[1], sl * um[2]), (sm * ul[0], sm * ul[1], sm * ul[2])


def _block_run(v: Variant):
    """The variant's block loop ``run(lo, hi, x, w, T, K, m, p, q, out)``: gather, compute,
    scatter (``p``, ``q`` unused; returns 0).

    It captures only numbers (the law codes, coefficients and column offsets), which numba
    compiles as constants (so the law branches fold away) and which keep it disk-cacheable.
    """
    at = np.float32 if v.precision == "float32" else np.float64
    one, zero, quarter = at(1.0), at(0.0), at(0.25)
    b2, b3, bt = at(v.b2), at(v.b3), at(v.bt)
    B = BLOCK
    cols = {c: i for i, c in enumerate(v.columns())}
    KA, CA = cols["ka0"], cols.get("ca0", 0)
    KT = cols.get("kt0", cols.get("kf0l", 0))
    T0 = cols.get("a00", cols.get("c00", 0))
    KS, INV6 = cols.get("ks", 0), cols.get("inv6v0", 0)
    KJ, CP, EJ = cols.get("kj", 0), cols.get("cp0", 0), cols.get("ej", 0)
    axes = v.volume == "axes"
    VL = _VOLUMETRIC[v.volumetric]
    coupling = v.coupling
    has_c0 = "c00" in cols or "a00" in cols
    AX, TO = _AXIAL[v.axial], _TORSION[v.torsion]
    energy = v.torsion in ENERGY_TORSION
    spec = v.volume == "spec"
    stress = v.axial == "stress-scaled"
    vol_on = v.volume in ("gradient", "spec")
    tors_on = v.torsion != "off"
    v_axial = bool(v.damp_axial)
    v_volume = vol_on and bool(v.damp_volume)
    v_axes = axes and bool(v.damp_volume)
    uses_w = v_axial or v_volume or v_axes
    damp_v = at(v.damp_volume)

    def run(lo, hi, x, w, T, K, m, p, q, out):  # p, q: unused scalars of the drivers
        X = np.empty(9 * B, at)
        W = np.empty(9 * B, at) if uses_w else X
        F = np.empty(12 * B, at)
        for blk in range(lo, hi):
            Tb = T[blk]
            Kb = K[blk]
            for j in range(B):  # edge vectors x_k - x_0, differences taken in float64
                i0 = Tb[j]
                for k in range(3):
                    i = Tb[(k + 1) * B + j]
                    for d in range(3):
                        X[(3 * k + d) * B + j] = at(x[i, d] - x[i0, d])
                        if uses_w:
                            W[(3 * k + d) * B + j] = at(w[i, d] - w[i0, d])
            for j in range(B):  # the lanes: no gathers, no branches (vectorised)
                a = (X[j], X[B + j], X[2 * B + j])
                b = (X[3 * B + j], X[4 * B + j], X[5 * B + j])
                c = (X[6 * B + j], X[7 * B + j], X[8 * B + j])
                g10, g11, g12 = at(Kb[j]), at(Kb[B + j]), at(Kb[2 * B + j])
                g20, g21, g22 = at(Kb[3 * B + j]), at(Kb[4 * B + j]), at(Kb[5 * B + j])
                g30, g31, g32 = at(Kb[6 * B + j]), at(Kb[7 * B + j]), at(Kb[8 * B + j])
                # stretch vectors zeta_l / l0_l: their lengths (stretches) and directions
                lam0, u0 = _unit(_comb(g10, g20, g30, a, b, c))
                lam1, u1 = _unit(_comb(g11, g21, g31, a, b, c))
                lam2, u2 = _unit(_comb(g12, g22, g32, a, b, c))
                jac = one
                if stress:
                    jac = at(Kb[INV6 * B + j]) * (
                        a[0] * (b[1] * c[2] - b[2] * c[1])
                        - a[1] * (b[0] * c[2] - b[2] * c[0])
                        + a[2] * (b[0] * c[1] - b[1] * c[0])
                    )
                s0 = _axial(AX, lam0, at(Kb[KA * B + j]), jac, b2, b3, one)
                s1 = _axial(AX, lam1, at(Kb[(KA + 1) * B + j]), jac, b2, b3, one)
                s2 = _axial(AX, lam2, at(Kb[(KA + 2) * B + j]), jac, b2, b3, one)
                if coupling:  # c_lm s_l s_m, s_l = lam_l - 1
                    c01, c02 = at(Kb[CP * B + j]), at(Kb[(CP + 1) * B + j])
                    c12 = at(Kb[(CP + 2) * B + j])
                    e0, e1, e2 = lam0 - one, lam1 - one, lam2 - one
                    s0 -= c01 * e1 + c02 * e2
                    s1 -= c01 * e0 + c12 * e2
                    s2 -= c02 * e0 + c12 * e1
                if v_axial:
                    wa = (W[j], W[B + j], W[2 * B + j])
                    wb = (W[3 * B + j], W[4 * B + j], W[5 * B + j])
                    wc = (W[6 * B + j], W[7 * B + j], W[8 * B + j])
                    s0 -= at(Kb[CA * B + j]) * _dot(_comb(g10, g20, g30, wa, wb, wc), u0)
                    s1 -= at(Kb[(CA + 1) * B + j]) * _dot(_comb(g11, g21, g31, wa, wb, wc), u1)
                    s2 -= at(Kb[(CA + 2) * B + j]) * _dot(_comb(g12, g22, g32, wa, wb, wc), u2)
                q0 = (s0 * u0[0], s0 * u0[1], s0 * u0[2])
                q1 = (s1 * u1[0], s1 * u1[1], s1 * u1[2])
                q2 = (s2 * u2[0], s2 * u2[1], s2 * u2[2])
                if tors_on:
                    for p in range(3):
                        kl = at(Kb[(KT + (p if energy else 2 * p)) * B + j])
                        km = kl if energy else at(Kb[(KT + 2 * p + 1) * B + j])
                        t0 = at(Kb[(T0 + p) * B + j]) if has_c0 else zero
                        if p == 0:
                            fl, fm = _pair(TO, u0, u1, lam0, lam1, kl, km, t0, bt, one)
                            q0, q1 = _add(q0, fl), _add(q1, fm)
                        elif p == 1:
                            fl, fm = _pair(TO, u0, u2, lam0, lam2, kl, km, t0, bt, one)
                            q0, q2 = _add(q0, fl), _add(q2, fm)
                        else:
                            fl, fm = _pair(TO, u1, u2, lam1, lam2, kl, km, t0, bt, one)
                            q1, q2 = _add(q1, fl), _add(q2, fm)
                if axes:  # V0 U(J), J = c_J det[z], z_l = lam_l u_l
                    z0 = (lam0 * u0[0], lam0 * u0[1], lam0 * u0[2])
                    z1 = (lam1 * u1[0], lam1 * u1[1], lam1 * u1[2])
                    z2 = (lam2 * u2[0], lam2 * u2[1], lam2 * u2[2])
                    x12, x20, x01 = _cross(z1, z2), _cross(z2, z0), _cross(z0, z1)
                    J = at(Kb[(KJ + 1) * B + j]) * _dot(z0, x12)
                    sv = -at(Kb[KJ * B + j]) * _dU(VL, J, one)
                    if v_axes:  # volume viscosity on dJ/dt = c_J sum_l (z_m x z_n) . dz_l/dt
                        wa = (W[j], W[B + j], W[2 * B + j])
                        wb = (W[3 * B + j], W[4 * B + j], W[5 * B + j])
                        wc = (W[6 * B + j], W[7 * B + j], W[8 * B + j])
                        dz0 = _comb(g10, g20, g30, wa, wb, wc)
                        dz1 = _comb(g11, g21, g31, wa, wb, wc)
                        dz2 = _comb(g12, g22, g32, wa, wb, wc)
                        rate = _dot(x12, dz0) + _dot(x20, dz1) + _dot(x01, dz2)
                        sv -= at(Kb[EJ * B + j]) * rate
                    q0, q1, q2 = _axpy(sv, x12, q0), _axpy(sv, x20, q1), _axpy(sv, x01, q2)
                # f_i = sum_l G'[i,l] q_l,  f_0 = -(f_1 + f_2 + f_3)
                f1 = _comb(g10, g11, g12, q0, q1, q2)
                f2 = _comb(g20, g21, g22, q0, q1, q2)
                f3 = _comb(g30, g31, g32, q0, q1, q2)
                f0 = (-(f1[0] + f2[0] + f3[0]), -(f1[1] + f2[1] + f3[1]), -(f1[2] + f2[2] + f3[2]))
                if vol_on:  # xi_j = x_j - x_b (eqs. 2.76-2.77)
                    xb = (
                        quarter * (a[0] + b[0] + c[0]),
                        quarter * (a[1] + b[1] + c[1]),
                        quarter * (a[2] + b[2] + c[2]),
                    )
                    r0, h0 = _unit((-xb[0], -xb[1], -xb[2]))
                    r1, h1 = _unit(_sub(a, xb))
                    r2, h2 = _unit(_sub(b, xb))
                    r3, h3 = _unit(_sub(c, xb))
                    coef = -at(Kb[KS * B + j]) * (r0 + r1 + r2 + r3 - at(Kb[(KS + 1) * B + j]))
                    if not spec:
                        hm = (
                            quarter * (h0[0] + h1[0] + h2[0] + h3[0]),
                            quarter * (h0[1] + h1[1] + h2[1] + h3[1]),
                            quarter * (h0[2] + h1[2] + h2[2] + h3[2]),
                        )
                        h0, h1, h2, h3 = _sub(h0, hm), _sub(h1, hm), _sub(h2, hm), _sub(h3, hm)
                    f0, f1 = _axpy(coef, h0, f0), _axpy(coef, h1, f1)
                    f2, f3 = _axpy(coef, h2, f2), _axpy(coef, h3, f3)
                    if v_volume:  # v_0 = 0 in the differences
                        v1 = (W[j], W[B + j], W[2 * B + j])
                        v2 = (W[3 * B + j], W[4 * B + j], W[5 * B + j])
                        v3 = (W[6 * B + j], W[7 * B + j], W[8 * B + j])
                        vm = (
                            quarter * (v1[0] + v2[0] + v3[0]),
                            quarter * (v1[1] + v2[1] + v3[1]),
                            quarter * (v1[2] + v2[2] + v3[2]),
                        )
                        f0 = _axpy(damp_v, vm, f0)
                        f1, f2 = _axpy(-damp_v, _sub(v1, vm), f1), _axpy(-damp_v, _sub(v2, vm), f2)
                        f3 = _axpy(-damp_v, _sub(v3, vm), f3)
                for d in range(3):
                    F[d * B + j] = f0[d]
                    F[(3 + d) * B + j] = f1[d]
                    F[(6 + d) * B + j] = f2[d]
                    F[(9 + d) * B + j] = f3[d]
            nv = min(B, m - blk * B)
            for j in range(nv):  # scatter (two lanes may share a node: scalar)
                for k in range(4):
                    i = Tb[k * B + j]
                    out[i, 0] += F[(3 * k) * B + j]
                    out[i, 1] += F[(3 * k + 1) * B + j]
                    out[i, 2] += F[(3 * k + 2) * B + j]

        return 0

    return compile_named(run, f"spring_run_{variant_id(v)}")


@cache
def spring_kernel(variant: Variant):
    """``(serial, parallel)`` force drivers of ``variant`` (compiled on first call).

    ``serial(x, w, T, K, m, p, q, out)``, ``parallel(x, w, T, K, m, p, q, ptr, buf, out)``;
    see :func:`springfem.blocks.block_drivers`.

    Parameters
    ----------
    variant
        The switched-on parts, laws and precision (:class:`Variant`).

    Returns
    -------
    serial, parallel
        The two drivers.
    """
    return block_drivers(_block_run(variant))


__all__ = ["BLOCK", "PRECISIONS", "Variant", "spring_kernel"]

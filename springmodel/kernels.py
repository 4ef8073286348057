"""Fused spring-force kernel (numba): every enabled spring part in one pass over the elements.

The kernel never forms the six intersection points. The two points of axis ``l`` carry
opposite forces ``+-g_l`` (eqs. 2.34, 2.42–2.43), so only the difference of their columns
of ``C^k`` matters (DESIGN §4)::

    zeta_l = sum_i G[k, i, l] x_i,     f_i = sum_l G[k, i, l] g_l,
    G[k, i, l] = C[k, i, 2l] - C[k, i, 2l+1] = grad N_i . zeta_l^0.

Per element it gathers the four vertices, builds the three axis vectors, accumulates the
axial, coupling, damping, torsion and axis-volume forces ``g_l`` of each axis, maps them to
the vertices, adds the barycentric volume spring (gradient or spec form) and its damping, and
scatters the four vertex forces. It computes what :func:`springmodel.springs.internal_forces`
computes.

Parallel scatter without races (``parallel=True``), two deterministic strategies:

``buffer`` (default)
    Static contiguous chunks (one per numba thread), one force buffer per chunk, reduced
    in chunk order at the end. Bit-identical between runs with the same number of threads.
    Two parallel regions per call.
``colour``
    Elements are greedily coloured once so that no two elements of one colour share a node,
    and stored colour by colour; within a colour a ``prange`` writes disjoint nodes. The
    summation order at every node is the colour order whatever the number of threads
    (bit-identical to a serial pass in colour order). One parallel region per colour
    (about 30 on box meshes): each is a barrier, which costs little on idle cores but a
    lot on a busy machine (with OpenMP's default active wait, 10x slower than serial).

Measured once (500k-tet six-split box, 2 cores, ``OMP_WAIT_POLICY=passive``, best of many
calls, shared machine), linear axial + cosine torsion + gradient volume: serial 13.3 M tets/s,
parallel ``buffer`` 25.7, ``colour`` 22.8, numpy oracle 0.31 (ratio 83x); cubic axial +
energy torsion: 10.9 / 21.4 / 17.8 / 0.39. All float64, ``fastmath=False``, ``cache=True``.
"""

from __future__ import annotations

import math
from typing import Literal

import numba
import numpy as np
from numba import njit, prange

from springfem.mesh import element_colouring

from .elements import SpringElements
from .options import SpringOptions

AXIAL_CODES = {"linear": 0, "quadratic": 1, "cubic": 1, "stress-scaled": 2}
TORSION_CODES = {"off": 0, "angle": 1, "cosine": 2, "cubic": 3, "energy": 4}
VOLUME_CODES = {"off": 0, "gradient": 1, "spec": 2}
#: Axis-volume codes by volumetric energy; coupling adds ``_A_COUPLING`` to the axial code.
AXIS_VOLUME_CODES = {"quadratic": 3, "log": 4, "simo-taylor": 5}
_A_POLY, _A_STRESS, _A_COUPLING = 1, 2, 8
_T_OFF, _T_ANGLE, _T_COSINE, _T_CUBIC, _T_ENERGY = 0, 1, 2, 3, 4
_V_OFF, _V_GRADIENT, _V_SPEC, _V_AXES_QUAD, _V_AXES_LOG = 0, 1, 2, 3, 4

# Per-element constants, one contiguous row each: P[k, :]
_KA, _L0, _KT, _T0, _KS, _LSUM, _INV_V0 = 0, 3, 6, 9, 12, 13, 14
_NP = 16
# Constants of the axis-volume and coupling springs, a second array Q[k, :] (read only when on)
_QC, _QKV, _QIDET, _QETA = 0, 3, 4, 5
_NQ = 6

Scatter = Literal["colour", "buffer"]
#: Below this many elements ``ForceKernel(parallel=None)`` runs serially.
PARALLEL_MIN_ELEMENTS = 20_000


# --------------------------------------------------------------------------- 3-vectors


@njit(cache=True)
def _row(a, i):
    return (a[i, 0], a[i, 1], a[i, 2])


@njit(cache=True)
def _add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@njit(cache=True)
def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(cache=True)
def _scale(s, a):
    return (s * a[0], s * a[1], s * a[2])


@njit(cache=True)
def _axpy(s, a, b):
    return (s * a[0] + b[0], s * a[1] + b[1], s * a[2] + b[2])


@njit(cache=True)
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(cache=True)
def _comb(g, k, l, a, b, c, d):
    """``sum_i G[k, i, l] y_i`` for the four vertex vectors ``a..d``."""
    ga, gb, gc, gd = g[k, 0, l], g[k, 1, l], g[k, 2, l], g[k, 3, l]
    return (
        ga * a[0] + gb * b[0] + gc * c[0] + gd * d[0],
        ga * a[1] + gb * b[1] + gc * c[1] + gd * d[1],
        ga * a[2] + gb * b[2] + gc * c[2] + gd * d[2],
    )


@njit(cache=True)
def _spread(g, k, i, g0, g1, g2):
    """``f_i = sum_l G[k, i, l] g_l``."""
    a, b, c = g[k, i, 0], g[k, i, 1], g[k, i, 2]
    return (
        a * g0[0] + b * g1[0] + c * g2[0],
        a * g0[1] + b * g1[1] + c * g2[1],
        a * g0[2] + b * g1[2] + c * g2[2],
    )


# --------------------------------------------------------------------------- one element


@njit(cache=True)
def _axial(L, l0, ka, axial, b2, b3, vol_ratio):
    d = L - l0
    if axial == _A_POLY:
        return -ka * (d + b2 * d * d / l0 + b3 * d * d * d / (l0 * l0))  # eq. 2.36
    if axial == _A_STRESS:
        return -ka * d * (l0 / L) * vol_ratio  # E (d/l0) (V/|zeta|), E = k l0^2/V0
    return -ka * d  # eq. 2.35


@njit(cache=True)
def _torsion(ul, um, Ll, Lm, kt, t0, torsion, bt):
    """Forces on the + ends of axes l and m of one torsion spring."""
    c = _dot(ul, um)  # eq. 2.32
    if torsion == _T_ENERGY:
        dc = c - t0
        fl = _scale(-kt * dc / Ll, _axpy(-c, ul, um))
        fm = _scale(-kt * dc / Lm, _axpy(-c, um, ul))
        return fl, fm
    if torsion == _T_COSINE:
        s = -kt * (c - t0)  # eqs. 2.44–2.45
    elif torsion == _T_CUBIC:
        dc = c - t0
        s = -kt * (dc + bt * dc * dc * dc)
    else:
        s = kt * (math.acos(min(max(c, -1.0), 1.0)) - t0)  # eqs. 2.40–2.41, restoring
    return _scale(s, um), _scale(s, ul)


@njit(cache=True)
def _dU(J, volume):
    """``U'(J) / kappa`` of the log (4) and Simo-Taylor (5) energies."""
    return math.log(J) / J if volume == _V_AXES_LOG else 0.5 * (J - 1.0 / J)


@njit(cache=True)
def _acc(out, i, f):
    out[i, 0] += f[0]
    out[i, 1] += f[1]
    out[i, 2] += f[2]


@njit(cache=True, inline="always")
def _element(
    k, x, v, tets, G, P, Q, axial, torsion, volume, damp_ax, damp_vol, b2, b3, bt, cax, cvol, dst
):
    """Forces of element ``k``, added to the rows ``tets[k]`` of ``dst``."""
    i0, i1, i2, i3 = tets[k, 0], tets[k, 1], tets[k, 2], tets[k, 3]
    xa, xb, xc, xd = _row(x, i0), _row(x, i1), _row(x, i2), _row(x, i3)
    z0 = _comb(G, k, 0, xa, xb, xc, xd)
    z1 = _comb(G, k, 1, xa, xb, xc, xd)
    z2 = _comb(G, k, 2, xa, xb, xc, xd)
    L0 = math.sqrt(_dot(z0, z0))
    L1 = math.sqrt(_dot(z1, z1))
    L2 = math.sqrt(_dot(z2, z2))
    u0 = _scale(1.0 / L0, z0)
    u1 = _scale(1.0 / L1, z1)
    u2 = _scale(1.0 / L2, z2)

    # axial springs and axial damping: signed magnitudes along each axis
    vol_ratio = 1.0
    if axial == _A_STRESS:
        e1, e2, e3 = _sub(xb, xa), _sub(xc, xa), _sub(xd, xa)
        det = (
            e1[0] * (e2[1] * e3[2] - e2[2] * e3[1])
            - e1[1] * (e2[0] * e3[2] - e2[2] * e3[0])
            + e1[2] * (e2[0] * e3[1] - e2[1] * e3[0])
        )
        vol_ratio = det / 6.0 * P[k, _INV_V0]
    law = axial & 7
    s0 = _axial(L0, P[k, _L0], P[k, _KA], law, b2, b3, vol_ratio)
    s1 = _axial(L1, P[k, _L0 + 1], P[k, _KA + 1], law, b2, b3, vol_ratio)
    s2 = _axial(L2, P[k, _L0 + 2], P[k, _KA + 2], law, b2, b3, vol_ratio)
    if axial & _A_COUPLING:  # Poisson coupling c_lm s_l s_m, s_l = |zeta_l|/l_l - 1
        e0, e1, e2 = L0 / P[k, _L0] - 1.0, L1 / P[k, _L0 + 1] - 1.0, L2 / P[k, _L0 + 2] - 1.0
        s0 -= (Q[k, _QC] * e1 + Q[k, _QC + 1] * e2) / P[k, _L0]
        s1 -= (Q[k, _QC] * e0 + Q[k, _QC + 2] * e2) / P[k, _L0 + 1]
        s2 -= (Q[k, _QC + 1] * e0 + Q[k, _QC + 2] * e1) / P[k, _L0 + 2]
    if damp_ax:
        va, vb, vc, vd = _row(v, i0), _row(v, i1), _row(v, i2), _row(v, i3)
        s0 -= cax * _dot(_comb(G, k, 0, va, vb, vc, vd), u0)
        s1 -= cax * _dot(_comb(G, k, 1, va, vb, vc, vd), u1)
        s2 -= cax * _dot(_comb(G, k, 2, va, vb, vc, vd), u2)
    g0 = _scale(s0, u0)
    g1 = _scale(s1, u1)
    g2 = _scale(s2, u2)

    # torsion springs, pairs (0,1), (0,2), (1,2)
    if torsion != _T_OFF:
        fl, fm = _torsion(u0, u1, L0, L1, P[k, _KT], P[k, _T0], torsion, bt)
        g0 = _add(g0, fl)
        g1 = _add(g1, fm)
        fl, fm = _torsion(u0, u2, L0, L2, P[k, _KT + 1], P[k, _T0 + 1], torsion, bt)
        g0 = _add(g0, fl)
        g2 = _add(g2, fm)
        fl, fm = _torsion(u1, u2, L1, L2, P[k, _KT + 2], P[k, _T0 + 2], torsion, bt)
        g1 = _add(g1, fl)
        g2 = _add(g2, fm)

    # axis-volume spring V0 U(J), J = det[z0 z1 z2] / det0; damping on dJ/dt
    if volume >= _V_AXES_QUAD:
        c12 = _cross(z1, z2)
        c20 = _cross(z2, z0)
        c01 = _cross(z0, z1)
        J = _dot(z0, c12) * Q[k, _QIDET]
        dU = J - 1.0 if volume == _V_AXES_QUAD else _dU(J, volume)
        sv = -Q[k, _QKV] * dU * Q[k, _QIDET]  # -V0 U'(J) / det0
        if damp_vol:
            va, vb, vc, vd = _row(v, i0), _row(v, i1), _row(v, i2), _row(v, i3)
            w0, w1 = _comb(G, k, 0, va, vb, vc, vd), _comb(G, k, 1, va, vb, vc, vd)
            w2 = _comb(G, k, 2, va, vb, vc, vd)
            Jdot = (_dot(c12, w0) + _dot(c20, w1) + _dot(c01, w2)) * Q[k, _QIDET]
            sv -= Q[k, _QETA] * Jdot * Q[k, _QIDET]
        g0 = _axpy(sv, c12, g0)
        g1 = _axpy(sv, c20, g1)
        g2 = _axpy(sv, c01, g2)

    fa = _spread(G, k, 0, g0, g1, g2)
    fb = _spread(G, k, 1, g0, g1, g2)
    fc = _spread(G, k, 2, g0, g1, g2)
    fd = _spread(G, k, 3, g0, g1, g2)

    # barycentric volume springs, xi_j = x_j - x_b (eqs. 2.76–2.77)
    if volume == _V_GRADIENT or volume == _V_SPEC:
        xm = _scale(0.25, _add(_add(xa, xb), _add(xc, xd)))
        ea, eb, ec, ed = _sub(xa, xm), _sub(xb, xm), _sub(xc, xm), _sub(xd, xm)
        ra = math.sqrt(_dot(ea, ea))
        rb = math.sqrt(_dot(eb, eb))
        rc = math.sqrt(_dot(ec, ec))
        rd = math.sqrt(_dot(ed, ed))
        ha, hb = _scale(1.0 / ra, ea), _scale(1.0 / rb, eb)
        hc, hd = _scale(1.0 / rc, ec), _scale(1.0 / rd, ed)
        coef = -P[k, _KS] * (ra + rb + rc + rd - P[k, _LSUM])
        if volume == _V_GRADIENT:
            hm = _scale(0.25, _add(_add(ha, hb), _add(hc, hd)))
            ha, hb, hc, hd = _sub(ha, hm), _sub(hb, hm), _sub(hc, hm), _sub(hd, hm)
        fa = _axpy(coef, ha, fa)
        fb = _axpy(coef, hb, fb)
        fc = _axpy(coef, hc, fc)
        fd = _axpy(coef, hd, fd)
        if damp_vol:
            va, vb, vc, vd = _row(v, i0), _row(v, i1), _row(v, i2), _row(v, i3)
            vm = _scale(0.25, _add(_add(va, vb), _add(vc, vd)))
            fa = _axpy(-cvol, _sub(va, vm), fa)
            fb = _axpy(-cvol, _sub(vb, vm), fb)
            fc = _axpy(-cvol, _sub(vc, vm), fc)
            fd = _axpy(-cvol, _sub(vd, vm), fd)
    _acc(dst, i0, fa)
    _acc(dst, i1, fb)
    _acc(dst, i2, fc)
    _acc(dst, i3, fd)


# --------------------------------------------------------------------------- drivers


@njit(cache=True, fastmath=False)
def _element_range(lo, hi, x, v, tets, G, P, Q, ax, to, vo, dax, dvol, b2, b3, bt, cax, cvol, dst):
    # _element is inlined here (numba IR), not in the parallel drivers, whose parfor
    # analysis does not accept it; the drivers call this serial loop on their blocks
    for k in range(lo, hi):
        _element(k, x, v, tets, G, P, Q, ax, to, vo, dax, dvol, b2, b3, bt, cax, cvol, dst)


@njit(cache=True, fastmath=False)
def _forces_serial(x, v, tets, G, P, Q, ax, to, vo, dax, dvol, b2, b3, bt, cax, cvol, out):
    out[:] = 0.0
    m = tets.shape[0]
    _element_range(0, m, x, v, tets, G, P, Q, ax, to, vo, dax, dvol, b2, b3, bt, cax, cvol, out)


@njit(cache=True, fastmath=False, parallel=True)
def _forces_colour(x, v, tets, G, P, Q, ax, to, vo, dax, dvol, b2, b3, bt, cax, cvol, ptr, out):
    n = out.shape[0]
    for i in prange(n):
        out[i, 0] = 0.0
        out[i, 1] = 0.0
        out[i, 2] = 0.0
    block = 512
    for c in range(ptr.shape[0] - 1):
        nblock = (ptr[c + 1] - ptr[c] + block - 1) // block
        for b in prange(nblock):  # no two elements of a colour share a node
            lo = ptr[c] + b * block
            hi = min(lo + block, ptr[c + 1])
            _element_range(
                lo, hi, x, v, tets, G, P, Q, ax, to, vo, dax, dvol, b2, b3, bt, cax, cvol, out
            )


@njit(cache=True, fastmath=False, parallel=True)
def _forces_buffer(
    x, v, tets, G, P, Q, ax, to, vo, dax, dvol, b2, b3, bt, cax, cvol, ptr, buf, out
):
    nchunk = ptr.shape[0] - 1
    n = out.shape[0]
    for t in prange(nchunk):  # one buffer per static chunk: deterministic
        b = buf[t]
        b[:] = 0.0
        _element_range(
            ptr[t], ptr[t + 1], x, v, tets, G, P, Q, ax, to, vo, dax, dvol, b2, b3, bt, cax, cvol, b
        )
    for i in prange(n):
        for d in range(3):
            s = 0.0
            for t in range(nchunk):
                s += buf[t, i, d]
            out[i, d] = s


# --------------------------------------------------------------------------- public API


def pack_constants(elements: SpringElements, options: SpringOptions) -> np.ndarray:
    """Per-element constant rows ``(m, 16)`` the kernel reads (see the ``_KA``.. offsets)."""
    m = elements.n_elements
    P = np.zeros((m, _NP))
    P[:, _KA : _KA + 3] = elements.k_axial
    P[:, _L0 : _L0 + 3] = elements.l0
    if options.torsion == "energy":
        P[:, _KT : _KT + 3] = elements.k_torsion
    else:
        P[:, _KT : _KT + 3] = elements.k_torsion_force
    P[:, _T0 : _T0 + 3] = elements.alpha0 if options.torsion == "angle" else elements.c0
    P[:, _KS] = elements.k_volume
    P[:, _LSUM] = elements.L0
    P[:, _INV_V0] = 1.0 / elements.V0
    return P


def pack_axis_constants(elements: SpringElements, options: SpringOptions) -> np.ndarray:
    """Constant rows ``(m, 6)`` of the axis-volume and coupling springs (``_QC``.. offsets)."""
    Q = np.zeros((elements.n_elements, _NQ))
    Q[:, _QC : _QC + 3] = elements.k_coupling
    Q[:, _QKV] = elements.k_axis_volume * elements.V0
    Q[:, _QIDET] = 1.0 / elements.det0
    Q[:, _QETA] = float(options.volume_damping) * elements.V0
    return Q


class ForceKernel:
    """Fused spring forces of a fixed set of elements and options.

    Parameters
    ----------
    elements
        Rest data (:func:`~springmodel.elements.build_spring_elements`).
    options
        Which parts are on and their laws.
    parallel
        Use all numba threads (race-free scatter, see the module docstring); ``None``
        (default) means parallel when there are at least :data:`PARALLEL_MIN_ELEMENTS`
        elements and more than one thread (on small meshes the thread start-up costs more
        than it saves, and much more on a busy machine).
    scatter
        ``buffer`` (default) or ``colour`` (parallel only).
    volume_form
        Overrides ``options.volume_form``.

    Examples
    --------
    >>> f = ForceKernel(elements, SpringOptions(torsion="energy")).forces(x)  # doctest: +SKIP
    """

    def __init__(
        self,
        elements: SpringElements,
        options: SpringOptions,
        parallel: bool | None = None,
        scatter: Scatter = "buffer",
        volume_form: str | None = None,
    ):
        if scatter not in ("colour", "buffer"):
            raise ValueError(f"scatter {scatter!r} is not one of colour, buffer")
        form = volume_form or getattr(options, "volume_form", "gradient")
        if form not in ("gradient", "spec"):
            raise ValueError(f"volume_form {form!r} is not one of gradient, spec")
        if options.axial not in AXIAL_CODES:
            raise ValueError(f"axial law {options.axial!r} is not one of {', '.join(AXIAL_CODES)}")
        if options.torsion not in TORSION_CODES:
            raise ValueError(
                f"torsion law {options.torsion!r} is not one of {', '.join(TORSION_CODES)}"
            )
        self.elements = elements
        self.options = options
        if parallel is None:
            parallel = elements.n_elements >= PARALLEL_MIN_ELEMENTS and numba.get_num_threads() > 1
        self.parallel = bool(parallel)
        self.scatter = scatter
        self.volume_form = form
        self.n_points = elements.n_points
        b2, b3 = (float(b) for b in options.axial_coefficients)
        if options.axial != "cubic":
            b3 = 0.0
        if options.axial == "linear":
            b2 = 0.0
        if options.axis_volume:
            volume_code = AXIS_VOLUME_CODES[options.volumetric]
        else:
            volume_code = VOLUME_CODES[form] if options.barycentric_volume else 0
        self._codes = (
            AXIAL_CODES[options.axial] + (_A_COUPLING if options.coupling else 0),
            TORSION_CODES[options.torsion],
            volume_code,
        )
        self._scalars = (b2, b3, float(options.torsion_cubic))
        self._cax = float(options.axial_damping)
        self._cvol = float(options.volume_damping) if options.volume else 0.0

        m = elements.n_elements
        self._perm = np.arange(m)
        self._ptr = np.array([0, m], dtype=np.int64)
        if self.parallel and scatter == "colour":
            colour = element_colouring(elements.tets, self.n_points)
            self._perm = np.argsort(colour, kind="stable")
            counts = np.bincount(colour)
            self._ptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        elif self.parallel:
            nchunk = max(1, numba.get_num_threads())
            self._ptr = np.linspace(0, m, nchunk + 1).round().astype(np.int64)
            self._buf = np.zeros((nchunk, self.n_points, 3))
        p = self._perm
        self._tets = np.ascontiguousarray(elements.tets[p], dtype=np.int64)
        self._G = np.ascontiguousarray(elements.G[p], dtype=np.float64)
        self._P = np.ascontiguousarray(pack_constants(elements, options)[p])
        if options.axis_volume or options.coupling:
            self._Q = np.ascontiguousarray(pack_axis_constants(elements, options)[p])
        else:
            self._Q = np.zeros((1, _NQ))
        self._dummy_v = np.zeros((1, 3))

    @property
    def n_colours(self) -> int:
        """Number of colours (1 unless ``scatter == "colour"`` and parallel)."""
        return self._ptr.size - 1 if (self.parallel and self.scatter == "colour") else 1

    def set_volume_stiffness(self, k_volume: np.ndarray) -> None:
        """Replace the volume constants (LMS), ``(m,)`` in the elements' order."""
        self._P[:, _KS] = np.asarray(k_volume, dtype=float)[self._perm]

    def forces(
        self, x: np.ndarray, v: np.ndarray | None = None, out: np.ndarray | None = None
    ) -> np.ndarray:
        """Nodal spring forces ``(n, 3)`` at positions ``x`` (and velocities ``v``)."""
        x = np.ascontiguousarray(x, dtype=np.float64)
        if out is None:
            out = np.empty((self.n_points, 3))
        elif out.shape != (self.n_points, 3) or out.dtype != np.float64:
            raise ValueError(f"out must be a float64 array of shape ({self.n_points}, 3)")
        dax = self._cax > 0 and v is not None
        dvol = self._cvol > 0 and v is not None and self._codes[2] != 0
        vv = np.ascontiguousarray(v, dtype=np.float64) if (dax or dvol) else self._dummy_v
        tp = (self._tets, self._G, self._P, self._Q)
        args = (x, vv, *tp, *self._codes, dax, dvol, *self._scalars, self._cax, self._cvol)
        if not self.parallel:
            _forces_serial(*args, out)
        elif self.scatter == "colour":
            _forces_colour(*args, self._ptr, out)
        else:
            _forces_buffer(*args, self._ptr, self._buf, out)
        return out

    def energy(self, x: np.ndarray) -> float:
        """Total spring energy (see :func:`springmodel.springs.spring_energy`)."""
        from .springs import spring_energy

        els = self.elements.with_volume_stiffness(self._P[np.argsort(self._perm), _KS])
        return spring_energy(np.asarray(x, float), els, self.options)[1]

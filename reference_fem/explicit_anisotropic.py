"""Explicit P1 FEM force kernels of the anisotropic laws, on the blocked layout.

Beside the isotropic kernels of :mod:`reference_fem.explicit_kernels` (same layout, same
drivers, same precisions), one kernel per anisotropic law and volumetric penalty:

- ``transverse-linear``: small-strain transversely isotropic elasticity
  (:mod:`reference_fem.materials`), ``sigma' = C' : eps'`` in the element frame;
- ``guccione``: :class:`~springfem.materials.laws.Guccione` with its penalty ``U(J)``;
- ``holzapfel-ogden``: :class:`~springfem.materials.laws.HolzapfelOgden` with its penalty.

The element frame ``R`` (rows: fibre, sheet, normal) is folded into the stored shape
gradients, ``g'_a = R grad N_a``: then ``F' = sum_a (x_a - x_0) (x) g'_a = F R^T`` is the
deformation gradient in the frame (the tissue laws' ``F'``,
:mod:`springfem.materials.laws.kinematics`) and ``f_a = -V P grad N_a = -V P' g'_a`` with
the frame stress ``P'`` (since ``P = P' R``), so a tissue law reads the same 10 constants
per element as the isotropic kernels (three rotated gradients and the rest volume) and never
rotates a stress. The linear law needs
``eps' = sym(R F') - I`` and ``f_a = -V R^T sigma' g'_a``, so it also stores ``R``
(19 constants). Per element, in the frame::

    guccione:         P' = F' S + U'(J) cof F',  S = C e^Q (B o E) + T_a e0 (x) e0
    holzapfel-ogden:  P' = a e c (F' - I1/(3J) cof F') + F' S + U'(J) cof F',
                      c = J^(-2/3), e = exp(b (c I1 - 3)),
                      S_00 = 2 psi_f' + T_a, S_11 = 2 psi_s', S_01 = S_10 = psi_fs'
    transverse-linear: sigma' = C' eps' (Voigt, engineering shears)

with ``U'(J)`` of the scene's ``volumetric`` (``log``: ``kappa ln J / J``, ``quadratic``:
``kappa (J - 1)``, ``simo-taylor``: ``kappa/2 (J - 1/J)``), ``cof F' = J F'^-T``, and the
Holzapfel–Ogden fibre and sheet terms only in tension (``I4 - 1 >`` :data:`TENSION`), as
the numpy laws define them. A tissue block runs its lanes through: ``F'`` and the
invariants (vectorised); the logarithm ``ln J`` of the log penalty and, for
Holzapfel–Ogden, ``J^(-2/3)`` (scalar: no vector ``log`` without SVML); the law's
exponentials (Guccione one, Holzapfel–Ogden four per element) in one vectorised pass of a
written-out ``exp`` (``2^k p(r)``: Cody–Waite reduction, the degree-13 Taylor polynomial,
``2^k`` from the bits of a round-to-integer constant; within 1 ulp of ``math.exp``, its
argument clamped to the finite range, which no stress-bearing state reaches); the stress
and forces (vectorised). Elements with ``J <= 0`` are counted; the tissue laws give them
no force.

A frame with ``det R = -1`` gets its normal negated (``J`` keeps its sign; every law here
is even in the normal).

Examples
--------
>>> import numpy as np
>>> serial, _ = anisotropic_kernel("guccione", "log", "float64")
>>> points = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> tets, frames = np.array([[0, 1, 2, 3]]), np.eye(3)[None]
>>> T, K = anisotropic_layout(tets, points, frames, "guccione", "float64")
>>> prm = np.array([2.0, 8.0, 2.0, 4.0, 50.0, 0.0, 0.0, 0.0, 0.0, 0.0])
>>> out = np.empty((4, 3))
>>> int(serial(points, T, K, 1, prm, out)), float(abs(out).max())  # no force at rest
(0, 0.0)
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np

from springfem.blocks import BLOCK, block_drivers, block_layout, compile_named
from springfem.materials.laws import TISSUE_LAWS, LawNames
from springfem.materials.laws.holzapfel_ogden import TENSION

_NO_VELOCITY = np.zeros((1, 3))  # the drivers pass velocities; the FEM forces need none
PRECISIONS = ("float64", "mixed", "float32")
#: The anisotropic laws: transverse-linear and every tissue law of the table.
ANISOTROPIC_LAWS = LawNames(("transverse-linear",))
#: The laws with a compiled kernel here; another tissue law runs :func:`generic_kernel`.
KERNEL_LAWS = ("transverse-linear", "guccione", "holzapfel-ogden")
VOLUMETRIC = ("log", "quadratic", "simo-taylor")
#: Length of the parameter vector every kernel takes (unused entries are zero).
NPARAM = 10
#: Constants per element: rotated gradients and volume; the linear law adds its frame.
NCOL = {law: 19 if law == "transverse-linear" else 10 for law in KERNEL_LAWS}


def right_handed(frames: np.ndarray) -> np.ndarray:
    """``frames`` with the normal (row 2) negated where ``det R < 0``.

    Parameters
    ----------
    frames
        ``(m, 3, 3)`` orthonormal frames (rows: fibre, sheet, normal).

    Returns
    -------
    ndarray
        A copy with ``det R = +1`` everywhere.

    Examples
    --------
    >>> import numpy as np
    >>> float(np.linalg.det(right_handed(np.diag([1.0, 1.0, -1.0])[None]))[0])
    1.0
    """
    R = np.array(frames, dtype=float)
    R[np.linalg.det(R) < 0, 2] *= -1.0
    return R


def anisotropic_layout(
    tets: np.ndarray, points: np.ndarray, frames: np.ndarray, law: str, precision: str
):
    """Blocked connectivity ``(nb, 4 B)`` int32 and constants ``(nb, NCOL[law] B)``.

    Parameters
    ----------
    tets, points
        Mesh (``m >= 1`` tets with positive volume).
    frames
        ``(m, 3, 3)`` orthonormal element frames (rows: fibre, sheet, normal).
    law
        One of :data:`KERNEL_LAWS`.
    precision
        Storage is float32 for ``mixed`` and ``float32``.

    Returns
    -------
    tuple of ndarray
        Constants per element: ``g'_a = R grad N_a`` (``a = 1..3``, 9 values), the rest
        volume and, for ``transverse-linear``, ``R`` row-major.

    Examples
    --------
    >>> import numpy as np
    >>> T, K = anisotropic_layout(np.array([[0, 1, 2, 3]]), np.eye(4)[:, 1:] * 2,
    ...                           np.eye(3)[None], "transverse-linear", "float64")
    >>> K.shape, round(float(K[0, 9 * 16]), 12)  # 19 constants of 16 lanes; V = 8/6
    ((1, 304), 1.333333333333)
    """
    if law not in KERNEL_LAWS:
        raise ValueError(f"law {law!r} is not one of {', '.join(KERNEL_LAWS)}")
    x = np.asarray(points, dtype=float)[tets]
    E = x[:, 1:] - x[:, :1]
    G = np.linalg.inv(E).transpose(0, 2, 1)  # rows: grad N_1..3
    R = right_handed(frames)
    Gp = np.einsum("kaJ,kIJ->kaI", G, R)  # rows: R grad N_a
    V = np.linalg.det(E) / 6.0
    cols = [Gp.reshape(-1, 9), V[:, None]]
    if law == "transverse-linear":
        cols.append(R.reshape(-1, 9))
    dtype = np.float64 if precision == "float64" else np.float32
    return block_layout(tets, np.concatenate(cols, axis=1).T, dtype)


def law_parameters(law: str, material=None, tissue=None) -> np.ndarray:
    """The kernel's parameter vector (length :data:`NPARAM`) of a law.

    Parameters
    ----------
    law
        One of :data:`ANISOTROPIC_LAWS`.
    material
        For ``transverse-linear``: a :class:`~springfem.scene.Material` with the five
        transverse constants.
    tissue
        For the tissue laws: the :class:`~springfem.materials.laws.TissueLaw` (its constants,
        ``kappa`` and ``active_tension``).

    Returns
    -------
    ndarray
        ``transverse-linear``: the frame's Voigt stiffness ``C00, C01, C02, C11, C12, C22,
        C33, C44, C55``; a tissue law: its constants (:meth:`~springfem.materials.laws.
        base.TissueLaw.keys`), ``kappa``, ``T_a`` (index :func:`active_index`); zero padded.

    Raises
    ------
    ValueError
        For another law, or a transverse matrix that is not orthotropic in the frame.

    Examples
    --------
    >>> from springfem.materials.laws import Guccione
    >>> law_parameters("guccione", tissue=Guccione(C=2.0, b_f=8.0, kappa=50.0))[:6].tolist()
    [2.0, 8.0, 1.0, 1.0, 50.0, 0.0]
    """
    p = np.zeros(NPARAM)
    if law == "transverse-linear":
        from springfem.materials import TRANSVERSE_KEYS, transverse_matrix

        C = transverse_matrix(*(getattr(material, k) for k in TRANSVERSE_KEYS))
        C = 0.5 * (C + C.T)
        mask = np.zeros((6, 6), bool)
        mask[:3, :3] = True
        mask[[3, 4, 5], [3, 4, 5]] = True
        if np.abs(C[~mask]).max() > 1e-12 * np.abs(C).max():
            raise ValueError("the transverse stiffness is not orthotropic in its frame")
        p[:9] = [C[0, 0], C[0, 1], C[0, 2], C[1, 1], C[1, 2], C[2, 2], C[3, 3], C[4, 4], C[5, 5]]
        return p
    if tissue is None or law != tissue.label:
        raise ValueError(f"law {law!r} needs its tissue law, one of {', '.join(TISSUE_LAWS)}")
    values = [getattr(tissue, k) for k in tissue.keys()] + [tissue.kappa, tissue.active_tension]
    if len(values) > NPARAM:
        raise ValueError(f"law {law!r} has {len(values) - 2} constants; the kernels take 8")
    p[: len(values)] = values
    return p


def _block_run(law: str, volumetric: str, at):
    """The block loop ``run(lo, hi, x, w, T, K, m, prm, q, out) -> n_inverted`` of ``law``
    (``w`` and ``q`` unused: the drivers of :func:`springfem.blocks.block_drivers` pass
    velocities and a second scalar).

    It captures only numbers and flags (compile-time constants: the law and penalty
    branches fold away), which keeps it disk-cacheable; as the isotropic loop it calls no
    helpers and is written out.
    """
    B = BLOCK
    one, zero, two, half = at(1.0), at(0.0), at(2.0), at(0.5)
    three, third, m23 = at(3.0), at(1.0 / 3.0), at(-2.0 / 3.0)
    tension = at(TENSION)
    lin = law == "transverse-linear"
    guc = law == "guccione"
    vlog = volumetric == "log"
    vquad = volumetric == "quadratic"
    NE = 1 if guc else 4  # exponentials per element (vectorised pass)
    f32 = at is np.float32
    ity = np.int32 if f32 else np.int64
    # exp(x) = 2^k p(r), k = round(x / ln 2), r = x - k ln 2 (Cody–Waite split of ln 2),
    # p the Taylor polynomial of degree 13 (|r| <= ln 2 / 2: truncation < 1e-17); 2^k by
    # the round-to-integer constant 1.5 2^52 (2^23 in float32), whose low bits hold k
    lo_x, hi_x = (at(-87.0), at(88.0)) if f32 else (at(-708.0), at(709.0))
    log2e = at(1.4426950408889634)
    ln2hi, ln2lo = (
        (at(0.693359375), at(-2.12194440e-4))
        if f32
        else (at(6.93147180369123816490e-01), at(1.90821492927058770002e-10))
    )
    magic = at(1.5 * 2.0**23) if f32 else at(1.5 * 2.0**52)
    magic_bits = int(np.array([magic], dtype=at).view(ity)[0])
    bias, shift = (127, 23) if f32 else (1023, 52)
    coef = [at(1.0 / math.factorial(i)) for i in range(14)]
    c0, c1, c2, c3, c4, c5, c6, c7, c8, c9, c10, c11, c12, c13 = coef

    def run(lo, hi, x, w, T, K, m, prm, q_, out):
        X = np.empty(9 * B, at)
        Fs = np.empty(9 * B, at)
        Jb = np.empty(B, at)
        A1 = np.empty(B, at)
        A2 = np.empty(B, at)
        A3 = np.empty(B, at)
        A4 = np.empty(B, at)
        A5 = np.empty(B, at)
        A6 = np.empty(B, at)
        Ea = np.empty(NE * B, at)  # exponents, then exponentials
        Eb = np.empty(NE * B, at)
        Ebits = Eb.view(ity)
        Fo = np.empty(12 * B, at)
        p0, p1, p2, p3, p4 = at(prm[0]), at(prm[1]), at(prm[2]), at(prm[3]), at(prm[4])
        p5, p6, p7, p8, p9 = at(prm[5]), at(prm[6]), at(prm[7]), at(prm[8]), at(prm[9])
        bad = 0
        for blk in range(lo, hi):
            Tb = T[blk]
            Kb = K[blk]
            for j in range(B):
                i0 = Tb[j]
                for k in range(3):
                    i = Tb[(k + 1) * B + j]
                    for d in range(3):
                        X[(3 * k + d) * B + j] = at(x[i, d] - x[i0, d])
            for j in range(B):  # F' = sum_a (x_a - x_0) (x) g'_a and invariants, vectorised
                ax, ay, az = X[j], X[B + j], X[2 * B + j]
                bx, by, bz = X[3 * B + j], X[4 * B + j], X[5 * B + j]
                cx, cy, cz = X[6 * B + j], X[7 * B + j], X[8 * B + j]
                g1 = (at(Kb[j]), at(Kb[B + j]), at(Kb[2 * B + j]))
                g2 = (at(Kb[3 * B + j]), at(Kb[4 * B + j]), at(Kb[5 * B + j]))
                g3 = (at(Kb[6 * B + j]), at(Kb[7 * B + j]), at(Kb[8 * B + j]))
                F0 = ax * g1[0] + bx * g2[0] + cx * g3[0]
                F1 = ax * g1[1] + bx * g2[1] + cx * g3[1]
                F2 = ax * g1[2] + bx * g2[2] + cx * g3[2]
                F3 = ay * g1[0] + by * g2[0] + cy * g3[0]
                F4 = ay * g1[1] + by * g2[1] + cy * g3[1]
                F5 = ay * g1[2] + by * g2[2] + cy * g3[2]
                F6 = az * g1[0] + bz * g2[0] + cz * g3[0]
                F7 = az * g1[1] + bz * g2[1] + cz * g3[1]
                F8 = az * g1[2] + bz * g2[2] + cz * g3[2]
                Fs[j], Fs[B + j], Fs[2 * B + j] = F0, F1, F2
                Fs[3 * B + j], Fs[4 * B + j], Fs[5 * B + j] = F3, F4, F5
                Fs[6 * B + j], Fs[7 * B + j], Fs[8 * B + j] = F6, F7, F8
                Jb[j] = (
                    F0 * (F4 * F8 - F5 * F7) + F1 * (F5 * F6 - F3 * F8) + F2 * (F3 * F7 - F4 * F6)
                )
                # C' = F'^T F' (frame)
                C00 = F0 * F0 + F3 * F3 + F6 * F6
                C11 = F1 * F1 + F4 * F4 + F7 * F7
                C22 = F2 * F2 + F5 * F5 + F8 * F8
                C01 = F0 * F1 + F3 * F4 + F6 * F7
                C02 = F0 * F2 + F3 * F5 + F6 * F8
                C12 = F1 * F2 + F4 * F5 + F7 * F8
                if guc:  # Q = sum_ab B_ab E_ab^2, E = (C' - I) / 2
                    e00, e11, e22 = half * (C00 - one), half * (C11 - one), half * (C22 - one)
                    e01, e02, e12 = half * C01, half * C02, half * C12
                    Ea[j] = (
                        p1 * e00 * e00
                        + p2 * (e11 * e11 + e22 * e22 + two * e12 * e12)
                        + two * p3 * (e01 * e01 + e02 * e02)
                    )
                elif not lin:  # holzapfel-ogden: I1, I4f - 1, I4s - 1, I8fs
                    A1[j] = C00 + C11 + C22
                    A2[j] = C00 - one
                    A3[j] = C11 - one
                    A4[j] = C01
            if not lin:
                for j in range(B):  # logarithms (and J^(-2/3)), scalar
                    J = Jb[j]
                    ok = J > zero
                    kappa = p4 if guc else p8
                    lnJ = zero
                    if vlog or not guc:  # one log per element (penalty and J^(-2/3))
                        lnJ = math.log(J) if ok else zero
                    if vlog:
                        s = kappa * lnJ / J if ok else zero
                    elif vquad:
                        s = kappa * (J - one)
                    else:
                        s = half * kappa * (J - one / J) if ok else zero
                    if guc:
                        A2[j] = s
                    else:  # holzapfel-ogden: J^(-2/3) and the four exponents
                        I1, xf, xs, xfs = A1[j], A2[j], A3[j], A4[j]
                        cJ = math.exp(m23 * lnJ) if ok else zero
                        A5[j] = cJ
                        A6[j] = s
                        Ea[j] = p1 * (cJ * I1 - three)
                        Ea[B + j] = p3 * xf * xf
                        Ea[2 * B + j] = p5 * xs * xs
                        Ea[3 * B + j] = p7 * xfs * xfs
                for j in range(NE * B):  # exp, vectorised (see above)
                    xa = min(max(Ea[j], lo_x), hi_x)
                    tt = xa * log2e + magic
                    kk = tt - magic
                    r = xa - kk * ln2hi - kk * ln2lo
                    pe = c13 * r + c12
                    pe = pe * r + c11
                    pe = pe * r + c10
                    pe = pe * r + c9
                    pe = pe * r + c8
                    pe = pe * r + c7
                    pe = pe * r + c6
                    pe = pe * r + c5
                    pe = pe * r + c4
                    pe = pe * r + c3
                    pe = pe * r + c2
                    pe = pe * r + c1
                    Ea[j] = pe * r + c0
                    Eb[j] = tt
                for j in range(NE * B):
                    Ebits[j] = (Ebits[j] - magic_bits + bias) << shift  # 2^k
                for j in range(NE * B):
                    Ea[j] *= Eb[j]
            for j in range(B):  # stress and forces, vectorised
                F0, F1, F2 = Fs[j], Fs[B + j], Fs[2 * B + j]
                F3, F4, F5 = Fs[3 * B + j], Fs[4 * B + j], Fs[5 * B + j]
                F6, F7, F8 = Fs[6 * B + j], Fs[7 * B + j], Fs[8 * B + j]
                g1 = (at(Kb[j]), at(Kb[B + j]), at(Kb[2 * B + j]))
                g2 = (at(Kb[3 * B + j]), at(Kb[4 * B + j]), at(Kb[5 * B + j]))
                g3 = (at(Kb[6 * B + j]), at(Kb[7 * B + j]), at(Kb[8 * B + j]))
                V = at(Kb[9 * B + j])
                J = Jb[j]
                if lin:
                    R0, R1, R2 = at(Kb[10 * B + j]), at(Kb[11 * B + j]), at(Kb[12 * B + j])
                    R3, R4, R5 = at(Kb[13 * B + j]), at(Kb[14 * B + j]), at(Kb[15 * B + j])
                    R6, R7, R8 = at(Kb[16 * B + j]), at(Kb[17 * B + j]), at(Kb[18 * B + j])
                    # H = R F' = R F R^T (the displacement gradient plus I, in the frame)
                    H0 = R0 * F0 + R1 * F3 + R2 * F6
                    H1 = R0 * F1 + R1 * F4 + R2 * F7
                    H2 = R0 * F2 + R1 * F5 + R2 * F8
                    H3 = R3 * F0 + R4 * F3 + R5 * F6
                    H4 = R3 * F1 + R4 * F4 + R5 * F7
                    H5 = R3 * F2 + R4 * F5 + R5 * F8
                    H6 = R6 * F0 + R7 * F3 + R8 * F6
                    H7 = R6 * F1 + R7 * F4 + R8 * F7
                    H8 = R6 * F2 + R7 * F5 + R8 * F8
                    e00, e11, e22 = H0 - one, H4 - one, H8 - one
                    s00 = p0 * e00 + p1 * e11 + p2 * e22
                    s11 = p1 * e00 + p3 * e11 + p4 * e22
                    s22 = p2 * e00 + p4 * e11 + p5 * e22
                    s12 = p6 * (H5 + H7)  # C33 gamma_12
                    s02 = p7 * (H2 + H6)  # C44 gamma_02
                    s01 = p8 * (H1 + H3)  # C55 gamma_01
                    # P~ = R^T sigma' (so that f_a = -V P~ g'_a)
                    P = (
                        R0 * s00 + R3 * s01 + R6 * s02,
                        R0 * s01 + R3 * s11 + R6 * s12,
                        R0 * s02 + R3 * s12 + R6 * s22,
                        R1 * s00 + R4 * s01 + R7 * s02,
                        R1 * s01 + R4 * s11 + R7 * s12,
                        R1 * s02 + R4 * s12 + R7 * s22,
                        R2 * s00 + R5 * s01 + R8 * s02,
                        R2 * s01 + R5 * s11 + R8 * s12,
                        R2 * s02 + R5 * s12 + R8 * s22,
                    )
                else:
                    V = V if J > zero else zero
                    # cof F' (= J F'^-T), row-major
                    k0, k1, k2 = F4 * F8 - F5 * F7, F5 * F6 - F3 * F8, F3 * F7 - F4 * F6
                    k3, k4, k5 = F2 * F7 - F1 * F8, F0 * F8 - F2 * F6, F1 * F6 - F0 * F7
                    k6, k7, k8 = F1 * F5 - F2 * F4, F2 * F3 - F0 * F5, F0 * F4 - F1 * F3
                    if guc:
                        cq, s = p0 * Ea[j], A2[j]  # C e^Q, U'(J)
                        C00 = F0 * F0 + F3 * F3 + F6 * F6
                        C11 = F1 * F1 + F4 * F4 + F7 * F7
                        C22 = F2 * F2 + F5 * F5 + F8 * F8
                        C01 = F0 * F1 + F3 * F4 + F6 * F7
                        C02 = F0 * F2 + F3 * F5 + F6 * F8
                        C12 = F1 * F2 + F4 * F5 + F7 * F8
                        # S = C e^Q (B o E) + T_a e0 (x) e0
                        S00 = cq * p1 * half * (C00 - one) + p5
                        S11 = cq * p2 * half * (C11 - one)
                        S22 = cq * p2 * half * (C22 - one)
                        S01 = cq * p3 * half * C01
                        S02 = cq * p3 * half * C02
                        S12 = cq * p2 * half * C12
                        P = (
                            F0 * S00 + F1 * S01 + F2 * S02 + s * k0,
                            F0 * S01 + F1 * S11 + F2 * S12 + s * k1,
                            F0 * S02 + F1 * S12 + F2 * S22 + s * k2,
                            F3 * S00 + F4 * S01 + F5 * S02 + s * k3,
                            F3 * S01 + F4 * S11 + F5 * S12 + s * k4,
                            F3 * S02 + F4 * S12 + F5 * S22 + s * k5,
                            F6 * S00 + F7 * S01 + F8 * S02 + s * k6,
                            F6 * S01 + F7 * S11 + F8 * S12 + s * k7,
                            F6 * S02 + F7 * S12 + F8 * S22 + s * k8,
                        )
                    else:
                        I1, xf, xs, xfs, cJ = A1[j], A2[j], A3[j], A4[j], A5[j]
                        cF = p0 * Ea[j] * cJ  # coefficient of F'
                        ck = A6[j] - cF * I1 * third / J if J > zero else zero  # of cof F'
                        # psi_i' = a_i x e^(b_i x^2); fibre and sheet only in tension
                        df = p2 * xf * Ea[B + j] if xf > tension else zero
                        ds = p4 * xs * Ea[2 * B + j] if xs > tension else zero
                        S00 = two * df + p9  # (+ T_a)
                        S11 = two * ds
                        S01 = p6 * xfs * Ea[3 * B + j]
                        P = (
                            cF * F0 + ck * k0 + F0 * S00 + F1 * S01,
                            cF * F1 + ck * k1 + F0 * S01 + F1 * S11,
                            cF * F2 + ck * k2,
                            cF * F3 + ck * k3 + F3 * S00 + F4 * S01,
                            cF * F4 + ck * k4 + F3 * S01 + F4 * S11,
                            cF * F5 + ck * k5,
                            cF * F6 + ck * k6 + F6 * S00 + F7 * S01,
                            cF * F7 + ck * k7 + F6 * S01 + F7 * S11,
                            cF * F8 + ck * k8,
                        )
                for r in range(3):  # f_a = -V P' g'_a (a = 1..3), f_0 = -(f_1 + f_2 + f_3)
                    f1 = -V * (P[3 * r] * g1[0] + P[3 * r + 1] * g1[1] + P[3 * r + 2] * g1[2])
                    f2 = -V * (P[3 * r] * g2[0] + P[3 * r + 1] * g2[1] + P[3 * r + 2] * g2[2])
                    f3 = -V * (P[3 * r] * g3[0] + P[3 * r + 1] * g3[1] + P[3 * r + 2] * g3[2])
                    Fo[(3 + r) * B + j] = f1
                    Fo[(6 + r) * B + j] = f2
                    Fo[(9 + r) * B + j] = f3
                    Fo[r * B + j] = -(f1 + f2 + f3)
            nv = min(B, m - blk * B)
            for j in range(nv):
                bad += 1 if Jb[j] <= zero else 0
                for k in range(4):
                    i = Tb[k * B + j]
                    out[i, 0] += Fo[(3 * k) * B + j]
                    out[i, 1] += Fo[(3 * k + 1) * B + j]
                    out[i, 2] += Fo[(3 * k + 2) * B + j]
        return bad

    name = f"fem_run_{law.replace('-', '_')}_{volumetric.replace('-', '_')}_{np.dtype(at).name}"
    return compile_named(run, name)


@cache
def anisotropic_kernel(law: str, volumetric: str = "log", precision: str = "float64"):
    """``(serial, parallel)`` force drivers of an anisotropic ``law`` (compiled on first call).

    ``serial(x, T, K, m, prm, out)`` and ``parallel(x, T, K, m, prm, ptr, buf, out)``
    overwrite ``out (n, 3)`` with the internal forces (``-`` the residual's internal force
    vector) and return the number of elements with ``J <= 0``. ``T, K`` come from
    :func:`anisotropic_layout`, ``prm`` from :func:`law_parameters`.

    Parameters
    ----------
    law
        One of :data:`KERNEL_LAWS`.
    volumetric
        The tissue laws' penalty ``U(J)``: ``log``, ``quadratic`` or ``simo-taylor``
        (ignored for ``transverse-linear``).
    precision
        ``float64``, ``mixed`` (float32 constants, float64 arithmetic) or ``float32``.

    Returns
    -------
    serial, parallel
        The two drivers.

    Raises
    ------
    ValueError
        For an unknown law, penalty or precision.

    Examples
    --------
    >>> import numpy as np
    >>> from springfem.materials import TRANSVERSE_KEYS
    >>> from springfem.scene import Material
    >>> mat = Material("transverse-linear", 1.0, 0.4, E_fiber=3.0, E_cross=1.0,
    ...                nu_fiber_cross=0.3, nu_cross=0.4, G_fiber=0.5)
    >>> serial, _ = anisotropic_kernel("transverse-linear")
    >>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    >>> T, K = anisotropic_layout(np.array([[0, 1, 2, 3]]), X, np.eye(3)[None],
    ...                           "transverse-linear", "float64")
    >>> out = np.empty((4, 3))
    >>> x = X * [1.01, 1.0, 1.0]  # 1 % fibre stretch: a fibre stress of about E_fiber / 100
    >>> _ = serial(x, T, K, 1, law_parameters("transverse-linear", mat), out)
    >>> bool(abs(out.sum(axis=0)).max() < 1e-15), bool(out[1, 0] < 0)  # net zero; restoring
    (True, True)
    """
    if law not in KERNEL_LAWS:
        raise ValueError(f"law {law!r} is not one of {', '.join(KERNEL_LAWS)}")
    if volumetric not in VOLUMETRIC:
        raise ValueError(f"volumetric {volumetric!r} is not one of {', '.join(VOLUMETRIC)}")
    if precision not in PRECISIONS:
        raise ValueError(f"precision {precision!r} is not one of {', '.join(PRECISIONS)}")
    if law == "transverse-linear":
        volumetric = "log"  # no penalty: one build
    run = _block_run(law, volumetric, np.float32 if precision == "float32" else np.float64)
    serial_w, parallel_w = block_drivers(run)

    def serial(x, T, K, m, prm, out):
        return serial_w(x, _NO_VELOCITY, T, K, m, prm, 0.0, out)

    def parallel(x, T, K, m, prm, ptr, buf, out):
        return parallel_w(x, _NO_VELOCITY, T, K, m, prm, 0.0, ptr, buf, out)

    return serial, parallel

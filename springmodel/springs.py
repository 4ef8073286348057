"""Spring forces, the readable numpy oracle: through the six intersection points and ``C^k``.

Every force here is computed on the intersection points ``q_j = sum_i C_ij x_i`` (eq. 2.25)
and distributed to the vertices with the same coefficients, ``f_i = sum_j C_ij f_j``
(eqs. 2.28–2.29), except the volume springs, which act on the vertices directly
(eqs. 2.76–2.77). The kernels (:mod:`springmodel.fastkernels`) must agree with this module.

Parts and laws (see :class:`~springmodel.options.SpringOptions`):

axial (2.35–2.38)
    Force ``s_l zeta_hat_l`` on ``q_{2l}`` and ``-s_l zeta_hat_l`` on ``q_{2l+1}`` with
    ``d = |zeta_l| - l0_l`` and

    * ``linear``: ``s = -k d`` (2.35), energy ``k d^2 / 2``;
    * ``quadratic``/``cubic``: ``s = -k (d + b2 d^2/l0 + b3 d^3/l0^2)`` (2.36; quadratic
      uses ``b2`` only), energy ``k (d^2/2 + b2 d^3/(3 l0) + b3 d^4/(4 l0^2))``;
    * ``stress-scaled``: force = axial stress x current cross-section,
      ``s = -E_l (d / l0) * (V / |zeta_l|)`` with the axial modulus
      ``E_l = k_l l0^2 / V0`` of the calibrated spring (so that at small strain it is the
      linear spring, and the law differs only by its large-strain geometry) and the
      element's mean cross-section normal to the axis ``A_l = V / |zeta_l|`` (current
      volume over current axis length). Applied as a ``±`` pair, so net force and torque are
      zero; it is not the gradient of an energy (``V`` depends on all four vertices).

    Optional axial damping ``-c_a ((v_{2l} - v_{2l+1}) . zeta_hat) zeta_hat`` on the pair
    (zero for rigid motion).

torsion, for each pair ``(l, m)`` in (0,1), (0,2), (1,2), with ``c = zh_l . zh_m``
    * ``energy``: the exact ``-dU/dx`` of ``U = k/2 (c - c0)^2``: on ``q_{2l}``
      ``-k (c - c0) (zh_m - c zh_l) / |zeta_l|``, on ``q_{2m}`` the same with ``l, m``
      swapped, minus on the odd points. Net force and net torque zero.
    * ``cosine`` (2.44–2.45): ``s = -k_f (c - c0)``; ``s zh_m`` on ``q_{2l}``, ``s zh_l`` on
      ``q_{2m}``, minus on the odd points. Not a gradient; net force zero, net torque
      ``s (|zeta_l| - |zeta_m|) zh_l x zh_m`` (nonzero when the axis segments differ).
    * ``cubic`` (2.47–2.50): the cosine law with ``s = -k_f (dc + b dc^3)``.
    * ``angle`` (2.40–2.41): the cosine law with ``s = k_f (alpha - alpha0)``. NOTE the sign:
      the spec writes ``-k (alpha - alpha0) zh_m``, which *opens* an angle that is already
      too large (``d alpha = -dc / sin alpha``): anti-restoring. The spec then derives the
      cosine law from it with ``alpha - alpha0 ~ c - c0``, whereas in fact
      ``alpha - alpha0 ~ -(c - c0)`` near 90°; the sign used here is the one for which the
      cosine law (the spec's default, restoring) is the small-angle form of the angle law.
      As in 2.33 and 2.44–2.45, the ends of axis ``m`` get the force along ``zh_l``
      (reading "``f_{m->l} = -f_{l->m}``" literally would push axis ``m`` along itself).
    ``k_f = 2 k / (l_l + l_m)`` (:attr:`SpringElements.k_torsion_force`).

volume (2.76–2.77), ``xi_j = x_j - x_b`` (the restoring sign, DESIGN §3)
    ``dL = sum_j |xi_j| - L0``; ``gradient`` form: ``f_j = -k_s dL (xh_j - mean_i xh_i)``,
    the exact ``-dU/dx`` of ``U = k_s/2 dL^2`` (the barycenter depends on every vertex),
    net force zero. ``spec`` form: ``f_j = -k_s dL xh_j`` as written, whose net force
    ``-k_s dL sum_j xh_j`` is nonzero for irregular tets. Damping ``-c (v_j - v_b)``
    (it also damps rigid rotation, as written in the spec).

Examples
--------
>>> import numpy as np
>>> from springfem.scene import Material
>>> from springmodel.elements import build_spring_elements
>>> from springmodel.options import SpringOptions
>>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> tets, frames = np.array([[0, 1, 2, 3]]), np.eye(3)[None]
>>> e = build_spring_elements(X, tets, frames, material=Material("linear", 1.0e4, 0.3))
>>> float(abs(internal_forces(X, None, e, SpringOptions())).max())  # no force at rest
0.0
>>> f = internal_forces(1.01 * X, None, e, SpringOptions())  # stretched: net force zero
>>> bool(abs(f.sum(axis=0)).max() < 1e-12)
True
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from .axis_springs import axis_spring_energy, axis_volume_axis_forces, coupling_axis_forces
from .calibration import TORSION_PAIRS
from .elements import SpringElements
from .options import LMSOptions, SpringOptions

VolumeForm = Literal["gradient", "spec"]


# --------------------------------------------------------------------------- helpers


def intersection_points(x: np.ndarray, elements: SpringElements) -> np.ndarray:
    """Current intersection points ``q_j = sum_i C_ij x_i`` (eq. 2.25), ``(m, 6, 3)``."""
    return elements.C.transpose(0, 2, 1) @ x[elements.tets]


def distribute(fq: np.ndarray, elements: SpringElements) -> np.ndarray:
    """Forces on the six points ``(m, 6, 3)`` -> vertex forces ``f_i = sum_j C_ij f_j``."""
    return elements.C @ fq


def scatter(fv: np.ndarray, tets: np.ndarray, n: int) -> np.ndarray:
    """Sum per-element vertex forces ``(m, 4, 3)`` into nodal forces ``(n, 3)``."""
    idx = tets.ravel()
    flat = fv.reshape(-1, 3)
    return np.stack([np.bincount(idx, weights=flat[:, c], minlength=n) for c in range(3)], axis=1)


def _axes(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    zeta = q[:, 0::2] - q[:, 1::2]  # (m, 3, 3), zeta_l = q_{2l} - q_{2l+1}
    L = np.linalg.norm(zeta, axis=-1)
    return zeta, L, zeta / L[..., None]  # eq. 2.31


def _volumes(X: np.ndarray) -> np.ndarray:
    return np.linalg.det(X[:, 1:] - X[:, :1]) / 6.0


def _pair_forces(fq: np.ndarray, s_l: np.ndarray, l: int, dir_l: np.ndarray) -> None:
    """Add ``s_l dir_l`` on ``q_{2l}`` and its opposite on ``q_{2l+1}``."""
    f = s_l[:, None] * dir_l
    fq[:, 2 * l] += f
    fq[:, 2 * l + 1] -= f


def _resolve_volume_form(options: SpringOptions, volume_form: VolumeForm | None) -> str:
    form = volume_form or getattr(options, "volume_form", "gradient")
    if form not in ("gradient", "spec"):
        raise ValueError(f"volume_form {form!r} is not one of gradient, spec")
    return form


# --------------------------------------------------------------------------- axial


def axial_magnitudes(
    L: np.ndarray, X: np.ndarray, elements: SpringElements, options: SpringOptions
) -> np.ndarray:
    """Signed axial force magnitudes ``s_l`` (force ``s zeta_hat`` on ``q_{2l}``), ``(m, 3)``."""
    k, l0 = elements.k_axial, elements.l0
    d = L - l0
    law = options.axial
    if law == "linear":
        return -k * d  # eq. 2.35
    if law in ("quadratic", "cubic"):
        b2, b3 = options.axial_coefficients
        b3 = b3 if law == "cubic" else 0.0
        return -k * (d + b2 * d**2 / l0 + b3 * d**3 / l0**2)  # eq. 2.36
    if law == "stress-scaled":
        V = _volumes(X)
        return -k * d * (l0 / L) * (V / elements.V0)[:, None]  # E (d/l0) (V/|zeta|)
    raise ValueError(f"axial law {law!r} is not one of linear, quadratic, cubic, stress-scaled")


def axial_forces(
    x: np.ndarray,
    v: np.ndarray | None,
    elements: SpringElements,
    options: SpringOptions,
) -> np.ndarray:
    """Axial spring forces (2.35–2.38) plus optional axial damping, nodal ``(n, 3)``."""
    X = x[elements.tets]
    q = intersection_points(x, elements)
    _, L, u = _axes(q)
    s = axial_magnitudes(L, X, elements, options)
    if options.axial_damping > 0 and v is not None:
        vq = intersection_points(v, elements)
        w = vq[:, 0::2] - vq[:, 1::2]  # relative velocity of the two ends
        s = s - options.axial_damping * np.einsum("klc,klc->kl", w, u)
    fq = np.zeros_like(q)
    for l in range(3):
        _pair_forces(fq, s[:, l], l, u[:, l])  # eq. 2.34: f_{l,2} = -f_{l,1}
    return scatter(distribute(fq, elements), elements.tets, x.shape[0])


# --------------------------------------------------------------------------- torsion


def torsion_forces(x: np.ndarray, elements: SpringElements, options: SpringOptions) -> np.ndarray:
    """Torsion spring forces for the law ``options.torsion``, nodal ``(n, 3)``."""
    law = options.torsion
    if law == "off":
        return np.zeros_like(x)
    q = intersection_points(x, elements)
    _, L, u = _axes(q)
    fq = np.zeros_like(q)
    kf = elements.k_torsion_force
    for p, (l, m) in enumerate(TORSION_PAIRS):
        ul, um = u[:, l], u[:, m]
        c = np.einsum("kc,kc->k", ul, um)  # eq. 2.32
        dc = c - elements.c0[:, p]
        if law == "energy":
            k = elements.k_torsion[:, p]
            _pair_forces(fq, -k * dc / L[:, l], l, um - c[:, None] * ul)
            _pair_forces(fq, -k * dc / L[:, m], m, ul - c[:, None] * um)
            continue
        if law == "cosine":
            s = -kf[:, p] * dc  # eqs. 2.44–2.45
        elif law == "cubic":
            s = -kf[:, p] * (dc + options.torsion_cubic * dc**3)  # eqs. 2.47–2.50
        elif law == "angle":
            alpha = np.arccos(np.clip(c, -1.0, 1.0))
            s = kf[:, p] * (alpha - elements.alpha0[:, p])  # eqs. 2.40–2.41, restoring sign
        else:
            raise ValueError(f"torsion law {law!r} is not one of off, angle, cosine, cubic, energy")
        _pair_forces(fq, s, l, um)  # f_{l->m} on the ends of axis l
        _pair_forces(fq, s, m, ul)  # f_{m->l} on the ends of axis m
    return scatter(distribute(fq, elements), elements.tets, x.shape[0])


# --------------------------------------------------------------------------- volume


def volume_forces(
    x: np.ndarray,
    v: np.ndarray | None,
    elements: SpringElements,
    options: SpringOptions,
    volume_form: VolumeForm | None = None,
) -> np.ndarray:
    """Barycentric volume spring forces (2.76–2.77), nodal ``(n, 3)``.

    ``volume_form`` overrides ``options.volume_form`` (``gradient`` or ``spec``).
    """
    form = _resolve_volume_form(options, volume_form)
    X = x[elements.tets]
    xb = X.mean(axis=1, keepdims=True)  # eq. 2.22
    xi = X - xb  # restoring sign: barycenter -> vertex
    r = np.linalg.norm(xi, axis=-1)
    xh = xi / r[..., None]
    dL = r.sum(axis=1) - elements.L0
    direction = xh - xh.mean(axis=1, keepdims=True) if form == "gradient" else xh
    f = -(elements.k_volume * dL)[:, None, None] * direction  # eq. 2.77
    if options.volume_damping > 0 and v is not None:
        V = v[elements.tets]
        f -= options.volume_damping * (V - V.mean(axis=1, keepdims=True))
    return scatter(f, elements.tets, x.shape[0])


def volume_measures(x: np.ndarray, elements: SpringElements) -> tuple[np.ndarray, np.ndarray]:
    """Current volumes ``V`` and radial sums ``sum_j |xi_j|``, each ``(m,)`` (inputs to LMS)."""
    X = x[elements.tets]
    r = np.linalg.norm(X - X.mean(axis=1, keepdims=True), axis=-1)
    return _volumes(X), r.sum(axis=1)


def lms_update(
    k_s: np.ndarray,
    k_s0: np.ndarray,
    V: np.ndarray,
    V0: np.ndarray,
    sum_xi: np.ndarray,
    sum_xi0: np.ndarray,
    opts: LMSOptions,
) -> np.ndarray:
    """One adaptive-stiffness step (eq. 2.81), on ``k_s / k_s0``, clamped.

    ``rule = "spec"``: ``k/k0 += mu (dV/V0) (L/L0)`` as written (a compressed element gets
    softer); ``rule = "abs"``: ``k/k0 += mu |dV/V0| (L/L0)`` (stiffens with any volume
    error). The ratio is clamped to ``[k_min, k_max]``.
    """
    ratio = np.asarray(k_s, float) / k_s0
    dv = (np.asarray(V, float) - V0) / V0
    if opts.rule == "spec":
        drive = dv
    elif opts.rule == "abs":
        drive = np.abs(dv)
    else:
        raise ValueError(f"LMS rule {opts.rule!r} is not one of spec, abs")
    ratio = ratio + opts.mu * drive * (np.asarray(sum_xi, float) / sum_xi0)  # eq. 2.81
    return np.clip(ratio, opts.k_min, opts.k_max) * k_s0


def axis_forces(
    x: np.ndarray, v: np.ndarray | None, elements: SpringElements, options: SpringOptions
) -> np.ndarray:
    """Axis-volume and Poisson-coupling forces (:mod:`springmodel.axis_springs`), ``(n, 3)``."""
    q = intersection_points(x, elements)
    zeta = q[:, 0::2] - q[:, 1::2]
    g = np.zeros_like(zeta)
    if options.axis_volume:
        zeta_dot = None
        if v is not None and options.volume_damping > 0:
            vq = intersection_points(v, elements)
            zeta_dot = vq[:, 0::2] - vq[:, 1::2]
        g += axis_volume_axis_forces(
            zeta, zeta_dot, elements, options.volumetric, options.volume_damping
        )
    if options.coupling:
        g += coupling_axis_forces(zeta, elements)
    fq = np.zeros_like(q)
    for l in range(3):
        fq[:, 2 * l] += g[:, l]
        fq[:, 2 * l + 1] -= g[:, l]
    return scatter(distribute(fq, elements), elements.tets, x.shape[0])


# --------------------------------------------------------------------------- totals


def internal_forces(
    x: np.ndarray,
    v: np.ndarray | None,
    elements: SpringElements,
    options: SpringOptions,
    volume_form: VolumeForm | None = None,
) -> np.ndarray:
    """Sum of the enabled spring forces at positions ``x`` and velocities ``v``, ``(n, 3)``.

    Only the enabled parts are computed: axial always, torsion unless ``off``, volume if
    ``options.volume`` (barycentric or axes), coupling if on; damping terms only if their
    coefficient is positive and ``v`` given.

    Parameters
    ----------
    x, v
        Positions and velocities ``(n, 3)`` (``v`` None: no damping).
    elements, options
        :class:`SpringElements` rest data and :class:`SpringOptions` parts and laws.
    volume_form
        Overrides ``options.volume_form``.

    Returns
    -------
    ndarray
    """
    f = axial_forces(x, v, elements, options)
    if options.torsion != "off":
        f += torsion_forces(x, elements, options)
    if options.barycentric_volume:
        f += volume_forces(x, v, elements, options, volume_form)
    if options.axis_volume or options.coupling:
        f += axis_forces(x, v, elements, options)
    return f


def is_conservative(options: SpringOptions, volume_form: VolumeForm | None = None) -> bool:
    """True if the enabled forces are ``-grad`` of :func:`spring_energy` (no damping, LMS)."""
    return (
        options.axial in ("linear", "quadratic", "cubic")
        and options.torsion in ("off", "energy")
        and (
            not options.barycentric_volume
            or _resolve_volume_form(options, volume_form) == "gradient"
        )
        and options.axial_damping == 0
        and (not options.volume or options.volume_damping == 0)
        and (options.lms is None or not options.barycentric_volume)
    )


def spring_energy(
    x: np.ndarray, elements: SpringElements, options: SpringOptions
) -> tuple[np.ndarray, float]:
    """Spring energy per element ``(m,)`` and in total.

    Exact potential of the energy forms (axial linear/polynomial, torsion ``energy``, volume
    ``gradient``). For the non-gradient laws it reports the nominal energy each law is
    derived from (``stress-scaled``: ``k d^2/2``; ``cosine``: ``k/2 dc^2``; ``cubic``:
    ``k (dc^2/2 + b dc^4/4)``; ``angle``: ``k/2 (alpha - alpha0)^2``, all with the energy
    constant ``k_torsion``), which is what an energy-drift measurement should watch.

    Parameters
    ----------
    x, elements, options
        Positions ``(n, 3)``, rest data and the switched-on parts.

    Returns
    -------
    W, total
        Energy per element ``(m,)`` (J) and its sum.
    """
    X = x[elements.tets]
    q = intersection_points(x, elements)
    _, L, u = _axes(q)
    k, l0 = elements.k_axial, elements.l0
    d = L - l0
    if options.axial in ("quadratic", "cubic"):
        b2, b3 = options.axial_coefficients
        b3 = b3 if options.axial == "cubic" else 0.0
    else:
        b2 = b3 = 0.0
    W = np.sum(k * (d**2 / 2 + b2 * d**3 / (3 * l0) + b3 * d**4 / (4 * l0**2)), axis=1)
    if options.torsion != "off":
        for p, (l, m) in enumerate(TORSION_PAIRS):
            c = np.einsum("kc,kc->k", u[:, l], u[:, m])
            dc = c - elements.c0[:, p]
            kt = elements.k_torsion[:, p]
            if options.torsion == "angle":
                da = np.arccos(np.clip(c, -1.0, 1.0)) - elements.alpha0[:, p]
                W += 0.5 * kt * da**2
            elif options.torsion == "cubic":
                W += kt * (dc**2 / 2 + options.torsion_cubic * dc**4 / 4)
            else:
                W += 0.5 * kt * dc**2
    if options.barycentric_volume:
        r = np.linalg.norm(X - X.mean(axis=1, keepdims=True), axis=-1)
        dL = r.sum(axis=1) - elements.L0
        W += 0.5 * elements.k_volume * dL**2
    if options.axis_volume or options.coupling:
        W += axis_spring_energy(q[:, 0::2] - q[:, 1::2], elements, options)
    return W, float(W.sum())

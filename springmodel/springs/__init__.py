"""Spring forces, the readable numpy oracle: through the six intersection points and ``C^k``.

Every force here is computed on the intersection points ``q_j = sum_i C_ij x_i`` (eq. 2.25)
and distributed to the vertices with the same coefficients, ``f_i = sum_j C_ij f_j``
(eqs. 2.28–2.29), except the volume springs, which act on the vertices directly
(eqs. 2.76–2.77). The kernels (:mod:`springmodel.fastkernels`) must agree with this package.

Modules, one part each: ``points`` (the six points, ``C^k`` and back, scatter), ``axial``,
``torsion``, ``volume`` (barycentric volume springs and the volume measures), ``lms``
(adaptive volume stiffness), ``axis_volume`` (axis-volume and Poisson-coupling forces),
``total`` (:func:`internal_forces`, :func:`is_conservative`) and ``energy``
(:func:`spring_energy`).

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
    * ``shear``: the same with ``c - c0`` replaced by ``dU/dc / k`` of
      ``U = k/2 delta^2``, ``delta = s0^3 (cot(theta) - cot(theta0))``
      (:mod:`springmodel.springs.shear`): ``k/2 tan^2(g)`` in a shear by ``g``, convex at
      every angle, where ``energy`` is ``k/2 sin^2(g)`` and softens past 45 deg.
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

volume (2.76–2.77), ``xi_j = x_j - x_b`` (the restoring sign, docs/spec.rst#the-volume-spring-sign)
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

from .axial import axial_forces, axial_magnitudes
from .axis_volume import axis_forces
from .energy import spring_energy
from .lms import lms_update
from .points import distribute, intersection_points, scatter
from .torsion import torsion_forces
from .total import internal_forces, is_conservative
from .volume import volume_forces, volume_measures

__all__ = [
    "axial_forces",
    "axial_magnitudes",
    "axis_forces",
    "distribute",
    "internal_forces",
    "intersection_points",
    "is_conservative",
    "lms_update",
    "scatter",
    "spring_energy",
    "torsion_forces",
    "volume_forces",
    "volume_measures",
]

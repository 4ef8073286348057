"""Why a spring static solve stopped part way: the element state at the last converged load.

A Newton solve that stops at a load factor below 1 is reported with the spring element's
extreme measures at the last converged state: the axis strains ``|zeta_l| / l0_l - 1``, the
largest shear angle between two axes (``90 deg - theta``, the angle from orthogonal) and the
element volume ratios ``J``. Two readings are attached when they apply:

* ``torsion = "energy"`` past a 40 deg shear angle: that law's energy is ``k/2 sin^2(g)`` in
  a shear by ``g``, its moment peaks at 45 deg and the element loses its shear stiffness
  (``torsion = "shear"`` keeps it, :mod:`springmodel.springs.shear`);
* the axis-volume spring's element pressures ``kappa (J - 1)`` larger than the element's
  shear modulus: nearly incompressible P1-type elements lock, and the geometric stiffness
  of those alternating pressures can make the tangent indefinite. With
  ``volume_average = "nodal"`` the nodal volume ratios ``J_a`` are added and the reading is
  on the nodal pressures ``kappa_a (J_a - 1)`` (:mod:`springmodel.nodal_volume`).

Examples
--------
>>> import numpy as np
>>> from springfem.scene import Material
>>> from springmodel.elements import build_spring_elements
>>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> e = build_spring_elements(X, np.array([[0, 1, 2, 3]]), np.eye(3)[None],
...                           material=Material("linear", 1.0e4, 0.3))
>>> m = axis_measures(X @ np.diag([1.1, 1.0, 1.0]), e)
>>> round(m["strain_max"], 6), round(m["shear_deg"], 6)
(0.1, 0.0)
"""

from __future__ import annotations

import numpy as np

from springfem.errors import SolverError
from springfem.mesh import tet_volumes

from .elements import SpringElements
from .options import SpringOptions
from .rest_geometry import TORSION_PAIRS

#: Shear angle (deg) from which the ``energy`` torsion law is named as the likely limit.
ENERGY_TORSION_LIMIT_DEG = 40.0


def axis_measures(x: np.ndarray, elements: SpringElements) -> dict[str, float]:
    """Extreme axis strains, shear angle and volume ratios at positions ``x``.

    Parameters
    ----------
    x
        Node positions ``(n, 3)``.
    elements
        Spring rest data (its rest volumes ``V0`` give the volume ratios).

    Returns
    -------
    dict
        ``strain_min``, ``strain_max``, ``shear_deg`` (largest angle from orthogonal between
        two axes, rest angle subtracted), ``J_min``, ``J_max`` and ``J`` ``(m,)``.
    """
    zeta = np.einsum("kil,kic->klc", elements.G, x[elements.tets])
    L = np.linalg.norm(zeta, axis=2)
    strain = L / elements.l0 - 1.0
    u = zeta / L[..., None]
    shear = 0.0
    for p, (a, b) in enumerate(TORSION_PAIRS):
        c = np.clip(np.einsum("kc,kc->k", u[:, a], u[:, b]), -1.0, 1.0)
        g = np.abs(np.arcsin(c) - np.arcsin(np.clip(elements.c0[:, p], -1.0, 1.0)))
        shear = max(shear, float(np.degrees(g).max()))
    J = tet_volumes(x, elements.tets) / elements.V0  # the tets' volume ratios
    return {
        "strain_min": float(strain.min()),
        "strain_max": float(strain.max()),
        "shear_deg": shear,
        "J_min": float(J.min()),
        "J_max": float(J.max()),
        "J": J,
    }


def stop_reason(
    x: np.ndarray,
    x0: np.ndarray,
    elements: SpringElements,
    options: SpringOptions,
    stiffening=None,
) -> str:
    """One clause on the element state at ``x`` (the last converged state), with a reading.

    Parameters
    ----------
    x, x0
        Node positions ``(n, 3)`` and their rest positions.
    elements, options
        The spring model's rest data and options.
    stiffening
        The model's :class:`~springmodel.stiffening.StiffeningPart` (its largest ``s_e`` is
        named), or None.

    Returns
    -------
    str
        e.g. ``axis strains -37% to +53%, shear angle up to 53 deg, volume ratio 0.961 to
        1.044`` and the readings that apply.
    """
    m = axis_measures(x, elements)
    text = (
        f"axis strains {m['strain_min']:+.0%} to {m['strain_max']:+.0%}, shear angle up to "
        f"{m['shear_deg']:.0f} deg, volume ratio {m['J_min']:.3g} to {m['J_max']:.3g}"
    )
    if options.nodal_volume:  # the pressures live on the nodes (springmodel.nodal_volume)
        from .nodal_volume import NodalVolume

        k = options.nodal_fraction * np.asarray(elements.k_axis_volume)
        term = NodalVolume(x0, elements.tets, k, options.volumetric)
        Ja = term.ratios(x)
        text += f", nodal volume ratio {Ja.min():.3g} to {Ja.max():.3g}"
    if stiffening is not None:
        s_max = float(np.max(stiffening.scale(x)[1]))
        text += (
            f", stiffening factor up to {s_max:.3g}"
            if np.isfinite(s_max)
            else (", an element past the stiffening's cap (exponent above 60)")
        )
    if options.torsion == "energy" and m["shear_deg"] >= ENERGY_TORSION_LIMIT_DEG:
        text += (
            "; the energy torsion law's moment peaks at 45 deg of shear, beyond which the "
            'element loses its shear stiffness (torsion = "shear" keeps it)'
        )
    if options.axis_volume:
        mu = np.median(elements.k_torsion / elements.V0[:, None])
        if options.nodal_volume:
            p = np.abs(term.kappa * (Ja - 1.0)).max()
        else:
            p = np.abs(np.asarray(elements.k_axis_volume) * (m["J"] - 1.0)).max()
        if mu > 0 and p > mu and options.nodal_volume:
            text += f"; nodal pressures kappa |J_a - 1| up to {p / mu:.3g} x the shear modulus"
        elif mu > 0 and p > mu:
            text += (
                f"; volume-spring pressures kappa |J - 1| up to {p / mu:.3g} x the shear "
                "modulus: a nearly incompressible P1-type element locks and their geometric "
                "stiffness can make the tangent indefinite"
            )
    return text


def stopped_error(
    exc: SolverError,
    x0: np.ndarray,
    elements: SpringElements,
    options: SpringOptions,
    stiffening=None,
) -> SolverError:
    """The spring model's :class:`SolverError` for a solver's ``exc`` (positions as state).

    The state becomes the displacement; a static solve that stopped part way
    (``exc.load_factor`` set) gets ``spring`` in front and :func:`stop_reason` at its last
    converged state after its message.

    Parameters
    ----------
    exc
        The solver's error; ``exc.state`` the last good positions ``(n, 3)`` or ``None``.
    x0
        Rest positions ``(n, 3)``.
    elements, options
        The spring model's rest data and options.
    stiffening
        The model's stiffening part or None (see :func:`stop_reason`).

    Returns
    -------
    SolverError
        With ``state`` the displacement ``(n, 3)`` (or ``None``) and ``load_factor`` kept.
    """
    if exc.state is None:
        return SolverError(str(exc), state=None, load_factor=exc.load_factor)
    x = np.asarray(exc.state, dtype=float).reshape(-1, 3)
    message = str(exc)
    if exc.load_factor is not None and np.isfinite(x).all():
        why = stop_reason(x, x0, elements, options, stiffening)
        message = f"spring {message}; at load factor {exc.load_factor:.4g}: {why}"
    return SolverError(message, state=x - x0, load_factor=exc.load_factor)

"""The energies Vertex Block Descent minimises, per element, in numpy: the stable neo-Hookean
density of :mod:`peers.xpbd.constraints` (the same ``mu', lam', gamma``) and isotropic linear
elasticity, with a vertex's gradient and its 3 x 3 Hessian block.

With ``F = sum_b x_b (x) g_b`` (``g_b = grad N_b``), the gradient of ``V psi(F)`` with respect
to vertex ``a`` is ``V P g_a`` and its Hessian block is ``V sum_JL A_rJsL g_J g_L`` with the
tangent moduli ``A = dP/dF``. For the stable neo-Hookean density
``psi = mu'/2 (I_C - 3) + lam'/2 (J - gamma)^2``::

    A = mu' I (x) I + lam' cof F (x) cof F + lam' (J - gamma) d cof F / dF

and the last term contracts to zero with ``g_a g_a`` (``d cof F_iJ / dF_kL = eps_ikm eps_JLN
F_mN`` is antisymmetric in ``J, L``), so the block is ``V (mu' |g_a|^2 I + lam' c c^T)``,
``c = cof F g_a``: positive definite for every ``F`` (``mu' > 0``, ``lam' > 0``), inverted
elements included. Linear elasticity (``psi = mu eps:eps + lam/2 tr(eps)^2``,
``eps = sym F - I``) has the constant block ``V (mu |g|^2 I + (mu + lam) g g^T)``, positive
definite too. No projection to positive definiteness is therefore ever needed for these two
energies (Chen et al. 2024 project blocks for laws whose blocks can be indefinite).

Examples
--------
>>> import numpy as np
>>> F = np.array([[1.1, 0.2, 0.0], [0.0, 0.9, 0.1], [0.05, 0.0, 1.2]])
>>> H = vertex_block(F, np.array([0.3, -0.2, 0.5]), 1.0, 2.0, 1.5, "stable-neo-hookean")
>>> bool(np.all(np.linalg.eigvalsh(H) > 0))
True
"""

from __future__ import annotations

import numpy as np

from ..xpbd.constraints import cofactor
from ..xpbd.constraints import energy_density as stable_density
from ..xpbd.constraints import first_piola as stable_piola

#: Law codes of the compiled kernels.
LAW_CODES = {"stable-neo-hookean": 0, "linear": 1}


def density(F: np.ndarray, mu: float, lam: float, gamma: float, law: str) -> np.ndarray:
    """Energy density ``psi(F)`` ``(...,)``; zero at rest.

    Parameters
    ----------
    F
        ``(..., 3, 3)``.
    mu, lam, gamma
        ``stable-neo-hookean``: the moduli of :func:`peers.xpbd.constraints.stable_neo_hookean`;
        ``linear``: the scene's ``mu, lam`` (``gamma`` unused).
    law
        A key of :data:`LAW_CODES`.

    Returns
    -------
    ndarray
    """
    if law == "stable-neo-hookean":
        return stable_density(F, mu, lam, gamma)
    eps = 0.5 * (F + np.swapaxes(F, -1, -2)) - np.eye(3)
    tr = np.trace(eps, axis1=-2, axis2=-1)
    return mu * np.einsum("...ij,...ij->...", eps, eps) + 0.5 * lam * tr**2


def first_piola(F: np.ndarray, mu: float, lam: float, gamma: float, law: str) -> np.ndarray:
    """``P = dpsi/dF`` ``(..., 3, 3)`` (arguments as :func:`density`)."""
    if law == "stable-neo-hookean":
        return stable_piola(F, mu, lam, gamma)
    eps = 0.5 * (F + np.swapaxes(F, -1, -2)) - np.eye(3)
    tr = np.trace(eps, axis1=-2, axis2=-1)
    return 2.0 * mu * eps + lam * tr[..., None, None] * np.eye(3)


def vertex_block(
    F: np.ndarray, g: np.ndarray, mu: float, lam: float, gamma: float, law: str
) -> np.ndarray:
    """The Hessian block ``d^2 psi / dx_a^2`` ``(3, 3)`` of one element at one vertex, per
    unit volume (the module docstring derives it).

    Parameters
    ----------
    F
        ``(3, 3)``.
    g
        The vertex's shape gradient ``grad N_a`` ``(3,)``.
    mu, lam, gamma, law
        As :func:`density`.

    Returns
    -------
    ndarray
    """
    gg = float(g @ g)
    if law == "stable-neo-hookean":
        c = cofactor(F[None])[0] @ g
        return mu * gg * np.eye(3) + lam * np.outer(c, c)
    return mu * gg * np.eye(3) + (mu + lam) * np.outer(g, g)


__all__ = ["LAW_CODES", "density", "first_piola", "vertex_block"]

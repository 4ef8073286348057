"""Exponential stiffening of the spring element, the shape of the Guccione law (beyond the spec).

The spec's springs are quadratic in their measures: calibrated from a tissue law's
small-strain tangent they are right at rest and ever softer than the law as it stretches
(Guccione, Holzapfel-Ogden: ``e^Q``). A pressurised ventricle of such springs has a largest
pressure it can carry (the balloon's limit point), and Land et al.'s 10 kPa lies beyond it.
``[spring] stiffening = "exponential"`` wraps the element's deviatoric spring energy ``W_q``
(axial + energy torsion + Poisson coupling; the volume springs stay as they are) the way the
Guccione law wraps its quadratic form ``Q``::

    W_e = V C/2 (exp(2 W_q / (C V)) - 1),       s_e = dW_e / dW_q = exp(2 W_q / (C V))

``C`` (Pa) is the law's ``C`` for ``guccione``, ``a_f / b_f`` for ``holzapfel-ogden`` (the
fibre term's shape, :func:`stiffening_modulus`) or ``[spring] stiffening_modulus``. To second
order ``W_e = W_q``, so the small-strain tangent and every calibration are unchanged; with the
exact calibration of a Guccione material ``2 W_q / (C V)`` is the law's ``Q`` to leading order
(its normal-strain coupling is the penalty's alone, which the axis-volume spring carries).

Because ``W_q`` is linear in the spring constants, the forces are the deviatoric forces of
constants scaled by ``s_e``: the model adds ``-(s_e - 1) grad W_q`` to the kernel's forces, and
``(s_e - 1) H_q + 2 s_e / (C V) g g^T`` (``g = grad W_q``) to its tangent
(:class:`StiffeningPart`). The element stiffens by ``s_e`` as it strains: an explicit run's
critical step, estimated at rest, shrinks by about ``sqrt(s_e)`` (lower ``dt_safety`` for
large strains; the blow-up detector names the step that fails).

Examples
--------
>>> import numpy as np
>>> round(float(stiffened_energy(np.array([0.5]), np.array([1.0]), 10.0)[0]), 12)  # C/2 (e^0.1 - 1)
0.525854590378
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from springfem.errors import InputError
from springfem.materials.laws import LAWS

from .hessian import TORSION_CODES, SpringHessian
from .hessian_numpy import polynomial_coefficients
from .options import SpringOptions
from .rest_geometry import TORSION_PAIRS
from .springs.shear import shear_derivatives, shear_energy

__all__ = [
    "MAX_EXPONENT",
    "StiffeningPart",
    "deviatoric_energy",
    "stiffened_energy",
    "stiffening_modulus",
]
#: Elements per block of :meth:`StiffeningPart.stiffness` (bounds its element matrices).
CHUNK = 16384
#: Largest exponent ``2 W_q / (C V)`` evaluated: beyond it the state is far outside any tissue
#: law's range (``e^60``) and the forces are reported as not finite, so that Newton cuts back.
MAX_EXPONENT = 60.0


def stiffening_modulus(options: SpringOptions, material) -> float:
    """The modulus ``C`` (Pa) of the stiffening: ``stiffening_modulus``, else the law's.

    The law's is its :meth:`~springfem.materials.laws.base.TissueLaw.stiffening_modulus`
    (``guccione``: its ``C``; ``holzapfel-ogden``: ``a_f / b_f``).

    Parameters
    ----------
    options
        Spring options (``stiffening``, ``stiffening_modulus``).
    material
        The scene's :class:`~springfem.scene.Material` (``law``, ``parameters``).

    Returns
    -------
    float
        ``C`` (Pa).

    Raises
    ------
    InputError
        Stiffening on, no modulus given and the law gives none (not ``guccione``, nor
        ``holzapfel-ogden`` with ``a_f, b_f > 0``): a scene error (exit 2).

    Examples
    --------
    >>> from springfem.scene import Material
    >>> opts = SpringOptions(torsion="energy", stiffening="exponential")
    >>> stiffening_modulus(opts, Material("guccione", 1.0, 0.49, parameters={"C": 2.0}))
    2.0
    """
    if options.stiffening_modulus is not None:
        return float(options.stiffening_modulus)
    law = getattr(material, "law", None)
    p = getattr(material, "parameters", {}) or {}
    modulus = LAWS[law].stiffening_modulus(p) if law in LAWS else None
    if modulus is not None:
        return modulus
    raise InputError(
        f'[spring] stiffening = "exponential" needs stiffening_modulus for law {law!r} '
        "(the defaults: guccione's C, holzapfel-ogden's a_f / b_f when both are positive)"
    )


def stiffened_energy(W_q: np.ndarray, V: np.ndarray, C: float) -> np.ndarray:
    """``W_e = V C/2 (exp(2 W_q / (C V)) - 1)`` of each element, ``(m,)``.

    Parameters
    ----------
    W_q
        Deviatoric spring energy per element ``(m,)`` (J).
    V
        Rest volumes ``(m,)`` (m³).
    C
        Stiffening modulus (Pa).

    Returns
    -------
    ndarray
        ``(m,)`` (J); ``inf`` beyond :data:`MAX_EXPONENT`.
    """
    q = 2.0 * W_q / (C * V)
    with np.errstate(over="ignore"):
        W = 0.5 * C * V * np.expm1(np.minimum(q, MAX_EXPONENT))
    return np.where(q <= MAX_EXPONENT, W, np.inf)


def deviatoric_energy(x: np.ndarray, elements, options: SpringOptions):
    """Energy ``W_q`` of the axial, torsion and coupling springs per element, and its gradient.

    The vectorised numpy reference of :mod:`springmodel.stiffening_kernel` (the model runs
    the compiled pass); the energy alone is also :func:`springmodel.springs.spring_energy`
    with the volume terms off, written again here to carry its gradient per element.

    ``W_q = sum_l f_l(|zeta_l|) + sum_lm k_lm phi(c_lm) + sum_lm c_lm s_l s_m`` (the
    polynomial axial law of eq. 2.36, the torsion law ``energy`` or ``shear``, the Poisson
    coupling) with ``zeta_l = sum_i G[k, i, l] x_i``.

    Parameters
    ----------
    x
        Node positions ``(n, 3)``.
    elements
        :class:`~springmodel.elements.SpringElements`.
    options
        Spring options (axial law and coefficients, torsion law, coupling).

    Returns
    -------
    W, grad
        ``(m,)`` (J) and ``dW / dx`` of each element's four vertices ``(m, 4, 3)`` (N).
    """
    el = elements
    zeta = np.einsum("kil,kic->klc", el.G, x[el.tets])
    L = np.linalg.norm(zeta, axis=-1)
    zh = zeta / L[..., None]
    d = L - el.l0
    b2, b3 = polynomial_coefficients(options)
    W = np.sum(el.k_axial * (d**2 / 2 + b2 * d**3 / (3 * el.l0) + b3 * d**4 / (4 * el.l0**2)), 1)
    df = el.k_axial * (d + b2 * d**2 / el.l0 + b3 * d**3 / el.l0**2)
    gz = df[..., None] * zh
    s = L / el.l0 - 1.0
    for p, (l, m) in enumerate(TORSION_PAIRS):
        if options.torsion != "off":
            c = np.einsum("kc,kc->k", zh[:, l], zh[:, m])
            kt, c0 = el.k_torsion[:, p], el.c0[:, p]
            if options.torsion == "shear":
                W += kt * shear_energy(c, c0)
                d1 = kt * shear_derivatives(c, c0)[0]
            else:
                W += 0.5 * kt * (c - c0) ** 2
                d1 = kt * (c - c0)
            gz[:, l] += d1[:, None] * (zh[:, m] - c[:, None] * zh[:, l]) / L[:, l, None]
            gz[:, m] += d1[:, None] * (zh[:, l] - c[:, None] * zh[:, m]) / L[:, m, None]
        if options.coupling:
            cp = el.k_coupling[:, p]
            W += cp * s[:, l] * s[:, m]
            gz[:, l] += (cp * s[:, m] / el.l0[:, l])[:, None] * zh[:, l]
            gz[:, m] += (cp * s[:, l] / el.l0[:, m])[:, None] * zh[:, m]
    return W, np.einsum("kil,klc->kic", el.G, gz)


class StiffeningPart:
    """The exponential stiffening of a :class:`~springmodel.model.SpringModel` (module text).

    The spring kernel keeps computing the quadratic element; this part adds the difference:
    forces ``-(s_e - 1) grad W_q``, energy ``W_e - W_q`` and tangent
    ``(s_e - 1) H_q + 2 s_e / (C V) g g^T`` per element.

    Parameters
    ----------
    elements
        The kernel's spring elements.
    options
        Spring options (the energy forms: :class:`~springmodel.options.SpringOptions`
        refuses stiffening of the others).
    modulus
        ``C`` (Pa), :func:`stiffening_modulus`.

    Examples
    --------
    >>> from springfem.mesh import box_mesh
    >>> from springfem.scene import Material
    >>> from springmodel.elements import build_spring_elements
    >>> mesh = box_mesh((1.0, 1.0, 1.0), (1, 1, 1))
    >>> opts = SpringOptions(volume="axes", torsion="shear", calibration="exact",
    ...                      stiffening="exponential", stiffening_modulus=1.0e4)
    >>> el = build_spring_elements(mesh.points, mesh.tets, np.tile(np.eye(3), (6, 1, 1)),
    ...                            opts, Material("linear", 1.0e4, 0.3))
    >>> part = StiffeningPart(el, opts, 1.0e4)
    >>> float(abs(part.forces(mesh.points)).max()), part.energy(mesh.points)  # none at rest
    (0.0, 0.0)
    """

    def __init__(self, elements, options: SpringOptions, modulus: float):
        replace(options, stiffening="exponential")  # SpringOptions refuses a non-energy
        self.elements, self.options, self.modulus = elements, options, float(modulus)
        self._hessian = None
        el = elements
        self._args = (
            np.ascontiguousarray(el.tets, dtype=np.int64), np.ascontiguousarray(el.G),
            np.ascontiguousarray(el.l0), np.ascontiguousarray(el.k_axial),
            np.ascontiguousarray(el.k_torsion), np.ascontiguousarray(el.c0),
            np.ascontiguousarray(el.k_coupling), np.ascontiguousarray(el.V0),
            *polynomial_coefficients(options), TORSION_CODES[options.torsion],
            bool(options.coupling), self.modulus, MAX_EXPONENT,
        )  # fmt: skip

    def _pass(self, x: np.ndarray, forces: bool, gradients: bool = False):
        """``W_q``, ``s_e``, the added forces (zero unless ``forces``) and, with
        ``gradients``, ``grad W_q`` per element (else ``None``)."""
        from .stiffening_kernel import stiffening_pass

        x = np.ascontiguousarray(x, dtype=float).reshape(-1, 3)
        m = self.elements.n_elements
        W, s, f = np.empty(m), np.empty(m), np.zeros((x.shape[0] if forces else 1, 3))
        g = np.empty((m if gradients else 1, 4, 3))
        stiffening_pass(x, *self._args, W, s, f, forces, g, gradients)
        return W, s, f, (g if gradients else None)

    def scale(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``W_q`` and ``s_e`` of every element.

        Parameters
        ----------
        x
            Node positions ``(n, 3)``.

        Returns
        -------
        W, s
            ``(m,)`` (J) and ``(m,)`` (``inf`` past :data:`MAX_EXPONENT`).
        """
        W, s, _, _ = self._pass(x, False)
        return W, s

    def forces(self, x: np.ndarray) -> np.ndarray:
        """Nodal forces ``-(s_e - 1) grad W_q`` added to the kernel's.

        Parameters
        ----------
        x
            Node positions ``(n, 3)``.

        Returns
        -------
        ndarray
            ``(n, 3)`` (N); not finite past :data:`MAX_EXPONENT` (Newton then cuts back).
        """
        with np.errstate(invalid="ignore", over="ignore"):
            return self._pass(x, True)[2]

    def energy(self, x: np.ndarray) -> float:
        """``sum_e (W_e - W_q)``, the energy added to the kernel's.

        Parameters
        ----------
        x
            Node positions ``(n, 3)``.

        Returns
        -------
        float
            (J); ``inf`` past :data:`MAX_EXPONENT`.
        """
        W, _, _, _ = self._pass(x, False)
        with np.errstate(invalid="ignore", over="ignore"):
            return float(np.sum(stiffened_energy(W, self.elements.V0, self.modulus) - W))

    def element_matrices(
        self,
        x: np.ndarray,
        lo: int = 0,
        hi: int | None = None,
        s: np.ndarray | None = None,
        g: np.ndarray | None = None,
    ) -> np.ndarray:
        """Tangent added per element: ``(s - 1) H_q + 2 s / (C V) g g^T``.

        Parameters
        ----------
        x
            Node positions ``(n, 3)``.
        lo, hi
            The elements ``lo:hi`` (default all).
        s, g
            ``s_e`` ``(m,)`` and ``grad W_q`` ``(m, 4, 3)`` of all elements at ``x``
            (computed when not given).

        Returns
        -------
        ndarray
            ``(hi - lo, 12, 12)``, rows as
            :meth:`springmodel.hessian.SpringHessian.element_matrices`.
        """
        el = self.elements
        hi = el.n_elements if hi is None else hi
        if self._hessian is None:
            zero = np.zeros(el.n_elements)
            deviatoric = replace(el, k_axis_volume=zero, k_volume=zero)
            opts = replace(self.options, volume=False, volume_average="element")
            self._hessian = SpringHessian(deviatoric, opts)
        x = np.asarray(x, float).reshape(-1, 3)
        if s is None or g is None:
            _, s, _, g = self._pass(x, False, gradients=True)
        s, g = s[lo:hi], g[lo:hi].reshape(-1, 12)
        H = self._hessian.element_matrices(x, lo=lo, hi=hi)
        with np.errstate(invalid="ignore", over="ignore"):
            H *= (s - 1.0)[:, None, None]
            H += (2.0 * s / (self.modulus * el.V0[lo:hi]))[:, None, None] * (
                g[:, :, None] * g[:, None, :]
            )
        return H

    def stiffness(self, x: np.ndarray):
        """The added tangent as a ``(3n, 3n)`` CSR matrix, :data:`CHUNK` elements at a time.

        Parameters
        ----------
        x
            Node positions ``(n, 3)``.

        Returns
        -------
        scipy.sparse.csr_matrix
            ``sum_e`` of :meth:`element_matrices` on the tets' DOFs.
        """
        m = self.elements.n_elements
        _, s, _, g = self._pass(x, False, gradients=True)
        blocks = []
        for lo in range(0, m, CHUNK):
            blocks.append((lo, self.element_matrices(x, lo, min(lo + CHUNK, m), s, g)))
        return self._hessian.assemble(blocks)

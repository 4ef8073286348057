"""The tissue element: Green axial and Green torsion springs, the law of their measures.

An axis vector follows the tet's deformation exactly, ``zeta_l = F zeta_l^0``, and the rest
axis vectors are parallel to the orthonormal frame axes ``a_l`` (docs/theory.rst), so with
``Z_l = zeta_l / l_l^0 = F a_l`` the springs measure the Cauchy–Green tensor in the frame::

    m_l  = Z_l . Z_l = C'_ll = 1 + 2 E_ll         (Green axial spring of axis l)
    m_lm = Z_l . Z_m = C'_lm = 2 E_lm             (Green torsion spring of the pair l, m)

The Green axial spring's energy ``k l0^2 E_ll^2 / 2`` (``axial = "green"``) and the Green
torsion ``k/2 (m_lm - m_lm^0)^2`` (``torsion = "green"``) are functions of these six
measures, and so is any law ``W(E)``: the element sees all of ``E``, under any deformation.
The old torsion measure ``cot theta`` of the ``shear`` law equals ``m_lm`` only while
``|Z_l x Z_m| = 1``, which a simple shear breaks.

The element's deviatoric energy ``W(m)`` (the volume term ``V0 U(J)`` stays on the
axis-volume spring of the fused kernel) is, by ``[spring] stiffening``:

- ``off``: the quadratic springs ``W_q`` (axial, Green torsion, Poisson coupling);
- ``exponential``: ``V C/2 (exp(2 W_q / (C V)) - 1)`` (:mod:`springmodel.stiffening`); with the
  ``exact`` calibration of a Guccione material ``2 W_q / (C V)`` is Guccione's ``Q`` exactly;
- ``law``: each spring group stiffens as the law's terms do. ``guccione``: one exponent for
  all springs, ``V C/2 (e^Q - 1)``, ``Q = sum_l b_l E_ll^2 + sum_lm 2 b_lm E_lm^2`` (the same
  energy as ``exponential``). ``holzapfel-ogden``: one modulus and exponent per group, the
  fibre axial spring ``a_f/(2 b_f) (e^{b_f (m_f - 1)^2} - 1)`` and the sheet axial spring
  (``a_s, b_s``) in tension only, the fibre–sheet torsion ``a_fs/(2 b_fs)
  (e^{b_fs m_fs^2} - 1)``, and the isotropic rest ``a/(2 b) (e^{b (I1bar - 3)} - 1)`` on the
  three axial springs and the axis volume, ``I1bar = J^{-2/3} sum_l m_l`` with
  ``J^2 = det C'(m)``. Another registered law: its own energy as a function of
  ``C'(m)`` (:func:`law_derivatives`, numpy; the two above are written out for the compiled
  pass and equal their laws to round-off). The axis-volume spring carries the law's
  ``kappa``.

The forces and tangent follow by the chain rule through the measures, which are quadratic in
the positions (their second derivatives are constant): ``dW/dZ_l = 2 W_l Z_l +
sum_m W_lm Z_m`` and ``zeta_l = sum_i G_il x_i``. :func:`tissue_energy` is the vectorised
numpy reference; the model runs the compiled pass :mod:`springmodel.tissue_kernel`.
The derivation: docs/tissue.rst#the-tissue-element-on-the-green-strain.

Examples
--------
Under a simple shear ``gamma`` of the frame's f–s plane the Green torsion of that pair is
``gamma = 2 E_fs`` and the sheet's axial measure ``1 + gamma^2``; ``cot theta`` is ``gamma``
too, but it does not change when the axes stretch, so its stress is not the law's:

>>> import numpy as np
>>> F = np.eye(3); F[0, 1] = 0.3
>>> m = frame_measures(np.eye(3)[None] @ F.T)  # Z_l = F a_l as rows
>>> np.round(m[0], 12).tolist()  # C_ff, C_ss, C_nn, C_fs, C_fn, C_sn
[1.0, 1.09, 1.0, 0.3, 0.0, 0.0]
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from springfem.errors import InputError
from springfem.materials.elastic import tissue_matrix
from springfem.materials.laws import TISSUE_LAWS, TissueLaw, small_strain_tangent, tissue_law

from .hessian_numpy import polynomial_coefficients
from .options import SpringOptions
from .presets import LAW_TERMS
from .rest_geometry import TORSION_PAIRS
from .tissue_generic import law_derivatives

__all__ = [
    "MODES",
    "TissueLawParameters",
    "TissuePart",
    "frame_measures",
    "kernel_split",
    "law_elements",
    "law_parameters",
    "measure_derivatives",
    "tissue_energy",
]
#: Elements per block of :meth:`TissuePart.stiffness`.
CHUNK = 16384
#: Largest exponent of any exponential evaluated (as :data:`springmodel.stiffening.MAX_EXPONENT`):
#: beyond it the energy is ``inf`` and the forces not finite, so that Newton cuts back.
MAX_EXPONENT = 60.0
#: ``I4 - 1`` above which a Holzapfel–Ogden fibre or sheet counts as in tension (the FEM's).
TENSION = 1e-12
#: The element's energy by code: quadratic springs, exponential stiffening, Guccione, HO.
MODES = {
    "springs": 0, "exponential": 1, **{law: 2 + i for i, law in enumerate(LAW_TERMS)}, "law": -1,
}  # fmt: skip
#: ``(l, m)`` of measure ``3 + p`` (the torsion pairs (0,1), (0,2), (1,2)).
_PAIRS = np.array(TORSION_PAIRS, dtype=np.int64)


@dataclass(frozen=True)
class TissueLawParameters:
    """What the element's energy is (module text).

    Attributes
    ----------
    mode
        A key of :data:`MODES`.
    modulus
        ``C`` of the exponential stiffening (``exponential``; 1 otherwise).
    law
        ``guccione``: ``(C, b_f, b_t, b_fs, 0, 0, 0, 0)``; ``holzapfel-ogden``:
        ``(a, b, a_f, b_f, a_s, b_s, a_fs, b_fs)``; zeros otherwise.
    b2, b3
        The axial springs' polynomial coefficients (eq. 2.36).
    tissue
        Mode ``law``: a tissue law without terms of its own here (not in
        :data:`~springmodel.presets.LAW_TERMS`), passive and without its penalty; the
        element's energy is the law's, in numpy (:func:`law_derivatives`).
    """

    mode: str
    modulus: float = 1.0
    law: tuple[float, ...] = (0.0,) * 8
    b2: float = 0.0
    b3: float = 0.0
    tissue: TissueLaw | None = None

    @property
    def code(self) -> int:
        return MODES[self.mode]


def law_parameters(options: SpringOptions, material, modulus: float | None) -> TissueLawParameters:
    """The element's energy for ``options`` and the scene's material.

    Parameters
    ----------
    options
        Spring options (``stiffening``, axial coefficients).
    material
        The scene's :class:`~springfem.scene.Material`.
    modulus
        ``C`` of the ``exponential`` stiffening (:func:`springmodel.stiffening.stiffening_modulus`).

    Returns
    -------
    TissueLawParameters

    Raises
    ------
    InputError
        ``stiffening = "law"`` with a law that is not a tissue law (a scene error).
    """
    b2, b3 = polynomial_coefficients(options)
    if options.stiffening == "off":
        return TissueLawParameters("springs", b2=b2, b3=b3)
    if options.stiffening == "exponential":
        return TissueLawParameters("exponential", float(modulus or 1.0), b2=b2, b3=b3)
    law = getattr(material, "law", None)
    if law not in TISSUE_LAWS:
        raise InputError(
            f'[spring] stiffening = "law" needs a tissue law ({", ".join(TISSUE_LAWS)}), '
            f"got {law!r}"
        )
    if law not in LAW_TERMS:
        passive = replace(tissue_law(material, kappa=0.0), active_tension=0.0)
        return TissueLawParameters("law", b2=b2, b3=b3, tissue=passive)
    p = material.parameters
    values = tuple(float(p[k]) for k in TISSUE_LAWS[law])
    return TissueLawParameters(law, law=values + (0.0,) * (8 - len(values)), b2=b2, b3=b3)


def law_kappa(material) -> float:
    """The bulk modulus of a tissue law's penalty as the calibration takes it (Pa).

    ``parameters.kappa``, or for an incompressible material the stand-in of
    :func:`springfem.materials.tissue_matrix`: the difference of its normal-block coupling
    with and without the penalty.
    """
    params = {k: float(v) for k, v in material.parameters.items()}
    with_penalty = tissue_matrix(material)[1, 2]
    return float(with_penalty - small_strain_tangent(material.law, params, kappa=0.0)[1, 2])


def law_elements(elements, options: SpringOptions, material):
    """The calibrated elements as the tissue element takes them.

    With ``stiffening = "law"`` the element is the law's own P1 element (no calibration
    mismatch), and its axis-volume spring carries the law's ``kappa`` (:func:`law_kappa`);
    this comes before the volume and strain are shared out between elements and nodes
    (:meth:`NodalPart.split <springmodel.nodal_volume.NodalPart.split>`,
    :meth:`NodalStrainPart.split <springmodel.nodal_strain.NodalStrainPart.split>`), which
    scale it. Other elements are returned as they are.

    Parameters
    ----------
    elements
        The calibrated :class:`~springmodel.elements.SpringElements`.
    options
        Spring options.
    material
        The scene's material.

    Returns
    -------
    SpringElements
    """
    if options.stiffening != "law":
        return elements
    m = elements.n_elements
    return replace(elements, mismatch=np.zeros(m), k_axis_volume=np.full(m, law_kappa(material)))


def kernel_split(elements, options: SpringOptions):
    """The fused kernel's share of a tissue element: its volume spring alone.

    The tissue pass owns the axial, torsion and coupling springs, so the kernel's copy has
    their constants at zero and the torsion off; its axis-volume spring is the elements'
    (the law's ``kappa`` with ``stiffening = "law"``, :func:`law_elements`).

    Parameters
    ----------
    elements
        The calibrated :class:`~springmodel.elements.SpringElements` (after the nodal
        splits).
    options
        Spring options with ``torsion = "green"``.

    Returns
    -------
    elements, options
        For :class:`~springmodel.spring_kernel.SpringKernel` and
        :class:`~springmodel.hessian.SpringHessian`.
    """
    zero = np.zeros((elements.n_elements, 3))
    kernel_elements = replace(elements, k_axial=zero, k_torsion=zero, k_coupling=zero)
    kernel_options = replace(
        options, axial="linear", axial_coefficients=(0.0, 0.0), torsion="off",
        coupling=False, stiffening="off", stiffening_modulus=None,
    )  # fmt: skip
    return kernel_elements, kernel_options


def frame_measures(Z: np.ndarray) -> np.ndarray:
    """The six measures ``m = (C'_00, C'_11, C'_22, C'_01, C'_02, C'_12)``, ``(m, 6)``.

    Parameters
    ----------
    Z
        ``Z_l = zeta_l / l_l^0`` as rows, ``(m, 3, 3)``.

    Returns
    -------
    ndarray
        Axial measures ``Z_l . Z_l``, then the torsion pairs' ``Z_l . Z_m``.
    """
    out = np.empty(Z.shape[:-2] + (6,))
    out[..., :3] = np.einsum("...lc,...lc->...l", Z, Z)
    for p, (l, m) in enumerate(TORSION_PAIRS):
        out[..., 3 + p] = np.einsum("...c,...c->...", Z[..., l, :], Z[..., m, :])
    return out


def _exp_term(a, b, x, on):
    """``psi = a/(2b)(e^{b x^2} - 1)`` and its first two derivatives (zero where not ``on``)."""
    q = b * x**2
    big = q > MAX_EXPONENT
    e = np.exp(np.minimum(q, MAX_EXPONENT))
    psi = np.where(big, np.inf, a / (2 * b) * (e - 1.0))
    d1, d2 = a * x * e, a * (1.0 + 2.0 * b * x**2) * e
    return np.where(on, psi, 0.0), np.where(on, d1, 0.0), np.where(on, d2, 0.0), np.where(on, e, 1)


def _det_derivatives(m: np.ndarray):
    """``det C'(m)``, its gradient ``(k, 6)`` and Hessian ``(k, 6, 6)`` in the measures."""
    c0, c1, c2, c01, c02, c12 = (m[:, i] for i in range(6))
    D = c0 * c1 * c2 + 2 * c01 * c02 * c12 - c0 * c12**2 - c1 * c02**2 - c2 * c01**2
    dD = np.stack(
        [c1 * c2 - c12**2, c0 * c2 - c02**2, c0 * c1 - c01**2,
         2 * (c02 * c12 - c2 * c01), 2 * (c01 * c12 - c1 * c02), 2 * (c01 * c02 - c0 * c12)],
        axis=1,
    )  # fmt: skip
    H = np.zeros((m.shape[0], 6, 6))
    for (i, j), v in {
        (0, 1): c2, (0, 2): c1, (1, 2): c0, (0, 5): -2 * c12, (1, 4): -2 * c02,
        (2, 3): -2 * c01, (3, 4): 2 * c12, (3, 5): 2 * c02, (4, 5): 2 * c01,
    }.items():  # fmt: skip
        H[:, i, j] = H[:, j, i] = v
    H[:, 3, 3], H[:, 4, 4], H[:, 5, 5] = -2 * c2, -2 * c1, -2 * c0
    return D, dD, H


def measure_derivatives(m: np.ndarray, elements, params: TissueLawParameters, hessian: bool):
    """Energy ``W(m)`` of each element, ``dW/dm`` ``(k, 6)``, ``d2W/dm2`` and its factor.

    Parameters
    ----------
    m
        Measures ``(k, 6)`` (:func:`frame_measures`) of all elements.
    elements
        :class:`~springmodel.elements.SpringElements` (constants, ``l0``, ``c0``, ``V0``).
    params
        :class:`TissueLawParameters`.
    hessian
        Also return ``d2W/dm2`` ``(k, 6, 6)`` (else ``None``).

    Returns
    -------
    W, dW, ddW, s
        ``(k,)`` (J), ``(k, 6)``, ``(k, 6, 6)`` or None, and the stiffening factor ``s``
        ``(k,)``: ``e^q`` of the exponential (the largest group's for Holzapfel–Ogden; 1 for
        the quadratic springs); ``W = inf`` past :data:`MAX_EXPONENT`.
    """
    el = elements
    k = m.shape[0]
    V = el.V0
    dW = np.zeros((k, 6))
    ddW = np.zeros((k, 6, 6)) if hessian else None
    diag = np.arange(3)
    if params.mode in ("springs", "exponential"):
        lam = np.sqrt(m[:, :3])
        s = lam - 1.0
        kl2 = el.k_axial * el.l0**2
        b2, b3 = params.b2, params.b3
        W = np.sum(kl2 * (s**2 / 2 + b2 * s**3 / 3 + b3 * s**4 / 4), axis=1)
        A = kl2 * (s + b2 * s**2 + b3 * s**3)  # dW/ds
        dW[:, :3] = A / (2 * lam)
        if hessian:
            B = kl2 * (1 + 2 * b2 * s + 3 * b3 * s**2)
            ddW[:, diag, diag] = B / (4 * lam**2) - A / (4 * lam**3)
        g = m[:, 3:] - el.c0
        W = W + 0.5 * np.sum(el.k_torsion * g**2, axis=1)
        dW[:, 3:] = el.k_torsion * g
        if hessian:
            ddW[:, 3 + diag, 3 + diag] = el.k_torsion
        for p, (a, b) in enumerate(TORSION_PAIRS):  # Poisson coupling c s_a s_b
            c = el.k_coupling[:, p]
            W = W + c * s[:, a] * s[:, b]
            dW[:, a] += c * s[:, b] / (2 * lam[:, a])
            dW[:, b] += c * s[:, a] / (2 * lam[:, b])
            if hessian:
                ddW[:, a, a] -= c * s[:, b] / (4 * lam[:, a] ** 3)
                ddW[:, b, b] -= c * s[:, a] / (4 * lam[:, b] ** 3)
                ddW[:, a, b] += c / (4 * lam[:, a] * lam[:, b])
                ddW[:, b, a] += c / (4 * lam[:, a] * lam[:, b])
        if params.mode == "springs":
            return W, dW, ddW, np.ones(k)
        CV = params.modulus * V
        q = 2.0 * W / CV
        e = np.exp(np.minimum(q, MAX_EXPONENT))
        We = np.where(q <= MAX_EXPONENT, 0.5 * CV * (e - 1.0), np.inf)
        if hessian:
            ddW = e[:, None, None] * ddW + (2 * e / CV)[:, None, None] * (
                dW[:, :, None] * dW[:, None, :]
            )
        return We, e[:, None] * dW, ddW, e
    if params.mode == "law":
        assert params.tissue is not None
        W, dW, ddW = law_derivatives(m, params.tissue, hessian)
        Vc = V[:, None]
        return V * W, Vc * dW, (None if ddW is None else Vc[:, :, None] * ddW), np.ones(k)
    if params.mode == "guccione":
        C, b_f, b_t, b_fs = params.law[:4]
        bl = np.array([b_f, b_t, b_t])
        bp = np.array([b_fs, b_fs, b_t])  # pairs fs, fn, sn
        Q = np.sum(bl * (m[:, :3] - 1.0) ** 2, axis=1) / 4 + np.sum(bp * m[:, 3:] ** 2, axis=1) / 2
        dQ = np.concatenate([bl * (m[:, :3] - 1.0) / 2, bp * m[:, 3:]], axis=1)
        e = np.exp(np.minimum(Q, MAX_EXPONENT))
        h = 0.5 * C * V * e
        W = np.where(Q <= MAX_EXPONENT, h - 0.5 * C * V, np.inf)
        if hessian:
            ddQ = np.diag(np.concatenate([bl / 2, bp]))
            ddW = h[:, None, None] * (ddQ + dQ[:, :, None] * dQ[:, None, :])
        return W, h[:, None] * dQ, ddW, e
    a, b, a_f, b_f, a_s, b_s, a_fs, b_fs = params.law
    D, dD, HD = _det_derivatives(m)
    I1 = m[:, :3].sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.where(D > 0, D, np.nan) ** (-1.0 / 3.0)
    I1b = r * I1
    dI1 = np.zeros(6)
    dI1[:3] = 1.0
    dIb = r[:, None] * dI1 - (I1 * r / (3 * D))[:, None] * dD
    q = b * (I1b - 3.0)
    e = np.exp(np.minimum(q, MAX_EXPONENT))
    W = np.where(q <= MAX_EXPONENT, a / (2 * b) * (e - 1.0), np.inf)
    d1, d2 = 0.5 * a * e, 0.5 * a * b * e
    dW = d1[:, None] * dIb
    s = e.copy()
    if hessian:
        rD = (r / (3 * D))[:, None, None]
        ddIb = (
            -rD * (dI1[None, :, None] * dD[:, None, :] + dD[:, :, None] * dI1[None, None, :])
            + (4.0 / 9.0 * I1 * r / D**2)[:, None, None] * (dD[:, :, None] * dD[:, None, :])
            - (I1 * r / (3 * D))[:, None, None] * HD
        )
        ddW = d2[:, None, None] * (dIb[:, :, None] * dIb[:, None, :]) + d1[:, None, None] * ddIb
    for ag, bg, i, x, tension in (
        (a_f, b_f, 0, m[:, 0] - 1.0, True),
        (a_s, b_s, 1, m[:, 1] - 1.0, True),
        (a_fs, b_fs, 3, m[:, 3], False),
    ):
        if ag == 0.0:
            continue
        psi, p1, p2, eg = _exp_term(ag, bg, x, (x > TENSION) if tension else np.ones(k, bool))
        W = W + psi
        dW[:, i] += p1
        if hessian:
            ddW[:, i, i] += p2
        s = np.maximum(s, eg)
    Vc = V[:, None]
    return V * W, Vc * dW, (None if ddW is None else Vc[:, :, None] * ddW), s


def _axis_Z(x: np.ndarray, elements) -> tuple[np.ndarray, np.ndarray]:
    """``Z_l = zeta_l / l_l^0`` ``(m, 3, 3)`` and ``G_il / l_l^0`` ``(m, 4, 3)``."""
    Gh = elements.G / elements.l0[:, None, :]
    return np.einsum("kil,kic->klc", Gh, x[elements.tets]), Gh


def _measure_gradient(Z: np.ndarray, dW: np.ndarray) -> np.ndarray:
    """``dW/dZ_l = 2 W_l Z_l + sum_m W_lm Z_m``, ``(m, 3, 3)``."""
    gZ = 2.0 * dW[:, :3, None] * Z
    for p, (l, m) in enumerate(TORSION_PAIRS):
        gZ[:, l] += dW[:, 3 + p, None] * Z[:, m]
        gZ[:, m] += dW[:, 3 + p, None] * Z[:, l]
    return gZ


def tissue_energy(x: np.ndarray, elements, params: TissueLawParameters):
    """Energy of each tissue element and its gradient: the numpy reference of the pass.

    Parameters
    ----------
    x
        Node positions ``(n, 3)``.
    elements
        :class:`~springmodel.elements.SpringElements`.
    params
        :class:`TissueLawParameters`.

    Returns
    -------
    W, grad, s
        ``(m,)`` (J), ``dW/dx`` of each element's vertices ``(m, 4, 3)`` (N) and the
        stiffening factor ``(m,)`` (:func:`measure_derivatives`).
    """
    Z, Gh = _axis_Z(np.asarray(x, float).reshape(-1, 3), elements)
    W, dW, _, s = measure_derivatives(frame_measures(Z), elements, params, False)
    return W, np.einsum("kil,klc->kic", Gh, _measure_gradient(Z, dW)), s


class TissuePart:
    """The deviatoric springs of the tissue element (module text) in a spring model.

    Parameters
    ----------
    elements
        The calibrated spring elements (their axial, torsion and coupling constants).
    params
        :class:`TissueLawParameters`.

    Examples
    --------
    >>> from springfem.mesh import box_mesh
    >>> from springfem.scene import Material
    >>> from springmodel.elements import build_spring_elements
    >>> mesh = box_mesh((1.0, 1.0, 1.0), (1, 1, 1))
    >>> opts = SpringOptions(volume="axes", torsion="green", calibration="exact")
    >>> el = build_spring_elements(mesh.points, mesh.tets, np.tile(np.eye(3), (6, 1, 1)),
    ...                            opts, Material("linear", 1.0e4, 0.3))
    >>> part = TissuePart(el, law_parameters(opts, None, None))
    >>> float(abs(part.forces(mesh.points)).max()), part.energy(mesh.points)  # none at rest
    (0.0, 0.0)
    """

    def __init__(self, elements, params: TissueLawParameters):
        self.elements, self.params = elements, params
        self._assembler = None
        el = elements
        self._args = (
            np.ascontiguousarray(el.tets, dtype=np.int64), np.ascontiguousarray(el.G),
            np.ascontiguousarray(el.l0), np.ascontiguousarray(el.k_axial),
            np.ascontiguousarray(el.k_torsion), np.ascontiguousarray(el.c0),
            np.ascontiguousarray(el.k_coupling), np.ascontiguousarray(el.V0),
            params.b2, params.b3, params.code, params.modulus,
            np.asarray(params.law, dtype=float), MAX_EXPONENT, TENSION,
        )  # fmt: skip

    def _pass(self, x: np.ndarray, forces: bool):
        from .tissue_kernel import tissue_pass

        x = np.ascontiguousarray(x, dtype=float).reshape(-1, 3)
        if self.params.mode == "law":  # a law without compiled terms: numpy
            W, grad, s = tissue_energy(x, self.elements, self.params)
            f = np.zeros((x.shape[0] if forces else 1, 3))
            if forces:
                tets = self.elements.tets.ravel()
                for c in range(3):
                    f[:, c] = -np.bincount(tets, grad[..., c].ravel(), minlength=x.shape[0])
            return W, s, f
        m = self.elements.n_elements
        W, s = np.empty(m), np.empty(m)
        f = np.zeros((x.shape[0] if forces else 1, 3))
        with np.errstate(invalid="ignore", over="ignore"):
            tissue_pass(x, *self._args, W, s, f, forces)
        return W, s, f

    def scale(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Energy ``(m,)`` (J) and stiffening factor ``(m,)`` of every element."""
        W, s, _ = self._pass(x, False)
        return W, s

    def forces(self, x: np.ndarray) -> np.ndarray:
        """Nodal forces ``-dW/dx`` ``(n, 3)`` (N); not finite past :data:`MAX_EXPONENT`."""
        return self._pass(x, True)[2]

    def energy(self, x: np.ndarray) -> float:
        """``sum_e W_e`` (J); ``inf`` past :data:`MAX_EXPONENT`."""
        return float(np.sum(self._pass(x, False)[0]))

    def element_matrices(self, x: np.ndarray, lo: int = 0, hi: int | None = None) -> np.ndarray:
        """Tangent ``d2W/dx2`` of elements ``lo:hi``, ``(hi - lo, 12, 12)`` (rows ``3 i + c``).

        ``H_Z = sum_ab W_ab dm_a dm_b^T + sum_a W_a d2m_a`` in the ``Z_l``
        (``d2m_l / dZ_l2 = 2 I``, ``d2m_lm / dZ_l dZ_m = I``), then ``x`` through
        ``Z_l = sum_i G_il x_i / l_l^0``.
        """
        el = self.elements
        hi = el.n_elements if hi is None else hi
        sub = _slice(el, lo, hi)
        Z, Gh = _axis_Z(np.asarray(x, float).reshape(-1, 3), sub)
        _, dW, ddW, _ = measure_derivatives(frame_measures(Z), sub, self.params, True)
        k = Z.shape[0]
        dm = np.zeros((k, 6, 3, 3))  # d m_a / d Z_l,c
        for l in range(3):
            dm[:, l, l] = 2.0 * Z[:, l]
        coef = np.zeros((k, 3, 3))  # sum_a W_a d2m_a = coef (x) I
        coef[:, [0, 1, 2], [0, 1, 2]] = 2.0 * dW[:, :3]
        for p, (l, m) in enumerate(TORSION_PAIRS):
            dm[:, 3 + p, l] = Z[:, m]
            dm[:, 3 + p, m] = Z[:, l]
            coef[:, l, m] = coef[:, m, l] = dW[:, 3 + p]
        with np.errstate(invalid="ignore", over="ignore"):
            HZ = np.einsum("kab,kalc,kbmd->klcmd", ddW, dm, dm, optimize=True)
            HZ += np.einsum("klm,cd->klcmd", coef, np.eye(3))
            H = np.einsum("kil,klcmd,kjm->kicjd", Gh, HZ, Gh, optimize=True)
        return H.reshape(k, 12, 12)

    def stiffness(self, x: np.ndarray):
        """The tangent as a ``(3n, 3n)`` CSR matrix, :data:`CHUNK` elements at a time."""
        if self._assembler is None:
            from .hessian import SpringHessian

            zero = replace(self.elements, k_axis_volume=np.zeros(self.elements.n_elements))
            self._assembler = SpringHessian(zero, SpringOptions(torsion="off", volume=False))
        m = self.elements.n_elements
        spans = [(lo, min(lo + CHUNK, m)) for lo in range(0, m, CHUNK)]
        blocks = [(lo, self.element_matrices(x, lo, hi)) for lo, hi in spans]
        return self._assembler.assemble(blocks)


def _slice(el, lo: int, hi: int):
    """The elements ``lo:hi`` (the arrays :func:`measure_derivatives` reads)."""
    s = slice(lo, hi)
    return replace(
        el, tets=el.tets[s], G=el.G[s], l0=el.l0[s], c0=el.c0[s], V0=el.V0[s],
        k_axial=el.k_axial[s], k_torsion=el.k_torsion[s], k_coupling=el.k_coupling[s],
        zeta0=el.zeta0[s], k_axis_volume=el.k_axis_volume[s], det0=el.det0[s],
    )  # fmt: skip

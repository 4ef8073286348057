"""Spring elements measured by the nodal-averaged deformation gradient (an alpha-FEM blend).

A spring element's energy is a function of its deformation gradient alone,
``W_e(F)`` (docs/theory.rst#the-axis-volume-ratio-is-j), so it can be evaluated on any
``F``. ``[spring] strain_average = "nodal"`` measures each element's springs with the
deformation gradient averaged over the patch of each of its vertices,

    Fbar_a = sum_{e ni a} V_e F_e / sum_{e ni a} V_e,

and blends that with the element's own ``F_e`` (the alpha finite element method of Liu,
Nguyen-Thoi & Lam 2008, the Puso & Solberg 2006 stabilisation of nodal integration)::

    W = sum_e [ alpha W_e(F_e) + (1 - alpha) / 4 sum_{a in e} W_e(Fbar_a) ]

with ``alpha = [spring] strain_stabilisation``. Linear tetrahedra are too stiff in bending
(``alpha = 1``, the plain element) and the nodal measure alone is too soft and has
spurious modes (``alpha = 0``, node-based smoothing): the element fraction ``alpha``
stabilises them (docs/volumetric.rst#stabilised-nodal-strain). The springs here are the
deviatoric ones: the volume stays on the nodal volumes of :mod:`springmodel.nodal_volume`.

Each term ``W_e(Fbar_a) / 4`` is computed by the ordinary spring kernel (or, with
``torsion = "green"``, the tissue element's pass, :mod:`springmodel.tissue_element`) on a
*virtual* element: element ``e``'s rest vertices mapped by ``Fbar_a``, ``y_i = Fbar_a X_i``
(four per element, ``4 m`` virtual elements). The virtual forces ``f_y`` give the nodal stress
``T_a = sum sum_i f_{y,i} X_i^T`` (``-dW/dFbar_a``), the virtual element matrices the
``9 x 9`` nodal moduli ``A_a``; with the sparse nodal gradient ``B`` (``Fbar = B x``) the
forces are ``B^T T`` and the tangent ``B^T diag(A_a) B``, which couples the nodes of two
rings.

Examples
--------
>>> import numpy as np
>>> from springfem.mesh import box_mesh
>>> mesh = box_mesh((2.0, 1.0, 1.0), (2, 1, 1))
>>> Gb = nodal_gradients(mesh.points, mesh.tets)
>>> F = np.array([[1.1, 0.2, 0.0], [0.0, 0.9, 0.0], [0.1, 0.0, 1.0]])
>>> Fbar = nodal_deformation_gradients(Gb, mesh.points @ F.T)  # exact for affine maps
>>> bool(np.allclose(Fbar, F))
True
"""

from __future__ import annotations

from dataclasses import fields, replace

import numpy as np
import scipy.sparse as sp

from springfem.mesh import tet_volumes
from springfem.mesh.nodal_average import shape_gradients

from .nodal_groups import (
    GROUP_TOLERANCE,
    copy_stresses,
    element_classes,
    group_pairs,
    nodal_moduli,
    nodal_stresses,
    probe_gradients,
    subset,
    virtual_positions_from_rows,
)

#: Virtual elements per block of the tissue pass's element matrices (bounds their memory).
CHUNK = 16384

__all__ = [
    "NodalStrainPart",
    "nodal_deformation_gradients",
    "nodal_gradients",
    "scaled_deviatoric",
    "virtual_elements",
]


def nodal_gradients(X: np.ndarray, tets: np.ndarray) -> tuple[sp.csr_matrix, ...]:
    """The nodal gradient operator: ``Fbar_a[:, beta] = (Gb[beta] @ x)[a]``.

    ``Gb[beta][a, j] = sum_{e ni a, j} V_e dN_j^e/dX_beta / sum_{e ni a} V_e`` (the
    volume-weighted average of the element gradients over the patch of node ``a``).

    Parameters
    ----------
    X
        Rest positions ``(n, 3)``.
    tets
        Connectivity ``(m, 4)``.

    Returns
    -------
    tuple of scipy.sparse.csr_matrix
        Three ``(n, n)`` matrices, one per rest direction ``beta``.
    """
    X = np.asarray(X, float)
    tets = np.asarray(tets, np.int64)
    n, m = X.shape[0], tets.shape[0]
    V = np.abs(tet_volumes(X, tets))
    Va = np.bincount(tets.ravel(), np.repeat(V, 4), minlength=n)
    g = shape_gradients(X, tets)
    rows = np.repeat(tets, 4, axis=1).ravel()  # a = tets[e, p] for every j
    cols = np.tile(tets, (1, 4)).ravel()  # j = tets[e, q]
    w = V[:, None, None] / np.where(Va > 0, Va, 1.0)[tets][:, :, None]  # (m, 4 a, 1)
    out = []
    for beta in range(3):
        vals = (w * g[:, None, :, beta]).reshape(m, 16)  # [e, p*4 + q]
        out.append(sp.csr_matrix((vals.ravel(), (rows, cols)), shape=(n, n)))
    return tuple(out)


def nodal_deformation_gradients(Gb, x: np.ndarray) -> np.ndarray:
    """``Fbar_a`` of every node, ``(n, 3, 3)``.

    Parameters
    ----------
    Gb
        :func:`nodal_gradients`.
    x
        Positions ``(n, 3)``.

    Returns
    -------
    numpy.ndarray
        ``(n, 3, 3)`` with ``Fbar[a, alpha, beta] = d x_alpha / d X_beta`` averaged at ``a``.
    """
    return np.stack([G @ x for G in Gb], axis=2)


def scaled_deviatoric(elements, weight: float):
    """Elements whose axial, torsion and coupling energy is ``weight`` times the input's.

    The constants are scaled by ``weight``; so is ``V0`` (the stiffening's ``C V``, so that
    the exponential wrapper scales too: ``w V C/2 (exp(2 w W_q / (C w V)) - 1)``), with the
    axis-volume stiffness divided by it (its energy ``V0 kappa U(J)`` is unchanged).

    Parameters
    ----------
    elements
        :class:`~springmodel.elements.SpringElements`.
    weight
        ``w > 0``.

    Returns
    -------
    SpringElements
    """
    w = float(weight)
    return replace(
        elements,
        k_axial=w * elements.k_axial,
        k_torsion=w * elements.k_torsion,
        k_coupling=w * elements.k_coupling,
        V0=w * elements.V0,
        k_axis_volume=elements.k_axis_volume / w,
    )


def virtual_elements(elements):
    """Four disconnected copies of every element (virtual nodes ``16 e + 4 p + i``).

    Parameters
    ----------
    elements
        :class:`~springmodel.elements.SpringElements` (rest data per element).

    Returns
    -------
    SpringElements
        ``4 m`` elements on ``16 m`` nodes; copy ``4 e + p`` of element ``e`` is the one its
        vertex ``p`` measures.
    """
    m = elements.n_elements
    idx = np.repeat(np.arange(m), 4)
    changes = {}
    for f in fields(elements):
        v = getattr(elements, f.name)
        if isinstance(v, np.ndarray) and v.ndim >= 1 and v.shape[0] == m and f.name != "tets":
            changes[f.name] = np.ascontiguousarray(v[idx])
    tets = np.arange(16 * m, dtype=np.int64).reshape(4 * m, 4)
    return replace(elements, tets=tets, n_points=16 * m, **changes)


class _Energy:
    """The energy of a set of (virtual) elements: the tissue pass, or the spring kernel with
    its Hessian and the exponential stiffening."""

    def __init__(self, elements, options, modulus: float | None, tissue):
        from .hessian import SpringHessian
        from .spring_kernel import SpringKernel
        from .stiffening import StiffeningPart
        from .tissue_element import TissuePart

        self.elements = elements
        opts = replace(options, volume_average="element", volume_stabilisation=None)
        self.tissue = None if tissue is None else TissuePart(elements, tissue)
        self.kernel = self.stiffening = None
        self._hessian: SpringHessian | None = None  # its CSR pattern, on the first tangent
        self._out: np.ndarray | None = None  # the kernel's force buffer
        self._options = opts
        if self.tissue is None:
            self.kernel = SpringKernel(elements, opts, parallel=None)
            if modulus is not None and options.stiffening != "off":
                self.stiffening = StiffeningPart(elements, opts, modulus)

    @property
    def hessian(self):
        """The spring Hessian of the elements (built on first use)."""
        from .hessian import SpringHessian

        if self._hessian is None:
            self._hessian = SpringHessian(self.elements, self._options)
        return self._hessian

    def energy(self, y: np.ndarray) -> float:
        if self.tissue is not None:
            return self.tissue.energy(y)
        W = self.kernel.energy(y)
        return W if self.stiffening is None else W + self.stiffening.energy(y)

    def forces(self, y: np.ndarray) -> np.ndarray:
        if self.tissue is not None:
            return self.tissue.forces(y)
        if self._out is None:
            self._out = np.empty((self.elements.n_points, 3))
        fy = self.kernel.forces(y, out=self._out)
        return fy if self.stiffening is None else fy + self.stiffening.forces(y)

    def element_matrices(self, y: np.ndarray, lo: int, hi: int) -> np.ndarray:
        if self.tissue is not None:
            return self.tissue.element_matrices(y, lo, hi)
        K = self.hessian.element_matrices(y, lo=lo, hi=hi)
        if self.stiffening is None:
            return K
        return K + self.stiffening.element_matrices(y, lo, hi)


class NodalStrainPart:
    """The nodal-strain springs of a :class:`~springmodel.model.SpringModel` (module text).

    The virtual elements are grouped by node and element class (:mod:`springmodel.nodal_groups`:
    about one per node when the elements share one law per volume), and ``Fbar = B x``,
    ``B^T T`` and ``B^T diag(A) B`` run on the mesh's
    :class:`~springfem.mesh.nodal_average.NodalAverage`.

    Parameters
    ----------
    X, tets
        Rest positions ``(n, 3)`` and connectivity ``(m, 4)``.
    elements
        The deviatoric spring elements of the nodal measure, with the weight
        ``(1 - alpha) / 4`` already in their constants (:func:`scaled_deviatoric`) and no
        volume stiffness.
    options
        Spring options (conservative laws).
    modulus
        Stiffening modulus ``C`` (Pa) when ``stiffening = "exponential"``, else None.
    tissue
        With ``torsion = "green"``: the tissue element's
        :class:`~springmodel.tissue_element.TissueLawParameters`; the virtual elements then
        run the tissue pass (:class:`~springmodel.tissue_element.TissuePart`) in place of the
        spring kernel and the stiffening.
    group
        Group the copies by node and class (default); ``False``: one virtual element per
        copy, ``4 m`` of them (the reference the grouping is tested against).
    """

    def __init__(self, X, tets, elements, options, modulus: float | None = None, tissue=None,
                 group: bool = True):  # fmt: skip
        from .nodal_groups import mesh_average

        self.X = np.asarray(X, float)
        self.tets = np.asarray(tets, np.int64)
        self.n = self.X.shape[0]
        self.average = mesh_average(X, tets)
        m = self.tets.shape[0]
        V = np.asarray(elements.V0, dtype=float)
        cls = np.arange(m)
        if group:
            cls = self._classes(elements, options, modulus, tissue)
        self.nodes, rep, scale = group_pairs(self.tets, cls, V)
        self.Xg = np.ascontiguousarray(self.X[self.tets[rep]])  # (g, 4, 3)
        self.elements = subset(elements, rep, scale)
        self.part = _Energy(self.elements, options, modulus, tissue)
        self.tissue = self.part.tissue
        self.grouped = bool(cls.max(initial=0) + 1 < m)
        self._y = np.empty((4 * self.nodes.size, 3))
        self._T = np.empty((self.n, 3, 3))

    def _classes(self, elements, options, modulus, tissue) -> np.ndarray:
        """Element classes, or one per element when the grouped sum misses (module text of
        :mod:`springmodel.nodal_groups`)."""
        m = self.tets.shape[0]
        V = np.asarray(elements.V0, dtype=float)
        copies = _Energy(subset(elements, np.arange(m)), options, modulus, tissue)
        F = probe_gradients()
        with np.errstate(all="ignore"):
            T = np.stack([copy_stresses(copies, self.X, self.tets, Ft) for Ft in F])
        if not np.isfinite(T).all():
            return np.arange(m)
        cls = element_classes(T[:2], V)
        k = int(cls.max(initial=0)) + 1
        if k == m:
            return cls
        first = np.full(k, m, dtype=np.int64)
        np.minimum.at(first, cls, np.arange(m))
        grouped = np.zeros((k, 3, 3))  # the third gradient: sum over each class, both ways
        np.add.at(grouped, cls, T[2])
        scale = np.bincount(cls, V, k) / V[first]
        rep = scale[:, None, None] * T[2][first]
        if np.abs(rep - grouped).max() > GROUP_TOLERANCE * np.abs(grouped).max():
            return np.arange(m)
        return cls

    @classmethod
    def split(cls, mesh, elements, options, modulus: float | None = None, tissue=None):
        """The nodal-strain part of a model (None when off) and the elements for its kernel.

        Parameters
        ----------
        mesh
            The scene's mesh (``points``, ``tets``).
        elements
            The kernel's spring elements (after :meth:`NodalPart.split
            <springmodel.nodal_volume.NodalPart.split>`).
        options
            :class:`~springmodel.options.SpringOptions` (``strain_average``,
            ``strain_stabilisation``).
        modulus
            Stiffening modulus or None.
        tissue
            The tissue element's law parameters (``torsion = "green"``) or None.

        Returns
        -------
        tuple
            ``(NodalStrainPart or None, elements for the spring kernel and Hessian)``: the
            kernel keeps the share ``alpha`` of the springs and all of its volume stiffness.
        """
        alpha = float(options.strain_stabilisation)
        if options.strain_average != "nodal" or alpha >= 1.0:  # alpha 1: all on the element
            return None, elements
        deviatoric = replace(elements, k_axis_volume=np.zeros(elements.n_elements))
        part = cls(mesh.points, mesh.tets, scaled_deviatoric(deviatoric, (1 - alpha) / 4),
                   options, modulus, tissue)  # fmt: skip
        if alpha > 0.0:
            return part, scaled_deviatoric(elements, alpha)
        zero = np.zeros_like(elements.k_axial)
        return part, replace(elements, k_axial=zero, k_torsion=zero, k_coupling=zero)

    def virtual_positions(self, x: np.ndarray) -> np.ndarray:
        """``y = Fbar_a X_i`` of every virtual element's vertices, ``(4 g, 3)``."""
        x = np.ascontiguousarray(x, dtype=float).reshape(-1, 3)
        rowptr, cols, gb = self.average.rows
        virtual_positions_from_rows(x, rowptr, cols, gb, self.nodes, self.Xg, self._y)
        return self._y

    def energy(self, x: np.ndarray) -> float:
        """``sum_e (1 - alpha)/4 sum_a W_e(Fbar_a)`` (J)."""
        return self.part.energy(self.virtual_positions(x))

    def stresses(self, x: np.ndarray) -> np.ndarray:
        """Nodal stresses ``T_a = -dW/dFbar_a`` ``(n, 3, 3)``."""
        fy = self.part.forces(self.virtual_positions(x))
        nodal_stresses(np.ascontiguousarray(fy, dtype=float), self.Xg, self.nodes, self._T)
        return self._T

    def forces(self, x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Nodal forces ``-dW/dx`` ``(n, 3)`` (N): ``B^T T`` (added to ``out`` if given)."""
        return self.average.transpose(self.stresses(x), out)

    def moduli(self, x: np.ndarray) -> np.ndarray:
        """``A_a = d^2 W / dFbar_a^2`` of every node, ``(n, 9, 9)`` (rows ``3 alpha + beta``)."""
        y = self.virtual_positions(x)
        A = np.zeros((self.n, 9, 9))
        k = self.elements.n_elements
        for lo in range(0, k, CHUNK):
            K = self.part.element_matrices(y, lo, min(lo + CHUNK, k))
            nodal_moduli(np.ascontiguousarray(K), self.Xg, self.nodes, lo, A)
        return A

    def add_tangent(self, x: np.ndarray, data: np.ndarray) -> np.ndarray:
        """``data += B^T diag(A_a) B`` on the pattern of :attr:`average`."""
        return self.average.add_tangent(self.moduli(x), data)

    def tangent(self, x: np.ndarray) -> sp.csr_matrix:
        """Tangent ``B^T diag(A_a) B`` ``(3n, 3n)`` (CSR, symmetric, the two-ring pattern)."""
        return self.average.matrix(self.add_tangent(x, self.average.zeros()))

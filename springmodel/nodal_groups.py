"""The nodal-strain springs evaluated once per node and element class, not once per copy.

:mod:`springmodel.nodal_strain` measures every element ``e`` at the averaged gradient
``Fbar_a`` of each of its vertices: ``4 m`` virtual elements. Elements whose energy per rest
volume is one function of ``F`` (same frame, same constants per volume: every element of the
exact calibration of one material in one frame) give at a node ``a``

    sum_{e ni a, e in c} W_e(Fbar_a) = (sum_{e ni a, e in c} V_e / V_r) W_r(Fbar_a),

the representative ``r`` of their class ``c`` with its constants scaled. So one virtual
element per (node, class) pair does the work of the node's whole patch: about ``n`` virtual
elements instead of ``4 m`` (16 times fewer on a tet mesh). The classes are found from the
elements' own stress per volume at two test gradients (:func:`element_classes`); the grouped
sum is then checked against the copies' at a third gradient, and the part falls back to one
group per copy (the plain ``4 m`` virtual elements) when it does not agree to round-off.

The compiled loops here gather ``y = Fbar_a X_i`` for the virtual elements, sum their forces
into the nodal stresses ``T_a = sum f_{y,i} X_i^T`` and their element matrices into the nodal
moduli ``A_a`` (``9 x 9``).

Examples
--------
>>> import numpy as np
>>> nodes, rep, scale = group_pairs(np.array([[0, 1, 2, 3], [1, 2, 3, 4]]), np.zeros(2, int),
...                                 np.array([1.0, 2.0]))
>>> nodes.tolist(), rep.tolist(), scale.tolist()  # one class: one group per node
([0, 1, 2, 3, 4], [0, 0, 0, 0, 0], [1.0, 3.0, 3.0, 3.0, 2.0])
"""

from __future__ import annotations

import weakref
from dataclasses import fields, replace

import numpy as np
from numba import njit

from springfem.mesh.nodal_average import NodalAverage

#: Relative agreement of the grouped and per-copy stresses the grouping must reach.
GROUP_TOLERANCE = 1e-10
#: Relative resolution of the class fingerprints (stress per volume at the test gradients).
FINGERPRINT_RESOLUTION = 1e-9
_OPERATORS: dict[tuple[int, int], tuple] = {}


def mesh_average(X: np.ndarray, tets: np.ndarray) -> NodalAverage:
    """The :class:`~springfem.mesh.nodal_average.NodalAverage` of ``X``, ``tets``, built once
    per pair of arrays (the nodal volume and nodal strain parts of a model share it)."""
    key = (id(X), id(tets))
    hit = _OPERATORS.get(key)
    if hit is not None and hit[0]() is X and hit[1]() is tets:
        return hit[2]
    op = NodalAverage.of(X, tets)
    try:
        refs = (weakref.ref(X), weakref.ref(tets))
    except TypeError:  # not weak-referenceable: no cache
        return op
    for k in [k for k, v in _OPERATORS.items() if v[0]() is None or v[1]() is None]:
        del _OPERATORS[k]
    _OPERATORS[key] = (*refs, op)
    return op


def subset(elements, idx: np.ndarray, scale: np.ndarray | None = None):
    """Elements ``idx`` of ``elements`` as disconnected elements (nodes ``4 k + i``), their
    energy scaled by ``scale`` (:func:`springmodel.nodal_strain.scaled_deviatoric`, per
    element).

    Parameters
    ----------
    elements
        :class:`~springmodel.elements.SpringElements`.
    idx
        ``(k,)`` element indices (repeats allowed).
    scale
        ``(k,)`` positive weights, or None.

    Returns
    -------
    SpringElements
        ``k`` elements on ``4 k`` nodes.
    """
    m = elements.n_elements
    idx = np.asarray(idx, dtype=np.int64)
    changes = {}
    for f in fields(elements):
        v = getattr(elements, f.name)
        if isinstance(v, np.ndarray) and v.ndim >= 1 and v.shape[0] == m and f.name != "tets":
            changes[f.name] = np.ascontiguousarray(v[idx])
    k = idx.size
    out = replace(elements, tets=np.arange(4 * k, dtype=np.int64).reshape(k, 4), n_points=4 * k,
                  **changes)  # fmt: skip
    if scale is None:
        return out
    s = np.asarray(scale, dtype=float)
    return replace(
        out, k_axial=s[:, None] * out.k_axial, k_torsion=s[:, None] * out.k_torsion,
        k_coupling=s[:, None] * out.k_coupling, V0=s * out.V0,
        k_axis_volume=out.k_axis_volume / s,
    )  # fmt: skip


def probe_gradients(count: int = 3, seed: int = 12345) -> np.ndarray:
    """``count`` fixed, well-conditioned deformation gradients near the identity."""
    rng = np.random.default_rng(seed)
    return np.eye(3) + 0.15 * rng.standard_normal((count, 3, 3))


def copy_stresses(energy_of, X: np.ndarray, tets: np.ndarray, F: np.ndarray) -> np.ndarray:
    """``T_e(F) = sum_i f_i X_i^T`` of every element at one gradient ``F``, ``(m, 3, 3)``.

    Parameters
    ----------
    energy_of
        An object with ``forces(y)`` over the elements as disconnected copies (``4 m``
        nodes).
    X, tets
        Rest positions and connectivity.
    F
        ``(3, 3)``.
    """
    Xe = X[tets]  # (m, 4, 3)
    y = np.einsum("ab,kib->kia", F, Xe).reshape(-1, 3)
    f = energy_of.forces(y).reshape(-1, 4, 3)
    return np.einsum("kia,kib->kab", f, Xe)


def element_classes(T: np.ndarray, V: np.ndarray) -> np.ndarray:
    """Class of every element from its stress per volume at the test gradients.

    Parameters
    ----------
    T
        ``(t, m, 3, 3)`` stresses of the copies at ``t`` test gradients.
    V
        ``(m,)`` the elements' volume measure (their scaled ``V0``).

    Returns
    -------
    numpy.ndarray
        ``(m,)`` class ids ``0 .. c - 1``; equal fingerprints to
        :data:`FINGERPRINT_RESOLUTION` of the largest one share a class.
    """
    m = T.shape[1]
    fp = (T / V[None, :, None, None]).transpose(1, 0, 2, 3).reshape(m, -1)
    scale = np.abs(fp).max(initial=0.0)
    if not (scale > 0) or not np.isfinite(fp).all():
        return np.arange(m)
    q = np.round(fp / (scale * FINGERPRINT_RESOLUTION)).astype(np.int64)
    _, cls = np.unique(q, axis=0, return_inverse=True)
    return cls.ravel()


def group_pairs(tets: np.ndarray, cls: np.ndarray, V: np.ndarray):
    """The (node, class) groups of the copies: node, representative element, scale.

    Parameters
    ----------
    tets
        ``(m, 4)``.
    cls
        ``(m,)`` class ids.
    V
        ``(m,)`` volume measure.

    Returns
    -------
    nodes, rep, scale
        ``(g,)`` each, sorted by node: the group's node, its class's first element and
        ``sum V_e / V_rep`` over the copies in it.
    """
    m = tets.shape[0]
    cls = np.asarray(cls, dtype=np.int64)
    k = int(cls.max(initial=0)) + 1
    first = np.full(k, m, dtype=np.int64)
    np.minimum.at(first, cls, np.arange(m))
    keys, inv = np.unique(tets.ravel() * k + np.repeat(cls, 4), return_inverse=True)
    S = np.bincount(inv.ravel(), np.repeat(V, 4), keys.size)
    rep = first[keys % k]
    return keys // k, rep, S / V[rep]


@njit(cache=True, fastmath=False)
def virtual_positions_from_rows(x, rowptr, cols, gb, nodes, Xg, y):  # pragma: no cover
    """:func:`virtual_positions` with ``Fbar_a = sum_c x_c (x) gb_ac`` formed on the fly, once
    per node (the groups are sorted by node; the row sums of
    :class:`~springfem.mesh.nodal_average.NodalAverage`, in its order)."""
    F = np.empty((3, 3))
    last = -1
    for g in range(nodes.shape[0]):
        a = nodes[g]
        if a != last:
            last = a
            for al in range(3):
                for be in range(3):
                    F[al, be] = 0.0
            for k in range(rowptr[a], rowptr[a + 1]):
                c = cols[k]
                for al in range(3):
                    xa = x[c, al]
                    for be in range(3):
                        F[al, be] += xa * gb[k, be]
        for i in range(4):
            for al in range(3):
                y[4 * g + i, al] = (
                    F[al, 0] * Xg[g, i, 0] + F[al, 1] * Xg[g, i, 1] + F[al, 2] * Xg[g, i, 2]
                )


@njit(cache=True, fastmath=False)
def virtual_positions(Fbar, nodes, Xg, y):  # pragma: no cover - compiled; tested via forces
    """``y[4 g + i] = Fbar[nodes[g]] Xg[g, i]``."""
    for g in range(nodes.shape[0]):
        a = nodes[g]
        for i in range(4):
            for al in range(3):
                y[4 * g + i, al] = (Fbar[a, al, 0] * Xg[g, i, 0] + Fbar[a, al, 1] * Xg[g, i, 1]
                                    + Fbar[a, al, 2] * Xg[g, i, 2])  # fmt: skip


@njit(cache=True, fastmath=False)
def nodal_stresses(fy, Xg, nodes, T):  # pragma: no cover - compiled; tested via forces
    """``T[a] = sum_{g of a} sum_i fy[4 g + i] Xg[g, i]^T`` (``T`` is overwritten)."""
    T[:] = 0.0
    for g in range(nodes.shape[0]):
        a = nodes[g]
        for i in range(4):
            for al in range(3):
                f = fy[4 * g + i, al]
                for be in range(3):
                    T[a, al, be] += f * Xg[g, i, be]


@njit(cache=True, fastmath=False)
def nodal_moduli(K, Xg, nodes, lo, A):  # pragma: no cover - compiled; tested via the tangent
    """``A[a][3 al + be, 3 ga + de] += sum_ij Xg_i[be] K_g[3i + al, 3j + ga] Xg_j[de]`` for the
    element matrices ``K`` of groups ``lo:lo + len(K)``."""
    Y = np.empty((3, 4, 3))  # Y[ga, i, de] = sum_j K[3i + al, 3j + ga] Xg_j[de] for one al
    for k in range(K.shape[0]):
        g = lo + k
        a = nodes[g]
        for al in range(3):
            for i in range(4):
                for ga in range(3):
                    for de in range(3):
                        v = 0.0
                        for j in range(4):
                            v += K[k, 3 * i + al, 3 * j + ga] * Xg[g, j, de]
                        Y[ga, i, de] = v
            for be in range(3):
                for ga in range(3):
                    for de in range(3):
                        v = 0.0
                        for i in range(4):
                            v += Xg[g, i, be] * Y[ga, i, de]
                        A[a, 3 * al + be, 3 * ga + de] += v

"""Zero-energy modes of a tangent stiffness: count the near-zero eigenvalues.

A consistent, stable discretisation of a free body has exactly six zero-energy modes (three
translations, three rotations); clamped, none. Any other eigenvalue of the tangent that is
near zero relative to the largest is a *spurious* mode: a deformation the discrete energy
does not see (hourglass modes of under-integrated elements, the element volume modes left
loose by nodal averaging). :func:`zero_modes` counts them and returns the modes, so a test
or ``springfem inspect`` can say how many there are and where they live.

Symmetric tangents use :func:`numpy.linalg.eigh` below :data:`DENSE_MAX_DOFS` and
shift-invert Lanczos (:func:`scipy.sparse.linalg.eigsh` with ``sigma`` just below 0) above,
asking for the ``k`` eigenvalues nearest zero. A mode is "near zero" when its eigenvalue is
at most ``rtol`` times the largest eigenvalue in magnitude.

Examples
--------
Two unit springs in series, fixed at one end (the matrix of the free DOFs): no zero mode.
Free at both ends: one (the translation).

>>> import numpy as np
>>> K = np.array([[2.0, -1.0], [-1.0, 1.0]])
>>> zero_modes(K).count
0
>>> zero_modes(np.array([[1.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])).count
1
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

#: Largest matrix solved densely (all eigenvalues); above it, shift-invert Lanczos.
DENSE_MAX_DOFS = 3000
#: Default threshold: eigenvalues at most this times the largest magnitude are zero.
RTOL = 1e-8


@dataclass(frozen=True)
class ZeroModes:
    """Near-zero eigenvalues of a tangent.

    Attributes
    ----------
    count
        How many eigenvalues satisfy ``|lambda| <= rtol * lambda_max``.
    values
        The smallest eigenvalues found (ascending by magnitude), divided by ``lambda_max``.
    modes
        The eigenvectors of the ``count`` near-zero eigenvalues, ``(n, count)``.
    lambda_max
        The largest eigenvalue magnitude.
    negative
        How many of the computed eigenvalues are below ``-rtol * lambda_max`` (an unstable
        state: the tangent is indefinite).
    """

    count: int
    values: np.ndarray
    modes: np.ndarray
    lambda_max: float
    negative: int


def _largest(K) -> float:
    if sp.issparse(K):
        n = K.shape[0]
        if n <= 2:
            return float(np.abs(np.linalg.eigvalsh(K.toarray())).max())
        return float(abs(spla.eigsh(K, k=1, which="LM", return_eigenvectors=False)[0]))
    return float(np.abs(np.linalg.eigvalsh(K)).max())


def zero_modes(K, rtol: float = RTOL, k: int = 12) -> ZeroModes:
    """Count the eigenvalues of a symmetric tangent that are near zero.

    Parameters
    ----------
    K
        A symmetric matrix (dense or sparse), usually the tangent restricted to the free
        DOFs (a clamped body) or the whole tangent (a free body).
    rtol
        The threshold relative to the largest eigenvalue magnitude.
    k
        Above :data:`DENSE_MAX_DOFS`: how many eigenvalues nearest zero to compute. The
        count is reliable when it is below ``k``; a count equal to ``k`` means "``k`` or
        more".

    Returns
    -------
    ZeroModes
    """
    n = K.shape[0]
    if n <= DENSE_MAX_DOFS:
        A = K.toarray() if sp.issparse(K) else np.asarray(K, dtype=float)
        A = 0.5 * (A + A.T)
        w, V = np.linalg.eigh(A)
        lam = float(np.abs(w).max()) if n else 0.0
    else:
        A = sp.csc_matrix(K, dtype=float)
        A = 0.5 * (A + A.T)
        lam = _largest(A)
        # shift just below zero so that the shifted matrix is not singular on a free body
        w, V = spla.eigsh(A, k=min(k, n - 1), sigma=-1e-6 * lam, which="LM")
    order = np.argsort(np.abs(w))
    w, V = w[order], V[:, order]
    scale = lam if lam > 0 else 1.0
    near = np.abs(w) <= rtol * scale
    return ZeroModes(
        count=int(near.sum()),
        values=w[: max(k, int(near.sum()))] / scale,
        modes=V[:, near],
        lambda_max=lam,
        negative=int((w < -rtol * scale).sum()),
    )


def spurious_modes(K, free_body: bool, rtol: float = RTOL, k: int = 12) -> int:
    """Zero modes beyond the rigid-body ones: ``count - 6`` (free body) or ``count``.

    Parameters
    ----------
    K
        The tangent (the whole matrix of a free body, the free block of a clamped one).
    free_body
        Whether six rigid-body modes are expected.
    rtol, k
        As :func:`zero_modes`.

    Returns
    -------
    int
        The number of spurious zero modes (negative if a rigid mode is missing, which
        means the tangent is not invariant under rigid motion).

    Examples
    --------
    >>> import numpy as np
    >>> spurious_modes(np.eye(3), free_body=False)
    0
    """
    return zero_modes(K, rtol, k).count - (6 if free_body else 0)

"""Voigt and Mandel forms of strains and stiffnesses, and their rotation to element frames.

Voigt order is ``(xx, yy, zz, yz, xz, xy)`` with engineering shear strains, so
``sigma = D @ eps`` and the fourth-order tensor is ``C[i, j, k, l] = D[v(i, j), v(k, l)]``.
The Mandel form ``W D W`` (``W = diag(1, 1, 1, √2, √2, √2)``) has the Frobenius norm of the
fourth-order tensor, so norms and rotations in it do not depend on the frame.

Examples
--------
>>> g = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
>>> bool(np.allclose(strain_voigt(strain_tensor(g)), g))
True
"""

from __future__ import annotations

import numpy as np

#: Tensor index pairs of the six Voigt components.
VOIGT_PAIRS = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))

#: Voigt index of the tensor index pair ``(i, j)``.
VOIGT = np.array([[0, 5, 4], [5, 1, 3], [4, 3, 2]])

_MANDEL_W = np.array([1.0, 1.0, 1.0, np.sqrt(2.0), np.sqrt(2.0), np.sqrt(2.0)])
_SHEAR_2 = np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0])


# ----------------------------------------------------------------------- Voigt / Mandel


def voigt_vector(A: np.ndarray) -> np.ndarray:
    """Stress-like Voigt vector ``[A00, A11, A22, A12, A02, A01]`` of symmetric ``A``.

    Parameters
    ----------
    A
        ``(..., 3, 3)`` symmetric tensors.

    Returns
    -------
    numpy.ndarray
        ``(..., 6)``; with engineering shear strains ``g``, ``A : eps = voigt_vector(A) . g``.

    Examples
    --------
    >>> voigt_vector(np.arange(9.0).reshape(3, 3))
    array([0., 4., 8., 5., 2., 1.])
    """
    return np.stack([A[..., i, j] for i, j in VOIGT_PAIRS], axis=-1)


def sym_to_mandel(A: np.ndarray) -> np.ndarray:
    """Mandel vector ``[A00, A11, A22, √2 A12, √2 A02, √2 A01]`` of symmetric ``A``.

    Parameters
    ----------
    A
        ``(..., 3, 3)`` symmetric tensors.

    Returns
    -------
    numpy.ndarray
        ``(..., 6)``, with ``|mandel(A)| = |A|_F``.

    Examples
    --------
    >>> A = np.array([[1.0, 2.0, 0.0], [2.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    >>> bool(np.isclose(np.linalg.norm(sym_to_mandel(A)), np.linalg.norm(A)))
    True
    """
    return voigt_vector(A) * _MANDEL_W


def strain_voigt(eps: np.ndarray) -> np.ndarray:
    """Engineering Voigt strain ``[e00, e11, e22, 2 e12, 2 e02, 2 e01]`` of symmetric ``eps``.

    Parameters
    ----------
    eps
        ``(..., 3, 3)`` symmetric strain tensors.

    Returns
    -------
    numpy.ndarray
        ``(..., 6)``.

    Examples
    --------
    >>> strain_voigt(np.array([[0.0, 0.5, 0.0], [0.5, 0.0, 0.0], [0.0, 0.0, 0.0]]))
    array([0., 0., 0., 0., 0., 1.])
    """
    return voigt_vector(eps) * _SHEAR_2


def strain_tensor(g: np.ndarray) -> np.ndarray:
    """Symmetric strain tensor of an engineering Voigt strain ``g`` (inverse of strain_voigt).

    Parameters
    ----------
    g
        ``(..., 6)`` engineering Voigt strains.

    Returns
    -------
    numpy.ndarray
        ``(..., 3, 3)``.

    Examples
    --------
    >>> g = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
    >>> bool(np.allclose(strain_voigt(strain_tensor(g)), g))
    True
    """
    g = np.asarray(g, dtype=float)
    eps = np.zeros((*g.shape[:-1], 3, 3))
    for a, (i, j) in enumerate(VOIGT_PAIRS):
        val = g[..., a] if i == j else 0.5 * g[..., a]
        eps[..., i, j] = val
        eps[..., j, i] = val
    return eps


def to_mandel(D: np.ndarray) -> np.ndarray:
    """Mandel form ``W D W`` of a Voigt stiffness (engineering strains).

    Parameters
    ----------
    D
        ``(..., 6, 6)`` Voigt stiffness.

    Returns
    -------
    numpy.ndarray
        ``(..., 6, 6)``, whose Frobenius norm is that of the fourth-order tensor.

    Examples
    --------
    >>> float(to_mandel(np.eye(6))[3, 3])
    2.0000000000000004
    """
    return D * _MANDEL_W[:, None] * _MANDEL_W[None, :]


def from_mandel(M: np.ndarray) -> np.ndarray:
    """Inverse of :func:`to_mandel`.

    Parameters
    ----------
    M
        ``(..., 6, 6)`` Mandel matrix.

    Returns
    -------
    numpy.ndarray
        ``(..., 6, 6)`` Voigt stiffness.

    Examples
    --------
    >>> bool(np.allclose(from_mandel(to_mandel(np.ones((6, 6)))), 1.0))
    True
    """
    return M / (_MANDEL_W[:, None] * _MANDEL_W[None, :])


def voigt_to_tensor(D: np.ndarray) -> np.ndarray:
    """Fourth-order tensor ``(..., 3, 3, 3, 3)`` of a Voigt stiffness ``(..., 6, 6)``.

    Parameters
    ----------
    D
        ``(..., 6, 6)`` Voigt stiffness (engineering shears).

    Returns
    -------
    numpy.ndarray
        ``C[..., i, j, k, l] = D[..., v(i, j), v(k, l)]``.

    Examples
    --------
    >>> D = 0.4 * np.ones((6, 6)) * (np.arange(6) < 3)[:, None] * (np.arange(6) < 3)
    >>> D += np.diag([0.8, 0.8, 0.8, 0.4, 0.4, 0.4])  # isotropic: lambda = mu = 0.4
    >>> float(voigt_to_tensor(D)[0, 1, 0, 1])  # mu
    0.4
    """
    return D[..., VOIGT[:, :, None, None], VOIGT[None, None, :, :]]


def tensor_to_voigt(C: np.ndarray) -> np.ndarray:
    """Voigt stiffness ``(..., 6, 6)`` of a (minor-symmetric) tensor ``(..., 3, 3, 3, 3)``.

    Parameters
    ----------
    C
        ``(..., 3, 3, 3, 3)`` stiffness tensor.

    Returns
    -------
    numpy.ndarray
        ``(..., 6, 6)``, the inverse of :func:`voigt_to_tensor`.

    Examples
    --------
    >>> D = 0.4 * np.ones((6, 6)) * (np.arange(6) < 3)[:, None] * (np.arange(6) < 3)
    >>> D += np.diag([0.8, 0.8, 0.8, 0.4, 0.4, 0.4])  # isotropic: lambda = mu = 0.4
    >>> bool(np.allclose(tensor_to_voigt(voigt_to_tensor(D)), D))
    True
    """
    i = np.array([p[0] for p in VOIGT_PAIRS])
    j = np.array([p[1] for p in VOIGT_PAIRS])
    return C[..., i[:, None], j[:, None], i[None, :], j[None, :]]


# ----------------------------------------------------------------------- rotations


def mandel_rotation(frames: np.ndarray) -> np.ndarray:
    """Orthogonal 6x6 maps ``m_local = Qm @ m_global`` of Mandel strain vectors.

    Parameters
    ----------
    frames
        ``(m, 3, 3)`` frames, local unit axes as rows (local components are ``Q @ v``).

    Returns
    -------
    numpy.ndarray
        ``(m, 6, 6)`` orthogonal matrices.

    Examples
    --------
    >>> Qm = mandel_rotation(np.eye(3)[None])
    >>> bool(np.allclose(Qm[0], np.eye(6)))
    True
    """
    Q = np.asarray(frames, dtype=float)
    basis = np.zeros((6, 3, 3))
    for a, (i, j) in enumerate(VOIGT_PAIRS):
        if i == j:
            basis[a, i, i] = 1.0
        else:
            basis[a, i, j] = basis[a, j, i] = 1.0 / np.sqrt(2.0)
    rotated = Q[:, None] @ basis[None] @ Q.transpose(0, 2, 1)[:, None]  # Q E_a Q^T
    # Mandel components of the rotated basis tensors are the columns of Qm
    return sym_to_mandel(rotated).transpose(0, 2, 1)


def rotate_to_global(C_local: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """Voigt matrix given in each element's frame -> global Voigt matrix.

    Parameters
    ----------
    C_local
        ``(6, 6)`` or ``(m, 6, 6)`` Voigt stiffness in the element frames.
    frames
        ``(m, 3, 3)`` element frames (rows = local axes).

    Returns
    -------
    numpy.ndarray
        ``(m, 6, 6)`` global Voigt stiffness.

    Examples
    --------
    >>> C = np.diag([3.0, 1.0, 1.0, 0.5, 0.5, 0.5])  # stiff along local x
    >>> swap = np.array([[[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]])  # fiber along y
    >>> float(rotate_to_global(C, swap)[0, 1, 1])
    3.0
    """
    Qm = mandel_rotation(frames)
    M = Qm.transpose(0, 2, 1) @ to_mandel(np.asarray(C_local, float)) @ Qm
    return from_mandel(M)


def rotate_tensor(C_local: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """Rotate local fourth-order tensors to the global frame.

    Parameters
    ----------
    C_local
        ``(..., 3, 3, 3, 3)`` tensors in the element frames.
    frames
        ``(..., 3, 3)``; ``frames[..., a, :]`` is local axis ``a`` as a global unit row.

    Returns
    -------
    numpy.ndarray
        ``C_ijkl = R_ai R_bj R_ck R_dl C_abcd``.

    Examples
    --------
    >>> D = 0.4 * np.ones((6, 6)) * (np.arange(6) < 3)[:, None] * (np.arange(6) < 3)
    >>> D += np.diag([0.8, 0.8, 0.8, 0.4, 0.4, 0.4])  # isotropic: lambda = mu = 0.4
    >>> C = voigt_to_tensor(D)
    >>> R = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    >>> bool(np.allclose(rotate_tensor(C, R), C))  # isotropic: unchanged
    True
    """
    C = np.einsum("...ai,...abcd->...ibcd", frames, C_local)
    C = np.einsum("...bj,...ibcd->...ijcd", frames, C)
    C = np.einsum("...ck,...ijcd->...ijkd", frames, C)
    return np.einsum("...dl,...ijkd->...ijkl", frames, C)

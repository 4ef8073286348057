"""Per-element anisotropy frames: three orthonormal axes per tet (fiber, sheet, normal).

A frame is a ``(3, 3)`` array whose rows are the axes: ``frame[0]`` the fiber, ``frame[1]``
the sheet, ``frame[2]`` the normal ``fiber x sheet``, so every frame is a proper rotation
(orthonormal, determinant +1). Frames for a mesh have shape ``(m, 3, 3)``.

Examples
--------
>>> f = orthonormal_frame([2.0, 0.0, 0.0], [1.0, 1.0, 0.0])
>>> f.round(12).tolist()
[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
>>> uniform_frames(5, [0, 0, 1], [1, 0, 0]).shape
(5, 3, 3)
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .errors import format_ids

#: ``sin`` of the smallest angle accepted between fiber and sheet.
PARALLEL_TOL = 1e-6

_AXIS_NAMES = ("x", "y", "z")


def rotation_matrix(
    axis: Sequence[float] | np.ndarray, angle_rad: float | np.ndarray
) -> np.ndarray:
    """Rotation by ``angle_rad`` about ``axis`` (right-hand rule), Rodrigues' formula.

    Parameters
    ----------
    axis
        Rotation axis ``(3,)``, any non-zero length.
    angle_rad
        Angle in radians; a scalar gives one ``(3, 3)`` matrix, an array of shape ``s``
        gives ``s + (3, 3)``.

    Returns
    -------
    numpy.ndarray
        ``(3, 3)`` or ``s + (3, 3)`` proper rotations.

    Examples
    --------
    >>> (rotation_matrix([0, 0, 1], np.pi / 2) @ [1.0, 0.0, 0.0]).round(12).tolist()
    [0.0, 1.0, 0.0]
    """
    k = np.asarray(axis, dtype=np.float64)
    if k.shape != (3,):
        raise ValueError(f"rotation axis must have 3 components, got shape {k.shape}")
    norm = np.linalg.norm(k)
    if not np.isfinite(norm) or norm == 0.0:
        raise ValueError(f"rotation axis must be finite and non-zero, got {k.tolist()}")
    k = k / norm
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    a = np.asarray(angle_rad, dtype=np.float64)[..., None, None]
    # R = I + sin(a) K + (1 - cos(a)) K^2
    return np.eye(3) + np.sin(a) * K + (1.0 - np.cos(a)) * (K @ K)


def orthonormal_frame(
    fiber: Sequence[float] | np.ndarray, sheet: Sequence[float] | np.ndarray
) -> np.ndarray:
    """Orthonormal right-handed frame from a fiber and a sheet direction (Gram-Schmidt).

    The fiber is normalised; the sheet loses its fiber component and is normalised; the
    normal is ``fiber x sheet``.

    Parameters
    ----------
    fiber, sheet
        Vectors of shape ``(..., 3)`` (broadcast against each other).

    Returns
    -------
    np.ndarray
        Frames ``(..., 3, 3)``; ``frame[..., l, :]`` is axis ``l``.

    Raises
    ------
    ValueError
        If a fiber is zero or not finite, or a sheet is zero or (nearly) parallel to its
        fiber (``sin`` of the angle below :data:`PARALLEL_TOL`). For a batch the message
        names the offending indices.
    """
    f = np.asarray(fiber, dtype=np.float64)
    s = np.asarray(sheet, dtype=np.float64)
    if f.shape[-1:] != (3,) or s.shape[-1:] != (3,):
        raise ValueError(f"fiber and sheet must have 3 components, got {f.shape} and {s.shape}")
    f, s = np.broadcast_arrays(f, s)
    fn = np.linalg.norm(f, axis=-1)
    bad = ~(np.isfinite(fn) & (fn > 0.0))
    if bad.any():
        raise ValueError(f"fiber vector is zero or not finite{_where(bad)}")
    f = f / fn[..., None]
    sn = np.linalg.norm(s, axis=-1)
    # two Gram-Schmidt passes: orthogonal to round-off even for a sheet close to the fiber
    t = s - np.sum(s * f, axis=-1, keepdims=True) * f
    t = t - np.sum(t * f, axis=-1, keepdims=True) * f
    tn = np.linalg.norm(t, axis=-1)
    bad = ~(np.isfinite(sn) & (tn > PARALLEL_TOL * sn))
    if bad.any():
        raise ValueError(f"sheet vector is zero or parallel to the fiber{_where(bad)}")
    t = t / tn[..., None]
    n = np.cross(f, t)
    return np.stack([f, t, n], axis=-2)


def uniform_frames(
    n_elements: int, fiber: Sequence[float] | np.ndarray, sheet: Sequence[float] | np.ndarray
) -> np.ndarray:
    """The same frame ``orthonormal_frame(fiber, sheet)`` for all ``n_elements`` tets.

    Parameters
    ----------
    n_elements
        Number of tets.
    fiber, sheet
        One fiber and one sheet direction ``(3,)`` (see :func:`orthonormal_frame`).

    Returns
    -------
    numpy.ndarray
        ``(n_elements, 3, 3)``; row ``l`` of each frame is axis ``l``.
    """
    frame = orthonormal_frame(fiber, sheet)
    if frame.shape != (3, 3):
        raise ValueError("uniform frames need one fiber and one sheet vector of 3 components")
    return np.ascontiguousarray(np.broadcast_to(frame, (int(n_elements), 3, 3)))


def helix_frames(
    centers: np.ndarray,
    fiber: Sequence[float] | np.ndarray,
    sheet: Sequence[float] | np.ndarray,
    axis: str | int,
    coord_range: tuple[float, float],
    angle_range_deg: tuple[float, float],
    about: str | int | Sequence[float] | np.ndarray | None = None,
) -> np.ndarray:
    """Rotating fiber field, like the transmural helix of myocardial fibers.

    The base frame ``orthonormal_frame(fiber, sheet)`` is rotated as a whole about the
    direction ``about`` by an angle that varies linearly with coordinate ``axis`` of the
    element centre: ``angle_range_deg[0]`` at ``coord_range[0]`` and ``angle_range_deg[1]``
    at ``coord_range[1]``; centres outside the range keep the angle of the nearer end.
    Rotating the whole frame keeps it orthonormal and right-handed.

    Parameters
    ----------
    centers
        Element centres ``(m, 3)``.
    fiber, sheet
        Base frame (the fiber at angle 0).
    axis
        Coordinate along which the angle varies: ``"x"``, ``"y"``, ``"z"`` or 0, 1, 2
        (the transmural direction of a wall).
    coord_range
        ``(c0, c1)``, ``c0 != c1``; e.g. endocardium and epicardium.
    angle_range_deg
        ``(a0, a1)`` in degrees, e.g. ``(60, -60)``. Positive angles turn counter-clockwise
        about ``about`` (right-hand rule).
    about
        Rotation axis: ``None`` (default) rotates about the direction of coordinate ``axis``
        itself, so the fiber turns within the planes of constant depth, as the helix angle
        does in a wall (measured about the transmural direction). Also accepted: a
        coordinate name or index, or a vector ``(3,)`` (e.g. the base frame's normal). The
        base fiber must not be parallel to the rotation axis, or it would not turn; if it is
        oblique to it, the fiber sweeps a cone and turns by less than the prescribed angle.

    Returns
    -------
    np.ndarray
        Frames ``(m, 3, 3)``.

    Examples
    --------
    >>> c = np.array([[0.0, 0, 0], [0.5, 0, 0], [1.0, 0, 0]])
    >>> F = helix_frames(c, [0, 1, 0], [1, 0, 0], "x", (0.0, 1.0), (60.0, -60.0))
    >>> np.degrees(np.arctan2(F[:, 0, 2], F[:, 0, 1])).round(9).tolist()
    [60.0, 0.0, -60.0]
    """
    centers = np.asarray(centers, dtype=np.float64)
    if centers.ndim != 2 or centers.shape[1] != 3:
        raise ValueError(f"element centres must have shape (m, 3), got {centers.shape}")
    k = _axis_index(axis, "helix axis")
    c0, c1 = (float(v) for v in coord_range)
    a0, a1 = (float(v) for v in angle_range_deg)
    if not (np.isfinite([c0, c1, a0, a1]).all() and c0 != c1):
        raise ValueError(
            f"helix range must be two different finite coordinates and angles finite, "
            f"got range {[c0, c1]} and angles {[a0, a1]}"
        )
    base = orthonormal_frame(fiber, sheet)
    if base.shape != (3, 3):
        raise ValueError("helix frames need one fiber and one sheet vector of 3 components")
    if about is None:
        about_vec = np.eye(3)[k]
    elif isinstance(about, str | int | np.integer):
        about_vec = np.eye(3)[_axis_index(about, "helix rotation axis")]
    else:
        about_vec = np.asarray(about, dtype=np.float64)
    about_n = np.linalg.norm(about_vec) if about_vec.shape == (3,) else 0.0
    if not (np.isfinite(about_n) and about_n > 0):
        raise ValueError(f"helix rotation axis must be a non-zero 3-vector, got {about!r}")
    if np.linalg.norm(np.cross(base[0], about_vec / about_n)) <= PARALLEL_TOL:
        raise ValueError(
            f"helix: the fiber {base[0].round(6).tolist()} is parallel to the rotation axis "
            f"{(about_vec / about_n).round(6).tolist()}, so it would not turn; choose a fiber "
            "across the rotation axis or pass 'about'"
        )
    t = np.clip((centers[:, k] - c0) / (c1 - c0), 0.0, 1.0)
    angle = np.radians(a0 + t * (a1 - a0))
    R = rotation_matrix(about_vec, angle)  # (m, 3, 3)
    # rows of the frame are axes: rotated axis l = R @ base[l], i.e. frame = base @ R^T
    return np.ascontiguousarray(np.einsum("lc,kdc->kld", base, R))


def cell_frames(fiber_vectors: np.ndarray, sheet_vectors: np.ndarray | None = None) -> np.ndarray:
    """Frames from per-cell fiber (and sheet) vectors, e.g. cell data of a mesh file.

    Parameters
    ----------
    fiber_vectors
        ``(m, 3)``, any non-zero lengths.
    sheet_vectors
        ``(m, 3)`` or ``None``. When missing, each sheet is the coordinate axis least aligned
        with the fiber (lowest index on ties) made orthogonal to it: deterministic, but the
        choice can jump between neighbouring cells, so use it only with laws that do not
        distinguish sheet from normal (e.g. transversely isotropic).

    Returns
    -------
    numpy.ndarray
        ``(m, 3, 3)`` orthonormal frames, rows fiber, sheet, normal.

    Raises
    ------
    ValueError
        Naming the cells whose fiber is zero or whose sheet is parallel to the fiber.
    """
    f = np.asarray(fiber_vectors, dtype=np.float64)
    if f.ndim != 2 or f.shape[1] != 3:
        raise ValueError(f"fiber vectors must have shape (m, 3), got {f.shape}")
    if sheet_vectors is None:
        pick = np.argmin(np.abs(f), axis=1)
        s = np.eye(3)[pick]
    else:
        s = np.asarray(sheet_vectors, dtype=np.float64)
        if s.shape != f.shape:
            raise ValueError(f"sheet vectors must have shape {f.shape}, got {s.shape}")
    return orthonormal_frame(f, s)


def _axis_index(axis: str | int, what: str) -> int:
    if isinstance(axis, str) and axis in _AXIS_NAMES:
        return _AXIS_NAMES.index(axis)
    if isinstance(axis, int | np.integer) and not isinstance(axis, bool) and 0 <= axis < 3:
        return int(axis)
    raise ValueError(f"{what} must be one of 'x', 'y', 'z' or 0, 1, 2, got {axis!r}")


def _where(bad: np.ndarray, limit: int = 8) -> str:
    """`` at elements 3, 7`` for a batch, empty for a single vector."""
    if bad.ndim == 0:
        return ""
    idx = np.argwhere(bad)
    return " at elements " + format_ids(idx if idx.shape[1] > 1 else idx[:, 0], limit)

"""Barycentric volume springs (eqs. 2.76–2.77) and the volume measures LMS reads.

``xi_j = x_j - x_b`` (barycenter to vertex, the restoring sign of
docs/spec.rst#the-volume-spring-sign) and
``dL = sum_j |xi_j| - L0``; the ``gradient`` and ``spec`` forms are described in
:mod:`springmodel.springs`.

Examples
--------
>>> import numpy as np
>>> from types import SimpleNamespace
>>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> V, L = volume_measures(X, SimpleNamespace(tets=np.array([[0, 1, 2, 3]])))
>>> round(float(V[0]), 12)  # the unit corner tet
0.166666666667
>>> resolve_volume_form(SimpleNamespace(volume_form="spec"), None)
'spec'
"""

from __future__ import annotations

import numpy as np

from springfem.mesh import tet_volumes

from ..elements import SpringElements
from ..options import SpringOptions, VolumeForm
from .points import scatter


def resolve_volume_form(options: SpringOptions, volume_form: VolumeForm | None) -> str:
    """The volume-spring form to use: ``volume_form`` if given, else ``options.volume_form``.

    Parameters
    ----------
    options
        Spring options (``volume_form``; ``gradient`` when the attribute is missing).
    volume_form
        ``gradient``, ``spec`` or None.

    Returns
    -------
    str
        ``gradient`` or ``spec``.

    Raises
    ------
    ValueError
        If the form is neither ``gradient`` nor ``spec``.
    """
    form = volume_form or getattr(options, "volume_form", "gradient")
    if form not in ("gradient", "spec"):
        raise ValueError(f"volume_form {form!r} is not one of gradient, spec")
    return form


def volume_forces(
    x: np.ndarray,
    v: np.ndarray | None,
    elements: SpringElements,
    options: SpringOptions,
    volume_form: VolumeForm | None = None,
) -> np.ndarray:
    """Barycentric volume spring forces (2.76–2.77) with optional damping, on the nodes.

    ``gradient``: ``f_j = -k_s dL (xh_j - mean_i xh_i)``, the exact ``-dU/dx`` of
    ``U = k_s/2 dL^2``; ``spec``: ``f_j = -k_s dL xh_j``. Damping ``-c (v_j - v_b)`` with
    ``c = options.volume_damping`` (N s/m).

    Parameters
    ----------
    x
        Node positions ``(n, 3)`` (m).
    v
        Node velocities ``(n, 3)`` (m/s), or None for no damping.
    elements
        Rest data: ``k_volume`` ``(n_tets,)`` (N/m) and ``L0`` ``(n_tets,)`` (m).
    options
        ``volume_form`` and ``volume_damping``.
    volume_form
        Overrides ``options.volume_form`` (``gradient`` or ``spec``).

    Returns
    -------
    ndarray
        Nodal forces ``(n, 3)`` (N); net force zero for ``gradient`` (not for ``spec`` on
        irregular tets).

    Raises
    ------
    ValueError
        If the volume form is neither ``gradient`` nor ``spec``.
    """
    form = resolve_volume_form(options, volume_form)
    X = x[elements.tets]
    xb = X.mean(axis=1, keepdims=True)  # eq. 2.22
    xi = X - xb  # restoring sign: barycenter -> vertex
    r = np.linalg.norm(xi, axis=-1)
    xh = xi / r[..., None]
    dL = r.sum(axis=1) - elements.L0
    direction = xh - xh.mean(axis=1, keepdims=True) if form == "gradient" else xh
    f = -(elements.k_volume * dL)[:, None, None] * direction  # eq. 2.77
    if options.volume_damping > 0 and v is not None:
        V = v[elements.tets]
        f -= options.volume_damping * (V - V.mean(axis=1, keepdims=True))
    return scatter(f, elements.tets, x.shape[0])


def volume_measures(x: np.ndarray, elements: SpringElements) -> tuple[np.ndarray, np.ndarray]:
    """Current volumes and radial sums of the elements (the inputs of LMS, eq. 2.81).

    Parameters
    ----------
    x
        Node positions ``(n, 3)`` (m).
    elements
        Anything with ``tets`` ``(n_tets, 4)``.

    Returns
    -------
    V, sum_xi
        Signed volumes ``(n_tets,)`` (m^3) and ``sum_j |x_j - x_b|`` ``(n_tets,)`` (m).
    """
    X = x[elements.tets]
    r = np.linalg.norm(X - X.mean(axis=1, keepdims=True), axis=-1)
    return tet_volumes(x, elements.tets), r.sum(axis=1)

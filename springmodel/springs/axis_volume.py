"""Axis-volume and Poisson-coupling springs as nodal forces (:mod:`springmodel.axis_springs`).

Both act on the axis vectors only: ``g_l`` on ``q_{2l}`` and ``-g_l`` on ``q_{2l+1}``,
distributed to the vertices with ``C^k``.

Examples
--------
>>> import numpy as np
>>> from springfem.scene import Material
>>> from springmodel.elements import build_spring_elements
>>> from springmodel.options import SpringOptions
>>> X = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> options = SpringOptions(volume="axes", torsion="energy")
>>> e = build_spring_elements(X, np.array([[0, 1, 2, 3]]), np.eye(3)[None],
...                           material=Material("linear", 1.0e4, 0.3), options=options)
>>> f = axis_forces(1.01 * X, None, e, options)  # expanded: pushed back, net force zero
>>> bool(abs(f.sum(axis=0)).max() < 1e-12), bool((f * (X - 0.25)).sum() < 0)
(True, True)
"""

from __future__ import annotations

import numpy as np

from ..axis_springs import axis_volume_axis_forces, coupling_axis_forces
from ..elements import SpringElements
from ..options import SpringOptions
from .points import distribute, intersection_points, scatter


def axis_forces(
    x: np.ndarray, v: np.ndarray | None, elements: SpringElements, options: SpringOptions
) -> np.ndarray:
    """Axis-volume (``volume = "axes"``) and Poisson-coupling forces, on the nodes.

    Parameters
    ----------
    x
        Node positions ``(n, 3)`` (m).
    v
        Node velocities ``(n, 3)`` (m/s), or None; used for the volume-rate damping of the
        axis-volume spring when ``options.volume_damping > 0``.
    elements
        Rest data: ``k_axis_volume`` ``(n_tets,)`` (Pa), ``k_coupling`` ``(n_tets, 3)`` (J),
        ``det0``, ``V0``.
    options
        ``axis_volume``, ``coupling``, ``volumetric`` (the ``U(J)``) and ``volume_damping``.

    Returns
    -------
    ndarray
        Nodal forces ``(n, 3)`` (N); zeros when both parts are off. Net force and net
        torque zero.
    """
    q = intersection_points(x, elements)
    zeta = q[:, 0::2] - q[:, 1::2]
    g = np.zeros_like(zeta)
    if options.axis_volume:
        zeta_dot = None
        if v is not None and options.volume_damping > 0:
            vq = intersection_points(v, elements)
            zeta_dot = vq[:, 0::2] - vq[:, 1::2]
        g += axis_volume_axis_forces(
            zeta, zeta_dot, elements, options.volumetric, options.volume_damping
        )
    if options.coupling:
        g += coupling_axis_forces(zeta, elements)
    fq = np.zeros_like(q)
    for l in range(3):
        fq[:, 2 * l] += g[:, l]
        fq[:, 2 * l + 1] -= g[:, l]
    return scatter(distribute(fq, elements), elements.tets, x.shape[0])

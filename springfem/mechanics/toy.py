"""A one-DOF mechanical system for the examples of the solver modules.

One tet whose node 3 moves along x only: mass 1, spring stiffness 4, load ``s`` (the load
factor), so the equilibrium is ``x = s / 4``, the period ``pi`` and the energy
``2 x^2 - s x``. It implements the whole
:class:`~springfem.mechanics.system.MechanicalSystem` protocol, with an analytic stiffness.

Examples
--------
>>> sys = Oscillator()
>>> float(sys.forces(sys.x0, None, 1.0)[3, 0]), sys.fixed_dofs.size
(1.0, 11)
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp


class Oscillator:
    """Node 3 of one tet on a spring of stiffness 4 along x, mass 1, load ``s`` along x.

    Attributes
    ----------
    x0
        Rest positions ``(4, 3)``.
    masses
        Nodal masses (all 1).
    fixed_dofs
        Every DOF but node 3's x.
    """

    x0 = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    masses = np.ones(4)
    fixed_dofs = np.array([0, 1, 2, 3, 4, 5, 6, 7, 8, 10, 11])

    def prescribed(self, s: float) -> np.ndarray:
        """Positions of the fixed DOFs (at rest for any load factor ``s``)."""
        return self.x0.reshape(-1)[self.fixed_dofs]

    def forces(self, x: np.ndarray, v: np.ndarray | None, s: float = 1.0) -> np.ndarray:
        """Nodal forces ``(4, 3)``: ``-4 x + s`` on node 3's x, zero elsewhere."""
        f = np.zeros((4, 3))
        f[3, 0] = -4.0 * x[3, 0] + s
        return f

    def energy(self, x: np.ndarray, s: float = 1.0) -> float:
        """Potential energy ``2 x^2 - s x`` of node 3."""
        return 2.0 * x[3, 0] ** 2 - s * x[3, 0]

    def stiffness(self, x: np.ndarray, s: float = 1.0) -> sp.csr_matrix:
        """``K = -df/dx``: 4 on node 3's x DOF."""
        return sp.csr_matrix(([4.0], ([9], [9])), shape=(12, 12))

    def element_nodes(self) -> np.ndarray:
        """The one tet."""
        return np.array([[0, 1, 2, 3]])

    def post_step(self, x: np.ndarray, dt: float) -> None:
        """Nothing to update between steps."""

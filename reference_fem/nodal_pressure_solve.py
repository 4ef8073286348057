"""Direct solves of the nodal-volume tangent through its nodal-pressure form.

The nodal-volume tangent (:mod:`reference_fem.nodal_volume`) is ``K = K_e + B^T D B``: P1
element blocks ``K_e`` plus the nodal volumetric term, ``B = dV_a/dx`` (a row per node) and
``D = diag((1 - f) U''(J_a) / V_a^0)``. ``B^T D B`` couples every node with its patch's
patches, so ``K`` has about four times P1's non-zeros and its factor fills accordingly. The
same correction solves the augmented system with the nodal pressures ``q = D B dx`` as
unknowns,

    [K_e   B^T   ] [dx]   [b]
    [B    -D^-1  ] [q ] = [0],

whose blocks have P1's stencil (``B`` couples a node with its patch only): a larger but
sparser, symmetric indefinite matrix, factorised as a saddle point. Only the factorisation
changes; residual, tangent and Newton are those of the displacement problem
(docs/fem.rst#nodal-volume-measurements).

Examples
--------
>>> import numpy as np, scipy.sparse as sp
>>> from springfem.mechanics import LinearSolver
>>> Ke = sp.csr_matrix(np.diag([2.0, 3.0]))
>>> B = sp.csr_matrix(np.array([[1.0, 1.0]]))
>>> K = with_nodal_parts(sp.csr_matrix(Ke + B.T @ B), Ke, B, np.array([1.0]))
>>> x = NodalPressureSolver(LinearSolver("direct")).solve(K, np.array([1.0, 1.0]))
>>> bool(np.allclose(x, np.linalg.solve(K.toarray(), [1.0, 1.0])))
True
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from springfem.mechanics import LinearSolver


def with_nodal_parts(K: sp.csr_matrix, Ke, B, d: np.ndarray) -> sp.csr_matrix:
    """Attach ``(K_e, B, D)`` to the assembled tangent ``K`` (which stays the operator).

    Parameters
    ----------
    K
        The tangent ``K_e + B^T diag(d) B`` (CSR).
    Ke, B, d
        Its element part, the nodal volume gradients ``(n_nodes, n_dofs)`` and the weights.

    Returns
    -------
    scipy.sparse.csr_matrix
        ``K`` itself.
    """
    K.nodal_parts = (Ke, B, np.asarray(d, dtype=float))
    return K


class _Augmented:
    """A factorised augmented system; ``solve(b)`` returns the displacement part."""

    def __init__(self, factor, n: int, m: int):
        self.factor, self.n, self.m = factor, n, m

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self.factor.solve(np.concatenate([np.asarray(b, dtype=float), np.zeros(self.m)]))[
            : self.n
        ]


class NodalPressureSolver:
    """A :class:`~springfem.mechanics.LinearSolver` that factorises a tangent carrying
    nodal parts (:func:`with_nodal_parts`) in its augmented form when the solve is direct;
    everything else goes to the wrapped solver.

    Parameters
    ----------
    solver
        The problem's linear solver (its statistics and direct backend are shared).
    """

    def __init__(self, solver: LinearSolver):
        self.solver = solver
        self.saddle = LinearSolver(
            solver.method, saddle_point=True, stats=solver.stats, direct=solver.direct
        )

    def __getattr__(self, name: str):
        return getattr(self.solver, name)

    def factorize(self, K, free=None, symmetric=None, where: str = "", reuse=None):
        """As :meth:`LinearSolver.factorize`; augmented for a direct solve of nodal parts."""
        parts = getattr(K, "nodal_parts", None)
        n_free = K.shape[0] if free is None else int(np.count_nonzero(free))
        if parts is None or self.solver.kind(n_free) != "direct" or not (parts[2] > 0).all():
            return self.solver.factorize(K, free, symmetric, where, reuse)
        Ke, B, d = parts
        A = sp.bmat([[Ke, B.T], [B, sp.diags(-1.0 / d)]], format="csr")
        keep = np.ones(K.shape[0], dtype=bool) if free is None else np.asarray(free, bool)
        mask = np.concatenate([keep, np.ones(B.shape[0], dtype=bool)])
        factor = self.saddle.factorize(A, mask, symmetric, where)
        return _Augmented(factor, K.shape[0], B.shape[0])

    def solve(self, K, b, free=None, symmetric=None, where: str = "") -> np.ndarray:
        """As :meth:`LinearSolver.solve`."""
        return self.factorize(K, free, symmetric, where).solve(b)

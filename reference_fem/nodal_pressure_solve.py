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

The augmented form can be singular where ``K`` is not. A mesh can carry more nodal
pressures than its free displacements can see: on the five-tet box splits ``B`` restricted
to the free DOFs has dependent rows (global checkerboard pressure modes ``q`` with
``B^T q = 0``, three on Land's beam at 24x3x3), and only the compliance ``-D^-1``, about
``1e-9`` of the matrix's largest entries for a nearly incompressible material, holds them.
A symmetric indefinite factorisation perturbs those pivots and its solutions miss. Every
solution is therefore checked against ``K`` itself (``|K dx - b| <=
RESIDUAL_ACCEPT |b|``); a factorisation that fails or misses is detected there, and the
solver then factorises the displacement tangent ``K`` (the penalty form, which has no
pressure unknowns and so no pressure modes) for the rest of the solve, and says so in
:attr:`NodalPressureSolver.note` (a solve's ``result.info["nodal_pressure"]``).

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

from typing import Any

import numpy as np
import scipy.sparse as sp

from springfem.errors import SolverError
from springfem.mechanics import LinearSolver
from springfem.mechanics.linsolve import RESIDUAL_ACCEPT


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
    """A factorised augmented system; ``solve(b)`` returns the displacement part.

    Each solution is checked against the displacement tangent ``K``; one that fails or
    misses hands the solve to ``K``'s own factorisation (:class:`NodalPressureSolver`).
    """

    def __init__(self, owner: NodalPressureSolver, factor, K, free, symmetric, where: str):
        self.owner, self.factor, self.K, self.free = owner, factor, K, free
        self.symmetric, self.where = symmetric, where
        self.fallback: Any = None  # K's own factorisation, once the augmented form missed

    def solve(self, b: np.ndarray) -> np.ndarray:
        b = np.asarray(b, dtype=float)
        if self.fallback is None and self.factor is not None:
            n, m = self.K.shape[0], self.K.nodal_parts[1].shape[0]
            try:
                x = self.factor.solve(np.concatenate([b, np.zeros(m)]))[:n]
            except SolverError as exc:
                self.owner.give_up(str(exc))
            else:
                if self._accepted(x, b):
                    return x
                self.owner.give_up("its solution misses the displacement tangent")
        if self.fallback is None:
            self.fallback = self.owner.solver.factorize(self.K, self.free, self.symmetric,
                                                        self.where)  # fmt: skip
        return self.fallback.solve(b)

    def _accepted(self, x: np.ndarray, b: np.ndarray) -> bool:
        keep = slice(None) if self.free is None else np.asarray(self.free, dtype=bool)
        r, bf = (self.K @ x - b)[keep], b[keep]
        bnorm = float(np.linalg.norm(bf))
        return bool(np.all(np.isfinite(x)) and np.linalg.norm(r) <= RESIDUAL_ACCEPT * bnorm)


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
        #: Why the augmented form was given up (``None`` while it solves).
        self.note: str | None = None

    def __getattr__(self, name: str):
        return getattr(self.solver, name)

    def give_up(self, reason: str) -> None:
        """Solve every later system by the displacement tangent, recording ``reason``."""
        if self.note is None:
            self.note = (
                "the nodal-pressure saddle point is singular on this mesh (pressure modes the "
                f"free displacements do not see: {reason}); solved by the displacement "
                "tangent, the penalty form"
            )

    def factorize(self, K, free=None, symmetric=None, where: str = "", reuse=None):
        """As :meth:`LinearSolver.factorize`; augmented for a direct solve of nodal parts."""
        parts = getattr(K, "nodal_parts", None)
        n_free = K.shape[0] if free is None else int(np.count_nonzero(free))
        direct = self.solver.kind(n_free) == "direct"
        if parts is None or not direct or not (parts[2] > 0).all() or self.note is not None:
            return self.solver.factorize(K, free, symmetric, where, reuse)
        Ke, B, d = parts
        A = sp.bmat([[Ke, B.T], [B, sp.diags(-1.0 / d)]], format="csr")
        keep = np.ones(K.shape[0], dtype=bool) if free is None else np.asarray(free, bool)
        mask = np.concatenate([keep, np.ones(B.shape[0], dtype=bool)])
        try:
            factor = self.saddle.factorize(A, mask, symmetric, where)
        except SolverError as exc:  # an exactly singular factor
            self.give_up(str(exc))
            return self.solver.factorize(K, free, symmetric, where, reuse)
        return _Augmented(self, factor, K, free, symmetric, where)

    def solve(self, K, b, free=None, symmetric=None, where: str = "") -> np.ndarray:
        """As :meth:`LinearSolver.solve`."""
        return self.factorize(K, free, symmetric, where).solve(b)

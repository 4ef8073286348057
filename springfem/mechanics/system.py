"""The mechanical system the solvers drive, and small helpers on it.

The solvers of :mod:`springfem.mechanics` never look at springs: they see nodal masses,
constrained DOFs, a force function, optionally an energy and an analytic tangent, and the
element connectivity (the sparsity pattern of the tangent). Anything with these members is
a :class:`MechanicalSystem` (structural typing: no base class to inherit).

DOF numbering: node ``i``, component ``c`` is DOF ``3 i + c`` (row-major flattening of an
``(n, 3)`` position array).

Examples
--------
>>> import numpy as np
>>> x = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
>>> B = rigid_body_modes(x)
>>> B.shape, int(np.linalg.matrix_rank(B))
((12, 6), 6)
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from springfem.errors import SolverError

SINGULAR_MESSAGE = "singular stiffness: the scene has no boundary condition that stops rigid motion"


@runtime_checkable
class MechanicalSystem(Protocol):
    """What a solver needs to know about a discretised body.

    Attributes
    ----------
    x0
        Rest positions, shape ``(n, 3)``.
    masses
        Lumped nodal masses ``(n,)``, all ``> 0``.
    fixed_dofs
        Constrained DOFs (``node * 3 + component``), int array.
    """

    x0: np.ndarray
    masses: np.ndarray
    fixed_dofs: np.ndarray

    def prescribed(self, scale: float) -> np.ndarray:
        """Positions at ``fixed_dofs`` (flattened ``x``) for the load factor ``scale``."""
        ...

    def forces(self, x: np.ndarray, v: np.ndarray | None, scale: float = 1.0) -> np.ndarray:
        """Total nodal force ``(n, 3)``: internal (with damping if ``v`` is given) plus
        external loads times ``scale``."""
        ...

    def energy(self, x: np.ndarray, scale: float = 1.0) -> float | None:
        """Total potential energy (internal minus the work of dead loads), or ``None`` when
        the forces are not the gradient of an energy."""
        ...

    def stiffness(self, x: np.ndarray, scale: float = 1.0) -> sp.csr_matrix | None:
        """Analytic tangent ``K = -d forces / dx`` (``3n x 3n``), or ``None``."""
        ...

    def element_nodes(self) -> np.ndarray:
        """Element connectivity ``(m, 4)``: nodes of an element are coupled in ``K``."""
        ...

    def post_step(self, x: np.ndarray, dt: float) -> None:
        """Hook called after every time step (e.g. the LMS stiffness update, eq. 2.81)."""
        ...


def n_dofs(system: MechanicalSystem) -> int:
    """Number of DOFs ``3 n``.

    Parameters
    ----------
    system
        The system.

    Returns
    -------
    int
        ``3 n``.
    """
    return 3 * int(np.asarray(system.x0).shape[0])


def free_dofs(system: MechanicalSystem) -> np.ndarray:
    """Sorted unconstrained DOFs.

    Parameters
    ----------
    system
        The system.

    Returns
    -------
    numpy.ndarray
        Free DOF indices (``3 node + component``).
    """
    mask = np.ones(n_dofs(system), dtype=bool)
    mask[np.asarray(system.fixed_dofs, dtype=np.int64)] = False
    return np.flatnonzero(mask)


def constrained_positions(
    system: MechanicalSystem, scale: float = 1.0, x: np.ndarray | None = None
) -> np.ndarray:
    """A copy of ``x`` (default: the rest positions) with the fixed DOFs set to
    ``prescribed(scale)``.

    Parameters
    ----------
    system
        The system.
    scale
        Load factor.
    x
        Positions ``(n, 3)`` (default: the rest positions).

    Returns
    -------
    numpy.ndarray
        ``(n, 3)`` positions.
    """
    out = np.array(system.x0 if x is None else x, dtype=float, copy=True).reshape(-1, 3)
    fixed = np.asarray(system.fixed_dofs, dtype=np.int64)
    if fixed.size:
        out.reshape(-1)[fixed] = system.prescribed(scale)
    return out


def rigid_body_modes(x: np.ndarray) -> np.ndarray:
    """The six infinitesimal rigid-body motions at positions ``x``, shape ``(3n, 6)``.

    Columns 0-2 are translations, 3-5 rotations about the centroid (``w x (x - c)``).
    Used to check that the constraints stop rigid motion and as the near-nullspace of
    smoothed-aggregation AMG. The one definition both models use.

    Parameters
    ----------
    x
        Node positions ``(n, 3)``.

    Returns
    -------
    numpy.ndarray
        ``(3 n, 6)``, interleaved DOFs (``3 node + component``).
    """
    x = np.asarray(x, dtype=float).reshape(-1, 3)
    r = x - x.mean(axis=0)
    n = x.shape[0]
    B = np.zeros((n, 3, 6))
    for c in range(3):
        B[:, c, c] = 1.0
    # w x r for unit w along x, y, z
    B[:, 1, 3], B[:, 2, 3] = -r[:, 2], r[:, 1]
    B[:, 0, 4], B[:, 2, 4] = r[:, 2], -r[:, 0]
    B[:, 0, 5], B[:, 1, 5] = -r[:, 1], r[:, 0]
    return B.reshape(3 * n, 6)


def node_adjacency(tets: np.ndarray, n_nodes: int) -> sp.csr_matrix:
    """Boolean node adjacency (``i ~ j`` when they share an element), diagonal included.

    Parameters
    ----------
    tets
        Element connectivity ``(m, k)``.
    n_nodes
        Number of nodes.

    Returns
    -------
    scipy.sparse.csr_matrix
        ``(n_nodes, n_nodes)`` int8 pattern.
    """
    tets = np.asarray(tets, dtype=np.int64)
    k = tets.shape[1]
    rows = np.repeat(tets, k, axis=1).ravel()
    cols = np.tile(tets, (1, k)).ravel()
    diag = np.arange(n_nodes)
    A = sp.csr_matrix(
        (
            np.ones(rows.size + n_nodes, dtype=np.int8),
            (np.concatenate([rows, diag]), np.concatenate([cols, diag])),
        ),
        shape=(n_nodes, n_nodes),
    )
    A.sum_duplicates()
    A.data[:] = 1
    return A


def check_constrained(system: MechanicalSystem, x: np.ndarray | None = None) -> None:
    """Raise :class:`SolverError` if the constraints leave a rigid-body motion free.

    Each connected part of the mesh (nodes linked through elements) must have constrained
    DOFs on which its rigid-body modes stay linearly independent (rank 6 for a solid part;
    5 for collinear nodes, 3 for a lone node). A part with a single fixed node, or one
    fixed along one axis only, can still rotate or slide. Mechanisms of the spring network
    itself are caught later, by the linear solver.

    Parameters
    ----------
    system
        The system.
    x
        Positions to test at (default: the rest positions).

    Returns
    -------
    None

    Raises
    ------
    SolverError
        Naming the part and the number of free rigid-body modes.
    """
    x = np.asarray(system.x0 if x is None else x, dtype=float).reshape(-1, 3)
    n = x.shape[0]
    fixed = np.asarray(system.fixed_dofs, dtype=np.int64)
    if fixed.size == 0:
        raise SolverError(SINGULAR_MESSAGE + " (no constrained DOF at all)")
    A = node_adjacency(system.element_nodes(), n)
    n_parts, label = connected_components(A, directed=False)
    is_fixed = np.zeros(3 * n, dtype=bool)
    is_fixed[fixed] = True
    for part in range(n_parts):
        nodes = np.flatnonzero(label == part)
        dofs = (3 * nodes[:, None] + np.arange(3)).ravel()
        B = rigid_body_modes(x[nodes])
        Bc = B[is_fixed[dofs]]
        full = np.linalg.matrix_rank(B, tol=1e-9 * max(np.abs(B).max(), 1e-300))
        got = np.linalg.matrix_rank(Bc, tol=1e-9 * max(np.abs(B).max(), 1e-300)) if Bc.size else 0
        if got < full:
            where = "" if n_parts == 1 else f" (part {part} of {n_parts}: {nodes.size} nodes)"
            raise SolverError(
                f"{SINGULAR_MESSAGE}{where}: {full - got} rigid-body mode(s) left free by "
                f"{int(is_fixed[dofs].sum())} constrained DOF(s)"
            )

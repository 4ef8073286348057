"""Size limits: a mesh too large for this machine is refused before it is built or solved.

Examples
--------
>>> check_mesh_size(48) is None
True
>>> check_mesh_size(10**9)[:12]
'1e+09 tets w'
"""

from __future__ import annotations

import os

#: Largest mesh accepted on any machine.
MAX_TETS = 20_000_000
#: Working set per tet of the spring model plus the P1 FEM (measured order of magnitude).
BYTES_PER_TET = 2_000


def machine_memory() -> int | None:
    """Physical memory of this machine.

    Returns
    -------
    int or None
        Bytes, or ``None`` if the OS does not say.
    """
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return None


def check_mesh_size(n_tets: int) -> str | None:
    """Why a mesh of ``n_tets`` tets is refused before it is built or solved, or ``None``.

    The working set of the spring model and the P1 reference is estimated at
    :data:`BYTES_PER_TET` per tet; a mesh is refused when that exceeds the machine's
    physical memory or when it has more than :data:`MAX_TETS` tets.

    Parameters
    ----------
    n_tets
        Number of tets of the mesh.

    Returns
    -------
    str or None
        The reason, with the estimate, or ``None`` when the mesh fits.
    """
    need = n_tets * BYTES_PER_TET
    mem = machine_memory()
    if mem is not None and need > mem:
        return (
            f"{n_tets:.3g} tets would need about {need / 2**30:.3g} GiB; this machine has "
            f"{mem / 2**30:.3g} GiB"
        )
    if n_tets > MAX_TETS:
        return (
            f"{n_tets:.3g} tets would need about {need / 2**30:.3g} GiB; the limit here is "
            f"{MAX_TETS:.0e} tets"
        )
    return None

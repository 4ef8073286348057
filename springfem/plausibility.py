"""Is a solution plausible? Checks of a displacement field against the body and its law.

A solver can converge to a state no tissue reaches: most of the volume gone at ν = 0.45, a
small-strain law at 30 % strain, a displacement larger than the body. :func:`check_solution`
looks at the deformed P1 elements of any model's vertex displacements and returns one
:class:`Finding` per implausible quantity, each naming the quantity, its value, where it is
and why it is implausible:

- the element volume ratios ``J``: an inverted element (``J <= 0``), or ``J`` outside
  :data:`J_RANGE`;
- the body's volume change against what the law allows: a nearly incompressible material
  (Poisson's ratio of at least :data:`NEARLY_INCOMPRESSIBLE`, an incompressible flag, or a
  bulk modulus of more than 10 × the shear modulus) should change its volume by at most
  :data:`VOLUME_CHANGE_NEARLY_INCOMPRESSIBLE`, any material by at most
  :data:`VOLUME_CHANGE_ANY`;
- the largest principal Green–Lagrange strain of a small-strain law beyond
  :data:`SMALL_STRAIN`;
- the largest displacement beyond the body's size (its bounding-box diagonal).

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({"mesh": {"generator": "box", "size": [1, 1, 1],
...     "divisions": [1, 1, 1]}, "material": {"law": "neo-hookean", "E": 3.0, "nu": 0.45}})
>>> u = -0.6 * scene.mesh.points  # the block shrunk to 40 % of its size: J = 0.064
>>> [f.quantity for f in check_solution(scene, u, "neo-hookean")]
['J', 'volume change']
>>> check_solution(scene, 0.0 * u, "neo-hookean")
[]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .mesh import displacement_gradients, tet_volumes
from .scene import Scene

#: Element volume ratios outside this range are not soft tissue under load.
J_RANGE = (0.2, 5.0)
#: A small-strain law is trusted up to this largest principal Green–Lagrange strain.
SMALL_STRAIN = 0.05
#: Poisson's ratio from which a material counts as nearly incompressible.
NEARLY_INCOMPRESSIBLE = 0.45
#: Largest plausible relative volume change of a nearly incompressible body.
VOLUME_CHANGE_NEARLY_INCOMPRESSIBLE = 0.1
#: Largest plausible relative volume change of any body.
VOLUME_CHANGE_ANY = 0.5
#: The small-strain laws.
LINEAR_LAWS = ("linear", "transverse-linear")


@dataclass(frozen=True)
class Finding:
    """One implausible quantity of a solution.

    Attributes
    ----------
    quantity
        ``J``, ``volume change``, ``strain`` or ``displacement``.
    value
        Its value (the extreme one).
    where
        Where it is (an element and its centroid), or ``""`` for the whole body.
    line
        The one-line warning.
    """

    quantity: str
    value: float
    where: str
    line: str


def nearly_incompressible(scene: Scene) -> bool:
    """Whether the scene's material is nearly incompressible (see the module docstring).

    Parameters
    ----------
    scene
        The scene.

    Returns
    -------
    bool
    """
    mat = scene.material
    if getattr(mat, "incompressible", False):
        return True
    nu = getattr(mat, "nu", None)
    if nu is not None and np.isfinite(nu) and nu >= NEARLY_INCOMPRESSIBLE:
        return True
    kappa = float(getattr(mat, "kappa", 0.0) or 0.0)
    mu = float(getattr(mat, "mu", 0.0) or 0.0)
    return mu > 0 and kappa > 10.0 * mu


def _at(scene: Scene, e: int) -> str:
    c = scene.mesh.points[scene.mesh.tets[e]].mean(axis=0)
    return f"element {e} at x = {np.round(c, 6).tolist()}"


def check_solution(scene: Scene, u: np.ndarray, law: str) -> list[Finding]:
    """The implausible quantities of a solution (empty when it is plausible).

    Parameters
    ----------
    scene
        The scene solved.
    u
        Vertex displacements ``(n, 3)``.
    law
        The law solved with (a result's ``law``; its first word counts: ``linear``,
        ``neo-hookean/coupled`` ...).

    Returns
    -------
    list of Finding
    """
    u = np.asarray(u, dtype=float).reshape(-1, 3)
    if not np.isfinite(u).all():
        return [Finding("displacement", float("nan"), "", "the displacement is not finite")]
    mesh = scene.mesh
    out: list[Finding] = []
    V0 = tet_volumes(mesh.points, mesh.tets)
    J = tet_volumes(mesh.points + u, mesh.tets) / V0
    e_lo, e_hi = int(np.argmin(J)), int(np.argmax(J))
    if J[e_lo] <= 0:
        n = int((J <= 0).sum())
        line = (
            f"{n} inverted elements (J <= 0; smallest J = {J[e_lo]:.3g} at {_at(scene, e_lo)}): "
            "the state is not a deformation"
        )
        out.append(Finding("J", float(J[e_lo]), _at(scene, e_lo), line))
    elif J[e_lo] < J_RANGE[0] or J[e_hi] > J_RANGE[1]:
        e = e_lo if J[e_lo] < J_RANGE[0] else e_hi
        line = (
            f"element volume ratio J = {J[e]:.3g} at {_at(scene, e)} is outside "
            f"{J_RANGE[0]:g}-{J_RANGE[1]:g}, no tissue's range under load"
        )
        out.append(Finding("J", float(J[e]), _at(scene, e), line))
    dV = float((V0 * J).sum() / V0.sum() - 1.0)
    incompressible = nearly_incompressible(scene)
    limit = VOLUME_CHANGE_NEARLY_INCOMPRESSIBLE if incompressible else VOLUME_CHANGE_ANY
    if abs(dV) > limit:
        what = "a nearly incompressible material" if incompressible else "soft tissue"
        line = (
            f"the volume changes by {dV:+.1%}, more than {limit:.0%}, implausible for {what}: "
            "check the load and the modulus"
        )
        out.append(Finding("volume change", dV, "", line))
    if law.split("/")[0] in LINEAR_LAWS:
        H = displacement_gradients(mesh.points, mesh.tets, u)
        E = 0.5 * (H + np.swapaxes(H, 1, 2) + np.swapaxes(H, 1, 2) @ H)
        eig = np.abs(np.linalg.eigvalsh(E)).max(axis=1)
        e = int(np.argmax(eig))
        if eig[e] > SMALL_STRAIN:
            line = (
                f"the {law} (small-strain) solution reaches {eig[e]:.1%} strain at "
                f"{_at(scene, e)} (> {SMALL_STRAIN:.0%}): use a finite-strain law "
                "(neo-hookean; compare does)"
            )
            out.append(Finding("strain", float(eig[e]), _at(scene, e), line))
    size = float(np.linalg.norm(mesh.points.max(axis=0) - mesh.points.min(axis=0)))
    norms = np.linalg.norm(u, axis=1)
    i = int(np.argmax(norms))
    if norms[i] > size:
        where = f"node {i} at x = {np.round(mesh.points[i], 6).tolist()}"
        line = (
            f"the largest displacement {norms[i]:.3g} at {where} exceeds the body's size "
            f"{size:.3g}: check the load and the modulus"
        )
        out.append(Finding("displacement", float(norms[i]), where, line))
    return out

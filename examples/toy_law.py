"""A new material law in one file: Saint Venant–Kirchhoff with a fibre term.

``W = mu E:E + lambda/2 (tr E)^2 + k_fibre E_ff^2`` with ``E`` the Green–Lagrange strain in
the element's (fiber, sheet, normal) frame (docs/laws.rst#add-a-law). The law gives its
energy, its second Piola stress ``S = dW/dE`` and ``dS/dE``; the base class turns them into
the first Piola stress and its tangent, adds the scene's volumetric penalty ``U(J)`` and the
active tension, and rotates to the global frame. The registration line makes ``law =
"fibre-svk"`` a scene law: the FEM reference, explicit dynamics, the spring model (its
tissue element takes the law's energy, its exact element the small-strain tangent the table
derives) and ``springfem verdict`` take it.

Run it: ``python examples/toy_law.py`` solves a small bar and prints its tip displacement.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from springfem.materials.laws import TissueLaw, register
from springfem.materials.laws.kinematics import green_lagrange, piola_from_pk2

_I = np.eye(3)


@dataclass(frozen=True)
class FibreSVK(TissueLaw):
    """Saint Venant–Kirchhoff with a fibre term (a toy law).

    Parameters
    ----------
    lame_mu, lame_lambda
        Lamé constants of the isotropic part.
    k_fibre
        Extra stiffness of the fibre strain ``E_ff`` (0: isotropic).
    """

    lame_mu: float = 1.0
    lame_lambda: float = 0.0
    k_fibre: float = 0.0
    label = "fibre-svk"
    nonnegative = ("lame_lambda", "k_fibre")
    example = {"lame_mu": 1.0, "lame_lambda": 1.0, "k_fibre": 1.0}

    def local(self, F: np.ndarray, tangent: bool):
        E = green_lagrange(F)
        trE = np.trace(E, axis1=-2, axis2=-1)
        Eff = E[..., 0, 0]
        W = self.lame_mu * np.einsum("...ab,...ab->...", E, E) + 0.5 * self.lame_lambda * trE**2
        W = W + self.k_fibre * Eff**2
        S = 2.0 * self.lame_mu * E + self.lame_lambda * trE[..., None, None] * _I
        S[..., 0, 0] += 2.0 * self.k_fibre * Eff
        CC = None
        if tangent:
            sym = 0.5 * (np.einsum("ac,bd->abcd", _I, _I) + np.einsum("ad,bc->abcd", _I, _I))
            CC = 2.0 * self.lame_mu * sym + self.lame_lambda * np.einsum("ab,cd->abcd", _I, _I)
            CC[0, 0, 0, 0] += 2.0 * self.k_fibre
            CC = np.broadcast_to(CC, F.shape[:-2] + (3, 3, 3, 3))
        P, A = piola_from_pk2(F, S, CC)
        return W, P, A


register(FibreSVK)


if __name__ == "__main__":
    from reference_fem import solve
    from springfem.scene import scene_from_dict

    scene = scene_from_dict({
        "mesh": {"generator": "box", "size": [4.0, 1.0, 1.0], "divisions": [8, 2, 2]},
        "material": {"law": "fibre-svk", "lame_mu": 1.0e3, "lame_lambda": 1.0e3,
                     "k_fibre": 2.0e3, "kappa": 1.0e3},
        "axes": {"fiber": [1.0, 0.0, 0.0], "sheet": [0.0, 1.0, 0.0]},
        "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}],
        "load": [{"type": "traction", "region": "x_max", "value": [0.0, 0.0, -5.0]}],
    })  # fmt: skip
    print("tip deflection", float(solve(scene, order=2).u_vertices[:, 2].min()))

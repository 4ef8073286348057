"""The ``[material]`` keys of the finite-strain tissue laws (:mod:`springfem.materials.laws`).

Examples
--------
>>> from springfem.scene.reader import TableReader
>>> kw = parse_tissue(TableReader({"C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0,
...                                "incompressible": True}, "material", "<scene>"), "guccione")
>>> kw["incompressible"], sorted(kw["parameters"])
(True, ['C', 'b_f', 'b_fs', 'b_t', 'kappa'])
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..materials.laws import law_class, small_strain_tangent
from .reader import TableReader
from .types import VOLUMETRIC

#: Keys a tissue material may have besides its law's constants.
TISSUE_KEYS = ("kappa", "incompressible", "volumetric", "active_tension")


def parse_tissue(r: TableReader, law: str) -> dict[str, Any]:
    """A tissue law's constants, ``kappa`` or ``incompressible``, ``volumetric`` and
    ``active_tension``.

    ``active_tension`` is the active fibre stress ``T_a`` (in the scene's stress unit,
    finite and not negative: a contraction; docs/fem.rst#active-tension), kept in
    ``parameters`` only when given.

    Parameters
    ----------
    r
        Reader over the ``[material]`` table.
    law
        A registered law (:data:`springfem.materials.laws.LAWS`).

    Returns
    -------
    dict
        ``Material`` keywords: ``parameters`` (the constants, ``kappa``, 0 when
        incompressible, and ``active_tension`` if given), ``incompressible``,
        ``volumetric``, and ``E``/``nu``: an isotropic equivalent for estimates only (the
        mean Voigt shear modulus of the small-strain tangent, and ``kappa`` or
        ``1000 mu`` when incompressible).
    """
    cls = law_class(law)
    params = {}
    for k in cls.keys():
        zero = k in cls.nonnegative
        params[k] = r.get(k, "float", nonneg=zero, positive=not zero)
    bad = cls.check(params)
    if bad is not None:
        raise r.fail(*bad)
    incompressible = r.get("incompressible", "bool", default=False)
    if incompressible:
        if r.has("kappa"):
            raise r.fail("kappa", "give either kappa or incompressible = true")
        kappa = 0.0
    else:
        kappa = r.get("kappa", "float", positive=True)
    volumetric = r.get("volumetric", "str", default="log", choices=VOLUMETRIC)
    params["kappa"] = kappa
    if r.has("active_tension"):
        params["active_tension"] = r.get("active_tension", "float", nonneg=True)
    mu = float(np.mean(np.diag(small_strain_tangent(law, params))[3:]))
    k_eq = kappa if kappa > 0 else 1000.0 * mu
    return {
        "parameters": params,
        "incompressible": incompressible,
        "volumetric": volumetric,
        "E": 9 * mu / (3 + mu / k_eq),  # = 9 k mu / (3 k + mu)
        "nu": (3 - 2 * mu / k_eq) / (2 * (3 + mu / k_eq)),
    }

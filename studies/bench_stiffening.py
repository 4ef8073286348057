"""The stiffened exact element's force pass for ``springfem bench forces --variants``.

Examples
--------
>>> from reference_fem.scenes import bench_scene
>>> import numpy as np
>>> scene = bench_scene(1000)
>>> x = scene.mesh.points.copy()
>>> name, call, meta = stiffened_case(scene, scene.mesh, x, np.empty_like(x))
>>> name, float(abs(call()).max()) < 1e-9  # no force at rest
('spring exact+stiffening float64 1 (variant)', True)
"""

from __future__ import annotations

import numpy as np

from springmodel.options import SpringOptions


def stiffened_case(scene, mesh, x: np.ndarray, out: np.ndarray):
    """The force pass of the stiffened exact element (the fused kernel plus the compiled
    stiffening pass, :mod:`springmodel.stiffening_kernel`), as the model runs it.

    Parameters
    ----------
    scene, mesh
        The bench scene and its mesh.
    x, out
        Positions ``(n, 3)`` and the kernel's output buffer.

    Returns
    -------
    tuple
        ``(name, call, meta)``: the case's name, its force pass and its row of metadata.
    """
    from springmodel.elements import build_spring_elements
    from springmodel.options import GREEN_AXIAL_COEFFICIENTS
    from springmodel.spring_kernel import SpringKernel
    from springmodel.stiffening import StiffeningPart

    mu = scene.material.mu
    o = SpringOptions(volume="axes", torsion="shear", calibration="exact", coupling=True,
                      axial="cubic", axial_coefficients=GREEN_AXIAL_COEFFICIENTS,
                      stiffening="exponential", stiffening_modulus=mu)  # fmt: skip
    els = build_spring_elements(mesh.points, mesh.tets, scene.frames, o, scene.material)
    kernel, part = SpringKernel(els, o, parallel=False), StiffeningPart(els, o, mu)
    meta = {"kernel": "spring[exact+stiffening]", "precision": "float64", "threads": "1",
            "bytes": None, "fem": "FEM neo-Hookean float64 1"}  # fmt: skip
    call = lambda: kernel.forces(x, None, out) + part.forces(x)  # noqa: E731
    return "spring exact+stiffening float64 1 (variant)", call, meta

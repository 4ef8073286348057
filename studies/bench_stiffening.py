"""The stiffened exact element's force pass for ``springfem bench forces --variants``.

Besides the whole pass as the model runs it (the fused kernel plus the compiled stiffening
pass, :mod:`springmodel.stiffening_kernel`), its parts are timed in the same rounds, to say
where the time goes: the fused kernel of the same element alone; the stiffening pass alone
with its outputs allocated once (:func:`stiffening_parts`); the pass without the forces
(``W_q`` and ``s_e`` only: the gather, the spring energies and the exponential); and the
pass compiled with numpy's error model (no division-by-zero checks) and with fastmath.

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

from functools import cache

import numpy as np

from springmodel.options import SpringOptions

_META = {"precision": "float64", "threads": "1", "bytes": None, "fem": "FEM neo-Hookean float64 1"}


def _parts(scene, mesh):
    from springmodel.elements import build_spring_elements
    from springmodel.options import GREEN_AXIAL_COEFFICIENTS
    from springmodel.spring_kernel import SpringKernel
    from springmodel.stiffening import StiffeningPart

    mu = scene.material.mu
    o = SpringOptions(volume="axes", torsion="shear", calibration="exact", coupling=True,
                      axial="cubic", axial_coefficients=GREEN_AXIAL_COEFFICIENTS,
                      stiffening="exponential", stiffening_modulus=mu)  # fmt: skip
    els = build_spring_elements(mesh.points, mesh.tets, scene.frames, o, scene.material)
    return SpringKernel(els, o, parallel=False), StiffeningPart(els, o, mu)


def stiffened_case(scene, mesh, x: np.ndarray, out: np.ndarray):
    """The force pass of the stiffened exact element as the model runs it, on positions ``x``
    into the kernel's buffer ``out``: ``(name, call, meta)``, the case's name, its force pass
    and its row of metadata.
    """
    kernel, part = _parts(scene, mesh)
    meta = {"kernel": "spring[exact+stiffening]", **_META}
    call = lambda: kernel.forces(x, None, out) + part.forces(x)  # noqa: E731
    return "spring exact+stiffening float64 1 (variant)", call, meta


@cache
def _recompiled(flags: tuple) -> object:
    """The stiffening pass compiled anew with other numba flags (for timing only)."""
    from numba import njit

    from springmodel.stiffening_kernel import stiffening_pass

    return njit(**dict(flags))(stiffening_pass.py_func)


def stiffening_parts(scene, mesh, x: np.ndarray, out: np.ndarray) -> list[tuple]:
    """The whole stiffened pass and its parts (module docstring), as ``(name, call, meta)``
    bench cases on positions ``x`` into the kernel's buffer ``out``.
    """
    from springmodel.stiffening_kernel import stiffening_pass

    kernel, part = _parts(scene, mesh)
    m = mesh.n_tets
    W, s, f, g = np.empty(m), np.empty(m), np.zeros((x.shape[0], 3)), np.empty((1, 4, 3))

    def run(fn, forces):
        return lambda: fn(x, *part._args, W, s, f, forces, g, False)

    passes = {
        "pass alone": run(stiffening_pass, True),
        "pass, W and s only": run(stiffening_pass, False),
        "pass, numpy error model": run(_recompiled((("error_model", "numpy"),)), True),
        "pass, fastmath": run(_recompiled((("error_model", "numpy"), ("fastmath", True))), True),
    }
    cases = [stiffened_case(scene, mesh, x, out)]
    name = "spring exact (stiffened element's kernel) float64 1 (variant)"
    cases.append((name, lambda: kernel.forces(x, None, out), {"kernel": "spring[exact]", **_META}))
    for label, call in passes.items():
        meta = {"kernel": f"stiffening {label}", **_META}
        cases.append((f"stiffening {label} float64 1 (variant)", call, meta))
    return cases

"""The spring model's force kernel object: rest data packed for its variant's compiled kernel.

:class:`SpringKernel` picks the :class:`~springmodel.fastkernels.Variant` of the options
(with and without the damping terms, for calls with and without velocities), packs the
compact constants of that variant (:func:`constant_columns`) in the blocked layout of
:mod:`springfem.blocks`, and runs the kernel of :func:`~springmodel.fastkernels.spring_kernel`
serially or on all threads.

Threads (:func:`parallel_by_default`): parallel from :data:`PARALLEL_MIN_ELEMENTS` elements
when numba has two threads or more; ``parallel=True`` uses every thread, ``False`` one. The
parallel driver gives each thread a static chunk of blocks and its own force buffer, summed
in chunk order (:func:`springfem.blocks.block_drivers`): the forces are bitwise the same from
call to call for a given thread count, and equal to the serial pass to round-off.
``springfem bench threads`` times both on idle-machine sizes and checks the threshold;
``springfem bench forces`` says whether the rule picks the faster at its size. Under another
process's load two threads are slower than one at every size: the rule is for a free core.

Examples
--------
>>> import numpy as np
>>> from springfem.mesh import box_mesh
>>> from springmodel.elements import build_spring_elements
>>> from springmodel.options import SpringOptions
>>> mesh = box_mesh((1.0, 1.0, 1.0), (2, 2, 2))
>>> el = build_spring_elements(mesh.points, mesh.tets, np.tile(np.eye(3), (mesh.n_tets, 1, 1)),
...                            material={"law": "linear", "E": 1.0, "nu": 0.3})
>>> kernel = SpringKernel(el, SpringOptions())
>>> float(abs(kernel.forces(mesh.points)).max()) < 1e-12  # no force at rest
True
"""

from __future__ import annotations

import numba
import numpy as np

from springfem.blocks import BLOCK, block_layout, chunks, set_column

from .fastkernels import _PAIRS, PRECISIONS, Variant, spring_kernel
from .options import SpringOptions

#: ``SpringKernel(parallel=None)`` follows :func:`parallel_by_default` while this is on.
PARALLEL_BY_DEFAULT = True
#: From this many elements two threads are faster than one on an idle machine, for every
#: kernel (``springfem bench threads``); below it, waking the threads and summing their
#: buffers costs more than they save.
PARALLEL_MIN_ELEMENTS = 20_000


def parallel_by_default(n_elements: int) -> bool:
    """The kernel's default: parallel from :data:`PARALLEL_MIN_ELEMENTS` elements when
    numba has two threads or more (and :data:`PARALLEL_BY_DEFAULT` is on).

    Parameters
    ----------
    n_elements
        Number of elements of the kernel.

    Returns
    -------
    bool
        Whether ``SpringKernel(parallel=None)`` runs on all threads.

    Examples
    --------
    >>> parallel_by_default(10)
    False
    """
    return (
        PARALLEL_BY_DEFAULT and n_elements >= PARALLEL_MIN_ELEMENTS and numba.get_num_threads() > 1
    )


def constant_columns(elements, variant: Variant) -> np.ndarray:
    """The constants ``(ncol, m)`` of ``variant`` from :class:`SpringElements` rest data.

    Parameters
    ----------
    elements
        :class:`~springmodel.elements.SpringElements`.
    variant
        Kernel variant; its ``columns()`` name the rows.

    Returns
    -------
    ndarray
        ``(ncol, m)``, one row per column name (lengths folded in, e.g. ``k_l l0_l^2``).
    """
    el = elements
    l0 = el.l0
    Gp = el.G[:, 1:, :] / l0[:, None, :]  # (m, 3 vertices, 3 axes)
    kf = el.k_torsion_force
    data: dict[str, np.ndarray] = {}
    for i in range(3):
        for l in range(3):
            data[f"g{i + 1}{l}"] = Gp[:, i, l]
    for l in range(3):
        data[f"ka{l}"] = el.k_axial[:, l] * l0[:, l] ** 2
        data[f"ca{l}"] = variant.damp_axial * l0[:, l] ** 2
    for p, (l, m) in enumerate(_PAIRS):
        data[f"kt{p}"] = el.k_torsion[:, p]
        data[f"kf{p}l"] = kf[:, p] * l0[:, l]
        data[f"kf{p}m"] = kf[:, p] * l0[:, m]
        data[f"c0{p}"] = el.c0[:, p]
        data[f"a0{p}"] = el.alpha0[:, p]
    data["inv6v0"] = 1.0 / (6.0 * el.V0)
    data["ks"] = el.k_volume
    cj = l0.prod(axis=1) / el.det0  # J = c_J det[zeta / l0]
    data["cj"] = cj
    data["kj"] = el.V0 * el.k_axis_volume * cj
    data["ej"] = variant.damp_volume * el.V0 * cj**2  # eta V0 dJ/dt c_J (...)
    for p in range(3):
        data[f"cp{p}"] = el.k_coupling[:, p]
    data["lsum"] = el.L0
    return np.stack([np.broadcast_to(data[c], (el.n_elements,)) for c in variant.columns()])


def needs_c0(elements, tol: float = 1e-14) -> bool:
    """False when every rest cosine is zero to round-off (orthonormal frames,
    docs/theory.rst#axis-vectors-are-parallel-to-the-frame).

    Parameters
    ----------
    elements
        :class:`~springmodel.elements.SpringElements` (``c0``).
    tol
        Largest ``|c0|`` counted as zero.

    Returns
    -------
    bool
        True if some ``|c0| > tol``.
    """
    return bool(np.abs(elements.c0).max(initial=0.0) > tol)


def variant_of(elements, options, precision: str = "float64", velocity: bool = True) -> Variant:
    """The :class:`Variant` of ``options`` on ``elements`` (``velocity=False``: no damping).

    Parameters
    ----------
    elements
        :class:`~springmodel.elements.SpringElements`.
    options
        :class:`~springmodel.options.SpringOptions`.
    precision
        ``float64``, ``mixed`` or ``float32``.
    velocity
        Include the damping terms.

    Returns
    -------
    Variant
        The kernel variant to compile.

    Raises
    ------
    ValueError
        For an unknown axial or torsion law or precision.
    """
    for part in ("axial", "torsion"):
        law, valid = getattr(options, part), SpringOptions.choices(part)
        if law not in valid:
            raise ValueError(f"{part} law {law!r} is not one of {', '.join(valid)}")
    if precision not in PRECISIONS:
        raise ValueError(f"precision {precision!r} is not one of {', '.join(PRECISIONS)}")
    b2, b3 = (float(b) for b in options.axial_coefficients)
    poly = options.axial in ("quadratic", "cubic")
    if options.volume == "axes":
        volume = "axes"
    else:
        volume = options.volume_form if options.volume else "off"
    return Variant(
        axial=options.axial,
        torsion=options.torsion,
        volume=volume,
        volumetric=getattr(options, "volumetric", "quadratic"),
        coupling=bool(getattr(options, "coupling", False)),
        damp_axial=float(options.axial_damping) if velocity else 0.0,
        damp_volume=float(options.volume_damping) if velocity and volume != "off" else 0.0,
        b2=b2 if poly else 0.0,
        b3=b3 if options.axial == "cubic" else 0.0,
        bt=float(options.torsion_cubic) if options.torsion == "cubic" else 0.0,
        c0=(options.energy_torsion or options.torsion in ("cosine", "cubic"))
        and needs_c0(elements),
        precision=precision,
    )


class SpringKernel:
    """Spring forces of a fixed set of elements and options, on the specialised kernel.

    Parameters
    ----------
    elements
        Rest data (:func:`~springmodel.elements.build_spring_elements`).
    options
        Which parts are on and their laws.
    parallel
        Use all numba threads (per-thread buffers); ``None`` (default):
        :func:`parallel_by_default` (from :data:`PARALLEL_MIN_ELEMENTS` elements).
    precision
        ``float64`` (default), ``mixed`` or ``float32`` (see the module docstring).

    Examples
    --------
    >>> kernel = SpringKernel(elements, SpringOptions(torsion="energy"))  # doctest: +SKIP
    >>> f = kernel.forces(x)                                              # doctest: +SKIP
    """

    def __init__(self, elements, options, parallel: bool | None = None, precision: str = "float64"):
        self.elements, self.options, self.precision = elements, options, precision
        self.n_points = elements.n_points
        self._variants = {vel: variant_of(elements, options, precision, vel) for vel in (0, 1)}
        store = np.float64 if precision == "float64" else np.float32
        self._T, self._K = block_layout(
            elements.tets, constant_columns(elements, self._variants[1]), store
        )
        self._K0 = (
            self._K
            if self._variants[0] == self._variants[1]
            else block_layout(elements.tets, constant_columns(elements, self._variants[0]), store)[
                1
            ]
        )
        if parallel is None:
            parallel = parallel_by_default(elements.n_elements)
        self.parallel = bool(parallel)
        self._ptr = chunks(self._T.shape[0])
        nchunk = self._ptr.size - 1
        self._buf = np.zeros((nchunk if self.parallel else 0, self.n_points, 3))
        self._dummy = np.zeros((1, 3))

    @property
    def bytes_per_element(self) -> int:
        """Bytes of constants and connectivity the kernel reads per element."""
        return int(self._K.shape[1] // BLOCK * self._K.itemsize + 16)

    def set_volume_stiffness(self, k_volume: np.ndarray) -> None:
        """Replace the volume constants (LMS), ``(m,)`` in the elements' order."""
        for K, v in ((self._K, self._variants[1]), (self._K0, self._variants[0])):
            if "ks" in v.columns():
                set_column(K, v.columns().index("ks"), np.asarray(k_volume, dtype=float))
        self.elements = self.elements.with_volume_stiffness(k_volume)

    def forces(
        self, x: np.ndarray, v: np.ndarray | None = None, out: np.ndarray | None = None
    ) -> np.ndarray:
        """Nodal spring forces ``(n, 3)`` at positions ``x`` (and velocities ``v``)."""
        x = np.ascontiguousarray(x, dtype=np.float64).reshape(self.n_points, 3)
        if out is None:
            out = np.empty((self.n_points, 3))
        vel = v is not None and self._variants[1].uses_velocity
        variant, K = (self._variants[1], self._K) if vel else (self._variants[0], self._K0)
        w = np.ascontiguousarray(v, dtype=np.float64) if vel else self._dummy
        serial, parallel = spring_kernel(variant)
        m = self.elements.n_elements
        if self.parallel:
            parallel(x, w, self._T, K, m, 0.0, 0.0, self._ptr, self._buf, out)
        else:
            serial(x, w, self._T, K, m, 0.0, 0.0, out)
        return out

    def energy(self, x: np.ndarray) -> float:
        """Total spring energy (see :func:`springmodel.springs.spring_energy`)."""
        from .springs import spring_energy

        return spring_energy(np.asarray(x, float), self.elements, self.options)[1]

"""Explicit P1 FEM: the internal forces of linear tets as a mechanical system.

The competitor the spring model has to beat (docs/fem.rst#explicit-p1-fem): a P1 element whose
gradient is
constant, so one pass over the elements gathers the four vertices, forms

    F = sum_i x_i (x) grad N_i = sum_{a=1..3} (x_a - x_0) (x) grad N_a

(``grad N_0 = -(grad N_1 + grad N_2 + grad N_3)``), evaluates the first Piola stress

    neo-Hookean (coupled):  P = mu (F - F^-T) + lam ln J F^-T,    F^-T = cof(F) / J
    linear:                 P = 2 mu eps + lam tr(eps) I,          eps = sym(F - I)

or, for the anisotropic laws (``transverse-linear``, ``guccione``, ``holzapfel-ogden``:
the scene's material and element frames), the law's stress in the element frame
(:mod:`reference_fem.explicit_anisotropic`), and scatters ``f_a = -V P grad N_a``
(``f_0 = -(f_1 + f_2 + f_3)``, so each element's net force is zero by construction). The
energies are those of :mod:`springfem.materials.laws.neo_hookean` (``psi = mu/2 (I1 - 3) - mu ln J +
lam/2 ln^2 J``), of small-strain elasticity and of :mod:`springfem.materials.laws`; per element
the kernel reads 4 int32 node ids and 10 constants (three shape gradients, rotated into the
element frame for the tissue laws, and the rest volume; ``transverse-linear`` adds the
frame, 19).

The kernels are those of :mod:`reference_fem.explicit_kernels` (isotropic) and
:mod:`reference_fem.explicit_anisotropic`: specialised per law and precision (``float64``,
``mixed``, ``float32``), on the blocked layout the spring kernels use, serial or parallel
(one force buffer per thread, summed in a fixed order), so the two models are compared
like for like.

Inverted elements (``J <= 0``) get no force from the kernel and are counted; for the
neo-Hookean and tissue laws :class:`ExplicitFem` then raises a
:class:`~springfem.errors.SolverError` naming the element and the step ("inverted element
k at step n") instead of letting NaN propagate, or (``on_inverted="nan"``) returns NaN at
the element's nodes so a Newton line search can back off.

Examples
--------
>>> from reference_fem.scenes import bench_scene
>>> fem = ExplicitFem(bench_scene(200))
>>> bool(abs(fem.internal(fem.x0)).max() < 1e-9)  # no force at rest (round-off only)
True
>>> fem.n_elements, fem.parallel  # small meshes run serially by default
(324, False)
"""

from __future__ import annotations

from typing import Any, Literal, cast

import numba
import numpy as np
import scipy.sparse as sp

from springfem.blocks import chunks
from springfem.errors import InputError, SolverError
from springfem.loads import external_forces, has_follower_loads, lumped_masses
from springfem.materials.laws import TISSUE_LAWS, LawNames, NeoHookean, TissueLaw, tissue_law
from springfem.materials.laws.kinematics import det
from springfem.mesh import tet_volumes
from springfem.scene import Scene, model_precision

from .explicit_anisotropic import (
    ANISOTROPIC_LAWS,
    KERNEL_LAWS,
    anisotropic_kernel,
    anisotropic_layout,
    law_parameters,
)
from .explicit_generic import generic_kernel
from .explicit_kernels import fem_kernel, fem_layout
from .space import p1_gradients

Law = str
Precision = Literal["float64", "mixed", "float32"]
OnInverted = Literal["raise", "nan", "ignore"]
LAWS = LawNames(("neo-hookean", "neo-hookean/coupled", "linear", "transverse-linear"))
_NEO, _LINEAR, _ANISOTROPIC = 0, 1, 2
#: ``ExplicitFem(parallel=None)`` runs serially unless this is on, as the spring kernel: two
#: threads were never faster than one here (neo-Hookean 0.64-0.73x wall at 210,912 tets on
#: the shared 2-core machine, reference_fem.explicit_kernels).
PARALLEL_BY_DEFAULT = False
#: With :data:`PARALLEL_BY_DEFAULT` on, below this many elements the kernel runs serially:
#: starting threads costs more than it saves on small meshes.
PARALLEL_MIN_ELEMENTS = 20_000


# --------------------------------------------------------------------------- energy


def strain_energy_density(F: np.ndarray, mu: float, lam: float, law: int) -> np.ndarray:
    """``psi(F)`` per element for ``(m, 3, 3)`` gradients (``inf`` where neo-Hookean J <= 0).

    Parameters
    ----------
    F
        Deformation gradients ``(m, 3, 3)``.
    mu, lam
        Lamé constants (Pa).
    law
        0: compressible neo-Hookean (coupled), 1: linear (small-strain).

    Returns
    -------
    ndarray
        Energy density ``(m,)`` (J/m^3).
    """
    if law == _NEO:
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(det(F) > 0, NeoHookean(mu, lam).energy(F), np.inf)
    eps = 0.5 * (F + F.transpose(0, 2, 1)) - np.eye(3)
    tr = np.trace(eps, axis1=1, axis2=2)
    return mu * np.einsum("kij,kij->k", eps, eps) + 0.5 * lam * tr**2


# --------------------------------------------------------------------------- the system


def _parse_law(scene: Scene, law: str) -> int:
    if law not in LAWS:
        raise InputError(f"explicit FEM law {law!r} is not one of {', '.join(LAWS)}")
    mat = scene.material
    if law in ANISOTROPIC_LAWS:
        if mat.law != law:
            raise InputError(
                f"explicit FEM law {law} needs a {law} material; the scene's is {mat.law}"
            )
        if mat.incompressible:
            raise InputError(
                f"explicit FEM of {law} needs a volumetric penalty: give [material] kappa "
                "instead of incompressible = true"
            )
        return _ANISOTROPIC
    if mat.law == "transverse-linear":
        raise InputError(
            f"explicit FEM law {law} is isotropic; the scene's material is transverse-linear "
            "(use law transverse-linear)"
        )
    if law.startswith("neo-hookean") and mat.law == "neo-hookean" and mat.formulation != "coupled":
        raise InputError(
            "explicit FEM implements the coupled neo-Hookean energy; the scene's material is "
            f"{mat.formulation} (use reference_fem.solve for the uncoupled forms)"
        )
    return _LINEAR if law == "linear" else _NEO


class ExplicitFem:
    """P1 FEM of a scene as a :class:`~springfem.mechanics.system.MechanicalSystem`.

    The solvers of :mod:`springfem.mechanics` (``explicit``, ``explicit_static``,
    ``stable_time_step``, ``static``) drive it as they drive the spring model: lumped masses
    ``rho V / 4``, the scene's Dirichlet conditions and P1 nodal loads
    (:func:`springfem.loads.external_forces`), forces from the fused kernel.

    Parameters
    ----------
    scene
        Mesh, material (``mu``, ``lam`` of the isotropic laws; an anisotropic law's own
        constants and the element frames), boundaries and loads.
    law
        ``neo-hookean`` (the coupled energy of :mod:`springfem.materials.laws.neo_hookean`, whatever
        the scene's isotropic law), ``linear`` (small-strain isotropic elasticity), or the scene's
        anisotropic law: ``transverse-linear``, ``guccione`` or ``holzapfel-ogden`` (with the
        material's ``kappa`` and ``volumetric`` penalty; an active tension ramps with the
        load factor of :meth:`forces`). Default (``None``): the scene's law if it is
        anisotropic, else ``neo-hookean``.
    parallel
        ``True``: parallel kernel on all numba threads; ``False``: serial, in mesh order;
        ``None`` (default): serial unless :data:`PARALLEL_BY_DEFAULT` is on, then parallel
        from :data:`PARALLEL_MIN_ELEMENTS` elements when there is more than one thread.
    precision
        ``float64`` (default), ``mixed`` (float32 constants, float64 arithmetic) or
        ``float32``; ``None``: the scene's ``[fem] precision``.
    on_inverted
        What a neo-Hookean force evaluation does when elements have ``J <= 0``: ``raise``
        a :class:`~springfem.errors.SolverError` naming the first inverted element and the
        step (counted by :meth:`post_step`), return ``nan`` forces at the inverted elements'
        nodes (lets a Newton line search back off), or ``ignore`` (the inverted elements
        contribute nothing). The linear law is defined for any ``F``; it only counts them.

    Attributes
    ----------
    last_inverted
        Number of elements with ``J <= 0`` at the last force evaluation.
    steps, time
        Time steps and simulated time seen by :meth:`post_step` since construction or
        :meth:`reset`.
    """

    def __init__(
        self,
        scene: Scene,
        law: str | None = None,
        parallel: bool | None = None,
        on_inverted: OnInverted = "raise",
        precision: Precision | None = None,
    ):
        if on_inverted not in ("raise", "nan", "ignore"):
            raise ValueError(f"on_inverted {on_inverted!r} is not one of raise, nan, ignore")
        if precision is None:
            from .options import FemOptions

            precision = cast(
                Precision, model_precision(scene, "fem", FemOptions.of(scene).precision)
            )
        self.precision: Precision = precision
        self.scene = scene
        if law is None:
            law = scene.material.law if scene.material.law in ANISOTROPIC_LAWS else "neo-hookean"
        self._law = _parse_law(scene, law)
        if self._law == _ANISOTROPIC:
            self.law = law
        else:
            self.law = "linear" if law == "linear" else "neo-hookean"
        self.on_inverted = on_inverted
        mat = scene.material
        self.mu, self.lam = float(mat.mu), float(mat.lam)
        mesh = scene.mesh
        self.tets = np.ascontiguousarray(mesh.tets, dtype=np.int64)
        self.x0 = np.array(mesh.points, dtype=float)
        self.n_points = self.x0.shape[0]
        G, V = p1_gradients(self.x0, self.tets)
        if np.any(V <= 0):
            k = int(np.flatnonzero(V <= 0)[0])
            raise InputError(f"element {k} has non-positive volume {V[k]:.3g} at rest")
        self.V0 = V
        m = self.tets.shape[0]
        if parallel is None:
            parallel = PARALLEL_BY_DEFAULT and m >= PARALLEL_MIN_ELEMENTS
        self.parallel = bool(parallel) and numba.get_num_threads() > 1
        self._grad = np.ascontiguousarray(G[:, 1:])  # grad N_1..3 (energy, in numpy)
        #: The tissue law (numpy; energy and tangent), None for the other laws.
        self.tissue: TissueLaw | None = None
        self.frames: np.ndarray | None = None
        self._active = 0.0
        if self._law == _ANISOTROPIC:
            self.frames = np.asarray(scene.frames, dtype=float)
            if law in TISSUE_LAWS:
                self.tissue = tissue_law(mat)
                self._active = self.tissue.active_tension
            self._params: tuple = (law_parameters(law, mat, self.tissue),)
            if law in KERNEL_LAWS:
                self._serial, self._parallel = anisotropic_kernel(law, mat.volumetric, precision)
                self._T, self._K = anisotropic_layout(
                    self.tets, self.x0, self.frames, law, precision
                )
            else:  # a tissue law without a compiled kernel: numpy, same forces
                assert self.tissue is not None
                self._serial, self._parallel = generic_kernel(
                    self.tissue, self.tets, self.x0, self.frames
                )
                self._T, self._K = self.tets, None
        else:
            self._params = (self.mu, self.lam)
            self._serial, self._parallel = fem_kernel(self.law, precision)
            self._T, self._K = fem_layout(self.tets, self.x0, precision)
        self.activation = 1.0
        self._ptr = chunks(self._T.shape[0])
        self._buf = np.zeros((self._ptr.size - 1 if self.parallel else 0, self.n_points, 3))
        # MechanicalSystem members
        self.masses = lumped_masses(scene)
        self.fixed_dofs, self._fixed_values = scene.dirichlet()
        self._follower = has_follower_loads(scene)
        self._f_dead = None if self._follower else external_forces(scene)
        self._K_linear: sp.csr_matrix | None = None
        self._assembly: tuple[Any, Any] | None = None  # (Space, BlockPattern), on first use
        self.last_inverted = 0
        self.evaluations = 0
        self.steps = 0
        self.time = 0.0

    @property
    def n_elements(self) -> int:
        return self.tets.shape[0]

    @property
    def _positive_J(self) -> bool:
        """Whether the law needs ``J > 0`` (neo-Hookean, tissue): inverted elements fail."""
        return self._law == _NEO or self.tissue is not None

    def set_activation(self, level: float) -> None:
        """Scale a tissue law's active tension to ``level`` (the load factor) in the kernel.

        :meth:`forces`, :meth:`energy` and :meth:`stiffness` set it from their ``scale``;
        :meth:`internal` and :meth:`kernel` use the level set last (1 at construction).

        Parameters
        ----------
        level
            Activation level, 1 for the material's full ``active_tension``.

        Examples
        --------
        >>> from dataclasses import replace
        >>> from springfem.mesh import box_mesh
        >>> from springfem.scene import scene_from_dict
        >>> scene = scene_from_dict({"mesh": box_mesh((1.0, 1.0, 1.0), (1, 1, 1)),
        ...     "material": {"law": "guccione", "C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0,
        ...                  "kappa": 50.0, "active_tension": 6.0}})
        >>> fem = ExplicitFem(scene)
        >>> full = abs(fem.internal(fem.x0)).max()  # at rest: the active stress alone
        >>> fem.set_activation(0.5)
        >>> round(float(abs(fem.internal(fem.x0)).max() / full), 12)
        0.5
        """
        if self._active and level != self.activation:
            self._params[0][len(TISSUE_LAWS[self.law]) + 1] = level * self._active
        self.activation = level

    def _law_now(self) -> TissueLaw:
        assert self.tissue is not None
        return self.tissue.activated(self.activation)

    def reset(self) -> None:
        """Zero the step and evaluation counters (a new run on the same system)."""
        self.steps, self.time, self.evaluations, self.last_inverted = 0, 0.0, 0, 0

    # -- kernel -------------------------------------------------------------------------

    def kernel(self, x: np.ndarray, out: np.ndarray | None = None) -> tuple[np.ndarray, int]:
        """Raw kernel: internal forces ``(n, 3)`` and the number of elements with ``J <= 0``
        (whose forces are left out for the neo-Hookean law)."""
        x = np.ascontiguousarray(x, dtype=np.float64).reshape(self.n_points, 3)
        if out is None:
            out = np.empty((self.n_points, 3))
        args = (x, self._T, self._K, self.n_elements, *self._params)
        if self.parallel:
            bad = self._parallel(*args, self._ptr, self._buf, out)
        else:
            bad = self._serial(*args, out)
        return out, int(bad)

    def inverted_elements(self, x: np.ndarray, count: int | None = None) -> np.ndarray:
        """Ids of the elements with ``J <= 0`` at positions ``x`` (mesh numbering).

        ``count`` (the kernel's count): if round-off makes the volume test find fewer, the
        ``count`` elements with the smallest volume ratio are returned.
        """
        J = tet_volumes(np.asarray(x, dtype=float).reshape(-1, 3), self.tets) / self.V0
        ids = np.flatnonzero(~(J > 0))
        if count is not None and ids.size < count:
            ids = np.sort(np.argsort(J, kind="stable")[:count])
        return ids

    def internal(self, x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Internal nodal forces ``(n, 3)``; inverted elements handled per ``on_inverted``."""
        self.evaluations += 1
        f, bad = self.kernel(x, out)
        self.last_inverted = bad
        if bad and self._positive_J and self.on_inverted != "ignore":
            ids = self.inverted_elements(x, bad)
            if self.on_inverted == "nan":
                f[self.tets[ids].ravel()] = np.nan
                return f
            k = int(ids[0])
            at = np.round(self.x0[self.tets[k]].mean(axis=0), 6).tolist()
            raise SolverError(
                f"explicit P1 FEM ({self.law}): inverted element {k} (J <= 0, rest centre {at}; "
                f"{bad} inverted in all) at step {self.steps + 1} ({self.steps} steps done, "
                f"t = {self.time:.4g} s; force evaluation {self.evaluations})"
            )
        return f

    # -- MechanicalSystem ---------------------------------------------------------------

    def prescribed(self, scale: float) -> np.ndarray:
        return self.x0.ravel()[self.fixed_dofs] + scale * self._fixed_values

    def external(self, x: np.ndarray, scale: float = 1.0) -> np.ndarray:
        """External nodal force ``(n, 3)`` times ``scale`` (follower pressure at ``x``)."""
        if self._f_dead is not None:
            return scale * self._f_dead
        return external_forces(self.scene, x=np.asarray(x).reshape(-1, 3), scale=scale)

    def forces(self, x: np.ndarray, v: np.ndarray | None = None, scale: float = 1.0) -> np.ndarray:
        """Internal plus external nodal forces (no viscous damping: ``v`` is not used)."""
        self.set_activation(scale)
        f = self.internal(x)
        f += self.external(x, scale)
        return f

    def strain_energy(self, x: np.ndarray) -> float:
        """``sum_e V_e psi(F_e)`` (``inf`` when a neo-Hookean or tissue element is inverted).

        The anisotropic laws' ``psi`` is the numpy law's (:mod:`springfem.materials.laws`, or
        ``eps : C : eps / 2`` of :mod:`reference_fem.materials`), at the current activation.
        """
        x = np.ascontiguousarray(x, dtype=np.float64).reshape(self.n_points, 3)
        X = x[self.tets]
        F = np.einsum("kac,kad->kcd", X[:, 1:] - X[:, :1], self._grad)
        if self._law != _ANISOTROPIC:
            psi = strain_energy_density(F, self.mu, self.lam, self._law)
        elif self.tissue is not None:
            with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
                psi = np.where(det(F) > 0, self._law_now().energy(F, self.frames), np.inf)
        else:
            from springfem.materials import VOIGT

            from .materials import material_groups

            D, group = material_groups(self.scene.material, self.scene.frames)
            eps = 0.5 * (F + F.transpose(0, 2, 1)) - np.eye(3)
            ev = eps[:, [0, 1, 2, 1, 0, 0], [0, 1, 2, 2, 2, 1]] * [1, 1, 1, 2, 2, 2]
            assert VOIGT[1, 2] == 3 and VOIGT[0, 1] == 5  # (xx, yy, zz, yz, xz, xy)
            psi = 0.5 * np.einsum("ki,kij,kj->k", ev, D[group], ev)
        return float(np.sum(self.V0 * psi))

    def energy(self, x: np.ndarray, scale: float = 1.0) -> float | None:
        """Strain energy minus the work of the dead loads; ``None`` with follower loads."""
        if self._follower:
            return None
        x = np.asarray(x, dtype=float).reshape(self.n_points, 3)
        work = scale * float(np.sum(self._f_dead * (x - self.x0)))
        self.set_activation(scale)
        return self.strain_energy(x) - work

    def stiffness(self, x: np.ndarray, scale: float = 1.0) -> sp.csr_matrix | None:
        """Tangent ``K = -d forces / dx`` (``None`` with follower loads).

        Assembled with :mod:`reference_fem.assembly` from the law's tangent
        (:class:`~springfem.materials.laws.neo_hookean.NeoHookean`, the tissue law of
        :mod:`springfem.materials.laws` in the element frames), constant for the linear laws.
        """
        if self._follower:
            return None
        from springfem.materials import isotropic_matrix

        from .assembly import BlockPattern, hyperelastic_element_arrays, stiffness_matrix
        from .space import Space

        if self._assembly is None:
            space = Space(self.scene.mesh, 1)
            self._assembly = (space, BlockPattern(space.element_nodes, space.n_nodes))
        space, pattern = self._assembly
        if self._law == _LINEAR or self.law == "transverse-linear":
            if self._K_linear is None:
                mat = self.scene.material
                if self._law == _LINEAR:
                    D, group = isotropic_matrix(mat.E, mat.nu)[None], np.zeros(self.n_elements, int)
                else:
                    from .materials import material_groups

                    D, group = material_groups(mat, self.scene.frames)
                K = stiffness_matrix(space, D, group.astype(np.int64), pattern)
                self._K_linear = sp.csr_matrix(K)
            return self._K_linear
        u = np.asarray(x, dtype=float).reshape(-1, 3) - self.x0
        if self.tissue is not None:
            self.set_activation(scale)
            frames = None if self.frames is None else self.frames[:, None]
            _, Ke = hyperelastic_element_arrays(space, self._law_now(), u, True, frames)
        else:
            _, Ke = hyperelastic_element_arrays(space, NeoHookean(self.mu, self.lam), u, True)
        assert Ke is not None  # asked for
        return sp.csr_matrix(pattern.matrix(Ke))

    def element_nodes(self) -> np.ndarray:
        return self.tets

    def post_step(self, x: np.ndarray, dt: float) -> None:
        """Count steps and time (for "inverted element k at step n")."""
        self.steps += 1
        self.time += dt

"""The spring model of a scene: rest data, fused kernel, loads, boundaries, solve.

:class:`SpringModel` is a :class:`~springfem.mechanics.system.MechanicalSystem`: the solvers of
:mod:`springfem.mechanics` drive it without knowing about springs. Only the parts the
scene's ``[spring]`` section switches on are computed.

Examples
--------
>>> from springfem.scene import scene_from_dict
>>> scene = scene_from_dict({
...     "mesh": {"generator": "box", "size": [0.1, 0.01, 0.01], "divisions": [10, 1, 1]},
...     "material": {"law": "linear", "E": 1.0e4, "nu": 0.3},
...     "boundary": [{"region": "x_min", "fix": ["x", "y", "z"]}]})
>>> model = SpringModel(scene)
>>> model.elements.n_elements
60
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from springfem.cardiac import cavity_summary, is_ventricle
from springfem.errors import InputError, SolverError
from springfem.loads import external_forces, has_follower_loads, lumped_masses, reactions
from springfem.mechanics.limits import SolveStopped
from springfem.model_api import ModelSolution
from springfem.result import Result, frame_cell_data, volume_summary
from springfem.scene import Scene, model_precision

from .advice import scene_warnings
from .elements import SpringElements, build_spring_elements
from .inert import inert_keys
from .nodal_strain import NodalStrainPart
from .nodal_volume import NodalPart
from .options import GREEN_AXIAL_COEFFICIENTS, SpringOptions
from .run_series import dynamic_series, end_of_run
from .spring_kernel import SpringKernel
from .springs import is_conservative, lms_update, volume_measures
from .stiffening import StiffeningPart, stiffening_modulus
from .stop_reason import stopped_error
from .tangent import MISMATCH_NORM
from .tissue_element import TissuePart, kernel_split, law_elements, law_parameters


class SpringModel:
    """The anisotropic spring model on a scene's mesh.

    Parameters
    ----------
    scene
        Mesh, material, axes, boundaries and loads.
    options
        Overrides ``SpringOptions.of(scene)`` (studies switch parts on and off this way).
    parallel
        Use the parallel kernel (all numba threads). ``None`` (default): the kernel's rule,
        :func:`springmodel.spring_kernel.parallel_by_default` (by mesh size).
    """

    def __init__(
        self, scene: Scene, options: SpringOptions | None = None, parallel: bool | None = None
    ):
        self.scene = scene
        if scene.material.parameters.get("active_tension"):
            raise InputError(
                f"{scene.name}: material.active_tension: the spring model carries no active "
                "tension (docs/tissue.rst#active-tension-in-the-spring-model); solve it with "
                "--model fem"
            )
        self.options = options or SpringOptions.of(scene)
        mesh = scene.mesh
        self.elements: SpringElements = build_spring_elements(
            mesh.points, mesh.tets, scene.frames, self.options, scene.material
        )
        # stiffening = "law": the law's own P1 element (no constants to miss, the law's kappa)
        self.elements = law_elements(self.elements, self.options, scene.material)
        # volume_average = "nodal": (part of) the volume term on nodal volumes, else None
        self.nodal, kernel_elements = NodalPart.split(
            mesh, self.elements, self.options, scene.material
        )
        modulus = None
        if self.options.stiffening == "exponential":
            modulus = stiffening_modulus(self.options, scene.material)
        tissue = None  # torsion = "green": what the tissue element's energy is
        if self.options.green_torsion:
            tissue = law_parameters(self.options, scene.material, modulus)
        # strain_average = "nodal": the springs' share measured by nodal F, else None
        self.nodal_strain, kernel_elements = NodalStrainPart.split(
            mesh, kernel_elements, self.options, modulus, tissue
        )
        # the element's own share (all of it, or alpha with nodal strain; none at alpha = 0):
        # stiffening = "exponential", the part added to the quadratic kernel; torsion =
        # "green", the tissue element's deviatoric springs (the kernel keeps the volume
        # spring alone); else None
        self.stiffening: StiffeningPart | TissuePart | None = None
        kernel_options = self.options
        own = self.nodal_strain is None or self.options.strain_stabilisation > 0.0
        if tissue is not None:
            if own:
                self.stiffening = TissuePart(kernel_elements, tissue)
            kernel_elements, kernel_options = kernel_split(kernel_elements, self.options)
        elif modulus is not None and own:
            self.stiffening = StiffeningPart(kernel_elements, self.options, modulus)
        self.kernel = SpringKernel(
            kernel_elements,
            kernel_options,
            parallel=parallel,
            precision=model_precision(scene, "spring", self.options.precision),
        )
        self.x0 = mesh.points.copy()
        self.masses = lumped_masses(scene)
        self.fixed_dofs, self._fixed_values = scene.dirichlet()
        self._follower = has_follower_loads(scene)
        self._f_dead = external_forces(scene) if not self._follower else None
        self._conservative = is_conservative(self.options) and not self._follower
        self._hessian = None  # the springs' analytic tangent (follower loads add their own)
        self._load_jacobian = None
        if is_conservative(self.options):
            try:
                from .hessian import SpringHessian

                self._hessian = SpringHessian(kernel_elements, kernel_options)
            except ImportError:
                self._hessian = None

    # -- MechanicalSystem -------------------------------------------------------------

    def prescribed(self, scale: float) -> np.ndarray:
        return self.x0.ravel()[self.fixed_dofs] + scale * self._fixed_values

    def external(self, x: np.ndarray, scale: float = 1.0) -> np.ndarray:
        """External nodal force ``(n, 3)`` at positions ``x`` times ``scale``."""
        if self._f_dead is not None:
            return scale * self._f_dead
        return external_forces(self.scene, x=x, scale=scale)

    def internal(self, x: np.ndarray, v: np.ndarray | None = None) -> np.ndarray:
        """Spring forces ``(n, 3)`` (fused kernel, plus the stiffening and nodal volume terms
        when on)."""
        f = self._element_forces(x, v)
        if self.nodal_strain is not None:
            f = f + self.nodal_strain.forces(x)
        return f if self.nodal is None else f + self.nodal.term.forces(x)

    def _element_forces(self, x: np.ndarray, v: np.ndarray | None) -> np.ndarray:
        """The kernel's forces and the stiffening's (the per-element terms)."""
        f = self.kernel.forces(x, v)
        return f if self.stiffening is None else f + self.stiffening.forces(x)

    def forces(self, x: np.ndarray, v: np.ndarray | None = None, scale: float = 1.0) -> np.ndarray:
        return self.internal(x, v) + self.external(x, scale)

    def energy(self, x: np.ndarray, scale: float = 1.0) -> float | None:
        if not self._conservative:
            return None
        work = float(np.sum(self._f_dead * (x - self.x0))) * scale
        nodal = 0.0 if self.nodal is None else self.nodal.term.energy(x)
        stiff = 0.0 if self.stiffening is None else self.stiffening.energy(x)
        strain = 0.0 if self.nodal_strain is None else self.nodal_strain.energy(x)
        return self.kernel.energy(x) + nodal + stiff + strain - work

    def stiffness(self, x: np.ndarray, scale: float = 1.0) -> sp.csr_matrix | None:
        """The springs' analytic tangent (with the stiffening and nodal terms), plus the
        coloured finite-difference Jacobian of the follower loads alone; ``None`` (the
        solvers' differences of all forces) for non-conservative laws, damping or LMS, or
        their differences with the nodal term's analytic tangent."""
        if self._hessian is None:
            if self.nodal is None:
                return None
            rest = lambda y: self._element_forces(y, None) + self.external(y, scale)  # noqa: E731
            return self.nodal.stiffness(x, None, rest)
        if self.nodal is not None:
            K = self.nodal.stiffness(x, self._hessian, None)
        else:
            K = self._hessian.matrix(x)
        if self.stiffening is not None:
            K = K + self.stiffening.stiffness(x)
        if self.nodal_strain is not None:
            K = K + self.nodal_strain.tangent(x)
        # a pressure's nodes share a facet, hence a tet: the colouring holds; at load factor 0
        # (the linear solve's tangent of the internal forces) the load has no stiffness
        if self._follower and scale != 0.0:
            if self._load_jacobian is None:
                from springfem.mechanics.fd_jacobian import ColoredJacobian

                self._load_jacobian = ColoredJacobian(self.elements.tets, self.elements.n_points)
            K = K + self._load_jacobian(lambda y: self.external(y, scale), x)
        return K

    def element_nodes(self) -> np.ndarray:
        return self.elements.tets

    def post_step(self, x: np.ndarray, dt: float) -> None:
        """LMS adaptive volume stiffness (eq. 2.81), once per time step."""
        lms = self.options.lms
        if lms is None or not self.options.barycentric_volume:
            return
        V, sum_xi = volume_measures(x, self.elements)
        k = lms_update(
            self.elements.k_volume, self.elements.k_volume0, V, self.elements.V0,
            sum_xi, self.elements.L0, lms,
        )  # fmt: skip
        self.elements = self.elements.with_volume_stiffness(k)
        self.kernel.set_volume_stiffness(k)
        if self._hessian is not None:
            self._hessian.set_volume_stiffness(k)

    # -- outputs ----------------------------------------------------------------------

    def cell_data(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """Per-element data for the VTU: axis strains, volume error, calibration residual
        (and the stiffening factor ``s_e`` when on)."""
        els = self.elements
        zeta = np.einsum("kil,kic->klc", els.G, x[els.tets])
        strain = np.linalg.norm(zeta, axis=2) / els.l0 - 1.0
        V = self.scene.mesh.volumes(x)
        out = {
            "axis_strain": strain,
            "volume_error": (V - els.V0) / els.V0,
            "calibration_mismatch": np.nan_to_num(els.mismatch),
            "k_volume_ratio": els.k_volume / np.where(els.k_volume0 > 0, els.k_volume0, 1.0),
        }
        if self.stiffening is not None:  # where the element stiffens: s_e = dW_e / dW_q
            out["stiffening_factor"] = self.stiffening.scale(x)[1]
        return out


def variant_label(options: SpringOptions) -> str:
    """Short description of the enabled spring parts in the ``[spring]`` keys' own words,
    e.g. ``axial=linear,torsion=cosine,volume=true,calibration=analytic``.

    Parameters
    ----------
    options
        Spring options.

    Returns
    -------
    str
        Comma-separated ``key=value`` items of the scene's ``[spring]`` section (a default
        sub-option is left out), ending with the calibration.

    Examples
    --------
    >>> variant_label(SpringOptions(volume="axes", torsion="energy", calibration="exact"))
    'axial=linear,torsion=energy,volume=axes,volumetric=quadratic,calibration=exact'
    """
    axial = options.axial
    if axial in ("quadratic", "cubic"):
        b = tuple(float(c) for c in options.axial_coefficients)
        axial = "green" if b == GREEN_AXIAL_COEFFICIENTS else f"{axial}({b[0]:g},{b[1]:g})"
    parts = [f"axial={axial}", f"torsion={options.torsion}"]
    if options.axis_volume:
        parts += ["volume=axes", f"volumetric={options.volumetric}"]
        if options.nodal_volume:
            parts.append("volume_average=nodal")
            if options.nodal_fraction < 1:
                parts.append(f"nodal_fraction={options.nodal_fraction:g}")
            if options.volume_stabilisation is not None:
                parts.append(f"volume_stabilisation={options.volume_stabilisation:g}")
        if options.strain_average == "nodal":
            parts.append("strain_average=nodal")
            parts.append(f"strain_stabilisation={options.strain_stabilisation:g}")
    elif options.volume:
        parts.append("volume=true")
        if options.volume_form != SpringOptions().volume_form:
            parts.append(f"volume_form={options.volume_form}")
    else:
        parts.append("volume=false")
    if options.coupling:
        parts.append("coupling=true")
    if options.stiffening != "off":
        parts.append(f"stiffening={options.stiffening}")
    if options.lms is not None:
        parts.append(f"lms={options.lms.rule}")
    parts.append(f"calibration={options.calibration}")
    return ",".join(parts)


def solve_spring(
    scene: Scene,
    options: SpringOptions | None = None,
    verbose: bool = False,
    parallel: bool | None = None,
    series_dir: str | Path | None = None,
) -> ModelSolution:
    """Build the spring model of ``scene`` and run the solver its options ask for.

    A timed run (``steps`` or ``t_end``) of a scene with ``[output] interval`` writes its
    time series into ``series_dir`` (:class:`springfem.series.SeriesWriter`); its result
    says "end of run" and whether it reached rest (``info["at_rest"]``), not "converged".

    Parameters
    ----------
    scene
        The scene.
    options
        Spring options; default ``SpringOptions.of(scene)``.
    verbose
        Print the solver's progress.
    parallel
        Run the force kernel in parallel (None: by mesh size).
    series_dir
        Folder of the time series of a timed run.

    Returns
    -------
    ModelSolution
        Result, displacements ``(n, 3)``, cell data and the solver's record (``info``).

    Raises
    ------
    SolverError
        Blow-up or divergence; ``state`` holds the last good displacement ``(n, 3)`` and
        ``load_factor`` its load factor when a static solve stopped part way.
    """
    from .solve import solve_with_options

    t0 = time.perf_counter()
    model = SpringModel(scene, options, parallel=parallel)
    opts = model.options
    writer = dynamic_series(scene, model, opts, series_dir)
    try:
        info = solve_with_options(model, opts, progress=verbose, callback=writer)
    except SolveStopped as exc:
        state = exc.state
        if state is not None:
            state = np.asarray(state).reshape(-1, 3) - model.x0
        if writer is not None:
            writer.close(plot=False)  # the frames reached stay a valid series
        raise SolveStopped(str(exc), state=state) from None
    except SolverError as exc:
        if writer is not None:
            writer.close(plot=False)
        raise stopped_error(exc, model.x0, model.elements, opts, model.stiffening) from None
    wall = time.perf_counter() - t0
    x = info.x
    u = x - model.x0
    residual = model.forces(x, None)
    iterations = int(getattr(info, "iterations", 0) or getattr(info, "steps", 0))
    warnings = scene_warnings(scene, model.elements.mismatch, opts)
    for line in warnings:
        print(f"springfem: warning: {line}", file=sys.stderr)
    notes = inert_keys(scene, opts)
    for line in notes:
        print(f"springfem: note: {line}", file=sys.stderr)
    extra = {
        "solver": opts.solver,
        "variant": variant_label(opts),
        "calibration_mismatch_median": float(np.nanmedian(model.elements.mismatch))
        if np.isfinite(model.elements.mismatch).any()
        else None,
        "calibration_mismatch_norm": MISMATCH_NORM,
        "warnings": warnings,
        "notes": notes,
        "message": getattr(info, "message", ""),
        "dt": getattr(info, "dt", None),
        "steps": int(getattr(info, "steps", 0) or 0),
        "residual": float(info.residual_history[-1]) if info.residual_history else None,
    }
    dynamic = opts.steps is not None or opts.t_end is not None
    if dynamic:
        extra.update(end_of_run(info, writer))
    result = Result(
        scene=scene.name,
        model="spring",
        element="spring",
        law=f"spring[{variant_label(opts)}]",
        counts={
            "nodes": scene.mesh.n_points,
            "tets": scene.mesh.n_tets,
            "dofs": 3 * scene.mesh.n_points,
            "fixed_dofs": int(model.fixed_dofs.size),
        },
        probes=scene.probe_displacements(u),
        volume=volume_summary(scene.mesh, u),
        reactions=reactions(scene, residual),
        wall_time=wall,
        converged=bool(info.converged) and not dynamic,
        iterations=iterations,
        info=extra,
        status=extra["status"] if dynamic else "converged",
    )
    if not info.converged:
        raise SolverError(
            f"spring model ({opts.solver}) did not converge: {getattr(info, 'message', '')}",
            state=u,
        )
    if is_ventricle(scene.mesh):
        result.info["cavity"] = cavity_summary(scene.mesh, u)
    cells = {**model.cell_data(x), **frame_cell_data(scene, u)}
    return ModelSolution(result, u, cells, info=info)


def with_options(scene: Scene, **changes) -> Scene:
    """A shallow copy of ``scene`` with ``[spring]`` options changed.

    Parameters
    ----------
    scene
        The scene.
    **changes
        :class:`~springmodel.options.SpringOptions` fields to replace.

    Returns
    -------
    Scene
        The copy.
    """
    return scene.with_options(spring=replace(SpringOptions.of(scene), **changes))

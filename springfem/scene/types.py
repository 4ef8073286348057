"""The scene's data: a mesh, a material, anisotropy frames, boundaries, loads and probes.

Examples
--------
>>> from springfem.mesh import box_mesh
>>> m = Material("linear", E=1.0e3, nu=0.25)
>>> m.mu, m.lam
(400.0, 400.0)
>>> s = Scene("s", box_mesh((1, 1, 1), (1, 1, 1)), m, np.tile(np.eye(3), (6, 1, 1)), [], [], [])
>>> s.dirichlet()[0].size, s.probe_displacements(np.zeros((8, 3)))
(0, {})
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from ..materials.laws import LawNames
from ..materials.laws.neo_hookean import FORMULATIONS as FORMULATIONS
from ..materials.laws.neo_hookean import VOLUMETRIC as VOLUMETRIC
from ..mesh import TetMesh
from ..regions import Region
from .load_time import TimeFunction
from .reader import TableReader

#: A material law's name (one of :data:`LAWS`).
Law = str
#: The material laws: three small-strain or isotropic ones, then every law of the table
#: :mod:`springfem.materials.laws`, which keep their constants in ``Material.parameters``
#: (keys in :data:`springfem.materials.laws.TISSUE_LAWS`).
LAWS = LawNames(("linear", "transverse-linear", "neo-hookean"))
LOAD_TYPES = ("traction", "pressure", "gravity", "force")
AXES_TYPES = ("uniform", "helix", "cells")
COMPONENTS = ("x", "y", "z")


#: Consistent unit systems a scene may declare (``units = "..."``), with the size of their
#: stress unit in Pa (length mm, force mN for kPa and N for MPa).
UNIT_SYSTEMS = {"SI": 1.0, "mm-kPa": 1.0e3, "mm-MPa": 1.0e6}
#: The length unit of each unit system, in m.
LENGTH_UNITS = {"SI": 1.0, "mm-kPa": 1.0e-3, "mm-MPa": 1.0e-3}
#: The density unit of each unit system, in kg/m³: its mass unit over its length unit cubed
#: (mm-kPa: mN = kg mm/s², so kg/mm³; mm-MPa: N = t mm/s², so t/mm³; time in s in all).
DENSITY_UNITS = {"SI": 1.0, "mm-kPa": 1.0e9, "mm-MPa": 1.0e12}
#: The density of a material that gives none, kg/m³ (water; soft tissue is 1000–1100).
DEFAULT_DENSITY = 1000.0


def default_density(units: str = "SI") -> float:
    """:data:`DEFAULT_DENSITY` in the unit system ``units`` (:data:`UNIT_SYSTEMS`).

    Parameters
    ----------
    units
        The scene's unit system.

    Returns
    -------
    float

    Examples
    --------
    >>> default_density(), default_density("mm-kPa"), default_density("mm-MPa")
    (1000.0, 1e-06, 1e-09)
    """
    return DEFAULT_DENSITY / DENSITY_UNITS[units]


@dataclass(frozen=True)
class Material:
    """Material parameters (SI units). Isotropic constants are derived where possible.

    For ``transverse-linear`` the fiber is axis 0 of each element's frame; ``E`` and ``nu``
    then hold an isotropic equivalent (``E_cross``, ``nu_cross``) used only for estimates
    such as the stable time step.

    Parameters
    ----------
    law
        One of :data:`LAWS`.
    E, nu
        Young's modulus (Pa) and Poisson's ratio.
    density
        kg/m³ (in the scene's unit system when read from a scene:
        :func:`default_density`).
    E_fiber, E_cross, nu_fiber_cross, nu_cross, G_fiber
        Transversely isotropic constants (``transverse-linear`` only).
    formulation, volumetric
        Neo-Hookean energy: ``coupled`` or ``uncoupled`` (isochoric/volumetric split) and
        the volumetric function ``U(J)`` of the uncoupled form (also the penalty ``U(J)``
        of the tissue laws).
    parameters
        A tissue law's constants (``guccione``: ``C, b_f, b_t, b_fs``; ``holzapfel-ogden``:
        ``a, b, a_f, b_f, a_s, b_s, a_fs, b_fs``), its bulk modulus ``kappa`` (0 when
        incompressible) and, when given, its active fibre tension ``active_tension``;
        ``E`` and ``nu`` then hold an isotropic equivalent for estimates.
    incompressible
        An incompressible tissue material (solved with ``[fem] formulation = "mixed"``).
    """

    law: Law
    E: float
    nu: float
    density: float = 1000.0
    E_fiber: float | None = None
    E_cross: float | None = None
    nu_fiber_cross: float | None = None
    nu_cross: float | None = None
    G_fiber: float | None = None
    formulation: Literal["coupled", "uncoupled"] = "coupled"
    volumetric: Literal["log", "quadratic", "simo-taylor"] = "log"
    parameters: dict[str, float] = field(default_factory=dict)
    incompressible: bool = False

    @property
    def mu(self) -> float:
        """Shear modulus ``E / (2 (1 + nu))``."""
        return self.E / (2.0 * (1.0 + self.nu))

    @property
    def lam(self) -> float:
        """Lamé's first parameter ``E nu / ((1 + nu)(1 - 2 nu))``."""
        return self.E * self.nu / ((1.0 + self.nu) * (1.0 - 2.0 * self.nu))

    @property
    def kappa(self) -> float:
        """Bulk modulus ``E / (3 (1 - 2 nu))``."""
        return self.E / (3.0 * (1.0 - 2.0 * self.nu))


@dataclass(frozen=True)
class Boundary:
    """Prescribed displacement: ``components`` of ``value`` on the region's nodes.

    Parameters
    ----------
    region
        Where.
    components
        Constrained components (0, 1, 2 for x, y, z).
    value
        ``(3,)`` prescribed displacement (zeros for ``fix``); only ``components`` count.
    """

    region: Region
    components: tuple[int, ...]
    value: np.ndarray  # (3,) prescribed displacement (zeros for `fix`)


@dataclass(frozen=True)
class Load:
    """An external load: traction (Pa, vector), pressure (Pa, scalar: t = -p n on the
    deformed surface), gravity (m/s², vector) or force (N, total vector on a region).

    Parameters
    ----------
    type
        One of :data:`LOAD_TYPES`.
    value
        ``(3,)`` vector, or ``(1,)`` for a pressure.
    region
        Where (``None`` for gravity).
    time
        The load factor as a function of time (:mod:`springfem.scene.load_time`), or
        ``None`` (always 1). Dynamic runs read it; static solves apply the full load.
    """

    type: Literal["traction", "pressure", "gravity", "force"]
    value: np.ndarray
    region: Region | None = None
    time: TimeFunction | None = None

    def factor(self, t: float) -> float:
        """The load factor at time ``t`` (1 without a time function)."""
        return 1.0 if self.time is None else self.time(t)


@dataclass(frozen=True)
class Probe:
    """A named point where displacements are reported, with its containing tet.

    Parameters
    ----------
    name
        Key in the result's ``probes``.
    point
        ``(3,)`` position at rest.
    tet
        Index of the tet containing it.
    bary
        ``(4,)`` barycentric coordinates of the point in that tet.
    """

    name: str
    point: np.ndarray
    tet: int
    bary: np.ndarray


@dataclass
class Scene:
    """Everything both models need to solve the same problem on the same mesh.

    Build one with :func:`~springfem.scene.scene_from_dict` (or read a file with
    :func:`~springfem.scene.load_scene`).

    Parameters
    ----------
    name
        Safe as a file name (:func:`~springfem.files.safe_filename`).
    mesh
        The mesh.
    material
        The material.
    frames
        ``(m, 3, 3)``: ``frames[k, l]`` is axis ``l`` (fiber, sheet, normal) of tet ``k``.
    boundaries, loads, probes
        In the order of the scene.
    options
        Parsed model sections by name (see :meth:`section`).
    path
        The scene file, if any.
    raw
        The scene's table as given.
    units
        The unit system the scene's numbers are in (:data:`UNIT_SYSTEMS`): ``SI`` or a
        consistent ``mm-kPa`` / ``mm-MPa``; only the plausibility warnings read it.
    """

    name: str
    mesh: TetMesh
    material: Material
    frames: np.ndarray  # (m, 3, 3): frames[k, l] = axis l of tet k
    boundaries: list[Boundary]
    loads: list[Load]
    probes: list[Probe]
    options: dict[str, Any] = field(default_factory=dict)
    path: Path | None = None
    raw: dict = field(default_factory=dict, repr=False)
    units: str = "SI"

    def section(self, name: str, parse: Callable[[TableReader], Any]) -> Any:
        """The parsed options of the model section ``[name]`` (parsed once, then cached).

        Parameters
        ----------
        name
            A registered model section (:func:`springfem.scene.model_sections`).
        parse
            The model's parser: takes a :class:`TableReader` over the section's table.

        Returns
        -------
        object
            Whatever ``parse`` returns (the model's options dataclass).
        """
        if name not in self.options:
            file = str(self.path) if self.path is not None else "<scene>"
            table = self.raw.get(name, {})
            self.options[name] = parse(TableReader(table, name, file, root=self.raw))
        return self.options[name]

    def with_options(self, **sections: Any) -> Scene:
        """A copy of this scene with the given model sections replaced.

        Parameters
        ----------
        **sections
            Section name -> parsed options (e.g. ``spring=SpringOptions(...)``).

        Returns
        -------
        Scene
            A shallow copy (mesh, material and the rest shared); this scene is unchanged.

        Examples
        --------
        >>> from springfem.mesh import box_mesh
        >>> s = Scene("s", box_mesh((1, 1, 1), (1, 1, 1)), Material("linear", 1.0, 0.3),
        ...           np.tile(np.eye(3), (6, 1, 1)), [], [], [])
        >>> s.with_options(fem="x").options["fem"], s.options
        ('x', {})
        """
        return replace(self, options={**self.options, **sections})

    def dirichlet(self) -> tuple[np.ndarray, np.ndarray]:
        """Constrained DOFs (node * 3 + component) and their prescribed displacements.

        Later boundaries override earlier ones on shared DOFs.

        Returns
        -------
        dofs : numpy.ndarray
            Sorted constrained DOF indices.
        values : numpy.ndarray
            Prescribed displacement of each.
        """
        values = np.full(3 * self.mesh.n_points, np.nan)
        for b in self.boundaries:
            for c in b.components:
                values[b.region.nodes * 3 + c] = b.value[c]
        dofs = np.flatnonzero(~np.isnan(values))
        return dofs, values[dofs]

    def probe_displacements(self, u: np.ndarray) -> dict[str, list[float]]:
        """Displacement at each probe, interpolated linearly in its tet from nodal ``u``.

        Parameters
        ----------
        u
            Nodal displacement ``(n, 3)`` or flat ``(3 n,)``.

        Returns
        -------
        dict
            Probe name -> ``[ux, uy, uz]``.
        """
        u = np.asarray(u).reshape(-1, 3)
        return {p.name: (p.bary @ u[self.mesh.tets[p.tet]]).tolist() for p in self.probes}

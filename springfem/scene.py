"""Scenes: a mesh, a material, anisotropy axes, boundaries, loads and probes, from TOML.

Scene files are data: they are parsed with :mod:`tomllib` and validated key by key; they
never execute code. Every problem raises :class:`~springfem.errors.SceneError` with one
line naming the file and the key.

Examples
--------
>>> s = parse_scene('''
... name = "cube"
... [mesh]
... generator = "box"
... size = [1.0, 1.0, 1.0]
... divisions = [2, 2, 2]
... [material]
... law = "linear"
... E = 1.0e3
... nu = 0.3
... [[boundary]]
... region = "x_min"
... fix = ["x", "y", "z"]
... ''')
>>> s.mesh.n_tets, s.material.mu
(48, 384.6153846153846)
"""

from __future__ import annotations

import math
import os
import tomllib
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from .errors import InputError, SceneError
from .materials.tissue import TISSUE_LAWS, tissue_tangent
from .mesh import Split, TetMesh, box_mesh, read_mesh
from .regions import Region, locate_points, resolve_region
from .result import safe_filename

Law = Literal["linear", "transverse-linear", "neo-hookean", "guccione", "holzapfel-ogden"]
# issue 11: the finite-strain tissue laws (keys in springfem.materials.tissue.TISSUE_LAWS)
LAWS = ("linear", "transverse-linear", "neo-hookean", "guccione", "holzapfel-ogden")
FORMULATIONS = ("coupled", "uncoupled")
VOLUMETRIC = ("log", "quadratic", "simo-taylor")
LOAD_TYPES = ("traction", "pressure", "gravity", "force")
AXES_TYPES = ("uniform", "helix", "cells")
COMPONENTS = ("x", "y", "z")


@dataclass(frozen=True)
class Material:
    """Material parameters (SI units). Isotropic constants are derived where possible.

    For ``transverse-linear`` the fiber is axis 0 of each element's frame; ``E`` and ``nu``
    then hold an isotropic equivalent (``E_cross``, ``nu_cross``) used only for estimates
    such as the stable time step.
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
    # issue 11: tissue laws keep their constants (and ``kappa``) here; ``incompressible``
    # materials need the mixed formulation
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
    """Prescribed displacement: ``components`` of ``value`` on the region's nodes."""

    region: Region
    components: tuple[int, ...]
    value: np.ndarray  # (3,) prescribed displacement (zeros for `fix`)


@dataclass(frozen=True)
class Load:
    """An external load: traction (Pa, vector), pressure (Pa, scalar: t = -p n on the
    deformed surface), gravity (m/s², vector) or force (N, total vector on a region)."""

    type: Literal["traction", "pressure", "gravity", "force"]
    value: np.ndarray
    region: Region | None = None


@dataclass(frozen=True)
class Probe:
    """A named point where displacements are reported, with its containing tet."""

    name: str
    point: np.ndarray
    tet: int
    bary: np.ndarray


@dataclass
class Scene:
    """Everything both models need to solve the same problem on the same mesh."""

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

    def section(self, name: str, parse: Callable[[TableReader], Any]) -> Any:
        """The parsed options of the model section ``[name]`` (parsed once, then cached).

        Parameters
        ----------
        name
            A name in :data:`MODEL_SECTIONS`.
        parse
            The model's parser: takes a :class:`TableReader` over the section's table.

        Returns
        -------
        object
            Whatever ``parse`` returns (the model's options dataclass).
        """
        if name not in self.options:
            file = str(self.path) if self.path is not None else "<scene>"
            self.options[name] = parse(TableReader(self.raw.get(name, {}), name, file))
        return self.options[name]

    def with_options(self, **sections: Any) -> Scene:
        """A copy of this scene with the given model sections replaced.

        Examples
        --------
        >>> s = Scene("s", box_mesh((1, 1, 1), (1, 1, 1)), Material("linear", 1.0, 0.3),
        ...           np.tile(np.eye(3), (6, 1, 1)), [], [], [])
        >>> s.with_options(fem="x").options["fem"], s.options
        ('x', {})
        """
        return replace(self, options={**self.options, **sections})

    def dirichlet(self) -> tuple[np.ndarray, np.ndarray]:
        """Constrained DOFs (node * 3 + component) and their prescribed displacements.

        Later boundaries override earlier ones on shared DOFs.
        """
        values = np.full(3 * self.mesh.n_points, np.nan)
        for b in self.boundaries:
            for c in b.components:
                values[b.region.nodes * 3 + c] = b.value[c]
        dofs = np.flatnonzero(~np.isnan(values))
        return dofs, values[dofs]

    def probe_displacements(self, u: np.ndarray) -> dict[str, list[float]]:
        """Displacement at each probe, interpolated linearly in its tet from nodal ``u``."""
        u = np.asarray(u).reshape(-1, 3)
        return {p.name: (p.bary @ u[self.mesh.tets[p.tet]]).tolist() for p in self.probes}


# ---------------------------------------------------------------------------- parsing

MODEL_SECTIONS = ("spring", "fem")
"""Sections that belong to a model: the core stores them, the model parses them."""

_SECTION_PARSERS: dict[str, Callable[[TableReader], Any]] = {}


def register_section(name: str, parse: Callable[[TableReader], Any]) -> None:
    """Register the parser of a model section, so scenes validate it when they load.

    Parameters
    ----------
    name
        One of :data:`MODEL_SECTIONS`.
    parse
        Takes a :class:`TableReader` over the section's table, returns the options object
        and raises :class:`SceneError` (via ``reader.fail``) on bad input.
    """
    if name not in MODEL_SECTIONS:
        raise ValueError(f"unknown model section {name!r}; valid: {', '.join(MODEL_SECTIONS)}")
    _SECTION_PARSERS[name] = parse


class TableReader:
    """Typed access to one TOML table with error messages naming file and key."""

    def __init__(self, table: Any, where: str, file: str):
        if not isinstance(table, dict):
            raise SceneError(f"{file}: {where} must be a table")
        self.t, self.where, self.file, self.used = table, where, file, set()

    def _key(self, key: str) -> str:
        key = _key_label(key)
        return f"{self.where}.{key}" if self.where else key

    def fail(self, key: str, msg: str) -> SceneError:
        return SceneError(f"{self.file}: {self._key(key)}: {msg}")

    def has(self, key: str) -> bool:
        return key in self.t

    def get(
        self,
        key: str,
        kind: str,
        default: Any = ...,
        choices=None,
        positive=False,
        nonneg=False,
        length=None,
    ):
        self.used.add(key)
        if key not in self.t:
            if default is ...:
                raise self.fail(key, "missing (required)")
            return default
        v = self.t[key]
        if kind == "str":
            if not isinstance(v, str):
                raise self.fail(key, f"must be a string, got {type(v).__name__}")
            if choices is not None and v not in choices:
                raise self.fail(key, f"{_show(v)} is not one of {', '.join(map(str, choices))}")
            return v
        if kind == "bool":
            if not isinstance(v, bool):
                raise self.fail(key, f"must be true or false, got {_show(v)}")
            return v
        if kind in ("float", "int"):
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise self.fail(key, f"must be a number, got {type(v).__name__}")
            if kind == "int" and not isinstance(v, int):
                raise self.fail(key, f"must be an integer, got {_show(v)}")
            self._check_number(key, v, kind == "int", positive, nonneg, v)
            return float(v) if kind == "float" else int(v)
        if kind in ("vec", "ivec"):
            if not isinstance(v, list) or (length is not None and len(v) != length):
                n = f"{length} " if length else ""
                raise self.fail(key, f"must be a list of {n}numbers, got {_show(v)}")
            for x in v:
                if isinstance(x, bool) or not isinstance(x, (int, float)):
                    raise self.fail(key, f"must be a list of numbers, got {_show(v)}")
                if kind == "ivec" and not isinstance(x, int):
                    raise self.fail(key, f"must be a list of integers, got {_show(v)}")
                self._check_number(key, x, kind == "ivec", positive, False, v, "entries ")
            return np.array(v, dtype=np.int64 if kind == "ivec" else float)
        raise AssertionError(kind)

    def _check_number(self, key, x, integer, positive, nonneg, shown, what="") -> None:
        """Finite, within :data:`MAX_MAGNITUDE` (or :data:`MAX_INT`), sign as required."""
        if not math.isfinite(x):
            raise self.fail(key, f"{what}must be finite, got {_show(shown)}")
        if positive and x <= 0:
            raise self.fail(key, f"{what}must be positive, got {_show(shown)}")
        if nonneg and x < 0:
            raise self.fail(key, f"{what}must not be negative, got {_show(shown)}")
        if integer and abs(x) > MAX_INT:
            raise self.fail(key, f"{what}must be at most {MAX_INT}, got {_show(shown)}")
        if not integer and abs(x) > MAX_MAGNITUDE:
            raise self.fail(key, f"{what}must lie within ±{MAX_MAGNITUDE:g}, got {_show(shown)}")
        if not integer and x != 0 and abs(x) < MIN_MAGNITUDE:
            raise self.fail(
                key,
                f"{what}must be 0 or at least {MIN_MAGNITUDE:g} in magnitude, got {_show(shown)}",
            )

    def finish(self) -> None:
        extra = sorted(set(self.t) - self.used)
        if extra:
            raise self.fail(extra[0], "unknown key")


def _key_label(key: str) -> str:
    """A key as written in a message: quoted when it holds spaces or control characters."""
    return key if key and key.isprintable() and not any(c.isspace() for c in key) else repr(key)


def _show(value: Any, limit: int = 60) -> str:
    """``repr`` of a scene value, cut to ``limit`` characters (one readable line)."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"


#: Largest magnitude of a number in a scene. SI values of soft-tissue problems are many
#: orders of magnitude inside it, and products of three such numbers (a volume, a force
#: times a length) stay finite in float64.
MAX_MAGNITUDE = 1e100
#: Smallest non-zero magnitude of a number in a scene (cubes stay normal float64 numbers).
MIN_MAGNITUDE = 1e-100
#: Largest integer in a scene (divisions, steps, iterations).
MAX_INT = 2**31 - 1

MAX_TETS = 20_000_000
BYTES_PER_TET = 2_000  # spring model + FEM P1 working set, measured order of magnitude


def machine_memory() -> int | None:
    """Physical memory of this machine in bytes, or ``None`` if the OS does not say."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return None


def check_mesh_size(n_tets: int) -> str | None:
    """Why a mesh of ``n_tets`` tets is refused before it is built or solved, or ``None``.

    The working set of the spring model and the P1 reference is estimated at
    :data:`BYTES_PER_TET` per tet; a mesh is refused when that exceeds the machine's
    physical memory or when it has more than :data:`MAX_TETS` tets.
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


def load_scene(path: str | os.PathLike) -> Scene:
    """Read and validate a scene file.

    Raises
    ------
    SceneError
        One line naming the file and the offending key.
    """
    path = Path(path)
    if not path.is_file():
        raise SceneError(f"scene file {path} does not exist")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(f"scene file {path} could not be read: {exc}") from None
    return parse_scene(text, path=path)


def parse_scene(text: str, path: str | os.PathLike | None = None) -> Scene:
    """Parse scene TOML ``text``; ``path`` (if any) anchors relative mesh paths.

    Parameters
    ----------
    text
        The TOML text.
    path
        The file it came from (names it in errors; its folder anchors ``mesh.file``).

    Returns
    -------
    Scene
        :func:`scene_from_dict` of the parsed table.
    """
    file = str(path) if path is not None else "<scene>"
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{file}: not valid TOML: {exc}") from None
    return scene_from_dict(data, path=path)


def scene_from_dict(data: dict, path: str | os.PathLike | None = None) -> Scene:
    """Build and validate a scene from a plain mapping: the one way scenes are made.

    The mapping has the layout of a scene file (``name``, ``[mesh]``, ``[material]``,
    ``[axes]``, ``[[boundary]]``, ``[[load]]``, ``[[probe]]`` and the model sections), so
    studies and tests build scenes as data and change a value by editing a dict.

    Parameters
    ----------
    data
        The scene table (not modified).
    path
        The scene file's path, if any: names it in errors and anchors relative mesh paths
        (default: the current folder).

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        One line naming the file and the offending key.

    Examples
    --------
    >>> box = {"generator": "box", "size": [1, 1, 1], "divisions": [1, 1, 1]}
    >>> s = scene_from_dict({"mesh": box, "material": {"law": "linear", "E": 1.0, "nu": 0.25}})
    >>> s.name, s.mesh.n_tets
    ('scene', 6)
    """
    file = str(path) if path is not None else "<scene>"
    base = Path(path).parent if path is not None else Path.cwd()
    top = TableReader(data, "", file)
    name = top.get("name", "str", default=Path(file).stem if path else "scene")
    safe = safe_filename(name)  # the name becomes part of default output paths
    for section in ("mesh", "material"):
        if section not in data:
            raise SceneError(f"{file}: [{section}]: missing section (required)")
    mesh = _parse_mesh(TableReader(data["mesh"], "mesh", file), base)
    top.used.add("mesh")
    material = _parse_material(TableReader(data["material"], "material", file))
    top.used.add("material")
    frames = _parse_axes(TableReader(data.get("axes", {}), "axes", file), mesh)
    top.used.add("axes")
    boundaries = [
        _parse_boundary(TableReader(b, f"boundary[{i}]", file), mesh)
        for i, b in enumerate(_array_of_tables(data, "boundary", file))
    ]
    loads = [
        _parse_load(TableReader(b, f"load[{i}]", file), mesh)
        for i, b in enumerate(_array_of_tables(data, "load", file))
    ]
    probes = [
        _parse_probe(TableReader(b, f"probe[{i}]", file), mesh)
        for i, b in enumerate(_array_of_tables(data, "probe", file))
    ]
    names = [p.name for p in probes]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise SceneError(f"{file}: probe: duplicate probe name {_show(dup[0])}")
    top.used.update({"boundary", "load", "probe"})
    options = {
        name: _SECTION_PARSERS[name](TableReader(data.get(name, {}), name, file))
        for name in MODEL_SECTIONS
        if name in _SECTION_PARSERS
    }
    top.used.update(MODEL_SECTIONS)
    top.finish()
    if safe != name:
        mesh.notes.append(
            f"{file}: name {_show(name)} can't be part of a folder name; using {safe!r}"
        )
    return Scene(
        name=safe,
        mesh=mesh,
        material=material,
        frames=frames,
        boundaries=boundaries,
        loads=loads,
        probes=probes,
        options=options,
        path=Path(path) if path is not None else None,
        raw=data,
    )


def _array_of_tables(data: dict, key: str, file: str) -> list:
    v = data.get(key, [])
    if not isinstance(v, list) or not all(isinstance(x, dict) for x in v):
        raise SceneError(f"{file}: {key}: must be an array of tables ([[{key}]])")
    return v


def _parse_mesh(r: TableReader, base: Path) -> TetMesh:
    if r.has("file") and r.has("generator"):
        raise r.fail("file", "give either file or generator, not both")
    if r.has("file"):
        rel = r.get("file", "str")
        p = Path(rel)
        p = p if p.is_absolute() else base / p
        scale = r.get("scale", "float", default=1.0, positive=True)
        r.finish()
        try:
            mesh = read_mesh(p, scale=scale)
        except InputError as exc:
            raise SceneError(f"{r.file}: mesh.file: {exc}") from None
        # a file's size can't be judged before reading it; reading needs far less memory
        # than solving, so the estimate is checked right after
        too_big = check_mesh_size(mesh.n_tets)
        if too_big:
            raise r.fail("file", too_big)
        return mesh
    gen = r.get("generator", "str", choices=("box",))
    size = r.get("size", "vec", length=3, positive=True)
    div = r.get("divisions", "ivec", length=3, positive=True)
    split: Split = r.get("split", "str", default="six", choices=opt_splits())
    origin = r.get("origin", "vec", default=np.zeros(3), length=3)
    r.finish()
    n_tets = math.prod(int(d) for d in div) * (6 if split.startswith("six") else 5)
    too_big = check_mesh_size(n_tets)
    if too_big:
        raise r.fail("divisions", too_big)
    assert gen == "box"
    try:
        return box_mesh(tuple(size), tuple(int(d) for d in div), split, tuple(origin))
    except InputError as exc:
        raise r.fail("size", str(exc)) from None


def opt_splits() -> tuple[str, ...]:
    from typing import get_args

    return get_args(Split)


def _parse_material(r: TableReader) -> Material:
    law = r.get("law", "str", choices=LAWS)
    density = r.get("density", "float", default=1000.0, positive=True)
    kw: dict[str, Any] = {"law": law, "density": density}
    if law == "transverse-linear":
        for k in ("E_fiber", "E_cross", "G_fiber"):
            kw[k] = r.get(k, "float", positive=True)
        kw["nu_fiber_cross"] = r.get("nu_fiber_cross", "float")
        kw["nu_cross"] = r.get("nu_cross", "float")
        if not -1.0 < kw["nu_cross"] < 1.0:
            raise r.fail("nu_cross", f"must lie in (-1, 1), got {kw['nu_cross']}")
        # positive definiteness of the compliance
        Ef, Ec, nfc, nc = kw["E_fiber"], kw["E_cross"], kw["nu_fiber_cross"], kw["nu_cross"]
        if 1 - nc - 2 * nfc**2 * Ec / Ef <= 0:
            raise r.fail(
                "nu_fiber_cross",
                f"{nfc} with nu_cross = {nc} gives an indefinite material "
                "(need 1 - nu_cross - 2 nu_fiber_cross^2 E_cross/E_fiber > 0)",
            )
        kw["E"], kw["nu"] = Ec, nc
    elif law in TISSUE_LAWS:  # issue 11
        kw.update(_parse_tissue(r, law))
    else:
        if r.has("mu") or r.has("kappa"):
            if r.has("E") or r.has("nu"):
                raise r.fail("mu", "give either E and nu, or mu and kappa")
            mu = r.get("mu", "float", positive=True)
            kappa = r.get("kappa", "float", positive=True)
            kw["E"] = 9 * mu / (3 + mu / kappa)  # = 9 kappa mu / (3 kappa + mu), no overflow
            kw["nu"] = (3 - 2 * mu / kappa) / (2 * (3 + mu / kappa))
        else:
            kw["E"] = r.get("E", "float", positive=True)
            kw["nu"] = r.get("nu", "float")
        if not -1.0 < kw["nu"] < 0.5:
            raise r.fail("nu", f"must lie in (-1, 0.5), got {kw['nu']}")
        if law == "neo-hookean":
            kw["formulation"] = r.get("formulation", "str", default="coupled", choices=FORMULATIONS)
            kw["volumetric"] = r.get("volumetric", "str", default="log", choices=VOLUMETRIC)
    r.finish()
    return Material(**kw)


def _parse_tissue(r: TableReader, law: str) -> dict[str, Any]:
    """Issue 11: keys of a tissue law, ``kappa`` or ``incompressible``, ``volumetric``.

    ``E`` and ``nu`` become an isotropic equivalent (for estimates only): the mean Voigt
    shear modulus of the small-strain tangent and ``kappa`` (``1000 mu`` if incompressible).
    """
    params = {}
    for k in TISSUE_LAWS[law]:
        if k.startswith("a"):
            params[k] = r.get(k, "float", nonneg=True)
        else:
            params[k] = r.get(k, "float", positive=True)
    if law == "holzapfel-ogden" and params["a"] == 0:
        raise r.fail("a", "must be positive (the isotropic term carries shear)")
    incompressible = r.get("incompressible", "bool", default=False)
    if incompressible:
        if r.has("kappa"):
            raise r.fail("kappa", "give either kappa or incompressible = true")
        kappa = 0.0
    else:
        kappa = r.get("kappa", "float", positive=True)
    volumetric = r.get("volumetric", "str", default="log", choices=VOLUMETRIC)
    params["kappa"] = kappa
    mu = float(np.mean(np.diag(tissue_tangent(law, params))[3:]))
    k_eq = kappa if kappa > 0 else 1000.0 * mu
    return {
        "parameters": params,
        "incompressible": incompressible,
        "volumetric": volumetric,
        "E": 9 * mu / (3 + mu / k_eq),
        "nu": (3 - 2 * mu / k_eq) / (2 * (3 + mu / k_eq)),
    }


def _parse_axes(r: TableReader, mesh: TetMesh) -> np.ndarray:
    from . import axes

    kind = r.get("type", "str", default="uniform", choices=AXES_TYPES)
    try:
        if kind == "cells":
            fkey = r.get("fiber_data", "str", default="fiber")
            skey = r.get("sheet_data", "str", default="sheet")
            r.finish()
            if fkey not in mesh.cell_data:
                have = ", ".join(sorted(mesh.cell_data)) or "none"
                raise r.fail(
                    "fiber_data", f"mesh has no cell data {_show(fkey)} (has: {_show(have)})"
                )
            fib = np.asarray(mesh.cell_data[fkey], dtype=float).reshape(mesh.n_tets, -1)[:, :3]
            sh = mesh.cell_data.get(skey)
            sh = None if sh is None else np.asarray(sh, float).reshape(mesh.n_tets, -1)[:, :3]
            bad = np.flatnonzero(np.linalg.norm(fib, axis=1) < 1e-12)
            if bad.size:
                raise r.fail("fiber_data", f"zero fiber vector at elements {bad[:8].tolist()}")
            return axes.cell_frames(fib, sh)
        fiber = r.get("fiber", "vec", default=np.array([1.0, 0.0, 0.0]), length=3)
        sheet = r.get("sheet", "vec", default=np.array([0.0, 1.0, 0.0]), length=3)
        if kind == "uniform":
            r.finish()
            return axes.uniform_frames(mesh.n_tets, fiber, sheet)
        axis = r.get("axis", "str", default="x", choices=COMPONENTS)
        rng = r.get("range", "vec", length=2)
        angles = r.get("angles", "vec", length=2)
        r.finish()
        return axes.helix_frames(mesh.centers(), fiber, sheet, axis, tuple(rng), tuple(angles))
    except ValueError as exc:
        if isinstance(exc, SceneError):
            raise
        raise SceneError(f"{r.file}: axes: {exc}") from None


def _coordinate(x: Any) -> bool:
    """A number usable as a coordinate: finite and within :data:`MAX_MAGNITUDE`."""
    return (
        isinstance(x, (int, float))
        and not isinstance(x, bool)
        and math.isfinite(x)
        and abs(x) <= MAX_MAGNITUDE
    )


def _parse_region(r: TableReader, mesh: TetMesh, key: str = "region") -> Region:
    r.used.add(key)
    if key not in r.t:
        raise r.fail(key, "missing (required)")
    spec = r.t[key]
    if isinstance(spec, dict):
        if set(spec) == {"box"}:
            box = spec["box"]
            ok = (
                isinstance(box, list)
                and len(box) == 2
                and all(
                    isinstance(c, list)
                    and len(c) == 3
                    and all(
                        isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                        for x in c
                    )
                    for c in box
                )
            )
            if not ok:
                raise r.fail(key, "box must be [[x0, y0, z0], [x1, y1, z1]] (finite numbers)")
        elif set(spec) == {"point"}:
            p = spec["point"]
            if not (isinstance(p, list) and len(p) == 3 and all(_coordinate(x) for x in p)):
                raise r.fail(key, "point must be [x, y, z] (finite numbers)")
        else:
            raise r.fail(key, "must be a name, { box = [[..],[..]] } or { point = [x,y,z] }")
    elif not isinstance(spec, str):
        raise r.fail(key, "must be a name, { box = [[..],[..]] } or { point = [x,y,z] }")
    try:
        return resolve_region(mesh, spec, where=f"{r.file}: {r._key(key)}")
    except InputError as exc:
        raise SceneError(str(exc)) from None


def _parse_boundary(r: TableReader, mesh: TetMesh) -> Boundary:
    region = _parse_region(r, mesh)
    if r.has("fix"):
        fix = r.t["fix"]
        r.used.add("fix")
        if not isinstance(fix, list) or not fix or not all(c in COMPONENTS for c in fix):
            raise r.fail("fix", f'must be a non-empty list of "x", "y", "z", got {_show(fix)}')
        comps = tuple(sorted({COMPONENTS.index(c) for c in fix}))
    else:
        comps = (0, 1, 2)
    if r.has("displacement"):
        value = r.get("displacement", "vec", length=3)
    elif r.has("fix"):
        value = np.zeros(3)
    else:
        raise r.fail("fix", "a boundary needs fix = [...] or displacement = [dx, dy, dz]")
    r.finish()
    return Boundary(region=region, components=comps, value=value)


def _parse_load(r: TableReader, mesh: TetMesh) -> Load:
    kind = r.get("type", "str", choices=LOAD_TYPES)
    if kind == "pressure":
        value = np.array([r.get("value", "float")])
    else:
        value = r.get("value", "vec", length=3)
    region = None
    if kind != "gravity":
        region = _parse_region(r, mesh)
        if kind in ("traction", "pressure") and region.facets.size == 0:
            raise r.fail("region", f"{region.name} contains no boundary facets for a {kind}")
    r.finish()
    return Load(type=kind, value=value, region=region)


def _parse_probe(r: TableReader, mesh: TetMesh) -> Probe:
    name = r.get("name", "str")
    point = r.get("point", "vec", length=3)
    r.finish()
    tet, bary = locate_points(mesh.points, mesh.tets, point[None])
    if tet[0] < 0:
        lo, hi = mesh.bounding_box()
        raise r.fail(
            "point",
            f"probe {_show(name)} at {point.tolist()} is outside the mesh "
            f"(bounding box {lo.tolist()} – {hi.tolist()})",
        )
    return Probe(name=name, point=point, tet=int(tet[0]), bary=bary[0])

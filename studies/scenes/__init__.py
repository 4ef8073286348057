"""The bundled scenes, and the scenes a study runs on.

Bundled scenes are the TOML files of this folder (``cantilever``, ``sag``, the Land
scenes, ...): :func:`scene_path` finds one by name or takes a file, :func:`bundled_table`
reads its table with ``--set``-style overrides applied.

A study is a function of a list of :class:`StudyScene`: a scene table (overrides applied),
the file that anchors its relative mesh path, a label for tables and figures, the series
of the study it serves, and the name of its closed-form reference, if any
(:mod:`studies.analytic`). The bundled report passes bundled scenes with overrides for the
variants it needs; ``springfem study NAME --scene FILE`` passes the user's scene, which
serves every series. A study's cache case of a scene carries the table and the SHA-256 of
the mesh file it names (:meth:`StudyScene.case`), so editing either recomputes the case.

Examples
--------
>>> bar = StudyScene.bundled("cantilever", {"mesh.divisions": [10, 1, 1]}, label="bar")
>>> bar.label, bar.table["mesh"]["divisions"], bar.build().mesh.n_tets
('bar', [10, 1, 1], 60)
>>> bar.scaled(10.0).table["load"][0]["value"]
[0.0, 0.0, -1.0]
>>> scene_path("sag").name
'sag.toml'
"""

from __future__ import annotations

import copy
import hashlib
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from springfem.errors import InputError

from ..overrides import apply_overrides, read_scene_table, scene_with_overrides

if TYPE_CHECKING:  # the scene module is imported when a scene is built (fast CLI start-up)
    from springfem.scene import Scene

#: The folder of the bundled scene files.
SCENES = Path(__file__).resolve().parent
#: The scene of ``springfem compare`` without an argument.
DEFAULT_SCENE = SCENES / "cantilever.toml"

Sets = Mapping[str, Any] | Iterable[tuple[str, Any]]


def bundled_names() -> list[str]:
    """The names of the bundled scenes (file stems), sorted.

    Returns
    -------
    list of str
    """
    return sorted(p.stem for p in SCENES.glob("*.toml"))


def scene_path(name: str | None) -> Path:
    """A scene file: ``name`` itself if it is a file, else the bundled scene of that name.

    Parameters
    ----------
    name
        A path, a bundled scene's name (``cantilever``, ``sag`` ...), or ``None`` for
        :data:`DEFAULT_SCENE`.

    Returns
    -------
    Path

    Raises
    ------
    InputError
        If it is neither (the message lists the bundled scenes).
    """
    if name is None:
        return DEFAULT_SCENE
    p = Path(name)
    if p.is_file():
        return p
    bundled = SCENES / f"{name}.toml"
    if bundled.is_file() and p.suffix == "":
        return bundled
    raise InputError(
        f"scene file {name} does not exist (bundled scenes: {', '.join(bundled_names())})"
    )


def _pairs(sets: Sets | None) -> list[tuple[str, Any]]:
    if sets is None:
        return []
    return list(sets.items()) if isinstance(sets, Mapping) else list(sets)


def bundled_table(name: str, sets: Sets | None = None) -> dict:
    """The table of a bundled scene with dotted-key overrides applied (a fresh copy).

    Parameters
    ----------
    name
        A bundled scene name.
    sets
        ``{dotted key: value}`` (the ``--set`` keys of :mod:`studies.overrides`).

    Returns
    -------
    dict

    Examples
    --------
    >>> bundled_table("cantilever", {"mesh.divisions": [20, 2, 2]})["mesh"]["divisions"]
    [20, 2, 2]
    """
    return apply_overrides(read_scene_table(scene_path(name)), _pairs(sets))


def mesh_digest(table: Mapping, path: str | None) -> str:
    """SHA-256 of the mesh file a scene table names (``""`` for a generated mesh).

    Parameters
    ----------
    table
        The scene table.
    path
        The scene file (relative mesh paths are relative to its folder).

    Returns
    -------
    str
        The hex digest, or ``""``.
    """
    mesh = table.get("mesh", {})
    if not isinstance(mesh, Mapping) or "file" not in mesh:
        return ""
    f = Path(mesh["file"])
    if not f.is_absolute() and path is not None:
        f = Path(path).parent / f
    try:
        return hashlib.sha256(f.read_bytes()).hexdigest()
    except OSError:
        return ""  # the scene validation names the missing file


def _scaled(value: Any, factor: float) -> Any:
    if isinstance(value, list):
        return [_scaled(v, factor) for v in value]
    return float(value) * factor


def scaled_table(table: Mapping, factor: float) -> dict:
    """A copy of ``table`` with every load value and prescribed displacement × ``factor``.

    Parameters
    ----------
    table
        The scene table.
    factor
        The load factor.

    Returns
    -------
    dict

    Examples
    --------
    >>> t = {"load": [{"type": "traction", "region": "x_max", "value": [0, 0, -1]}]}
    >>> scaled_table(t, 10.0)["load"][0]["value"]
    [0.0, 0.0, -10.0]
    """
    data = copy.deepcopy(dict(table))
    for load in data.get("load", []):
        if "value" in load:
            load["value"] = _scaled(load["value"], factor)
    for bc in data.get("boundary", []):
        if "displacement" in bc:
            bc["displacement"] = _scaled(bc["displacement"], factor)
    return data


@dataclass(frozen=True)
class StudyScene:
    """A scene a study runs on.

    Attributes
    ----------
    label
        Its name in tables, figures and headline keys.
    table
        The scene table, overrides applied.
    path
        The scene file (anchors a relative mesh path); ``None`` for a bundled table.
    roles
        The study's series this scene serves (empty: every series).
    analytic
        The name of its closed-form reference in :mod:`studies.analytic`, or ``None``.
    user
        A user's scene (``study NAME --scene FILE``) rather than a bundled one.
    params
        What a study records about the scene beyond its table (its stretch, mesh size ...):
        part of every case of the scene, so the study's frames can read them back.
    """

    label: str
    table: dict = field(repr=False)
    path: str | None = None
    roles: tuple[str, ...] = ()
    analytic: str | None = None
    user: bool = False
    params: dict = field(default_factory=dict)

    @classmethod
    def bundled(
        cls,
        name: str,
        sets: Sets | None = None,
        label: str | None = None,
        roles: tuple[str, ...] = (),
        analytic: str | None = None,
    ) -> StudyScene:
        """A bundled scene with overrides.

        Parameters
        ----------
        name
            The bundled scene's name.
        sets
            ``{dotted key: value}`` overrides.
        label
            Its label (default ``name``).
        roles, analytic
            As the attributes.

        Returns
        -------
        StudyScene
        """
        return cls(label or name, bundled_table(name, sets), None, tuple(roles), analytic)

    @classmethod
    def from_file(cls, path: str | Path, sets: Sets | None = None) -> StudyScene:
        """A user's scene file with overrides, validated now (errors before any solve).

        Parameters
        ----------
        path
            The scene file or a bundled scene's name.
        sets
            ``(dotted key, value)`` pairs (``--set``).

        Returns
        -------
        StudyScene
            Labelled by the table's ``name``, else the file's stem.
        """
        file = scene_path(str(path)).resolve()
        pairs = _pairs(sets)
        raw = read_scene_table(file)
        scene_with_overrides(raw, pairs, file)  # errors now, not in a worker
        table = apply_overrides(raw, pairs)
        return cls(str(table.get("name") or file.stem), table, str(file), user=True)

    def serves(self, role: str) -> bool:
        """Whether this scene takes part in the study's series ``role``.

        Parameters
        ----------
        role
            A series name.

        Returns
        -------
        bool
        """
        return not self.roles or role in self.roles

    def with_sets(self, sets: Sets, label: str | None = None) -> StudyScene:
        """The same scene with more overrides (and optionally another label).

        Parameters
        ----------
        sets
            ``{dotted key: value}``.
        label
            The new label (default: unchanged).

        Returns
        -------
        StudyScene
        """
        table = apply_overrides(self.table, _pairs(sets))
        return replace(self, table=table, label=label or self.label)

    def scaled(self, factor: float) -> StudyScene:
        """The same scene with its loads and prescribed displacements × ``factor``.

        Parameters
        ----------
        factor
            The load factor.

        Returns
        -------
        StudyScene
        """
        if factor == 1.0:
            return self
        return replace(self, table=scaled_table(self.table, factor))

    def build(self) -> Scene:
        """The validated scene.

        Returns
        -------
        Scene
        """
        return scene_with_overrides(self.table, (), self.path)

    def case(self, study: str, version: int, **extra: Any) -> dict[str, Any]:
        """A JSON-able cache case of this scene: its table, file, mesh digest and ``extra``.

        Parameters
        ----------
        study
            The study's name (two studies' cases never share a key).
        version
            The study's case version.
        **extra
            What else decides the case (model, level, load factor ...).

        Returns
        -------
        dict
            ``study``, ``version``, ``scene`` (the label), ``table``, the scene's ``params``,
            ``path`` and ``mesh_digest`` (a user's scene), and ``extra``.
        """
        case = {"study": study, "version": version, "scene": self.label, "table": self.table}
        case.update(self.params)
        if self.path is not None:
            case["path"] = self.path
            case["mesh_digest"] = mesh_digest(self.table, self.path)
        return {**case, **extra}


#: The bundled scenes the comparison studies (accuracy, ablation) run on, with the name of
#: their closed-form reference (:mod:`studies.analytic`).
COMPARISON_SCENES = {
    "cantilever": "timoshenko",
    "stretch-fiber": "uniaxial-fiber",
    "stretch-cross": "uniaxial-cross",
    "sag": None,
}
#: The cantilever on other meshes: unstructured (jittered Delaunay tets) and elongated cells.
CANTILEVER_MESHES = ("cantilever-unstructured", "cantilever-elongated")


def comparison_scenes(
    divisions: Mapping[str, Any],
    extra: Mapping[str, Any],
    roles: Callable[[str], tuple[str, ...]] = lambda name: (),
) -> list[StudyScene]:
    """The bundled comparison scenes on given meshes, then the cantilever on other meshes.

    Parameters
    ----------
    divisions
        Scene name (of :data:`COMPARISON_SCENES`) -> box divisions (``None``: its own).
    extra
        ``cantilever-unstructured`` -> the grid of its jittered Delaunay tets,
        ``cantilever-elongated`` -> its box divisions (names of :data:`CANTILEVER_MESHES`).
    roles
        Scene name -> its roles.

    Returns
    -------
    list of StudyScene

    Examples
    --------
    >>> [s.label for s in comparison_scenes({"sag": None}, {"cantilever-elongated": (4, 1, 1)})]
    ['sag', 'cantilever-elongated']
    """
    out = []
    for name, d in divisions.items():
        sets = {} if d is None else {"mesh.divisions": list(d)}
        out.append(StudyScene.bundled(name, sets, None, roles(name), COMPARISON_SCENES[name]))
    for name, d in extra.items():
        if name not in CANTILEVER_MESHES:
            raise InputError(f"no cantilever mesh {name!r}; known: {', '.join(CANTILEVER_MESHES)}")
        sets = {"name": name, "mesh.divisions": list(d)}
        if name == "cantilever-unstructured":
            sets.update({"mesh.split": "delaunay", "mesh.seed": 0})
        out.append(StudyScene.bundled("cantilever", sets, name, roles(name), "timoshenko"))
    return out


def case_scene(case: Mapping[str, Any], factor: float = 1.0) -> Scene:
    """The scene of a :meth:`StudyScene.case`, its loads × ``factor``.

    Parameters
    ----------
    case
        The case.
    factor
        The load factor.

    Returns
    -------
    Scene
    """
    table = case["table"] if factor == 1.0 else scaled_table(case["table"], factor)
    return scene_with_overrides(table, (), case.get("path"))


def require(scenes: list[StudyScene], study: str) -> None:
    """Refuse an empty scene list in one line.

    Parameters
    ----------
    scenes
        The scenes a study was given.
    study
        Its name.

    Raises
    ------
    InputError
        If ``scenes`` is empty.
    """
    if not scenes:
        raise InputError(f"study {study}: no scene to run on")

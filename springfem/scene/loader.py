"""Scene files: TOML text read with :mod:`tomllib`, then :func:`scene_from_dict`.

Scene files are data: they are parsed and validated key by key; they never execute code.

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

import os
import tomllib
from pathlib import Path

from ..errors import SceneError
from ..plugins import scene_folders
from .build import scene_from_dict
from .types import Scene


def load_scene(path: str | os.PathLike) -> Scene:
    """Read and validate a scene file.

    Parameters
    ----------
    path
        A TOML scene file (relative mesh paths in it are relative to its folder), or the
        name of a scene in a folder an installed package registers
        (:func:`springfem.plugins.scene_folders`: ``"cantilever"``, ``"sag"`` ...).

    Returns
    -------
    Scene
        :func:`~springfem.scene.scene_from_dict` of the file's table.

    Raises
    ------
    SceneError
        One line naming the file and the offending key.

    Examples
    --------
    >>> load_scene("cantilever").mesh.n_tets
    3840
    """
    path = named_scene(Path(path))
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(f"scene file {path} could not be read: {exc}") from None
    return parse_scene(text, path=path)


def named_scene(path: Path) -> Path:
    """``path`` if it is a file, else the registered scene of that name.

    Parameters
    ----------
    path
        A file, or a bare name (no folder, no suffix).

    Returns
    -------
    Path

    Raises
    ------
    SceneError
        Neither a file nor a registered name (the message lists the names).
    """
    if path.is_file():
        return path
    folders = scene_folders()
    if path.suffix == "" and path.parent == Path("."):
        for folder in folders:
            if (folder / f"{path.name}.toml").is_file():
                return folder / f"{path.name}.toml"
    names = sorted({p.stem for f in folders for p in f.glob("*.toml")})
    listed = f" (named scenes: {', '.join(names)})" if names else ""
    raise SceneError(f"scene file {path} does not exist{listed}")


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

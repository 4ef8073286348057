"""The manual's scene-key reference is the parsers' own list, and reaches every branch.

The reference (docs/scenes.rst#every-key-by-section) is generated when the manual is built,
from :func:`springfem.scene.reference.reference_rst`. Independent of the recording: the
string keys written in the parsers' source (an AST scan,
:func:`springfem.scene.reference.literal_keys`) must all appear in the generated tables,
read back from their reStructuredText, so a key in a branch the corpus does not reach
fails here too.
"""

import re
from pathlib import Path

import pytest

from springfem.scene.reference import accepted_keys, literal_keys, reference_rst

SCENES_PAGE = Path(__file__).resolve().parents[2] / "docs" / "scenes.rst"


@pytest.fixture(scope="module")
def keys():
    return accepted_keys()


def _tables(text: str) -> dict[str, set[str]]:
    """Section -> the keys of its table, read back from the generated reStructuredText."""
    out: dict[str, set[str]] = {}
    section = None
    for line in text.splitlines():
        if m := re.match(r"\.\. list-table:: ``(.+)``$", line):
            section = m[1]
            out[section] = set()
        elif section and (m := re.match(r"   \* - ``(.+)``$", line)):
            out[section].add(m[1])
    return out


def test_the_manual_generates_the_reference():
    assert ".. springfem-scene-keys::" in SCENES_PAGE.read_text(encoding="utf-8")


def test_the_generated_tables_hold_every_recorded_key(keys):
    tables = _tables(reference_rst())
    assert tables == {section: set(ks) for section, ks in keys.items()}


def test_every_key_in_the_parsers_source_is_in_the_reference():
    documented = {k for section in _tables(reference_rst()).values() for k in section}
    assert literal_keys() - documented == set()


def test_the_check_sees_a_missing_key():
    # the reading-back above can fail: a table without a row loses that key
    text = reference_rst().replace("   * - ``scale``\n", "   * - ``scale_gone``\n")
    documented = {k for section in _tables(text).values() for k in section}
    assert "scale" in literal_keys() - documented


def test_known_keys_of_each_section(keys):
    """A few keys read off the scene-file format by hand (docs/scenes.rst's example)."""
    assert {"law", "E", "nu", "density"} <= set(keys["material (linear)"])
    assert {"C", "b_f", "b_t", "b_fs", "kappa", "incompressible"} <= set(
        keys["material (guccione)"]
    )
    assert {"type", "fiber", "sheet", "range", "angles", "fiber_data"} <= set(keys["axes"])
    assert set(keys["load"]) == {"type", "region", "value", "time"}
    assert set(keys["load.time"]) == {"ramp", "hold", "release", "table"}
    assert set(keys["dynamics.damping"]) == {"mass", "stiffness", "ratio", "frequencies"}
    assert keys["spring"]["torsion"]["choices"] == (
        "off", "angle", "cosine", "cubic", "energy", "shear", "green"
    )  # fmt: skip
    assert keys["fem"]["order"]["kind"] == "int"

"""The README's scene-key reference is the parsers' own list, and reaches every branch.

Independent of the recording: the string keys written in the parsers' source (an AST scan,
:func:`springfem.scene.reference.literal_keys`) must all appear in the generated reference,
so a key in a branch the corpus does not reach fails here too.
"""

import re
from pathlib import Path

import pytest

from springfem.scene.reference import accepted_keys, literal_keys, reference_markdown

README = Path(__file__).resolve().parents[2] / "README.md"


@pytest.fixture(scope="module")
def keys():
    return accepted_keys()


def test_the_readme_reference_is_up_to_date():
    text = README.read_text()
    m = re.search(r"<!-- scene-keys:begin -->\n(.*?)<!-- scene-keys:end -->", text, re.S)
    assert m, "README.md has no scene-keys block"
    assert m.group(1) == reference_markdown(), (
        "README's scene keys differ from the parsers: run "
        "`python -m springfem.scene.reference` and paste its output between the markers"
    )


def test_every_key_in_the_parsers_source_is_in_the_reference(keys):
    documented = {k for section in keys.values() for k in section}
    assert literal_keys() - documented == set()


def test_known_keys_of_each_section(keys):
    """A few keys read off the scene-file format by hand (README's example and docs)."""
    assert {"law", "E", "nu", "density"} <= set(keys["material (linear)"])
    assert {"C", "b_f", "b_t", "b_fs", "kappa", "incompressible"} <= set(
        keys["material (guccione)"]
    )
    assert {"type", "fiber", "sheet", "range", "angles", "fiber_data"} <= set(keys["axes"])
    assert set(keys["load"]) == {"type", "region", "value"}
    assert keys["spring"]["torsion"]["choices"] == (
        "off", "angle", "cosine", "cubic", "energy", "shear", "green"
    )  # fmt: skip
    assert keys["fem"]["order"]["kind"] == "int"

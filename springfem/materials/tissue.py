"""The tissue laws' names and small-strain tangents, read off the law table.

The laws themselves are :mod:`springfem.materials.laws` (one module each); this module
keeps the names the models and studies import.

Examples
--------
>>> sorted(TISSUE_LAWS)[:2]
['guccione', 'holzapfel-ogden']
>>> float(tissue_tangent("guccione", {"C": 2.0, "b_f": 8.0, "b_t": 2.0, "b_fs": 4.0})[0, 0])
16.0
"""

from .laws import TISSUE_LAWS
from .laws import small_strain_tangent as tissue_tangent

__all__ = ["TISSUE_LAWS", "tissue_tangent"]

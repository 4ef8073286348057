"""springmodel: the anisotropic tetrahedral spring model (imports only the core ``springfem``).

Examples
--------
>>> from springmodel.options import SpringOptions
>>> o = SpringOptions()  # the spec's defaults
>>> o.axial, o.torsion, o.calibration
('linear', 'cosine', 'analytic')
"""

from . import options as _options  # noqa: F401  (registers the [spring] scene section)

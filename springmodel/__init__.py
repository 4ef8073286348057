"""springmodel: the anisotropic tetrahedral spring model (imports only the core ``springfem``)."""

from . import options as _options  # noqa: F401  (registers the [spring] scene section)

"""Co-rotational linear P1 tetrahedra: a fast peer of the spring model, through the model
plug-in API of :mod:`springfem.model_api` (it imports only the core).

Modules: :mod:`.polar` (the element rotation, stable for inverted elements),
:mod:`.kernel` (the compiled force kernel and its numpy twin), :mod:`.system` (the
mechanical system with the consistent and the warped tangent), :mod:`.plugin` (the models
``corotational`` and ``corotational-warped``). docs/plugins.rst describes it.

Examples
--------
>>> from corotational.plugin import models
>>> models()[0].label
'co-rotational P1 (consistent tangent)'
"""

from .system import Corotational

__all__ = ["Corotational"]

"""Material matrices both models use (the spring calibration and the FEM alike).

- :mod:`.elastic`: Lamé parameters, isotropic / orthotropic / transversely isotropic
  matrices and compliances, a scene material's small-strain matrix.
- :mod:`.voigt`: Voigt and Mandel forms, strain vectors, rotations to element frames.

Examples
--------
>>> D = isotropic_matrix(1.0, 0.25)
>>> round(float(D[0, 0]), 12), float(D[0, 1]), float(D[3, 3])
(1.2, 0.4, 0.4)
"""

from .elastic import (
    TRANSVERSE_KEYS,
    is_transverse,
    isotropic_matrix,
    lame_matrix,
    lame_parameters,
    material_matrix,
    orthotropic_compliance,
    transverse_compliance,
    transverse_matrix,
)
from .voigt import (
    VOIGT,
    VOIGT_PAIRS,
    from_mandel,
    mandel_rotation,
    rotate_tensor,
    rotate_to_global,
    strain_tensor,
    strain_voigt,
    sym_to_mandel,
    tensor_to_voigt,
    to_mandel,
    voigt_to_tensor,
    voigt_vector,
)

__all__ = [
    "TRANSVERSE_KEYS",
    "VOIGT",
    "VOIGT_PAIRS",
    "from_mandel",
    "is_transverse",
    "isotropic_matrix",
    "lame_matrix",
    "lame_parameters",
    "mandel_rotation",
    "material_matrix",
    "orthotropic_compliance",
    "rotate_tensor",
    "rotate_to_global",
    "strain_tensor",
    "strain_voigt",
    "sym_to_mandel",
    "tensor_to_voigt",
    "to_mandel",
    "transverse_compliance",
    "transverse_matrix",
    "voigt_to_tensor",
    "voigt_vector",
]

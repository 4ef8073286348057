"""springfem.volumetric (the U(J) the axis-volume spring uses; a core module).

References: central differences of U and U', the small-strain limit ``U''(1) = kappa``. The
FEM's laws (springfem.materials.laws.neo_hookean, springfem.materials.laws) use this same function.
"""

from __future__ import annotations

import numpy as np
import pytest

from springfem.errors import InputError
from springfem.volumetric import VOLUMETRIC_ENERGIES, volumetric_energy

J = np.array([0.3, 0.8, 1.0, 1.3, 2.5])


@pytest.mark.parametrize("kind", VOLUMETRIC_ENERGIES)
def test_derivatives_by_finite_differences(kind):
    # h = 1e-6: central-difference error ~h^2 U''' + eps U / h, below 1e-8 here
    U, dU, d2U = volumetric_energy(J, 2.0, kind)
    h = 1e-6
    Up, dUp, _ = volumetric_energy(J + h, 2.0, kind)
    Um, dUm, _ = volumetric_energy(J - h, 2.0, kind)
    np.testing.assert_allclose(dU, (Up - Um) / (2 * h), rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(d2U, (dUp - dUm) / (2 * h), rtol=1e-8, atol=1e-10)
    U1, dU1, d2U1 = volumetric_energy(np.array([1.0]), 2.0, kind)
    assert (U1[0], dU1[0], d2U1[0]) == (0.0, 0.0, pytest.approx(2.0, rel=1e-15))


def test_unknown_energy_is_a_clear_error():
    with pytest.raises(InputError, match="is not one of quadratic, log, simo-taylor"):
        volumetric_energy(J, 1.0, "cubic")

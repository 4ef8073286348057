"""An edge mass–spring network: a linear spring on every mesh edge, lumped masses, the
scene's loads and supports (docs/peers.rst#mass-spring), as a
:class:`~springfem.mechanics.MechanicalSystem` for the core's integrators and Newton.

Examples
--------
>>> from peers.mass_spring.network import CALIBRATIONS
>>> CALIBRATIONS
('van-gelder', 'tensor-fit')
"""

from .network import MassSpring

__all__ = ["MassSpring"]

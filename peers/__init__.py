"""Fast peers of the spring model that users pick instead of it, measured against the
hyperelastic FEM reference on the same mesh (docs/peers.rst). They import only the core.

Subpackages: :mod:`peers.xpbd` (extended position-based dynamics with the stable
neo-Hookean tetrahedral constraints of Macklin & Müller 2021) and :mod:`peers.mass_spring`
(springs on the mesh edges with van Gelder's 1998 stiffness). :mod:`peers.plugin` makes them
models of the plug-in API (:mod:`springfem.model_api`).

Examples
--------
>>> from peers.xpbd.constraints import stable_neo_hookean
>>> stable_neo_hookean(mu=1.0, lam=2.0)  # Lamé lam + mu in the energy: (lam, mu) at rest
(1.0, 3.0, 1.3333333333333333)
"""

"""Python API: load a scene, solve it with each model, compare, change a parameter, write VTU."""

from dataclasses import replace
from pathlib import Path
from tempfile import mkdtemp

import numpy as np

import reference_fem
from springfem.result import write_result
from springfem.scene import load_scene
from springmodel.model import solve_spring
from springmodel.options import SpringOptions

scene = load_scene("studies/scenes/cantilever.toml")  # or any scene file of yours

fem = reference_fem.solve(scene, order=1)  # P1 FEM on the same mesh
spring = solve_spring(scene)  # the spring model, with the scene's [spring] options

u_fem, u_spring = fem.u_vertices, spring.u  # (n_nodes, 3) nodal displacements, m
model_error = np.linalg.norm(u_spring - u_fem) / np.linalg.norm(u_fem)
tip_fem, tip_spring = fem.result.probes["tip"][2], spring.result.probes["tip"][2]
print(f"tip deflection: FEM P1 {tip_fem:.4e} m, spring {tip_spring:.4e} m")
print(f"model error (spring vs P1, relative L2): {model_error:.1%}")

# change a parameter and re-solve: energy-consistent torsion instead of the default cosine
energy = replace(SpringOptions.of(scene), torsion="energy")
spring_energy = solve_spring(scene, energy)

out = Path(mkdtemp())
json_path, vtu_path = write_result(out, spring_energy.result, scene.mesh, spring_energy.u)
print(f"wrote {vtu_path.name} and {json_path.name}")

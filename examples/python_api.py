"""Python API: load a scene, list the models, solve it with two, compare, write VTU."""

from pathlib import Path
from tempfile import mkdtemp

import numpy as np

import springfem
from springfem.result import write_result
from springfem.scene import load_scene

scene = load_scene("studies/scenes/cantilever.toml")  # or any scene file of yours

print(", ".join(springfem.models()))  # every model: spring elements, FEM, plug-ins
fem = springfem.solve(scene, "P1")  # P1 FEM on the same mesh
spring = springfem.solve(scene, "spring")  # the spring model, the scene's [spring] options

u_fem, u_spring = fem.u, spring.u  # (n_nodes, 3) nodal displacements, m
model_error = np.linalg.norm(u_spring - u_fem) / np.linalg.norm(u_fem)
tip_fem, tip_spring = fem.result.probes["tip"][2], spring.result.probes["tip"][2]
print(f"tip deflection: FEM P1 {tip_fem:.4e} m, spring {tip_spring:.4e} m")
print(f"model error (spring vs P1, relative L2): {model_error:.1%}")
for line in spring.warnings:  # what the command line would warn about the state
    print(f"warning: {line}")

# another model by name: the spring variant with the energy-consistent torsion
spring_energy = springfem.solve(scene, springfem.get_model("spring-energy"))

out = Path(mkdtemp())
json_path, vtu_path = write_result(out, spring_energy.result, scene.mesh, spring_energy.u)
print(f"wrote {vtu_path.name} and {json_path.name}")

"""A small organ mesh for the tutorial (docs/tutorial.rst): an ellipsoid cut flat at one end.

gmsh builds the body and names its parts as physical groups, which springfem reads as the
scene's regions: the volume ``organ``, the flat cut ``hilum`` (where the organ is held) and
the rest of the surface ``capsule``. Run as ``python organ_mesh.py [element size in m]``; it
writes ``organ.msh`` (gmsh 4.1, about a thousand tets at the default size).
"""

import sys

import gmsh

SEMI_AXES = (0.06, 0.03, 0.025)  # m: a kidney-sized ellipsoid
CUT_X = -0.045  # m: the flat face (hilum) at x = CUT_X
size = float(sys.argv[1]) if len(sys.argv) > 1 else 0.012

gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("organ")
occ = gmsh.model.occ
ball = occ.addSphere(0.0, 0.0, 0.0, 1.0)
occ.dilate([(3, ball)], 0.0, 0.0, 0.0, *SEMI_AXES)
keep = occ.addBox(CUT_X, -1.0, -1.0, 2.0, 2.0, 2.0)
body, _ = occ.intersect([(3, ball)], [(3, keep)])
occ.synchronize()

surfaces = [tag for dim, tag in gmsh.model.getBoundary(body, oriented=False)]
flat = [s for s in surfaces if gmsh.model.getBoundingBox(2, s)[3] < CUT_X + 1e-4]
gmsh.model.addPhysicalGroup(3, [body[0][1]], name="organ")
gmsh.model.addPhysicalGroup(2, flat, name="hilum")
gmsh.model.addPhysicalGroup(2, [s for s in surfaces if s not in flat], name="capsule")

gmsh.option.setNumber("Mesh.MeshSizeMin", size)
gmsh.option.setNumber("Mesh.MeshSizeMax", size)
gmsh.model.mesh.generate(3)
gmsh.write("organ.msh")
gmsh.finalize()
print(f"wrote organ.msh (element size {size} m)")

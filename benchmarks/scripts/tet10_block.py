#!/usr/bin/env python3
"""Writes a gmsh tet10 mesh of a steel block with a bore, for the large reduction run of
BENCHMARKS.md ("Craig-Bampton reduction", 1M-dof tet10 body): a 2.6 m x 1 m x 1 m block
along x with a cylindrical bore of radius 0.25 m through it along y, meshed by gmsh
(unstructured, Delaunay/HXT, second order), physical groups "body" (volume), "root"
(face x = 0) and "tip" (face x = 2.6). MSH 4.1, binary.

Usage: python3 tet10_block.py OUT.msh [MESH_SIZE]   (needs `pip install gmsh`)
Element size 0.035 m: 326 358 nodes, 0.98 M nodal dofs (3 per node); 0.042 m: 0.58 M."""
import sys

import gmsh

out = sys.argv[1]
h = float(sys.argv[2]) if len(sys.argv) > 2 else 0.035
L, W, H, R = 2.6, 1.0, 1.0, 0.25

gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 1)
gmsh.model.add("block")
box = gmsh.model.occ.addBox(0, 0, 0, L, W, H)
bore = gmsh.model.occ.addCylinder(L / 2, 0, H / 2, 0, W, 0, R)
gmsh.model.occ.cut([(3, box)], [(3, bore)])
gmsh.model.occ.synchronize()
vols = [t for _, t in gmsh.model.getEntities(3)]
eps = 1e-6
root = [t for _, t in gmsh.model.getEntitiesInBoundingBox(-eps, -eps, -eps, eps, W + eps, H + eps, 2)]
tip = [t for _, t in gmsh.model.getEntitiesInBoundingBox(L - eps, -eps, -eps, L + eps, W + eps, H + eps, 2)]
gmsh.model.addPhysicalGroup(3, vols, name="body")
gmsh.model.addPhysicalGroup(2, root, name="root")
gmsh.model.addPhysicalGroup(2, tip, name="tip")
gmsh.option.setNumber("Mesh.MeshSizeMin", h)
gmsh.option.setNumber("Mesh.MeshSizeMax", h)
gmsh.option.setNumber("Mesh.Algorithm3D", 10)  # HXT: parallel Delaunay
gmsh.option.setNumber("Mesh.ElementOrder", 2)
gmsh.option.setNumber("Mesh.SecondOrderLinear", 1)  # straight edges: mid-side nodes at mid-edge
gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
gmsh.option.setNumber("Mesh.Binary", 1)
gmsh.model.mesh.generate(3)
nodes, _, _ = gmsh.model.mesh.getNodes()
print(f"{len(nodes)} nodes, {3 * len(nodes)} nodal dofs")
gmsh.write(out)
gmsh.finalize()

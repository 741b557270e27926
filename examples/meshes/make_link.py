#!/usr/bin/env python3
"""Writes link_hex8.msh (gmsh MSH 4.1 ASCII): the coupler of examples/four_bar.toml, a bar of
0.30 m x 0.02 m x 0.01 m along x from the origin, nx x ny x nz hex8 bricks (gmsh node order),
with physical groups "link" (volume), "end0" (face x = 0) and "end1" (face x = 0.30).
gmsh is not needed: the structured mesh is written directly. Run: python3 make_link.py"""
import os

L, W, T = 0.30, 0.02, 0.01
nx, ny, nz = 15, 2, 1

def tag(i, j, k):
    return 1 + i + (nx + 1) * (j + (ny + 1) * k)

nodes = [(tag(i, j, k), i * L / nx, j * W / ny, k * T / nz)
         for k in range(nz + 1) for j in range(ny + 1) for i in range(nx + 1)]
hexes = []
for k in range(nz):
    for j in range(ny):
        for i in range(nx):
            # gmsh hex8: bottom face counter-clockwise, then top face.
            hexes.append([tag(i, j, k), tag(i + 1, j, k), tag(i + 1, j + 1, k), tag(i, j + 1, k),
                          tag(i, j, k + 1), tag(i + 1, j, k + 1), tag(i + 1, j + 1, k + 1), tag(i, j + 1, k + 1)])
def face(i):
    return [[tag(i, j, k), tag(i, j + 1, k), tag(i, j + 1, k + 1), tag(i, j, k + 1)]
            for k in range(nz) for j in range(ny)]
end0, end1 = face(0), face(nx)

out = ["$MeshFormat", "4.1 0 8", "$EndMeshFormat",
       "$PhysicalNames", "3", '2 2 "end0"', '2 3 "end1"', '3 1 "link"', "$EndPhysicalNames",
       "$Entities", "0 0 2 1",
       f"1 0 0 0 0 {W} {T} 1 2 0",
       f"2 {L} 0 0 {L} {W} {T} 1 3 0",
       f"1 0 0 0 {L} {W} {T} 1 1 0",
       "$EndEntities",
       "$Nodes", f"1 {len(nodes)} 1 {len(nodes)}", f"3 1 0 {len(nodes)}"]
out += [str(n[0]) for n in nodes]
out += [f"{x:.17g} {y:.17g} {z:.17g}" for _, x, y, z in nodes]
out += ["$EndNodes"]
n_el = len(hexes) + len(end0) + len(end1)
out += ["$Elements", f"3 {n_el} 1 {n_el}"]
e = 1
out.append(f"2 1 3 {len(end0)}")
for q in end0:
    out.append(" ".join(map(str, [e] + q))); e += 1
out.append(f"2 2 3 {len(end1)}")
for q in end1:
    out.append(" ".join(map(str, [e] + q))); e += 1
out.append(f"3 1 5 {len(hexes)}")
for h in hexes:
    out.append(" ".join(map(str, [e] + h))); e += 1
out += ["$EndElements", ""]
here = os.path.dirname(os.path.abspath(__file__))
with open(os.path.join(here, "link_hex8.msh"), "w") as f:
    f.write("\n".join(out))

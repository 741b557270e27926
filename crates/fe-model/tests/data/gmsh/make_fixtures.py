"""Generate the gmsh fixtures of `tests/unit/gmsh.rs`.

Run from this directory with the gmsh Python API (tested with gmsh 4.15.2 from PyPI):

    python3 -m venv /tmp/gmshvenv && /tmp/gmshvenv/bin/pip install gmsh
    /tmp/gmshvenv/bin/python make_fixtures.py

Every mesh is a box [0, 1] x [0, 0.2] x [0, 0.2] (a stubby cantilever along x) with the
physical groups

    3 "body"   the volume
    2 "clamp"  the face x = 0
    2 "tip"    the face x = 1

and, in the hex8 mesh only, a named physical point "tip_corner" at (1, 0.2, 0.2) and an
unnamed physical curve (tag 10) on the edge y = z = 0, to exercise dimension-0 and -1 groups
and the "physical_<dim>_<tag>" fallback name.

Each mesh is written as MSH 4.1 ASCII, MSH 4.1 binary, MSH 2.2 ASCII and MSH 2.2 binary:
`<name>_41.msh`, `<name>_41_bin.msh`, `<name>_22.msh`, `<name>_22_bin.msh`.

It also writes `gmsh_reference_elements.txt`: gmsh's own reference coordinates of the nodes
of each element type we read (from `gmsh.model.mesh.getElementProperties`), one line per
node, `type node u v w`. The Rust tests check their node-ordering tables against it, so
the tables are tied to gmsh's definition, not to our memory of its documentation.
"""

import gmsh

L, W, H = 1.0, 0.2, 0.2
FORMATS = [("41", 4.1, 0), ("41_bin", 4.1, 1), ("22", 2.2, 0), ("22_bin", 2.2, 1)]


def box(name, nx, ny, nz, recombine):
    """Transfinite box: hexes if `recombine`, else tets (gmsh splits each hex cell)."""
    gmsh.model.add(name)
    v = gmsh.model.occ.addBox(0, 0, 0, L, W, H)
    gmsh.model.occ.synchronize()
    for dim, tag in gmsh.model.getEntities(1):
        x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(dim, tag)
        n = nx if abs(x1 - x0) > 1e-6 else (ny if abs(y1 - y0) > 1e-6 else nz)
        gmsh.model.mesh.setTransfiniteCurve(tag, n + 1)
    for _, tag in gmsh.model.getEntities(2):
        gmsh.model.mesh.setTransfiniteSurface(tag)
        if recombine:
            gmsh.model.mesh.setRecombine(2, tag)
    gmsh.model.mesh.setTransfiniteVolume(v)
    if recombine:
        gmsh.model.mesh.setRecombine(3, v)
    return v


def face_at_x(x):
    for dim, tag in gmsh.model.getEntities(2):
        x0, _, _, x1, _, _ = gmsh.model.getBoundingBox(dim, tag)
        if abs(x0 - x) < 1e-6 and abs(x1 - x) < 1e-6:
            return tag
    raise RuntimeError(f"no face at x = {x}")


def groups(volume):
    gmsh.model.addPhysicalGroup(3, [volume], 1, name="body")
    gmsh.model.addPhysicalGroup(2, [face_at_x(0.0)], 2, name="clamp")
    gmsh.model.addPhysicalGroup(2, [face_at_x(L)], 3, name="tip")


def extra_groups():
    """A named physical point and an unnamed physical curve (hex8 mesh only)."""
    corner = [t for _, t in gmsh.model.getEntities(0)
              if max(abs(a - b) for a, b in zip(gmsh.model.getValue(0, t, []), [L, W, H]))
              < 1e-6]
    gmsh.model.addPhysicalGroup(0, corner, 4, name="tip_corner")
    edge = [t for d, t in gmsh.model.getEntities(1)
            if max(abs(c) for c in gmsh.model.getBoundingBox(d, t)[1:3] +
                   gmsh.model.getBoundingBox(d, t)[4:6]) < 1e-6]
    gmsh.model.addPhysicalGroup(1, edge, 10)  # no name: read as "physical_1_10"


def wedge(name, nx):
    """Triangulated face x = 0 extruded along x in `nx` layers: prisms (gmsh type 6)."""
    gmsh.model.add(name)
    p = [gmsh.model.geo.addPoint(0, y, z, 0.1) for y, z in [(0, 0), (W, 0), (W, H), (0, H)]]
    lines = [gmsh.model.geo.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]
    s = gmsh.model.geo.addPlaneSurface([gmsh.model.geo.addCurveLoop(lines)])
    out = gmsh.model.geo.extrude([(2, s)], L, 0, 0, numElements=[nx], recombine=True)
    gmsh.model.geo.synchronize()
    top = out[0][1]
    vol = out[1][1]
    gmsh.model.addPhysicalGroup(3, [vol], 1, name="body")
    gmsh.model.addPhysicalGroup(2, [s], 2, name="clamp")
    gmsh.model.addPhysicalGroup(2, [top], 3, name="tip")


def save(name):
    for suffix, version, binary in FORMATS:
        gmsh.option.setNumber("Mesh.MshFileVersion", version)
        gmsh.option.setNumber("Mesh.Binary", binary)
        gmsh.write(f"{name}_{suffix}.msh")


def main():
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)

    v = box("hex8", 4, 2, 2, recombine=True)
    groups(v)
    extra_groups()
    gmsh.model.mesh.generate(3)
    save("hex8")

    v = box("hex20", 4, 1, 1, recombine=True)
    groups(v)
    gmsh.model.mesh.generate(3)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 1)  # serendipity: 20 nodes, not 27
    gmsh.model.mesh.setOrder(2)
    save("hex20")

    v = box("tet4", 3, 1, 1, recombine=False)
    groups(v)
    gmsh.model.mesh.generate(3)
    save("tet4")

    v = box("tet10", 2, 1, 1, recombine=False)
    groups(v)
    gmsh.model.mesh.generate(3)
    gmsh.model.mesh.setOrder(2)
    save("tet10")

    wedge("wedge6", 3)
    gmsh.model.mesh.generate(3)
    save("wedge6")

    with open("gmsh_reference_elements.txt", "w") as f:
        f.write("# gmsh_type node u v w: gmsh's reference coordinates of each node "
                f"(gmsh {gmsh.__version__}, getElementProperties)\n")
        for t in [1, 2, 3, 4, 5, 6, 9, 11, 15, 16, 17]:
            _, dim, _, n, local, _ = gmsh.model.mesh.getElementProperties(t)
            for i in range(n):
                c = list(local[i * dim:(i + 1) * dim]) + [0.0] * (3 - dim)
                f.write(f"{t} {i} {c[0]:g} {c[1]:g} {c[2]:g}\n")
    gmsh.finalize()


if __name__ == "__main__":
    main()

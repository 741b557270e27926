"""Generate the Abaqus and Nastran fixtures of `tests/unit/import.rs` from the gmsh fixtures.

Run from this directory with meshio (tested with meshio 5.3.5 from PyPI):

    python3 -m venv /tmp/meshiovenv && /tmp/meshiovenv/bin/pip install meshio
    /tmp/meshiovenv/bin/python make_fixtures.py

Each mesh of `../gmsh/<name>_41.msh` (a box [0, 1] x [0, 0.2] x [0, 0.2]) is written as

* `<name>.inp` (Abaqus): meshio writes the nodes and elements, in Abaqus' node order; we add
  the node sets `clamp` (x = 0) and `tip` (x = 1), the element set `body` (GENERATE), the
  material `steel` and a `*SOLID SECTION`. meshio picks element formulations with reduced or
  hybrid integration (C3D8RH, C3D20RH, C3D10MH); the file gets the plain names (C3D8, C3D20,
  C3D10), the elements whose node orders are the same. `hex8.inp` takes its material from
  `materials.inc` through `*INCLUDE`.
* `<name>.bdf` (Nastran): meshio writes the elements in Nastran's node order (its CHEXA and
  CTETRA cards are parsed back here and rewritten with PID 1); GRIDs in large field with
  full precision; MAT1, PSOLID, an SPC1 (SID 1, components 123) on the clamp nodes, and an
  RBE2 (EID 2) from a new grid at the tip centre (1, 0.1, 0.1) to the tip nodes, in small field.
* `hex8_small.bdf` (every card small field; hex8's coordinates fit 8 columns exactly) and
  `tet10_free.bdf` (every card free field).

So the node orders of the Abaqus and Nastran files come from meshio, independently of the
reader's tables, and the Rust tests check that the same solid gives the same frequencies
from all three formats.
"""

import meshio

STEEL = (2.1e11, 0.3, 7850.0)
VOLUME_TYPES = ("tetra", "tetra10", "hexahedron", "hexahedron20", "wedge")
# meshio's Abaqus names -> the elements with the same node order and full integration.
ABAQUS_NAMES = {"C3D8RH": "C3D8", "C3D20RH": "C3D20", "C3D10MH": "C3D10"}


def volume_mesh(name):
    m = meshio.read(f"../gmsh/{name}_41.msh")
    return meshio.Mesh(m.points, [c for c in m.cells if c.type in VOLUME_TYPES])


def ids_at(points, x):
    return [i + 1 for i, p in enumerate(points) if abs(p[0] - x) < 1e-12]


def lines_of(ids, per_line=16):
    return [", ".join(str(i) for i in ids[k:k + per_line]) for k in range(0, len(ids), per_line)]


def write_abaqus(name, mesh):
    meshio.write(f"{name}.inp", mesh)
    with open(f"{name}.inp") as f:
        text = f.read()
    for meshio_name, plain in ABAQUS_NAMES.items():
        text = text.replace(f"TYPE={meshio_name}", f"TYPE={plain}")
    n_elements = sum(len(c.data) for c in mesh.cells)
    out = [text.rstrip("\n")]
    out.append("** Sets, material and section (make_fixtures.py)")
    for set_name, x in (("clamp", 0.0), ("tip", 1.0)):
        out.append(f"*NSET, NSET={set_name}")
        out.extend(lines_of(ids_at(mesh.points, x)))
    out.append("*ELSET, ELSET=body, GENERATE")
    out.append(f"1, {n_elements}, 1")
    material = ["*MATERIAL, NAME=steel", "*ELASTIC", f"{STEEL[0]!r}, {STEEL[1]!r}",
                "*DENSITY", f"{STEEL[2]!r}"]
    if name == "hex8":
        with open("materials.inc", "w") as f:
            f.write("** Included by hex8.inp\n" + "\n".join(material) + "\n")
        out.append("*INCLUDE, INPUT=materials.inc")
    else:
        out.extend(material)
    out.append("*SOLID SECTION, ELSET=body, MATERIAL=steel")
    out.append(",")
    with open(f"{name}.inp", "w") as f:
        f.write("\n".join(out) + "\n")


def meshio_element_cards(mesh):
    """(name, fields) of meshio's element cards: connectivity in Nastran's node order."""
    meshio.write("_tmp.bdf", mesh)
    cards = []
    with open("_tmp.bdf") as f:
        for line in f:
            line = line.rstrip("\n")
            if line.startswith("C"):
                name = line[:8].strip().rstrip("_")
                cards.append([name, [line[8 + 8 * k:16 + 8 * k].strip() for k in range(8)]])
            elif line.startswith("+") and cards:
                cards[-1][1] += [line[8 + 8 * k:16 + 8 * k].strip() for k in range(8)]
    import os
    os.remove("_tmp.bdf")
    out = []
    for name, fields in cards:
        while fields and fields[-1] == "":
            fields.pop()
        fields[1] = "1"  # PID (meshio leaves it blank)
        out.append((name, fields))
    return out


def short(v, width, exact=True):
    """The shortest text of v that reads back to the same double and fits `width`; with
    `exact=False`, the closest text that fits."""
    for digits in range(1, 18):
        s = nastran_text(v, digits)
        if parse(s) == v:
            break
    if not exact:
        while len(s) > width:
            digits -= 1
            s = nastran_text(v, digits)
    # Fixed fields round (hex8's 0.1 is 0.1000000000000001 in gmsh); the tests compare
    # frequencies to 1e-10, so a coordinate may move by 1e-12 of the box at most.
    assert len(s) <= width and abs(parse(s) - v) <= 1e-12, (v, s)
    return s


def parse(s):
    """Reads Nastran's shorthand back (2.1+11, -1.5-3)."""
    body = s.lstrip("-")
    for k in range(1, len(body)):
        if body[k] in "+-" and body[k - 1] != "e":
            return float(s[:len(s) - len(body) + k] + "e" + body[k:])
    return float(s)


def nastran_text(v, digits):
    s = f"{v:.{digits}g}"
    if "e" in s:
        mantissa, exponent = s.split("e")
        if "." not in mantissa:
            mantissa += "."
        s = mantissa + ("%+d" % int(exponent))  # Nastran shorthand: 2.1+11
    elif "." not in s:
        s += "."
    if s.startswith("0.") and len(s) > 2:
        s = s[1:]
    if s.startswith("-0.") and len(s) > 3:
        s = "-" + s[2:]
    return s


def small(name, fields):
    out, first = [], True
    for k in range(0, max(len(fields), 1), 8):
        head = name if first else "+"
        out.append(f"{head:<8}" + "".join(f"{f:<8}" for f in fields[k:k + 8]))
        first = False
    return "\n".join(line.rstrip() for line in out)


def large(name, fields):
    out = []
    for k in range(0, max(len(fields), 1), 4):
        head = name + "*" if k == 0 else "*"
        out.append(f"{head:<8}" + "".join(f"{f:>16}" for f in fields[k:k + 4]))
    return "\n".join(line.rstrip() for line in out)


def free(name, fields):
    out = []
    for k in range(0, max(len(fields), 1), 8):
        head = name if k == 0 else "+"
        out.append(",".join([head] + fields[k:k + 8]))
    return "\n".join(out)


def write_nastran(filename, mesh, grid_format, other_format):
    n = len(mesh.points)
    cards = ["$ Written by make_fixtures.py from the gmsh fixture (meshio's element cards)",
             "BEGIN BULK"]
    width = {"large": 16, "small": 8, "free": 24}[grid_format]
    emit_grid = {"large": large, "small": small, "free": free}[grid_format]
    emit = {"small": small, "free": free}[other_format]
    for i, p in enumerate(mesh.points):
        cards.append(emit_grid("GRID", [str(i + 1), ""] + [short(float(c), width, exact=False) for c in p]))
    for name, fields in meshio_element_cards(mesh):
        cards.append(emit(name, fields))
    cards.append(emit("MAT1", ["1", short(STEEL[0], 8), "", short(STEEL[1], 8), short(STEEL[2], 8)]))
    cards.append(emit("PSOLID", ["1", "1"]))
    cards.append(emit("SPC1", ["1", "123"] + [str(i) for i in ids_at(mesh.points, 0.0)]))
    cards.append(emit("GRID", [str(n + 1), "", "1.", ".1", ".1"]))
    cards.append(emit("RBE2", ["2", str(n + 1), "123456"] + [str(i) for i in ids_at(mesh.points, 1.0)]))
    cards.append(emit("EIGRL", ["10", "", "", "6"]))
    cards.append("ENDDATA")
    with open(filename, "w") as f:
        f.write("\n".join(cards) + "\n")


def main():
    for name in ["hex8", "hex20", "tet4", "tet10", "wedge6"]:
        mesh = volume_mesh(name)
        write_abaqus(name, mesh)
        write_nastran(f"{name}.bdf", mesh, "large", "small")
    write_nastran("hex8_small.bdf", volume_mesh("hex8"), "small", "small")
    write_nastran("tet10_free.bdf", volume_mesh("tet10"), "free", "free")


if __name__ == "__main__":
    main()

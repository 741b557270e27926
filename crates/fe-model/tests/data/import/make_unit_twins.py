"""Write the mm-t-s twins and the relabelled copy of the hex20 fixtures (no dependencies).

Run from this directory: `python3 make_unit_twins.py`.

* `hex20_mm.inp`, `hex20_mm.bdf`: `hex20.inp` and `hex20.bdf` in mm-t-s units (mm, t, s:
  N, MPa, t/mm^3): every coordinate times 1000, E in MPa (divided by 1e6), the density in
  t/mm^3 (divided by 1e12). Read with `units = "mm-t-s"` they are the SI model again.
* `hex20_labels.inp`: `hex20.inp` with non-contiguous node and element numbers (node n is
  100 n + n % 7, element e is 10 e + 3), for the labels shown in messages and outputs.
"""

import re


def scale_inp(text):
    out, block = [], None
    for line in text.splitlines():
        if line.startswith("*"):
            block = line.split(",")[0].strip().upper()
            out.append(line)
            continue
        if line.startswith("**") or not line.strip():
            out.append(line)
            continue
        if block == "*NODE":
            f = [x.strip() for x in line.split(",")]
            out.append(", ".join([f[0]] + [repr(float(x) * 1000.0) for x in f[1:]]))
        elif block == "*ELASTIC":
            E, nu = [float(x) for x in line.split(",")]
            out.append(f"{E / 1e6!r}, {nu!r}")
        elif block == "*DENSITY":
            out.append(repr(float(line) / 1e12))
        else:
            out.append(line)
    return "\n".join(out) + "\n"


def nastran_real(field):
    """Nastran's shorthand (`7.85+3`, `.2`) as a float."""
    m = re.fullmatch(r"([+-]?[0-9.]+)([+-][0-9]+)?", field.strip())
    return float(m.group(1)) * 10.0 ** int(m.group(2) or 0)


def scale_bdf(text):
    lines = text.splitlines()
    out, k = [], 0
    while k < len(lines):
        line = lines[k]
        if line.startswith("GRID*"):
            fields = [line[8 + 16 * i : 24 + 16 * i].strip() for i in range(4)]
            x3 = lines[k + 1][8:24].strip()
            x = [nastran_real(v) * 1000.0 for v in (fields[2], fields[3], x3)]
            out.append(f"GRID,{fields[0]},,{x[0]!r},{x[1]!r},{x[2]!r}")
            k += 2
            continue
        if line.startswith("GRID "):
            fields = [line[8 + 8 * i : 16 + 8 * i].strip() for i in range(5)]
            x = [nastran_real(v) * 1000.0 for v in fields[2:5]]
            out.append(f"GRID,{fields[0]},,{x[0]!r},{x[1]!r},{x[2]!r}")
        elif line.startswith("MAT1"):
            fields = [line[8 + 8 * i : 16 + 8 * i].strip() for i in range(5)]
            E, nu, rho = nastran_real(fields[1]), nastran_real(fields[3]), nastran_real(fields[4])
            out.append(f"MAT1,{fields[0]},{E / 1e6!r},,{nu!r},{rho / 1e12!r}")
        elif line.startswith("$ Written"):
            out.append("$ hex20.bdf in mm-t-s units (make_unit_twins.py)")
        else:
            out.append(line)
        k += 1
    return "\n".join(out) + "\n"


def relabel_inp(text):
    node = lambda n: 100 * n + n % 7
    element = lambda e: 10 * e + 3
    out, block = [], None
    for line in text.splitlines():
        if line.startswith("*") and not line.startswith("**"):
            block = line.split(",")[0].strip().upper()
            if block == "*ELSET":
                line = "*ELSET, ELSET=body"
            out.append(line)
            continue
        if line.startswith("**") or not line.strip():
            out.append(line)
            continue
        f = [x.strip() for x in line.split(",")]
        if block == "*NODE":
            out.append(", ".join([str(node(int(f[0])))] + f[1:]))
        elif block == "*ELEMENT":
            out.append(",".join([str(element(int(f[0])))] + [str(node(int(x))) for x in f[1:]]))
        elif block == "*NSET":
            out.append(", ".join(str(node(int(x))) for x in f if x))
        elif block == "*ELSET":
            # The GENERATE line 1, 4, 1 as the element labels.
            out.append(", ".join(str(element(e)) for e in range(int(f[0]), int(f[1]) + 1, int(f[2]))))
        else:
            out.append(line)
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    inp = open("hex20.inp").read()
    open("hex20_mm.inp", "w").write(scale_inp(inp))
    open("hex20_mm.bdf", "w").write(scale_bdf(open("hex20.bdf").read()))
    open("hex20_labels.inp", "w").write(relabel_inp(inp))

"""Writes the large-field twin of a small-field Nastran deck, as pre-processors write it:
every card `NAME*`, four 16-column fields a line, a continuation marker `*N<k>` in columns
73-80 and the same marker in columns 1-8 of the continuation line. The field texts are
kept, so the twin holds the same numbers.

    python3 to_large_field.py hex8_small.bdf hex8_large.bdf
"""
import sys


def cards(lines):
    """(name, data fields) of each small-field card; other lines as (None, line)."""
    out = []
    for line in lines:
        if line.startswith("$") or line.strip() in ("BEGIN BULK", "ENDDATA"):
            out.append((None, line))
            continue
        head = line[:8].strip()
        fields = [line[8 + 8 * i:16 + 8 * i].strip() for i in range(8)]
        if head.startswith("+") or head == "":
            out[-1][1].extend(fields)
        else:
            out.append((head, fields))
    return out


def large(name, fields, counter):
    while fields and fields[-1] == "":
        fields.pop()
    rows = [fields[i:i + 4] for i in range(0, max(len(fields), 1), 4)]
    text = []
    for r, row in enumerate(rows):
        head = f"{name}*" if r == 0 else marker
        line = f"{head:<8}" + "".join(f"{f:>16}" for f in row)
        if r + 1 < len(rows):
            counter[0] += 1
            marker = f"*N{counter[0]}"
            line = f"{line:<72}{marker}"
        text.append(line.rstrip())
    return text


def main(src, dst):
    counter = [0]
    out = []
    for name, fields in cards(open(src).read().splitlines()):
        if name is None:
            out.append(fields if not fields.startswith("$") else f"$ Large-field twin of {src}, written by to_large_field.py")
        else:
            out.extend(large(name, fields, counter))
    with open(dst, "w") as f:
        f.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])

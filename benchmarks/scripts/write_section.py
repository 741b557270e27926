#!/usr/bin/env python3
"""Writes a generated table into BENCHMARKS.md (the benchmark scripts write their tables
there, with the machine and the commands).

    python3 benchmarks/scripts/write_section.py NAME FILE [BENCHMARKS.md]

Replaces the lines between `<!-- BEGIN generated: NAME -->` and `<!-- END generated: NAME -->`
with the contents of FILE, up to FILE's hand-written part (the line starting with
`<!-- written by hand below`), each heading demoted by two levels so that it nests under
BENCHMARKS.md's sections (lines in fenced code blocks, such as shell comments, are kept). Fails, naming the marker, when the markers are missing.
"""
import sys


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    name, source = sys.argv[1], sys.argv[2]
    target = sys.argv[3] if len(sys.argv) == 4 else "BENCHMARKS.md"
    begin, end = f"<!-- BEGIN generated: {name} -->", f"<!-- END generated: {name} -->"
    text = open(target).read()
    if begin not in text or end not in text or text.index(begin) > text.index(end):
        sys.exit(f"{target}: no '{begin}' ... '{end}' block to write the {name} table into")
    body = []
    fenced = False
    for line in open(source):
        if line.startswith("<!-- written by hand below"):
            break
        if line.startswith("```"):
            fenced = not fenced
        body.append("##" + line if line.startswith("#") and not fenced else line)
    head, rest = text.split(begin, 1)
    tail = rest.split(end, 1)[1]
    generated = "".join(body).strip("\n")
    open(target, "w").write(f"{head}{begin}\n{generated}\n{end}{tail}")
    print(f"{target}: wrote the {name} table from {source}")


if __name__ == "__main__":
    main()

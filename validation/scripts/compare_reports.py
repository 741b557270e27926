#!/usr/bin/env python3
"""Compare two validation reports (REPORT.md) row by row.

    python3 validation/scripts/compare_reports.py BEFORE/REPORT.md AFTER/REPORT.md [--tol 1e-9]

Run both versions with `--full-precision` (`cargo run --release -p validation --
--full-precision --report-dir DIR`) so the tables carry 17 significant digits; the script
also works on the default 7-digit reports, then differences below about 1e-7 are invisible.

Tables with tolerances are matched by section title and quantity; reference, flexmbs value,
relative error and pass/fail are compared. Convergence and comparison grids are matched by
section title and row label, cell by cell; wall-clock columns (us/step, build [s], ...) are
skipped. For every shared row the script prints the largest relative difference
|a - b| / max(|a|, |b|) of its numbers; rows and sections found in one report only are listed
as new or removed. Exit status 1 when a shared row differs by more than --tol or changes its
pass/fail or its text, 0 otherwise.
"""

import argparse
import re
import sys

TABLE_HEADER = ["quantity", "reference", "flexmbs", "rel. error", "tolerance"]
# Grid columns that are wall-clock timings: machine load, not results.
TIMING = re.compile(r"us/|µs|\[s\]|wall|cpu|seconds", re.IGNORECASE)
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def cells(line):
    """The cells of a Markdown table row. Quantities may hold '|' (|w - w_exact|), so a
    row is split on ' | ' and trimmed of its outer bars."""
    inner = line.strip()
    if inner.startswith("| "):
        inner = inner[2:]
    if inner.endswith(" |"):
        inner = inner[:-2]
    return [c.strip() for c in inner.split(" | ")]


def parse(path):
    """{section title: (kind, header, [(label, cells)])} with kind 'table' or 'grid'."""
    sections = {}
    title, header, kind, rows = None, None, None, None
    with open(path, encoding="utf-8") as f:
        lines = f.read().splitlines()
    for i, line in enumerate(lines):
        if line.startswith("### "):
            title, header = line[4:].strip(), None
            continue
        if title is None or not line.startswith("|"):
            continue
        if line.startswith("|---"):
            continue
        nxt = lines[i + 1] if i + 1 < len(lines) else ""
        if header is None and nxt.startswith("|---"):
            header = cells(line)
            kind = "table" if header == TABLE_HEADER else "grid"
            rows = []
            key, n = title, 2
            while key in sections:  # a title used twice keeps both sections
                key, n = f"{title} #{n}", n + 1
            sections[key] = (kind, header, rows)
            continue
        if header is None:
            continue
        c = cells(line)
        if kind == "table" and len(c) > len(TABLE_HEADER):
            # A quantity holding ' | ': the last four cells are the numbers.
            c = [" | ".join(c[: len(c) - 4])] + c[-4:]
        rows.append(c)
    # Row labels: a table's quantity; a grid's leading non-numeric cells (or its first
    # cell), with an occurrence count for repeated labels.
    out = {}
    for key, (kind, header, rows) in sections.items():
        labelled, seen = {}, {}
        for c in rows:
            if kind == "table":
                label = c[0]
            else:
                lead = [c[0]]
                for x in c[1:]:
                    if NUMBER.fullmatch(x):
                        break
                    lead.append(x)
                    if len(lead) == 2:
                        break
                label = " | ".join(lead)
            seen[label] = seen.get(label, 0) + 1
            if seen[label] > 1:
                label = f"{label} #{seen[label]}"
            labelled[label] = c
        out[key] = (kind, header, labelled)
    return out


def rel(a, b):
    if a == b:
        return 0.0
    return abs(a - b) / max(abs(a), abs(b))


def numbers(cell):
    return [float(x) for x in NUMBER.findall(cell)]


def compare_row(kind, header, a, b):
    """(largest relative difference, the column it is in, list of textual changes)."""
    worst, where, changes = 0.0, "", []
    if kind == "table":
        for j, name in ((1, "reference"), (2, "flexmbs"), (3, "rel. error")):
            x, y = float(a[j]), float(b[j])
            if rel(x, y) > worst:
                worst, where = rel(x, y), f"{name}: {a[j]} -> {b[j]}"
        fa, fb = "FAIL" in a[4], "FAIL" in b[4]
        if fa != fb:
            changes.append(f"pass/fail {'FAIL' if fa else 'pass'} -> {'FAIL' if fb else 'pass'}")
        if a[4].replace("**FAIL**", "").strip() != b[4].replace("**FAIL**", "").strip():
            changes.append(f"tolerance {a[4]} -> {b[4]}")
        return worst, where, changes
    for j, (x, y) in enumerate(zip(a, b)):
        col = header[j] if j < len(header) else str(j)
        if TIMING.search(col):
            continue
        nx, ny = numbers(x), numbers(y)
        if len(nx) != len(ny) or re.sub(NUMBER, "#", x) != re.sub(NUMBER, "#", y):
            if x != y:
                changes.append(f"{col}: '{x}' -> '{y}'")
            continue
        for u, v in zip(nx, ny):
            if rel(u, v) > worst:
                worst, where = rel(u, v), f"{col}: {x} -> {y}"
    if len(a) != len(b):
        changes.append(f"{len(a)} cells -> {len(b)} cells")
    return worst, where, changes


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("--tol", type=float, default=1e-9, help="relative difference reported as a change")
    ap.add_argument("--all", action="store_true", help="print every shared row, not only the changed ones")
    args = ap.parse_args()
    before, after = parse(args.before), parse(args.after)

    shared_rows = changed = 0
    worst = (0.0, "")
    for title, (kind, header, rows_a) in before.items():
        if title not in after:
            print(f"removed section: {title}")
            continue
        kind_b, header_b, rows_b = after[title]
        if kind != kind_b or [h for h in header if not TIMING.search(h)] != [
            h for h in header_b if not TIMING.search(h)
        ]:
            print(f"changed columns: {title}: {header} -> {header_b}")
            continue
        for label, a in rows_a.items():
            if label not in rows_b:
                print(f"removed row: {title}: {label}")
                continue
            shared_rows += 1
            d, where, changes = compare_row(kind, header, a, rows_b[label])
            if d > worst[0]:
                worst = (d, f"{title}: {label}")
            if d > args.tol or changes:
                changed += 1
            if args.all or d > args.tol or changes:
                extra = f"  ({'; '.join(changes)})" if changes else ""
                at = f"  [{where}]" if d > 0 else ""
                print(f"{d:9.2e}  {title}: {label}{at}{extra}")
        for label in rows_b:
            if label not in rows_a:
                print(f"new row: {title}: {label}")
    for title in after:
        if title not in before:
            print(f"new section: {title} ({len(after[title][2])} rows)")
    print(
        f"{shared_rows} shared rows in {sum(t in after for t in before)} shared sections; "
        f"{changed} above {args.tol:.0e} or changed in text; "
        f"largest relative difference {worst[0]:.2e}" + (f" ({worst[1]})" if worst[1] else "")
    )
    return 1 if changed else 0


if __name__ == "__main__":
    sys.exit(main())

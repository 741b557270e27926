#!/usr/bin/env python3
"""Compare the CSV files of two results folders cell by cell.

    python3 validation/scripts/compare_results.py BEFORE-results AFTER-results [--tol 1e-9]

For two runs of the same study by two versions of flexmbs (`flexmbs run study.toml --out DIR`
with each version's program), every CSV file below the first folder is matched by its
relative path in the second; headers must agree, and every numeric cell is compared two ways:
relative to itself, |a - b| / max(|a|, |b|, floor) (`floor`, --floor, default 1e-12 times the
column's largest magnitude, keeps round-off zeros from counting as large changes), and
relative to its column, |a - b| / max |column| (the measure for a signal that passes through
zero, such as a deflection or a torque). Prints one line per file (rows, cells, both largest
differences) and the files found in one folder only. Exit status 1 when a file differs by
more than --tol relative to its column, its header or its row count changed, or a file is
missing from the second folder.
"""

import argparse
import csv
import os
import sys


def read(path):
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    return (rows[0], rows[1:]) if rows else ([], [])


def number(cell):
    try:
        return float(cell)
    except ValueError:
        return None


def csv_files(root):
    out = set()
    for dirpath, _, files in os.walk(root):
        for name in files:
            if name.endswith(".csv"):
                out.add(os.path.relpath(os.path.join(dirpath, name), root))
    return out


def compare(a_path, b_path, floor):
    """(rows, numeric cells, largest relative difference, where, problems)."""
    ha, ra = read(a_path)
    hb, rb = read(b_path)
    problems = []
    if ha != hb:
        problems.append(f"header {ha} -> {hb}")
    if len(ra) != len(rb):
        problems.append(f"{len(ra)} rows -> {len(rb)} rows")
    # Per column: the largest magnitude, for the floor of the relative difference.
    scale = {}
    for row in ra:
        for j, c in enumerate(row):
            x = number(c)
            if x is not None:
                scale[j] = max(scale.get(j, 0.0), abs(x))
    cells, worst, where, worst_col = 0, 0.0, "", 0.0
    for i, (x_row, y_row) in enumerate(zip(ra, rb)):
        for j, (x, y) in enumerate(zip(x_row, y_row)):
            u, v = number(x), number(y)
            if u is None or v is None:
                if x != y:
                    problems.append(f"row {i + 1} column {j + 1}: '{x}' -> '{y}'")
                continue
            cells += 1
            if u == v:
                continue
            d = abs(u - v) / max(abs(u), abs(v), floor * scale.get(j, 0.0), 1e-300)
            worst_col = max(worst_col, abs(u - v) / max(scale.get(j, 0.0), abs(v), 1e-300))
            if d > worst:
                col = ha[j] if j < len(ha) else str(j + 1)
                worst, where = d, f"row {i + 1}, {col}: {x} -> {y}"
    return len(ra), cells, (worst, worst_col), where, problems


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("--tol", type=float, default=1e-9)
    ap.add_argument("--floor", type=float, default=1e-12, help="relative to the column's largest value")
    args = ap.parse_args()
    a, b = csv_files(args.before), csv_files(args.after)
    failed = False
    total_cells, total_worst, total_col = 0, (0.0, ""), (0.0, "")
    for rel in sorted(a):
        if rel not in b:
            print(f"missing in {args.after}: {rel}")
            failed = True
            continue
        rows, cells, worst, where, problems = compare(
            os.path.join(args.before, rel), os.path.join(args.after, rel), args.floor
        )
        (worst, worst_col) = worst
        total_cells += cells
        if worst > total_worst[0]:
            total_worst = (worst, f"{rel} {where}")
        if worst_col > total_col[0]:
            total_col = (worst_col, rel)
        flag = worst_col > args.tol or problems
        failed |= bool(flag)
        print(f"{'DIFF ' if flag else ''}{rel}: {rows} rows, {cells} cells, largest {worst:.2e}"
              + f" (of the column's largest: {worst_col:.2e})"
              + (f" at {where}" if worst > args.tol else "")
              + (f"; {'; '.join(problems[:3])}" if problems else ""))
    for rel in sorted(b - a):
        print(f"new in {args.after}: {rel}")
    print(f"{len(a & b)} files, {total_cells} numeric cells; largest relative difference "
          f"{total_worst[0]:.2e}" + (f" ({total_worst[1]})" if total_worst[1] else "")
          + f"; of its column's largest value {total_col[0]:.2e}" + (f" ({total_col[1]})" if total_col[1] else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

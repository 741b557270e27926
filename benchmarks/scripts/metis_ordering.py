"""METIS nested-dissection orderings of the K_ii patterns written by the ordering bench.

Usage: python metis_ordering.py DIR SIZE[,SIZE...]

Reads DIR/graph_<size>.bin (written by `REDUCTION_ORDERING_EXPORT=DIR cargo bench -p reduction
--bench ordering`: n as u64, n + 1 row pointers as u64, column indices as u32, the adjacency of
K_ii without its diagonal), orders it with METIS_NodeND (pymetis, METIS's default options:
graph compression, multilevel bisection with FM separator refinement, minimum-degree leaves)
and writes DIR/perm_<size>.bin (perm[k] = row eliminated k-th, u64), which
`REDUCTION_ORDERING_IMPORT=DIR` makes the bench analyse with the same symbolic Cholesky as ours.
"""

import sys
import time

import numpy as np
import pymetis


def main():
    directory, sizes = sys.argv[1], sys.argv[2].split(",")
    for size in sizes:
        raw = open(f"{directory}/graph_{size}.bin", "rb").read()
        n = int(np.frombuffer(raw, dtype="<u8", count=1)[0])
        xadj = np.frombuffer(raw, dtype="<u8", count=n + 1, offset=8).astype(np.int32)
        adjncy = np.frombuffer(raw, dtype="<u4", offset=8 * (n + 2)).astype(np.int32)
        t = time.process_time()
        perm, iperm = pymetis.nested_dissection(pymetis.CSRAdjacency(xadj, adjncy))
        seconds = time.process_time() - t
        perm = np.asarray(perm, dtype="<u8")
        assert sorted(perm.tolist()) == list(range(n))
        perm.tofile(f"{directory}/perm_{size}.bin")
        print(f"{size}: METIS_NodeND on {n} rows, {len(adjncy)} off-diagonal entries: {seconds:.2f} s CPU")


if __name__ == "__main__":
    main()

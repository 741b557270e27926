#!/usr/bin/env python3
"""scipy reference for `benches/eigen.rs`: eigsh(K, M=M, sigma=0, k=20) on the same matrices.

Usage (benchmarks/scripts/reduction_vs_scipy.sh runs it on the Craig-Bampton blocks' K_ii, M_ii):
    REDUCTION_BENCH_MTX_DIR=/tmp/eigmtx cargo bench -p reduction --bench eigen   # writes the .mtx
    python3 crates/reduction/benches/scipy_eigsh.py /tmp/eigmtx [n ...]

For every K_<n>.mtx / M_<n>.mtx pair in the folder (or the sizes given), times scipy's
ARPACK shift-invert mode (sigma = 0, which='LM', the default tolerance 0 = machine
precision), whose factorisation of K - sigma M is SuperLU via scipy.sparse.linalg.splu.
Prints the wall and CPU time of the eigsh call, the peak RSS of this process (resource.getrusage,
ru_maxrss is in kB on Linux), and, if eigenvalues_<n>.txt from the Rust bench is present,
the largest relative difference between the two sets of eigenvalues.

Needs numpy and scipy (e.g. `python3 -m venv /tmp/venv && /tmp/venv/bin/pip install scipy`).
"""

import glob
import os
import re
import resource
import sys
import time

import numpy as np
import scipy
import scipy.io
import scipy.sparse
import scipy.sparse.linalg

K_MODES = 20


def peak_rss_mb():
    # ru_maxrss: kilobytes on Linux, bytes on macOS.
    r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return r / 1024.0 if sys.platform != "darwin" else r / 1024.0**2


def cpu_seconds():
    # User + system time of this process: on a shared machine, less noisy than wall time.
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def run(folder, n):
    t = time.perf_counter()
    K = scipy.sparse.csc_matrix(scipy.io.mmread(os.path.join(folder, f"K_{n}.mtx")))
    M = scipy.sparse.csc_matrix(scipy.io.mmread(os.path.join(folder, f"M_{n}.mtx")))
    t_read = time.perf_counter() - t
    rss_before = peak_rss_mb()
    cpu = cpu_seconds()
    t = time.perf_counter()
    w, v = scipy.sparse.linalg.eigsh(K, k=K_MODES, M=M, sigma=0.0, which="LM")
    t_eig = time.perf_counter() - t
    cpu = cpu_seconds() - cpu
    order = np.argsort(w)
    w = w[order]
    v = v[:, order]
    res = [
        np.linalg.norm(K @ v[:, j] - w[j] * (M @ v[:, j])) / np.linalg.norm(K @ v[:, j])
        for j in range(K_MODES)
    ]
    print(f"== n = {n}, nnz(K) = {K.nnz} (read {t_read:.1f} s)")
    print(f"scipy {scipy.__version__}, numpy {np.__version__}")
    print(f"eigsh(K, M=M, sigma=0, k={K_MODES}) incl. SuperLU factorisation: {t_eig * 1e3:10.0f} ms "
          f"(CPU user+sys {cpu * 1e3:.0f} ms)")
    print(f"peak RSS (ru_maxrss, whole process): {peak_rss_mb():10.0f} MB (after reading the matrices: {rss_before:.0f} MB)")
    print(f"worst relative residual: {max(res):.2e}")
    print("frequencies (Hz):", " ".join(f"{np.sqrt(max(x, 0.0)) / (2 * np.pi):.2f}" for x in w))
    ours = os.path.join(folder, f"eigenvalues_{n}.txt")
    rel = float("nan")
    if os.path.exists(ours):
        w_ours = np.loadtxt(ours)
        rel = np.max(np.abs(w_ours - w) / np.abs(w))
        print(f"largest relative difference to reduction's eigenvalues: {rel:.2e}")
    # One machine-readable line for benchmarks/scripts/reduction_vs_scipy.sh.
    print(f"RESULT size={n} n={K.shape[0]} eigsh_s={t_eig:.3f} eigsh_cpu_s={cpu:.3f} peak_mb={peak_rss_mb():.0f} "
          f"worst_residual={max(res):.3e} difference={rel:.3e}")


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        sys.exit(2)
    folder = sys.argv[1]
    sizes = sys.argv[2:]
    if not sizes:
        # Names as written by the benches: K_<dofs>.mtx (eigen) or K_<size>.mtx (craig_bampton,
        # e.g. K_50k.mtx); smallest file first.
        paths = sorted(glob.glob(os.path.join(folder, "K_*.mtx")), key=os.path.getsize)
        sizes = [re.match(r"K_(\w+)\.mtx", os.path.basename(p)).group(1) for p in paths]
    for n in sizes:
        run(folder, n)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""scipy reference for `benches/eigen.rs`: eigsh(K, M=M, sigma=0, k=20) on the same matrices.

Usage (benchmarks/scripts/reduction_vs_scipy.sh runs it on the Craig-Bampton blocks' K_ii, M_ii,
benchmarks/compare_all.sh with `--solver pardiso`):
    REDUCTION_BENCH_MTX_DIR=/tmp/eigmtx cargo bench -p reduction --bench eigen   # writes the .mtx
    python3 crates/reduction/benches/scipy_eigsh.py [--solver superlu|pardiso] [--tol TOL] /tmp/eigmtx [n ...]

For every K_<n>.mtx / M_<n>.mtx pair in the folder (or the sizes given), times scipy's
ARPACK shift-invert mode (sigma = 0, which='LM', tolerance `--tol`, default 0 = machine
precision). With `--solver superlu` (the default) the factorisation of K - sigma M is SuperLU
via scipy.sparse.linalg.splu. With `--solver pardiso` it is MKL PARDISO through the `pypardiso`
package: the Cholesky factorisation of the upper triangle of K (matrix type 2, symmetric
positive definite; MKL's default METIS nested-dissection ordering), passed to eigsh as `OPinv`
whose solves reuse the factor (phase 33); the factorisation alone is timed too (`factor_s`), and
then, after that factor is freed, pypardiso's default LU factorisation of the whole K (matrix
type 11, `factor_lu_s`).
Prints the wall and CPU time of the eigsh call (factorisation included), the peak RSS of this
process after it (resource.getrusage, ru_maxrss is in kB on Linux), and, if
eigenvalues_<n>.txt from the Rust bench is present, the largest relative difference between
the two sets of eigenvalues. The matrices read are cached beside the .mtx files as .npz, so
that repeated runs do not parse the text again (the reading is not timed).

Needs numpy and scipy (e.g. `python3 -m venv /tmp/venv && /tmp/venv/bin/pip install scipy`),
and pypardiso for `--solver pardiso`.
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


def peak_rss_mib():
    # ru_maxrss: kilobytes on Linux, bytes on macOS.
    r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return r / 1024.0 if sys.platform != "darwin" else r / 1024.0**2


def cpu_seconds():
    # User + system time of this process: on a shared machine, less noisy than wall time.
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def read(folder, name):
    """A Matrix Market file as CSC, through an .npz cache beside it."""
    cache = os.path.join(folder, f"{name}.npz")
    if os.path.exists(cache):
        return scipy.sparse.load_npz(cache).tocsc()
    A = scipy.sparse.csc_matrix(scipy.io.mmread(os.path.join(folder, f"{name}.mtx")))
    scipy.sparse.save_npz(cache, A, compressed=False)
    return A


def pardiso_eigsh(K, M, tol):
    """eigsh with MKL PARDISO's Cholesky factor of K as the shift-invert operator (sigma = 0).
    Returns the eigenpairs and the factorisation's wall time."""
    import pypardiso

    upper = scipy.sparse.triu(K, format="csr")
    upper.sort_indices()
    solver = pypardiso.PyPardisoSolver(mtype=2)
    t = time.perf_counter()
    solver.factorize(upper)
    t_factor = time.perf_counter() - t
    solver.set_phase(33)

    def solve(x):
        # Phase 33 straight to PARDISO: pypardiso's solve() would hash the matrix at every call
        # to check that it is the factorised one.
        return solver._call_pardiso(upper, np.asfortranarray(x, dtype=np.float64))

    op = scipy.sparse.linalg.LinearOperator(K.shape, matvec=solve, matmat=solve, dtype=np.float64)
    w, v = scipy.sparse.linalg.eigsh(K, k=K_MODES, M=M, sigma=0.0, which="LM", OPinv=op, tol=tol)
    solver.free_memory(everything=True)
    return w, v, t_factor


def pardiso_lu_seconds(K):
    """Wall time of pypardiso's default factorisation (LU of the whole matrix, matrix type 11)."""
    import pypardiso

    A = K.tocsr()
    A.sort_indices()
    solver = pypardiso.PyPardisoSolver()
    t = time.perf_counter()
    solver.factorize(A)
    t = time.perf_counter() - t
    solver.free_memory(everything=True)
    return t


def run(folder, n, solver="superlu", tol=0.0):
    t = time.perf_counter()
    K = read(folder, f"K_{n}")
    M = read(folder, f"M_{n}")
    t_read = time.perf_counter() - t
    rss_before = peak_rss_mib()
    cpu = cpu_seconds()
    t = time.perf_counter()
    t_factor = float("nan")
    if solver == "pardiso":
        w, v, t_factor = pardiso_eigsh(K, M, tol)
    else:
        w, v = scipy.sparse.linalg.eigsh(K, k=K_MODES, M=M, sigma=0.0, which="LM", tol=tol)
    t_eig = time.perf_counter() - t
    cpu = cpu_seconds() - cpu
    peak = peak_rss_mib()
    order = np.argsort(w)
    w = w[order]
    v = v[:, order]
    res = [
        np.linalg.norm(K @ v[:, j] - w[j] * (M @ v[:, j])) / np.linalg.norm(K @ v[:, j])
        for j in range(K_MODES)
    ]
    print(f"== n = {n}, nnz(K) = {K.nnz} (read {t_read:.1f} s)")
    print(f"scipy {scipy.__version__}, numpy {np.__version__}")
    what = "PARDISO Cholesky" if solver == "pardiso" else "SuperLU"
    print(f"eigsh(K, M=M, sigma=0, k={K_MODES}, tol={tol:g}) incl. {what} factorisation: {t_eig * 1e3:10.0f} ms "
          f"(CPU user+sys {cpu * 1e3:.0f} ms)")
    print(f"peak RSS (ru_maxrss, whole process): {peak:10.0f} MiB (after reading the matrices: {rss_before:.0f} MiB)")
    t_lu = float("nan")
    if solver == "pardiso":
        t_lu = pardiso_lu_seconds(K)
        print(f"PARDISO factorisation alone: Cholesky of triu(K) {t_factor * 1e3:.0f} ms, pypardiso's default LU of K {t_lu * 1e3:.0f} ms")
    print(f"worst relative residual: {max(res):.2e}")
    print("frequencies (Hz):", " ".join(f"{np.sqrt(max(x, 0.0)) / (2 * np.pi):.2f}" for x in w))
    ours = os.path.join(folder, f"eigenvalues_{n}.txt")
    rel = float("nan")
    if os.path.exists(ours):
        w_ours = np.loadtxt(ours)
        rel = np.max(np.abs(w_ours - w) / np.abs(w))
        print(f"largest relative difference to reduction's eigenvalues: {rel:.2e}")
    # One machine-readable line for benchmarks/scripts/reduction_vs_scipy.sh.
    print(f"RESULT size={n} n={K.shape[0]} solver={solver} eigsh_s={t_eig:.3f} eigsh_cpu_s={cpu:.3f} peak_mib={peak:.0f} "
          f"worst_residual={max(res):.3e} difference={rel:.3e} factor_s={t_factor:.3f} factor_lu_s={t_lu:.3f}")


def main():
    args = sys.argv[1:]
    solver, tol = "superlu", 0.0
    while args and args[0].startswith("--"):
        if len(args) < 2:
            sys.exit(f"{args[0]}: needs a value\n{__doc__}")
        if args[0] == "--solver" and args[1] in ("superlu", "pardiso"):
            solver = args[1]
        elif args[0] == "--tol":
            tol = float(args[1])
        else:
            sys.exit(f"unknown option {args[0]} {args[1]}\n{__doc__}")
        args = args[2:]
    if not args:
        print(__doc__)
        sys.exit(2)
    folder = args[0]
    sizes = args[1:]
    if not sizes:
        # Names as written by the benches: K_<dofs>.mtx (eigen) or K_<size>.mtx (craig_bampton,
        # e.g. K_50k.mtx); smallest file first.
        paths = sorted(glob.glob(os.path.join(folder, "K_*.mtx")), key=os.path.getsize)
        sizes = [re.match(r"K_(\w+)\.mtx", os.path.basename(p)).group(1) for p in paths]
    for n in sizes:
        run(folder, n, solver, tol)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""How the axial force along the slider-crank rod (validation problem C2) changes its bending,
independently of flexmbs: the rod as a quasi-static pinned-pinned Euler-Bernoulli beam under the
inertia of its rigid-body motion, EI w'''' - (N w')' = q, solved by a sine-series Galerkin
method (pure Python, no dependencies).

The rigid rod's acceleration is linear along it, so its transverse load q(x) is linear and its
axial force N(x) is quadratic (the slider, half the rod's mass, pulls at one end). The script
compares the extrema of the midpoint deflection over one crank revolution for N(x) exact,
uniform (its mean: what the interface coordinates of one superelement carry), and the mean plus
the first K cosine terms: what K axial fixed-interface modes (strains cos(k pi x/L)) give a
Craig-Bampton body whose axial force follows from its own inertia (the L2 projection of N).
Geometric stiffening makes the bending feel N weighted by w'^2, largest at the pinned ends,
where the truncated cosine series is worst:

    python3 benchmarks/scripts/axial_force_series.py [angles]     # default 72 crank angles

The theory guide's section 3.7 (static correction for the interfaces' inertia) quotes it.
"""

import math
import sys

R, L, OMEGA = 0.15, 0.30, 150.0  # crank, rod, crank speed
E, RHO, D = 200e9, 7870.0, 0.006  # round steel rod
A = math.pi * D * D / 4
EI = E * math.pi * D**4 / 64
RHO_A = RHO * A
M_SLIDER = 0.5 * RHO_A * L
TERMS = 24  # sine terms of w
NQ = 600  # midpoint quadrature points along the rod
S = [(i + 0.5) * L / NQ for i in range(NQ)]
DS = L / NQ


def slider_x(phi):
    return R * math.cos(phi) + math.sqrt(L * L - (R * math.sin(phi)) ** 2)


def loads(phi):
    """Transverse load q and axial force N (tension positive) at the points S, crank angle phi."""
    dt = 1e-5
    t = phi / OMEGA
    a_slider = (slider_x(OMEGA * (t + dt)) - 2 * slider_x(OMEGA * t) + slider_x(OMEGA * (t - dt))) / dt**2
    ax, ay = R * math.cos(phi), R * math.sin(phi)
    e = ((slider_x(phi) - ax) / L, -ay / L)
    n = (-e[1], e[0])
    aa = (-R * OMEGA**2 * math.cos(phi), -R * OMEGA**2 * math.sin(phi))
    f = []
    for s in S:
        a = (aa[0] + s / L * (a_slider - aa[0]), aa[1] + s / L * (0.0 - aa[1]))
        f.append((-RHO_A * a[0], -RHO_A * a[1]))
    q = [fx * n[0] + fy * n[1] for fx, fy in f]
    f_axial = [fx * e[0] + fy * e[1] for fx, fy in f]
    # The slider's force on the rod, (-m a, R_y): R_y from the rod's moment balance about A.
    moment = sum(s * qq * DS for s, qq in zip(S, q))
    r_y = (-moment / L + M_SLIDER * a_slider * n[0]) / n[1]
    n_end = -M_SLIDER * a_slider * e[0] + r_y * e[1]
    N = [0.0] * NQ
    acc = 0.0
    for i in range(NQ - 1, -1, -1):
        acc += 0.5 * f_axial[i] * DS
        N[i] = n_end + acc
        acc += 0.5 * f_axial[i] * DS
    return q, N


def midpoint_deflection(q, N):
    k = [(j + 1) * math.pi / L for j in range(TERMS)]
    cos = [[math.cos(kj * s) for s in S] for kj in k]
    sin = [[math.sin(kj * s) for s in S] for kj in k]
    M = [[0.0] * (TERMS + 1) for _ in range(TERMS)]
    for i in range(TERMS):
        M[i][i] += EI * k[i] ** 4 * L / 2
        M[i][TERMS] = sum(a * b for a, b in zip(q, sin[i])) * DS
        for j in range(i, TERMS):
            v = sum(x * a * b for x, a, b in zip(N, cos[i], cos[j])) * DS * k[i] * k[j]
            M[i][j] += v
            if j != i:
                M[j][i] += v
    for i in range(TERMS):
        p = max(range(i, TERMS), key=lambda r: abs(M[r][i]))
        M[i], M[p] = M[p], M[i]
        for r in range(i + 1, TERMS):
            c = M[r][i] / M[i][i]
            for col in range(i, TERMS + 1):
                M[r][col] -= c * M[i][col]
    x = [0.0] * TERMS
    for i in range(TERMS - 1, -1, -1):
        x[i] = (M[i][TERMS] - sum(M[i][j] * x[j] for j in range(i + 1, TERMS))) / M[i][i]
    return sum(x[j] * math.sin(k[j] * L / 2) for j in range(TERMS))


def cosine_series(N, terms):
    mean = sum(N) / len(N)
    out = [mean] * len(N)
    for j in range(1, terms + 1):
        c = [math.cos(j * math.pi * s / L) for s in S]
        a = sum(x * y for x, y in zip(N, c)) / sum(y * y for y in c)
        out = [o + a * y for o, y in zip(out, c)]
    return out


def main():
    angles = int(sys.argv[1]) if len(sys.argv) > 1 else 72
    variants = [("exact N(x)", lambda N: N), ("uniform (mean)", lambda N: [sum(N) / NQ] * NQ)]
    variants += [(f"mean + {t} cosine term{'s' if t > 1 else ''}", lambda N, t=t: cosine_series(N, t)) for t in (1, 2, 3, 5)]
    w = {name: [] for name, _ in variants}
    for i in range(angles):
        q, N = loads(2 * math.pi * i / angles)
        for name, f in variants:
            w[name].append(midpoint_deflection(q, f(N)))
    exact = w["exact N(x)"]
    print(f"| axial force | max w [mm] | min w [mm] | extrema against exact N(x) |")
    print("|---|---:|---:|---:|")
    for name, _ in variants:
        v = w[name]
        d = 100 * max(abs(max(v) / max(exact) - 1), abs(min(v) / min(exact) - 1))
        sign = 1 if max(v) >= max(exact) else -1
        print(f"| {name} | {1e3 * max(v):.5f} | {1e3 * min(v):.5f} | {sign * d:+.3f} % |")


if __name__ == "__main__":
    main()

"""The slider-crank's rod diameter against the peak deflection of its midpoint: a parameter
study on a local Dask cluster (docs/python.md, "Worked example: rod diameter").

    pip install "./crates/python[sweep]" matplotlib
    python examples/python/rod_diameter.py [OUT.png]

Runs examples/slider_crank.toml for 8 rod diameters over one crank revolution at 150 rad/s
and plots the largest |midpoint deflection| against the diameter, with the slope of the
quasi-static estimate w ~ 1/d^2 (the inertia load grows with d^2, the bending stiffness with
d^4) for comparison.
"""

import sys
from pathlib import Path

import numpy as np

import flexmbs

HERE = Path(__file__).resolve().parent
STUDY = HERE.parent / "slider_crank.toml"


def main(out: Path):
    diameters = np.linspace(0.004, 0.011, 8)
    variants = flexmbs.grid(**{"sections.rod.d": diameters.tolist()})
    for v in variants:
        v["analyses.run-up.t_end"] = 2 * np.pi / 150.0  # one revolution
    table = flexmbs.sweep(
        STUDY,
        variants,
        {"peak_deflection": flexmbs.peak_abs("rod-mid")},
        client="local",  # or a dask.distributed.Client connected to a cluster
        n_workers=2,
        results_dir=out.parent / "rod_diameter-results",
    )
    print(table[["sections.rod.d", "peak_deflection", "error", "seconds"]])
    d = np.asarray(table["sections.rod.d"], dtype=float)
    w = np.asarray(table["peak_deflection"], dtype=float)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4), dpi=120)
    ax.loglog(d * 1e3, w * 1e3, "o-", label="flexmbs, 4 superelements, 2 modes each")
    ax.loglog(d * 1e3, w[0] * 1e3 * (d / d[0]) ** -2, "--", color="gray", label=r"quasi-static $w \propto d^{-2}$")
    ax.set_xlabel("rod diameter d [mm]")
    ax.set_ylabel("peak |midpoint deflection| [mm]")
    ax.set_title("Slider-crank at 150 rad/s: rod diameter against deflection")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out)
    print(f"plot: {out}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("rod_diameter.png"))

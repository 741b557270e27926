"""A PD controller in Python turns a flexible arm on a motor hub to 1 rad
(examples/controlled_arm.toml; docs/python.md, "Worked example: a controlled arm").

    pip install ./crates/python matplotlib
    python examples/python/controlled_arm.py [OUT.png]

Between time steps the controller reads the hub's angle and rate, computes the motor torque
tau = kp (target - angle) - kd rate, and sets it as the value of the study's point load
`motor`; the arm's tip deflection (seen from the hub) is recorded.
"""

import sys
from pathlib import Path

import numpy as np

import flexmbs

HERE = Path(__file__).resolve().parent
STUDY = HERE.parent / "controlled_arm.toml"


def main(out: Path):
    sim = flexmbs.Study.load(STUDY).simulation()
    target, kp, kd = 1.0, 20.0, 5.0  # rad, N m/rad, N m s/rad
    t, angle, tip, torque = [], [], [], []
    while sim.time < sim.end_time - 1e-9:
        theta, rate = sim.sensor("angle")[0], sim.sensor("rate")[0]
        tau = kp * (target - theta) - kd * rate
        sim.set_load("motor", moment=[0.0, 0.0, tau])
        sim.step()
        t.append(sim.time)
        angle.append(sim.sensor("angle")[0])
        tip.append(sim.sensor("tip")[1])
        torque.append(tau)
    t, angle, tip, torque = map(np.asarray, (t, angle, tip, torque))
    print(f"final angle {angle[-1]:.5f} rad, peak tip deflection {np.abs(tip).max() * 1e3:.3f} mm, "
          f"over the last second {np.abs(tip[t > 2.0]).max() * 1e3:.4f} mm")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, figsize=(6, 6), dpi=120, sharex=True)
    axes[0].plot(t, angle)
    axes[0].axhline(target, color="gray", ls="--")
    axes[0].set_ylabel("hub angle [rad]")
    axes[1].plot(t, tip * 1e3)
    axes[1].set_ylabel("tip deflection [mm]")
    axes[2].plot(t, torque)
    axes[2].set_ylabel("motor torque [N m]")
    axes[2].set_xlabel("t [s]")
    for a in axes:
        a.grid(True, alpha=0.3)
    fig.suptitle("PD control of a flexible arm (kp = 20 N m/rad, kd = 5 N m s/rad)")
    fig.tight_layout()
    fig.savefig(out)
    print(f"plot: {out}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("controlled_arm.png"))

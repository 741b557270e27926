"""Stepping a dynamic analysis from Python: the same numbers as a run, sensors and state
between steps, named loads set by a controller, the PD loop around a flexible arm, failures."""

import math

import numpy as np
import pytest

import flexmbs


def test_stepping_gives_the_run(examples, tmp_path):
    study = flexmbs.Study.load(examples / "slider_crank.toml")
    run = study.run(t_end=0.005, results_dir=tmp_path / "run")["run-up"]
    sim = study.simulation()
    assert sim.analysis == "run-up" and sim.dt == 1e-4 and sim.end_time == pytest.approx(0.126)
    assert sim.sensor_names == list(run.sensors)
    rows = {n: [sim.sensor(n)] for n in sim.sensor_names}
    times = [sim.time]
    for _ in range(50):
        iterations = sim.step()
        assert 1 <= iterations <= 20
        for n, v in sim.sensors().items():
            rows[n].append(v)
        times.append(sim.time)
    assert sim.steps == 50
    # Every step of the run, to the last bit: the run steps the same integrator.
    np.testing.assert_array_equal(np.array(times), run.sensor("rod-mid").time)
    for n in sim.sensor_names:
        np.testing.assert_array_equal(np.array(rows[n]), run.sensor(n).values, err_msg=n)
    assert sim.sensor_columns("rod-mid") == run.sensor("rod-mid").labels


def test_advance_state_and_node_motions(examples):
    sim = flexmbs.Study.load(examples / "slider_crank.toml").simulation()
    n = sim.advance_to(0.0031)
    assert n == 31 and sim.time == pytest.approx(0.0031, abs=1e-12)
    assert sim.advance_to(0.001) == 0
    s = sim.state()
    assert s["time"] == sim.time
    assert len(s["labels"]) == len(s["velocity"]) == len(s["acceleration"])
    assert s["rotations"].shape[1] == 4
    np.testing.assert_allclose(np.linalg.norm(s["rotations"], axis=1), 1.0, atol=1e-12)
    m = sim.node_motions()
    k = m["names"].index("crank.A") if "crank.A" in m["names"] else None
    assert m["position"].shape == (len(m["names"]), 3) and m["orientation"].shape == (len(m["names"]), 4)
    # The crank turns at 150 rad/s: its pin A is on the circle of 0.15 m at angle 150 t.
    if k is not None:
        angle = 150.0 * sim.time
        np.testing.assert_allclose(m["position"][k, :2], [0.15 * math.cos(angle), 0.15 * math.sin(angle)], atol=1e-12)
    crank = sim.sensor("crank-angle")[0]
    assert crank == pytest.approx(150.0 * sim.time, rel=1e-12)


def test_named_loads(examples, tmp_path):
    # The arm with the motor moment set from Python equals the arm with it in the study file.
    study = flexmbs.Study.load(examples / "controlled_arm.toml")
    assert study.simulation().load_names == ["motor"]
    fixed = flexmbs.Study.load(examples / "controlled_arm.toml")
    fixed["loads.motor.moment"] = [0.0, 0.0, 1.5]
    reference = fixed.run(t_end=0.2, results_dir=tmp_path / "fixed")["motion"].sensor("angle")
    sim = study.simulation()
    sim.set_load("motor", moment=[0.0, 0.0, 1.5])
    sim.advance_to(0.2)
    assert sim.sensor("angle")[0] == reference.values[-1, 0]
    # A load the study does not have, and a call without a value.
    with pytest.raises(flexmbs.FlexmbsError) as e:
        sim.set_load("motr", moment=[0, 0, 1])
    assert "motor" in str(e.value)
    with pytest.raises(ValueError):
        sim.set_load("motor")


def test_pd_loop_around_the_flexible_arm(examples):
    """A PD controller in Python turns the hub to 1 rad; the tip of the flexible arm settles."""
    sim = flexmbs.Study.load(examples / "controlled_arm.toml").simulation()
    target, kp, kd = 1.0, 20.0, 5.0
    angle, tip_y, torque = [], [], []
    while sim.time < 3.0 - 1e-9:
        theta = sim.sensor("angle")[0]
        rate = sim.sensor("rate")[0]
        tau = kp * (target - theta) - kd * rate
        sim.set_load("motor", moment=[0.0, 0.0, tau])
        sim.step()
        angle.append(theta)
        tip_y.append(sim.sensor("tip")[1])
        torque.append(tau)
    angle, tip_y = np.array(angle), np.array(tip_y)
    t = np.arange(len(angle)) * sim.dt
    # The closed loop: J = 0.38 kg m^2 about the axis, so omega_n = sqrt(kp / J) = 7.3 rad/s and
    # zeta = kd / (2 sqrt(kp J)) = 0.9; it settles (2 %) in about 4 / (zeta omega_n) = 0.6 s.
    assert abs(angle[-1] - target) < 2e-3
    late = t > 2.0
    assert np.max(np.abs(angle[late] - target)) < 1e-2
    # The arm bends while the hub accelerates (the tip lags, a deflection of a few mm) and
    # straightens when it stops: the last second's deflection is under 1 % of the peak.
    peak = np.max(np.abs(tip_y))
    assert peak > 1e-4
    assert np.max(np.abs(tip_y[late])) < 0.01 * peak
    # The torque went to zero with the error.
    assert abs(torque[-1]) < 0.05


def test_a_failed_step_says_where(examples):
    sim = flexmbs.Study.load(examples / "controlled_arm.toml").simulation()
    sim.advance_to(0.01)
    # A moment of 1e9 N m on the hub: Newton cannot follow within the step.
    sim.set_load("motor", moment=[0.0, 0.0, 1e9])
    with pytest.raises(flexmbs.SolveError) as e:
        sim.advance_to(1.0)
    err = e.value
    assert err.time is not None and err.time > 0.01
    assert err.step is not None
    # The state stays at the last converged step.
    assert sim.time < err.time

"""Stepping a dynamic analysis from Python: the same numbers as a run, sensors and state
between steps, named loads and actuator efforts set by a controller, the PD loop around a
flexible arm, failures that say where and keep what was computed."""

import json
import math

import numpy as np
import pytest

import flexmbs
from conftest import STUDIES


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
    # The motor moment doubled from Python at t = 0.1 s equals the same change written in the
    # study file as a time function (a step between 0.1 and the next step's time, 0.102 s):
    # the load is evaluated at the end of each step, so both runs see the same values.
    study = flexmbs.Study.load(examples / "controlled_arm.toml")
    study["loads.motor.moment"] = [0.0, 0.0, 1.5]
    assert study.simulation().load_names == ["motor"]
    fixed = flexmbs.Study.load(examples / "controlled_arm.toml")
    fixed["loads.motor.moment"] = [0.0, 0.0, 1.5]
    fixed["loads.motor.function"] = {
        "type": "table",
        "t": [0.0, 0.1005, 0.1006, 1.0],
        "value": [1.0, 1.0, 2.0, 2.0],
        "interpolation": "linear",
    }
    reference = fixed.run(t_end=0.2, results_dir=tmp_path / "fixed")["motion"].sensor("angle")
    sim = study.simulation()
    sim.advance_to(0.1)
    sim.set_load("motor", moment=[0.0, 0.0, 3.0])
    sim.advance_to(0.2)
    assert sim.sensor("angle")[0] == reference.values[-1, 0]
    # Against the rigid rotation: theta = M t^2 / (2 J) with J = 0.377 kg m^2 about the axis
    # (hub 0.05, arm rho A (1.05^3 - 0.05^3) / 3 = 0.327); the arm's bending changes it by
    # less than 1 %.
    J = 0.05 + 2700.0 * math.pi * 0.02**2 / 4 * (1.05**3 - 0.05**3) / 3
    rigid = 1.5 * 0.2**2 / (2 * J) + 1.5 * (0.2 - 0.1) ** 2 / (2 * J)
    assert sim.sensor("angle")[0] == pytest.approx(rigid, rel=1e-2)
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
    # Where: the time of the failed step (and its number and residual when Newton is what
    # failed; here the arm's floating frame cannot follow first).
    assert err.time is not None and err.time > 0.01
    assert f"t = {err.time:.6f}" in str(err)
    # The state stays at the last converged step.
    assert sim.time < err.time


# An actuator on the hub's joint, for a controller outside the study: a torque on the joint
# coordinate (reacted by the ground), zero by its own law.
DRIVE = """
[[actuators]]
name = "drive"
joint = "motor-axis"
function = { type = "constant-speed", speed = 0.0 }

[[sensors]]
name = "drive-torque"
type = "actuator-effort"
of = "drive"
"""


def pd_loop(sim, set_torque, t_end, target=1.0, kp=20.0, kd=5.0):
    """A PD law on the hub angle, computed from the sensors after each step and set for the
    next; the hub angle, the tip's deflection and the torque at every step."""
    angle, tip_y, torque = [], [], []
    while sim.time < t_end - 1e-9:
        theta = sim.sensor("angle")[0]
        rate = sim.sensor("rate")[0]
        tau = kp * (target - theta) - kd * rate
        set_torque(tau)
        sim.step()
        angle.append(theta)
        tip_y.append(sim.sensor("tip")[1])
        torque.append(tau)
    return np.array(angle), np.array(tip_y), np.array(torque)


def test_pd_loop_through_an_actuator_effort(examples):
    """The PD loop closed through an actuator on the hub's joint instead of the point load:
    the same torque about the same axis, so the same motion; the hub settles at 1 rad."""
    text = (examples / "controlled_arm.toml").read_text() + DRIVE
    study = flexmbs.Study.from_toml(text, base_dir=examples, name="controlled_arm.toml")
    sim = study.simulation()
    assert sim.actuator_names == ["drive"]
    assert sim.held_actuator("drive") is None
    angle, tip_y, torque = pd_loop(sim, lambda tau: sim.set_actuator("drive", tau), 3.0)
    # The actuator-effort sensor writes the held value: the last torque set.
    assert sim.held_actuator("drive") == torque[-1]
    assert sim.sensor("drive-torque")[0] == torque[-1] == sim.actuator_effort("drive")
    t = np.arange(len(angle)) * sim.dt
    # Settling as in the loop through the load (J = 0.38 kg m^2, omega_n = 7.3 rad/s, zeta =
    # 0.9: 2 % in about 0.6 s).
    assert abs(angle[-1] - 1.0) < 2e-3
    assert np.max(np.abs(angle[t > 2.0] - 1.0)) < 1e-2
    # The same loop through the point load `motor` (a moment about the joint's axis at the
    # joint): equal to the Newton tolerance (relative residual 1e-10 per step, summed over
    # 1500 steps of a stable loop), far below the 1 rad the hub turns.
    ref = flexmbs.Study.load(examples / "controlled_arm.toml").simulation()
    ref_angle, ref_tip, _ = pd_loop(ref, lambda tau: ref.set_load("motor", moment=[0.0, 0.0, tau]), 3.0)
    np.testing.assert_allclose(angle, ref_angle, rtol=0, atol=1e-7)
    np.testing.assert_allclose(tip_y, ref_tip, rtol=0, atol=1e-9)
    # Released: the actuator's own law (zero) acts again, and the hub coasts.
    sim.release_actuator("drive")
    assert sim.held_actuator("drive") is None and sim.actuator_effort("drive") == 0.0
    sim.step()
    assert sim.sensor("drive-torque")[0] == 0.0
    # Errors: an actuator the study does not have (the names it has in the message).
    with pytest.raises(flexmbs.FlexmbsError) as e:
        sim.set_actuator("drve", 1.0)
    assert "drive" in str(e.value)
    with pytest.raises(flexmbs.FlexmbsError) as e:
        sim.set_actuator("drive", float("nan"))
    assert "finite" in str(e.value)


def failing_arm(examples):
    """The controlled arm with a motor moment that jumps to 3000 N m at t = 0.05 s, and
    Newton allowed 4 iterations without smaller steps: the time integration stops at the
    step after the jump's (t = 0.056 s, step 28: the jump is carried by a step of the
    table's linear ramp, the hub then spins too fast for 4 iterations)."""
    study = flexmbs.Study.load(examples / "controlled_arm.toml")
    study.update(
        {
            "loads.motor.moment": [0.0, 0.0, 1.0],
            "loads.motor.function": {
                "type": "table",
                "t": [0.0, 0.0499, 0.05, 1.0],
                "value": [0.0, 0.0, 3000.0, 3000.0],
                "interpolation": "linear",
            },
            "analyses.motion.max_iterations": 4,
            "analyses.motion.dt_min": 2e-3,
        }
    )
    return study


def test_a_run_that_fails_mid_way_says_where_and_keeps_its_results(examples, tmp_path):
    study = failing_arm(examples)
    out = tmp_path / "failing"
    with pytest.raises(flexmbs.SolveError) as e:
        study.run(t_end=0.2, results_dir=out)
    err = e.value
    # Where: the analysis, the time and number of the step that failed, Newton's residual.
    assert err.analysis == "motion"
    assert err.time == pytest.approx(0.056, abs=1e-12)
    assert err.step == 28
    assert err.residual is not None and err.residual > 1e-3
    assert "Newton did not converge at t = 0.056000 (step 28)" in str(err)
    assert str(out) in str(err)
    # What was computed before: the 27 converged steps and the start, in the exception ...
    partial = err.partial["motion"]
    angle = partial.sensor("angle")
    assert len(angle.time) == 28 and angle.time[-1] == pytest.approx(0.054, abs=1e-12)
    assert partial.summary["status"] == "failed"
    # ... and in the results folder, as the program keeps them.
    rows = np.loadtxt(out / "motion" / "angle.csv", delimiter=",", skiprows=1, ndmin=2)
    np.testing.assert_array_equal(rows[:, 0], angle.time)
    np.testing.assert_array_equal(rows[:, 1], angle.values[:, 0])
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed"
    assert "Newton did not converge" in summary["analyses"][0]["error"]


def test_a_simulation_that_fails_says_where_and_can_go_on(examples):
    sim = failing_arm(examples).simulation()
    with pytest.raises(flexmbs.SolveError) as e:
        sim.advance_to(0.2)
    err = e.value
    # The step that failed, as in the run (the same integrator).
    assert (err.analysis, err.step) == ("motion", 28)
    assert err.time == pytest.approx(0.056, abs=1e-12) and err.residual > 1e-3
    assert err.partial is None
    # The state stays at the last converged step.
    assert sim.time == pytest.approx(0.054, abs=1e-12) and sim.steps == 27


# A clamped steel hex20 bar 1 x 0.1 x 0.1 m reduced with 2 modes, stress shapes and a load
# point "tip" at (1, 0.05, 0.05), loaded there by "tip-force" and shaken for 2 ms; "top" is the
# largest von Mises stress over the node set y1.
TIP = [2e2, -3e3, 1e3]
LOAD_POINT_BAR = """
[[materials]]
name = "steel"
E = 210e9
nu = 0.3
rho = 7850.0

[[parts]]
name = "bar"
material = "steel"

[parts.box]
size = [1.0, 0.1, 0.1]
divisions = [10, 2, 2]
element = "hex20"

[[parts.interfaces]]
name = "root"
set = "x0"
spider = "rbe2"

[parts.reduction]
modes = 2
stress_shapes = true
load_points = [{ name = "tip", node_at = [1.0, 0.05, 0.05] }]

[[bodies]]
name = "bar"
part = "bar"

[[supports]]
at = "bar.root"
type = "clamp"

[[loads]]
name = "tip-force"
type = "point"
at = "bar.tip"
force = [%s, %s, %s]
%s
[[sensors]]
name = "top"
type = "stress"
of = "bar"
set = "y1"

[[analyses]]
type = "dynamic"
name = "shake"
t_end = 0.002
dt = 1e-4
"""


def test_set_load_changes_a_load_at_a_load_point_between_steps(tmp_path):
    # The tip force doubled from Python after the third step equals the same change written in
    # the study file as a time function (1 up to 3e-4 s, the third step's end, 2 from 4e-4 s, the
    # fourth's): the load is evaluated at the end of each step, so both runs see the same
    # values, to the bit.
    def simulation(name, function=""):
        text = LOAD_POINT_BAR % (*TIP, function)
        study = flexmbs.Study.from_toml(text, base_dir=tmp_path, name=f"{name}.toml")
        return study.simulation(cache=tmp_path / "cache")

    table = 'function = { type = "table", t = [0.0, 3e-4, 4e-4, 1.0], value = [1.0, 1.0, 2.0, 2.0] }\n'
    a, b, d = simulation("unchanged"), simulation("changed"), simulation("tabled", table)
    assert "tip-force" in a.load_names
    for _ in range(3):
        for s in (a, b, d):
            s.step()
    b.set_load("tip-force", force=[2.0 * x for x in TIP])
    for _ in range(10):
        for s in (a, b, d):
            s.step()
        assert b.sensors().keys() == d.sensors().keys()
        for name, values in b.sensors().items():
            np.testing.assert_array_equal(values, d.sensors()[name], err_msg=f"{name} at t = {b.time}")
    # And the change acts: the unchanged run is far below (about half the stress).
    va, vb = a.sensor("top")[0], b.sensor("top")[0]
    assert vb > 1.5 * va
    # A load point has a force and a moment; an unknown name and a bad value are named.
    b.set_load("tip-force", moment=[0.0, 0.0, 0.0])
    with pytest.raises(flexmbs.FlexmbsError) as e:
        b.set_load("tip-forse", force=TIP)
    assert "tip-force" in str(e.value)
    with pytest.raises(flexmbs.FlexmbsError) as e:
        b.set_load("tip-force", force=[math.nan, 0.0, 0.0])
    assert "non-finite" in str(e.value)


def test_a_sensor_is_read_alone_and_one_that_is_not_finite_is_located(tmp_path):
    # The study the study crate's tests read too.
    cart = (STUDIES / "pendulum_cart.toml").read_text()
    sim = flexmbs.Study.from_toml(cart, base_dir=tmp_path, name="cart.toml").simulation(cache=tmp_path / "cache")
    sim.advance_to(0.1)
    # "travel" is read without evaluating "gap", which is no longer finite: 10 m/s x 0.1 s.
    assert sim.sensor("travel")[0] == pytest.approx(1.0, abs=1e-12)
    with pytest.raises(flexmbs.SolveError) as e:
        sim.sensor("gap")
    err = e.value
    assert "sensor 'gap'" in str(err) and "t = 0.100000" in str(err)
    assert err.key == "sensors[1]" and err.line is not None
    assert err.time == pytest.approx(0.1, abs=1e-12) and err.step == 10
    with pytest.raises(flexmbs.SolveError):
        sim.sensors()


def test_stepping_retries_a_failed_step_as_the_run_does(tmp_path):
    """The snapping truss needs one retried step (at t = 0.11 s): stepped from Python, every
    output row equals the run's to the bit; ``step(dt)`` takes a step of its own size, and
    the steps after it land on the end time."""
    study = flexmbs.Study.load(STUDIES / "snapping_truss.toml")
    run = study.run(results_dir=tmp_path / "run")["dynamic"].sensor("apex")
    sim = study.simulation()
    ys = [sim.sensor("apex")[1]]
    while sim.time < sim.end_time - 1e-12:
        sim.step()
        ys.append(sim.sensor("apex")[1])
    np.testing.assert_array_equal(np.array(ys), run.values[:, 1])
    sim = study.simulation()
    assert sim.step(dt=2.5e-3) >= 1
    assert sim.time == 2.5e-3
    sim.advance_to(0.5)
    assert sim.time == pytest.approx(0.5, abs=1e-15)
    with pytest.raises(ValueError):
        sim.step(dt=-1.0)


def test_a_stepped_simulation_writes_the_results_folder_of_the_run(examples, tmp_path):
    study = flexmbs.Study.load(examples / "slider_crank.toml")
    study.run(analysis="run-up", results_dir=tmp_path / "run")
    sim = study.simulation(results_dir=tmp_path / "stepped")
    sim.advance_to(sim.end_time)
    summary = sim.finish_results()
    assert summary is not None and summary["status"] == "complete"
    assert sim.finish_results() is None
    run_dir, stepped_dir = tmp_path / "run" / "run-up", tmp_path / "stepped" / "run-up"
    files = sorted(p.relative_to(run_dir) for p in run_dir.rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(stepped_dir) for p in stepped_dir.rglob("*") if p.is_file())
    assert any(f.suffix == ".csv" for f in files)
    for f in files:
        assert (run_dir / f).read_bytes() == (stepped_dir / f).read_bytes(), f

"""Force laws evaluated inside the implicit step (``flexmbs.ForceLaw``): an elbow damper
written in Python gives the motion of the study's own PID law on a flexible double pendulum,
both follow the rigid double pendulum with the same damper (scipy's solve_ivp), a raising
law stops the solve where it happened, the law acts in a Simulation stepped by hand, and a
law reading a position sensor sees the sensor's value inside the step."""

import shutil

import numpy as np
import pytest

import flexmbs
from conftest import STUDIES

C = 1.0  # N m s/rad: the damper of the study's PID (kd = 1)
L = 0.5  # m: each link


def damper_law(**kwargs):
    return flexmbs.ForceLaw(lambda t, q, qd: {"elbow-damper": -C * qd["elbow"]}, outputs=["elbow-damper"], **kwargs)


@pytest.fixture
def study(tmp_path):
    shutil.copy(STUDIES / "flexible_double_pendulum.toml", tmp_path)
    return flexmbs.Study.load(tmp_path / "flexible_double_pendulum.toml")


def peak_error(a, b):
    """The largest difference of `a` and `b`, and the largest |a| (the motion's peak)."""
    return np.max(np.abs(a - b)), np.max(np.abs(a))


def test_in_step_damper_matches_the_pid(study, tmp_path):
    pid = study.run(results_dir=tmp_path / "pid")["swing"]
    for law in (damper_law(), damper_law(reads=["elbow"], differences="forward")):
        forced = study.run(results_dir=tmp_path / "law", forces=law)["swing"]
        np.testing.assert_array_equal(forced.sensor("elbow").time, pid.sensor("elbow").time)
        for name in ("shoulder", "elbow", "tip", "torque"):
            err, peak = peak_error(forced.sensor(name).values, pid.sensor(name).values)
            # The same equations to Newton's tolerance: 1e-6 of the motion's peak.
            assert err <= 1e-6 * peak, f"{name}: {err:.3e} (peak {peak:.3e})"


def rigid_tip(study, t):
    """The tip of the rigid double pendulum with the flexible links' mass, centre of mass and
    inertia, and the elbow damper, solved by solve_ivp (rtol 1e-11) at the times `t`."""
    from scipy.integrate import solve_ivp

    (_, link), = study.reduce()
    m, I = link.mass, link.inertia[2, 2]
    a = -link.center_of_mass[1]  # the centre of mass below the link's joint
    g = 9.81

    def rhs(_, y):
        p1, p2, w1, w2 = y  # absolute angles from the hanging position and their rates
        s, c = np.sin(p1 - p2), np.cos(p1 - p2)
        M = np.array([[I + m * a * a + m * L * L, m * L * a * c], [m * L * a * c, I + m * a * a]])
        tau = -C * (w2 - w1)  # the elbow damper on the lower link, its reaction on the upper
        f = np.array(
            [
                -m * L * a * s * w2 * w2 - (m * a + m * L) * g * np.sin(p1) - tau,
                m * L * a * s * w1 * w1 - m * a * g * np.sin(p2) + tau,
            ]
        )
        return [w1, w2, *np.linalg.solve(M, f)]

    y0 = [np.radians(40.0), np.radians(10.0), 0.0, 0.0]
    sol = solve_ivp(rhs, (t[0], t[-1]), y0, t_eval=t, rtol=1e-11, atol=1e-12, method="DOP853")
    p1, p2 = sol.y[0], sol.y[1]
    return np.stack([L * np.sin(p1) + L * np.sin(p2), -L * np.cos(p1) - L * np.cos(p2)], axis=1)


def test_both_follow_the_rigid_double_pendulum(study, tmp_path):
    forced = study.run(results_dir=tmp_path / "law", forces=damper_law())["swing"]
    tip = forced.sensor("tip")
    rigid = rigid_tip(study, tip.time)
    # Stiff links (30 mm steel, first bending mode above 200 Hz): the flexible tip is the
    # rigid one to their deflection and the time step's error, well within 1 mm.
    err = np.max(np.linalg.norm(tip.values[:, :2] - rigid, axis=1))
    assert err < 1e-3, f"tip off the rigid pendulum's by {err:.3e} m"
    pid = study.run(results_dir=tmp_path / "pid")["swing"]
    err = np.max(np.linalg.norm(pid.sensor("tip").values[:, :2] - rigid, axis=1))
    assert err < 1e-3, f"PID tip off the rigid pendulum's by {err:.3e} m"


def test_a_raising_law_gives_a_located_error(study, tmp_path):
    def law(t, q, qd):
        if t > 0.0105:
            raise ZeroDivisionError("the controller divided by zero")
        return {"elbow-damper": -C * qd["elbow"]}

    with pytest.raises(flexmbs.SolveError) as caught:
        study.run(results_dir=tmp_path / "raise", forces=flexmbs.ForceLaw(law, outputs=["elbow-damper"]))
    e = caught.value
    assert e.time == pytest.approx(0.011) and e.step == 11 and e.analysis == "swing"
    assert "force law 'forces'" in str(e) and "ZeroDivisionError" in str(e), str(e)
    assert isinstance(e.__cause__, ZeroDivisionError)
    # The steps before it are kept.
    assert len(e.partial["swing"].sensor("elbow").time) == 11


@pytest.mark.parametrize(
    "result, message",
    [
        ({"elbow-damper": float("nan")}, "(output 'elbow-damper')"),
        ({}, "it returned no value for 'elbow-damper'"),
        ({"elbow-damper": 0.0, "wrist": 1.0}, "it returned 'wrist', which is not one of its outputs"),
        ([1.0], "not a dict"),
    ],
)
def test_a_bad_result_is_refused_by_name(study, tmp_path, result, message):
    law = flexmbs.ForceLaw(lambda t, q, qd: result, outputs=["elbow-damper"])
    with pytest.raises(flexmbs.SolveError, match="force law") as caught:
        study.run(results_dir=tmp_path / "bad", forces=law)
    assert message in str(caught.value)
    assert caught.value.time == 0.0 or caught.value.time == pytest.approx(0.001)


def test_unknown_names_are_refused_before_the_run(study, tmp_path):
    with pytest.raises(flexmbs.FlexmbsError, match="wrist"):
        study.run(results_dir=tmp_path / "u", forces=flexmbs.ForceLaw(lambda t, q, qd: {}, outputs=["wrist"]))
    with pytest.raises(flexmbs.FlexmbsError, match="knee"):
        study.run(results_dir=tmp_path / "u", forces=damper_law(reads=["knee"]))


def test_the_law_acts_in_a_stepped_simulation(study, tmp_path):
    run = study.run(results_dir=tmp_path / "law", forces=damper_law())["swing"]
    sim = study.simulation(forces=damper_law())
    elbow = [sim.sensor("elbow")[0]]
    for _ in range(200):
        sim.step()
        elbow.append(sim.sensor("elbow")[0])
    # The run steps the same integrator with the same law: the same numbers.
    np.testing.assert_array_equal(np.array(elbow), run.sensor("elbow").column(0)[:201])
    # The actuator reports the law's effort: -c times the elbow's rate.
    state = sim.state()
    k = next(i for i, label in enumerate(state["labels"]) if "elbow" in label)
    assert sim.actuator_effort("elbow-damper") == pytest.approx(-C * state["velocity"][k], rel=1e-12)


def test_a_law_reading_a_position_sensor_sees_it_inside_the_step(study, tmp_path):
    calls = []

    def law(t, q, qd):
        calls.append((t, q["tip.position_x"], q["tip.position_y"], qd["tip.position_x"]))
        assert set(q) == set(qd) == {"elbow", "tip.position_x", "tip.position_y", "tip.position_z"}
        # The damper, plus a term of the tip that is zero: the PID's motion.
        return {"elbow-damper": -C * qd["elbow"] + 0.0 * q["tip.position_y"]}

    forces = flexmbs.ForceLaw(law, outputs=["elbow-damper"], reads=["elbow", "tip"])
    sim = study.simulation(forces=forces)
    pid = study.simulation()
    for _ in range(20):
        calls.clear()
        sim.step()
        pid.step()
        tip = sim.sensor("tip")
        t = sim.time
        # Called in the step's Newton iterations at the step's time, at the converged state
        # among them: the sensor's value of the step (central differences move it by 1e-6).
        now = [c for c in calls if c[0] == t]
        assert len(now) >= 4, calls
        x, y = min(((cx, cy) for _, cx, cy, _ in now), key=lambda p: abs(p[0] - tip[0]) + abs(p[1] - tip[1]))
        assert abs(x - tip[0]) < 1e-12 and abs(y - tip[1]) < 1e-12, (x, y, tip)
    # The tip's term is zero: the PID's motion, to Newton's tolerance.
    err, peak = peak_error(np.array(sim.sensor("elbow")), np.array(pid.sensor("elbow")))
    assert err <= 1e-6 * peak, f"{err:.3e} (peak {peak:.3e})"


def test_sensors_a_law_cannot_read_are_refused(study, tmp_path):
    with pytest.raises(flexmbs.FlexmbsError, match="sensor 'torque' is not a position or velocity sensor"):
        study.run(results_dir=tmp_path / "u", forces=damper_law(reads=["elbow", "torque"]))
    with pytest.raises(flexmbs.FlexmbsError, match="did you mean"):
        study.run(results_dir=tmp_path / "u", forces=damper_law(reads=["elbow", "tip.position_w"]))

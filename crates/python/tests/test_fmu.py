"""The FMU of a study (`flexmbs export-fmu`, `Study.export_fmu`) in FMPy, an importer that
shares no code with flexmbs: the archive and its model description are valid, a master
stepping at the analysis' step gets the numbers of `flexmbs run`, longer communication steps
land on the same points, a saved state redoes a step bit for bit, a controller closing the
loop through the FMU moves the mechanism as the same controller stepping `flexmbs.Simulation`
does, errors come back as statuses with messages, and instances are independent."""

import math
import os
import shutil
import zipfile
from pathlib import Path

import numpy as np
import pytest

import flexmbs
from conftest import cli_path

import fmpy  # noqa: E402  (a test dependency: the pyproject `test` extra)
from fmpy import extract, read_model_description  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE  # noqa: E402


def library():
    """The FMU library: $FLEXMBS_FMU_LIBRARY, else beside the `flexmbs` program (CI builds it
    with `cargo build --release -p flexmbs-fmu`)."""
    env = os.environ.get("FLEXMBS_FMU_LIBRARY")
    if env:
        return Path(env)
    cli = cli_path()
    p = cli.parent / "libflexmbs_fmu.so" if cli else None
    if p is None or not p.is_file():
        pytest.fail("the FMU library is not built: cargo build --release -p flexmbs-fmu, or set FLEXMBS_FMU_LIBRARY")
    return p


# An actuator on the controlled arm's hub joint and a sensor of its effort (as in
# test_simulation), and the rho_inf of its analysis as an FMU parameter.
DRIVE = """
[[actuators]]
name = "drive"
joint = "motor-axis"
function = { type = "constant-speed", speed = 0.0 }

[[sensors]]
name = "drive-torque"
type = "actuator-effort"
of = "drive"

[fmu]
parameters = ["analyses.motion.rho_inf"]
"""


def arm_fmu(examples, tmp_path):
    study = examples / "controlled_arm_drive.toml"
    study.write_text((examples / "controlled_arm.toml").read_text() + DRIVE)
    fmu = tmp_path / "arm.fmu"
    flexmbs.Study.load(study).export_fmu(fmu, library=library())
    return study, fmu


class Slave:
    """An FMPy FMU2Slave with a logger that keeps the messages, and the variables by name."""

    def __init__(self, fmu, folder, name="instance", unzipped=None):
        """`folder`: where to extract the FMU; `unzipped`: an FMU extracted before (its library
        already loaded: a second instance of the same library)."""
        self.md = read_model_description(str(fmu))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.outputs = [v.name for v in self.md.modelVariables if v.causality == "output"]
        if unzipped is None:
            unzipped = extract(str(fmu), str(folder))
        self.folder = Path(unzipped)
        self.messages = []

        def log(_env, _name, status, _category, message):
            self.messages.append((status, message.decode()))

        # The FMU allocates nothing through the master (canNotUseMemoryManagementFunctions).
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(log)
        self.fmu = FMU2Slave(
            guid=self.md.guid,
            unzipDirectory=unzipped,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.t = 0.0

    def start(self, stop=None, parameters=None):
        self.fmu.instantiate(callbacks=self.callbacks)
        self.fmu.setupExperiment(startTime=0.0, stopTime=stop)
        for name, value in (parameters or {}).items():
            self.fmu.setReal([self.vr[name]], [value])
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        return self

    def get(self, names=None):
        names = names or self.outputs
        return np.array(self.fmu.getReal([self.vr[n] for n in names]))

    def set(self, name, value):
        self.fmu.setReal([self.vr[name]], [value])

    def step(self, h):
        self.fmu.doStep(currentCommunicationPoint=self.t, communicationStepSize=h)
        self.t += h

    def errors(self):
        return [m for s, m in self.messages if s >= 3]

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def test_the_archive_and_its_model_description_are_valid(examples, tmp_path, cli):
    fmu = tmp_path / "slider_crank.fmu"
    cli("export-fmu", examples / "slider_crank.toml", "-o", fmu)
    # An archive that Python's own reader reads, every CRC right.
    with zipfile.ZipFile(fmu) as z:
        assert z.testzip() is None
        names = z.namelist()
    assert "modelDescription.xml" in names
    assert "binaries/linux64/slider_crank.so" in names
    assert "resources/flexmbs-fmu.json" in names and "resources/files/slider_crank.toml" in names
    # The reduced bodies travel with it: the FMU does not reduce them again.
    assert any(n.startswith("resources/cache/") for n in names)
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(str(fmu))
    assert md.fmiVersion == "2.0" and md.coSimulation.canGetAndSetFMUstate
    assert md.defaultExperiment.stopTime == "0.126" or float(md.defaultExperiment.stopTime) == 0.126
    variables = {v.name: v for v in md.modelVariables}
    deflection = variables["rod-mid.deflection"]
    assert deflection.causality == "output" and deflection.unit == "m"
    assert variables["crank-angle.coordinate_0"].unit == "rad"
    # Every sensor column is an output; the slider-crank has no actuators nor point loads.
    study = flexmbs.Study.load(examples / "slider_crank.toml")
    sim = study.simulation()
    columns = sum(len(sim.sensor_columns(n)) for n in sim.sensor_names)
    assert len([v for v in md.modelVariables if v.causality == "output"]) == columns
    assert not [v for v in md.modelVariables if v.causality == "input"]
    # A master's stop time after the analysis' end (0.126 s) extends the analysis to it.
    result = fmpy.simulate_fmu(str(fmu), stop_time=0.13, output_interval=1e-3)
    assert result["time"][-1] == pytest.approx(0.13, abs=1e-12)
    assert result["crank-angle.coordinate_0"][-1] == pytest.approx(150.0 * 0.13, rel=1e-9)


def test_a_missing_library_says_how_to_build_it(examples, tmp_path):
    with pytest.raises(flexmbs.FlexmbsError) as e:
        flexmbs.Study.load(examples / "slider_crank.toml").export_fmu(tmp_path / "x.fmu", library=tmp_path / "none.so")
    assert "cargo build --release -p flexmbs-fmu" in str(e.value)


def read_csv(path):
    return np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def test_communication_steps_of_dt_give_the_run(examples, tmp_path, cli):
    fmu = tmp_path / "slider_crank.fmu"
    cli("export-fmu", examples / "slider_crank.toml", "-o", fmu)
    out = tmp_path / "run"
    cli("run", examples / "slider_crank.toml", "--t-end", "0.005", "--out", out)
    result = fmpy.simulate_fmu(str(fmu), stop_time=0.005, output_interval=1e-4)
    sim = flexmbs.Study.load(examples / "slider_crank.toml").simulation()
    for sensor in sim.sensor_names:
        rows = read_csv(out / "run-up" / f"{sensor}.csv")
        np.testing.assert_allclose(result["time"], rows[:, 0], rtol=0, atol=1e-15)
        for k, column in enumerate(sim.sensor_columns(sensor)):
            name = f"{sensor}.{column.rsplit(' [', 1)[0].replace(' ', '_')}"
            expected = rows[:, k + 1]
            scale = max(np.max(np.abs(expected)), 1e-300)
            np.testing.assert_allclose(result[name], expected, rtol=1e-12, atol=1e-12 * scale, err_msg=name)


def test_longer_communication_steps_land_on_the_same_points(examples, tmp_path):
    fmu = tmp_path / "slider_crank.fmu"
    flexmbs.Study.load(examples / "slider_crank.toml").export_fmu(fmu, library=library())
    dt, t_end = 1e-4, 0.006
    results = {}
    for n in (1, 5, 10):
        s = Slave(fmu, tmp_path / f"x{n}").start(stop=t_end)
        values = {}
        for i in range(round(t_end / (n * dt))):
            s.step(n * dt)
            values[round(s.t / dt)] = s.get()
        s.close()
        results[n] = values
    # Several steps of the analysis per communication step, the inputs held: at the common
    # points the same numbers as one step per communication step.
    for n in (5, 10):
        for k, v in results[n].items():
            np.testing.assert_allclose(v, results[1][k], rtol=1e-12, atol=1e-15)
    # A communication step that is no multiple of dt: its last step shortened to land on it.
    # The motion stays that of steps of dt (the deflection, the slider, the crank); the
    # driver's effort and the energy, which carry the rod's vibration at the step's own
    # frequency, are not compared.
    s = Slave(fmu, tmp_path / "x25").start(stop=t_end)
    for _ in range(round(t_end / 2.5e-4)):
        s.step(2.5e-4)
    motion = [n for n in s.outputs if n.split(".")[0] in ("rod-mid", "slider", "crank-angle")]
    end = s.get(motion)
    s.close()
    k = [s.outputs.index(n) for n in motion]
    ref = results[1][60][k]
    assert np.all(np.abs(end - ref) <= 1e-4 * np.max(np.abs(ref)))


def test_a_saved_state_redoes_a_step_bit_for_bit(examples, tmp_path):
    study, fmu = arm_fmu(examples, tmp_path)
    s = Slave(fmu, tmp_path / "a").start()
    dt = 2e-3
    for i in range(10):
        s.set("drive", 0.5 * math.sin(i))
        s.step(dt)
    state = s.fmu.getFMUstate()
    t = s.t
    s.set("drive", 2.0)
    s.step(5 * dt)
    first = s.get()
    # A master that rejects the step: back, a shorter step, then back again and the same one.
    s.fmu.setFMUstate(state)
    s.t = t
    s.set("drive", -1.0)
    s.step(dt)
    shorter = s.get()
    s.fmu.setFMUstate(state)
    s.t = t
    s.set("drive", 2.0)
    s.step(5 * dt)
    again = s.get()
    assert np.array_equal(first, again)
    assert not np.array_equal(first, shorter)
    s.fmu.freeFMUstate(state)
    s.close()


def pd_fmu(s, steps, kp=20.0, kd=5.0, target=1.0, dt=2e-3):
    """A PD law on the hub angle in the master: outputs read after each step, the torque set
    on the actuator input for the next."""
    angle, rate = "angle." + angle_column(s), "rate." + rate_column(s)
    angles = []
    for _ in range(steps):
        theta, omega = s.get([angle, rate])
        s.set("drive", kp * (target - theta) - kd * omega)
        s.step(dt)
        angles.append(theta)
    return np.array(angles)


def angle_column(s):
    return next(n for n in s.outputs if n.startswith("angle.")).split(".", 1)[1]


def rate_column(s):
    return next(n for n in s.outputs if n.startswith("rate.")).split(".", 1)[1]


def pd_simulation(sim, steps, kp=20.0, kd=5.0, target=1.0):
    angles = []
    for _ in range(steps):
        theta, omega = sim.sensor("angle")[0], sim.sensor("rate")[0]
        sim.set_actuator("drive", kp * (target - theta) - kd * omega)
        sim.step()
        angles.append(theta)
    return np.array(angles)


def test_a_controller_in_the_master_moves_the_arm_as_in_python(examples, tmp_path):
    study, fmu = arm_fmu(examples, tmp_path)
    s = Slave(fmu, tmp_path / "a").start()
    through_fmu = pd_fmu(s, 300)
    s.close()
    sim = flexmbs.Study.load(study).simulation()
    in_python = pd_simulation(sim, 300)
    np.testing.assert_allclose(through_fmu, in_python, rtol=1e-12, atol=1e-14)
    # The loop does move the arm towards 1 rad.
    assert through_fmu[-1] > 0.5


def test_point_load_inputs_and_parameters(examples, tmp_path):
    study, fmu = arm_fmu(examples, tmp_path)
    s = Slave(fmu, tmp_path / "a")
    assert {"motor.moment.x", "motor.moment.y", "motor.moment.z", "drive"} <= set(s.vr)
    s.start(parameters={"analyses.motion.rho_inf": 0.5})
    for _ in range(20):
        s.set("motor.moment.z", 1.5)
        s.step(2e-3)
    fmu_angle = s.get(["angle." + angle_column(s)])[0]
    s.close()
    ref = flexmbs.Study.load(study)
    ref["analyses.motion.rho_inf"] = 0.5
    sim = ref.simulation()
    sim.set_load("motor", moment=[0.0, 0.0, 1.5])
    sim.advance_to(0.04)
    assert fmu_angle == pytest.approx(sim.sensor("angle")[0], rel=1e-12, abs=1e-15)
    # A parameter value the study refuses: refused when set, with the study's message.
    s = Slave(fmu, tmp_path / "b")
    s.fmu.instantiate(callbacks=s.callbacks)
    with pytest.raises(Exception):
        s.fmu.setReal([s.vr["analyses.motion.rho_inf"]], [2.0])
    assert any("rho_inf" in m for m in s.errors())
    s.fmu.freeInstance()


def test_errors_are_statuses_with_messages(examples, tmp_path):
    study, fmu = arm_fmu(examples, tmp_path)
    s = Slave(fmu, tmp_path / "a").start()
    # A value reference the FMU does not have.
    with pytest.raises(Exception):
        s.fmu.getReal([99999])
    assert any("99999" in m for m in s.errors())
    # An input that is not a number.
    with pytest.raises(Exception):
        s.set("drive", float("nan"))
    assert any("finite" in m for m in s.errors())
    # An output cannot be set.
    with pytest.raises(Exception):
        s.set("angle." + angle_column(s), 1.0)
    # A solver failure: a moment of 1e9 N m the arm cannot follow within a step; the error
    # says where and the FMU stays at the last converged step.
    s.set("motor.moment.z", 1e9)
    with pytest.raises(Exception):
        for _ in range(50):
            s.step(2e-3)
    assert any("analysis 'motion'" in m and "t = " in m for m in s.errors())
    s.fmu.freeInstance()
    # A resource folder without its study: instantiation fails with the reason.
    t = Slave(fmu, tmp_path / "b")
    shutil.rmtree(t.folder / "resources" / "files")
    with pytest.raises(Exception):
        t.fmu.instantiate(callbacks=t.callbacks)
    assert any("cannot read" in m for m in t.errors())


def test_two_instances_in_one_process_are_independent(examples, tmp_path):
    study, fmu = arm_fmu(examples, tmp_path)
    # Each alone.
    alone = []
    for kp in (20.0, 40.0):
        s = Slave(fmu, tmp_path / f"alone{kp}").start()
        alone.append(pd_fmu(s, 100, kp=kp))
        s.close()
    # Both in one library, stepped in turn.
    a = Slave(fmu, tmp_path / "both", name="a").start()
    b = Slave(fmu, None, name="b", unzipped=str(a.folder)).start()
    angles = ([], [])
    for _ in range(100):
        for s, kp, out in ((a, 20.0, angles[0]), (b, 40.0, angles[1])):
            out.append(pd_fmu(s, 1, kp=kp)[0])
    a.close()
    b.close()
    assert np.array_equal(np.array(angles[0]), alone[0])
    assert np.array_equal(np.array(angles[1]), alone[1])
    assert not np.array_equal(alone[0], alone[1])


def test_a_study_with_a_mesh_carries_the_mesh_and_its_reduced_body(examples, tmp_path):
    fmu = tmp_path / "four_bar.fmu"
    flexmbs.Study.load(examples / "four_bar.toml").export_fmu(fmu, library=library())
    with zipfile.ZipFile(fmu) as z:
        names = z.namelist()
    assert "resources/files/meshes/link_hex8.msh" in names
    cached = sorted(n for n in names if n.startswith("resources/cache/"))
    assert any(n.endswith(".rbody") for n in cached)
    assert validate_fmu(str(fmu)) == []
    # Run from its own folder, the FMU finds its reduced body in the cache it carries: it
    # reduces nothing (the cache holds what it held).
    s = Slave(fmu, tmp_path / "x").start(stop=0.01)
    for _ in range(5):
        s.step(1e-3)
    s.close()
    after = sorted("resources/cache/" + p.name for p in (s.folder / "resources" / "cache").iterdir())
    assert after == cached


def test_reset_starts_again_from_the_study(examples, tmp_path):
    study, fmu = arm_fmu(examples, tmp_path)
    s = Slave(fmu, tmp_path / "a").start(parameters={"analyses.motion.rho_inf": 0.5})
    first = pd_fmu(s, 20)
    # Back to the instantiated state: parameters and inputs at their start values.
    s.fmu.reset()
    s.t = 0.0
    rho = s.vr["analyses.motion.rho_inf"]
    assert s.fmu.getReal([rho]) == [0.8]
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.setReal([rho], [0.5])
    s.fmu.enterInitializationMode()
    s.fmu.exitInitializationMode()
    assert np.array_equal(pd_fmu(s, 20), first)
    s.close()


# FMI 3.0: the same study as an FMI 3.0 Co-Simulation FMU (`--fmi-version 3`,
# `export_fmu(..., fmi_version=3)`), the same library through its fmi3 functions.

from fmpy.fmi3 import FMU3Slave, fmi3LogMessageCallback  # noqa: E402


class Slave3(Slave):
    """An FMPy FMU3Slave with the interface of `Slave`."""

    def __init__(self, fmu, folder, name="instance", unzipped=None):
        self.md = read_model_description(str(fmu))
        assert self.md.fmiVersion == "3.0"
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.outputs = [v.name for v in self.md.modelVariables if v.causality == "output"]
        if unzipped is None:
            unzipped = extract(str(fmu), str(folder))
        self.folder = Path(unzipped)
        self.messages = []

        def log(_env, status, _category, message):
            self.messages.append((status, message.decode()))

        self.log = log
        self.fmu = FMU3Slave(
            guid=self.md.instantiationToken,
            unzipDirectory=unzipped,
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.t = 0.0

    def instantiate(self):
        self.fmu.instantiate(logMessage=self.log)

    def start(self, stop=None, parameters=None):
        self.instantiate()
        for name, value in (parameters or {}).items():
            self.fmu.setFloat64([self.vr[name]], [value])
        self.fmu.enterInitializationMode(startTime=0.0, stopTime=stop)
        self.fmu.exitInitializationMode()
        return self

    def get(self, names=None):
        names = names or self.outputs
        return np.array(self.fmu.getFloat64([self.vr[n] for n in names]))

    def set(self, name, value):
        self.fmu.setFloat64([self.vr[name]], [value])

    def step(self, h):
        event, terminate, early, last = self.fmu.doStep(currentCommunicationPoint=self.t, communicationStepSize=h)
        assert not (event or terminate or early)
        self.t += h
        assert last == pytest.approx(self.t, abs=1e-12)


def test_fmi3_is_valid_and_gives_the_numbers_of_fmi2_and_the_run(examples, tmp_path, cli):
    two, three = tmp_path / "two.fmu", tmp_path / "three.fmu"
    cli("export-fmu", examples / "slider_crank.toml", "-o", two)
    cli("export-fmu", examples / "slider_crank.toml", "--fmi-version", "3", "-o", three)
    with zipfile.ZipFile(three) as z:
        assert z.testzip() is None
        names = z.namelist()
    assert "binaries/x86_64-linux/slider_crank.so" in names
    assert validate_fmu(str(three)) == []
    md2, md3 = read_model_description(str(two)), read_model_description(str(three))
    assert md3.fmiVersion == "3.0" and md3.coSimulation.canGetAndSetFMUstate
    assert md3.instantiationToken == md2.guid
    v2 = {v.name: v for v in md2.modelVariables}
    v3 = {v.name: v for v in md3.modelVariables}
    assert v3.pop("time").causality == "independent"
    assert set(v2) == set(v3)
    for name, v in v3.items():
        assert v.type == "Float64" and v.valueReference == v2[name].valueReference
        assert (v.causality, v.variability, v.unit) == (v2[name].causality, v2[name].variability, v2[name].unit)
    assert {u.name for u in md3.unitDefinitions} >= {"m", "rad"}
    assert [o.variable.name for o in md3.outputs] == [o.variable.name for o in md2.outputs]
    # Communication steps of dt: the outputs of the FMI 2.0 FMU to the last bit, and so those
    # of `flexmbs run`.
    r2 = fmpy.simulate_fmu(str(two), stop_time=0.005, output_interval=1e-4)
    r3 = fmpy.simulate_fmu(str(three), stop_time=0.005, output_interval=1e-4)
    assert len(r3) == len(r2) == 51
    for name in r2.dtype.names:
        assert np.array_equal(r3[name], r2[name]), name
    out = tmp_path / "run"
    cli("run", examples / "slider_crank.toml", "--t-end", "0.005", "--out", out)
    sim = flexmbs.Study.load(examples / "slider_crank.toml").simulation()
    for sensor in sim.sensor_names:
        rows = read_csv(out / "run-up" / f"{sensor}.csv")
        for k, column in enumerate(sim.sensor_columns(sensor)):
            name = f"{sensor}.{column.rsplit(' [', 1)[0].replace(' ', '_')}"
            expected = rows[:, k + 1]
            scale = max(np.max(np.abs(expected)), 1e-300)
            np.testing.assert_allclose(r3[name], expected, rtol=1e-12, atol=1e-12 * scale, err_msg=name)


def arm_fmu3(examples, tmp_path):
    study = examples / "controlled_arm_drive.toml"
    study.write_text((examples / "controlled_arm.toml").read_text() + DRIVE)
    fmu = tmp_path / "arm3.fmu"
    info = flexmbs.Study.load(study).export_fmu(fmu, library=library(), fmi_version=3)
    assert info["fmi_version"] == "3.0"
    return study, fmu


def test_fmi3_a_controller_in_the_master_moves_the_arm_as_in_python(examples, tmp_path):
    study, fmu = arm_fmu3(examples, tmp_path)
    s = Slave3(fmu, tmp_path / "a").start()
    through_fmu = pd_fmu(s, 300)
    s.close()
    sim = flexmbs.Study.load(study).simulation()
    in_python = pd_simulation(sim, 300)
    np.testing.assert_allclose(through_fmu, in_python, rtol=1e-12, atol=1e-14)
    assert through_fmu[-1] > 0.5


def test_fmi3_saved_state_parameters_and_errors(examples, tmp_path):
    study, fmu = arm_fmu3(examples, tmp_path)
    s = Slave3(fmu, tmp_path / "a").start(parameters={"analyses.motion.rho_inf": 0.5})
    for i in range(10):
        s.set("drive", 0.5 * math.sin(i))
        s.step(2e-3)
    # A saved state redoes a step bit for bit.
    state = s.fmu.getFMUState()
    t = s.t
    s.set("drive", 2.0)
    s.step(1e-2)
    first = s.get()
    s.fmu.setFMUState(state)
    s.t = t
    s.set("drive", 2.0)
    s.step(1e-2)
    assert np.array_equal(first, s.get())
    s.fmu.freeFMUState(state)
    # A value reference the FMU does not have, for Float64 and for a type it has no variable of.
    with pytest.raises(Exception):
        s.fmu.getFloat64([99999])
    assert any("99999" in m for m in s.errors())
    with pytest.raises(Exception):
        s.fmu.getInt8([99998])
    assert any("99998" in m and "Int8" in m for m in s.errors())
    with pytest.raises(Exception):
        s.fmu.getInt8([s.vr["drive"]])
    assert any("is of type Float64, not Int8" in m for m in s.errors())
    # An input that is not a number.
    with pytest.raises(Exception):
        s.set("drive", float("nan"))
    assert any("finite" in m for m in s.errors())
    # An output cannot be set.
    with pytest.raises(Exception):
        s.set("angle." + angle_column(s), 1.0)
    s.close()
    # A parameter value the study refuses: refused when set, with the study's message.
    b = Slave3(fmu, tmp_path / "b")
    b.instantiate()
    with pytest.raises(Exception):
        b.fmu.setFloat64([b.vr["analyses.motion.rho_inf"]], [2.0])
    assert any("rho_inf" in m for m in b.errors())
    b.fmu.freeInstance()
    # A wrong instantiation token: no instance, the reason logged.
    c = Slave3(fmu, tmp_path / "c")
    c.fmu.guid = "{not-this-fmu}"
    with pytest.raises(Exception):
        c.instantiate()
    assert any("not the FMU's" in m for m in c.errors())


def test_a_controller_held_over_longer_communication_steps_converges_at_first_order(examples, tmp_path):
    # The master's PD torque is held over each communication step H (zero-order hold), so the
    # motion with H = m dt departs from that with H = dt by O(H - dt): first order. The hub
    # angle at t = 0.6 s for m = 1, 2, 3 and 5: the error ratios follow (m - 1), 2 and 2
    # (measured 1.89 and 1.83). Longer holds leave the asymptotic range: at H = 10 dt = 0.02 s
    # the hold's lag makes the sampled loop ring (the angle overshoots and swings back).
    _, fmu = arm_fmu(examples, tmp_path)
    dt, t_end = 2e-3, 0.6
    final = {}
    for m in (1, 2, 3, 5):
        s = Slave(fmu, tmp_path / f"h{m}").start()
        pd_fmu(s, round(t_end / (m * dt)), dt=m * dt)
        final[m] = s.get(["angle." + angle_column(s)])[0]
        s.close()
    errors = {m: abs(final[m] - final[1]) for m in (2, 3, 5)}
    assert errors[2] > 1e-5, errors
    for coarse, fine in ((3, 2), (5, 3)):
        ratio, expected = errors[coarse] / errors[fine], (coarse - 1) / (fine - 1)
        assert expected / 1.25 < ratio < expected * 1.25, (coarse, fine, errors)

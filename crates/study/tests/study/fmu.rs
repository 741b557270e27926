use super::{example, example_as, scratch};
use std::path::PathBuf;
use study::fmu::{FmiVersion, Instance, Manifest, Value, VarKind, VarType};
use study::{Options, Simulation};

/// The entries of a ZIP archive of stored entries (what `study::fmu::zip` writes), read from
/// its central directory: an independent reader of the format (Python's `zipfile` and FMPy
/// read the same archives in the package's tests).
fn unzip(bytes: &[u8]) -> Vec<(String, Vec<u8>)> {
    let u16_at = |i: usize| u16::from_le_bytes([bytes[i], bytes[i + 1]]) as usize;
    let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap()) as usize;
    let end = bytes.len() - 22;
    assert_eq!(u32_at(end), 0x0605_4b50, "end of central directory");
    let (n, mut at) = (u16_at(end + 10), u32_at(end + 16));
    let mut entries = Vec::new();
    for _ in 0..n {
        assert_eq!(u32_at(at), 0x0201_4b50);
        assert_eq!(u16_at(at + 10), 0, "stored");
        let (crc, size, name_len) = (u32_at(at + 16), u32_at(at + 24), u16_at(at + 28));
        let extra = u16_at(at + 30) + u16_at(at + 32);
        let offset = u32_at(at + 42);
        let name = String::from_utf8(bytes[at + 46..at + 46 + name_len].to_vec()).unwrap();
        let local_len = 30 + u16_at(offset + 26) + u16_at(offset + 28);
        let data = bytes[offset + local_len..offset + local_len + size].to_vec();
        assert_eq!(study::fmu::zip::crc32(&data) as usize, crc, "{name}");
        entries.push((name, data));
        at += 46 + name_len + extra;
    }
    entries
}

/// The FMU of the built-in example `name` exported and unpacked into a scratch folder: the
/// resources folder and the manifest.
fn exported(name: &str) -> (PathBuf, Manifest) {
    let file = example(name);
    let dir = scratch(&format!("fmu-{name}"));
    let library = dir.join("lib.so");
    std::fs::write(&library, b"the library").unwrap();
    let fmu = dir.join(format!("{name}.fmu"));
    let e = study::fmu::export(&file, None, FmiVersion::V2, &library, &fmu).unwrap();
    assert_eq!(e.model_identifier, name);
    let entries = unzip(&std::fs::read(&fmu).unwrap());
    let names: Vec<&str> = entries.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names[0], "modelDescription.xml");
    assert!(names.contains(&format!("binaries/linux64/{name}.so").as_str()));
    let unpacked = dir.join("unpacked");
    for (n, data) in &entries {
        let p = unpacked.join(n);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, data).unwrap();
    }
    let resources = unpacked.join("resources");
    let manifest: Manifest =
        serde_json::from_str(&std::fs::read_to_string(resources.join(study::fmu::MANIFEST)).unwrap()).unwrap();
    let xml = std::fs::read_to_string(unpacked.join("modelDescription.xml")).unwrap();
    assert!(xml.contains(&format!("guid=\"{}\"", manifest.guid)));
    (resources, manifest)
}

fn vr(m: &Manifest, name: &str) -> u32 {
    m.variables
        .iter()
        .position(|v| v.name == name)
        .unwrap_or_else(|| panic!("no {name}")) as u32
}

fn outputs(inst: &mut Instance) -> Vec<f64> {
    let m = inst.manifest().clone();
    m.variables
        .iter()
        .enumerate()
        .filter(|(_, v)| matches!(v.kind, VarKind::Output { .. }))
        .map(|(i, _)| match inst.get(i as u32, VarType::Real).unwrap() {
            Value::Real(x) => x,
            other => panic!("{other:?}"),
        })
        .collect()
}

#[test]
fn an_instance_steps_the_simulation_bit_for_bit() {
    let (resources, m) = exported("slider_crank");
    // Every sensor column is an output, with its unit.
    let deflection = &m.variables[vr(&m, "rod-mid.deflection") as usize];
    assert_eq!(deflection.unit.as_deref(), Some("m"));
    let mut inst = Instance::new(&resources, Some(&m.guid)).unwrap();
    inst.setup_experiment(0.0, Some(0.01)).unwrap();
    inst.initialize().unwrap();
    let study = study::load(&example("slider_crank")).unwrap();
    let mut sim = Simulation::new(&study, "run-up", &Options::default()).unwrap();
    let flat = |sim: &Simulation| sim.read().unwrap().concat();
    assert_eq!(outputs(&mut inst), flat(&sim));
    let dt = m.step;
    for k in 0..20 {
        inst.do_step(k as f64 * dt, dt).unwrap();
        sim.step().unwrap();
        assert_eq!(outputs(&mut inst), flat(&sim), "step {k}");
    }
    // Five steps per communication step land on the same point.
    inst.do_step(20.0 * dt, 5.0 * dt).unwrap();
    for _ in 0..5 {
        sim.step().unwrap();
    }
    assert_eq!(outputs(&mut inst), flat(&sim));
    // Saved, stepped, restored and stepped again: the same bits.
    let saved = inst.save();
    let t = inst.time().unwrap();
    inst.do_step(t, 3.0 * dt).unwrap();
    let first = outputs(&mut inst);
    inst.restore(&saved).unwrap();
    assert_eq!(inst.time(), Some(t));
    inst.do_step(t, 1.5 * dt).unwrap();
    assert_ne!(outputs(&mut inst), first);
    inst.restore(&saved).unwrap();
    inst.do_step(t, 3.0 * dt).unwrap();
    assert_eq!(outputs(&mut inst), first);
    // A communication step that does not start where the FMU is, and one past the end.
    let e = inst.do_step(0.0, dt).unwrap_err().to_string();
    assert!(e.contains("restore a saved state"), "{e}");
    let e = inst.do_step(inst.time().unwrap(), 1.0).unwrap_err().to_string();
    assert!(e.contains("t_end"), "{e}");
}

#[test]
fn inputs_and_parameters_are_checked_when_set() {
    let file = example("controlled_arm");
    let text = std::fs::read_to_string(&file).unwrap()
        + "\n[fmu]\nparameters = [\"analyses.motion.rho_inf\", \"output.every\"]\n";
    std::fs::write(&file, text).unwrap();
    let dir = scratch("fmu-arm-params");
    let library = dir.join("lib.so");
    std::fs::write(&library, b"x").unwrap();
    let fmu = dir.join("arm.fmu");
    let e = study::fmu::export(&file, Some("motion"), FmiVersion::V2, &library, &fmu).unwrap();
    let names: Vec<&str> = e.variables.iter().map(|v| v.name.as_str()).collect();
    for n in [
        "motor.moment.x",
        "motor.moment.z",
        "analyses.motion.rho_inf",
        "output.every",
    ] {
        assert!(names.contains(&n), "{n} in {names:?}");
    }
    let unpacked = dir.join("unpacked");
    for (n, data) in unzip(&std::fs::read(&fmu).unwrap()) {
        let p = unpacked.join(n);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, data).unwrap();
    }
    let resources = unpacked.join("resources");
    let mut inst = Instance::new(&resources, None).unwrap();
    let m = inst.manifest().clone();
    let rho = vr(&m, "analyses.motion.rho_inf");
    assert_eq!(inst.get(rho, VarType::Real).unwrap(), Value::Real(0.8));
    // A value the study refuses, with the study's message; the wrong type; unknown references.
    let err = inst.set(rho, Value::Real(2.0)).unwrap_err().to_string();
    assert!(err.contains("rho_inf"), "{err}");
    assert!(inst.set(rho, Value::Integer(1)).is_err());
    let every = vr(&m, "output.every");
    assert_eq!(inst.get(every, VarType::Integer).unwrap(), Value::Integer(1));
    let err = inst.get(9999, VarType::Real).unwrap_err().to_string();
    assert!(err.contains("9999"), "{err}");
    inst.set(rho, Value::Real(0.5)).unwrap();
    // Inputs: finite numbers only; outputs cannot be set.
    let z = vr(&m, "motor.moment.z");
    let err = inst.set(z, Value::Real(f64::NAN)).unwrap_err().to_string();
    assert!(err.contains("finite"), "{err}");
    let angle = m.variables.iter().position(|v| v.name.starts_with("angle.")).unwrap() as u32;
    assert!(inst.set(angle, Value::Real(1.0)).is_err());
    inst.set(z, Value::Real(1.5)).unwrap();
    inst.initialize().unwrap();
    // The parameters are final once the mechanism is built.
    assert!(inst.set(rho, Value::Real(0.6)).is_err());
    for k in 0..10 {
        inst.do_step(k as f64 * m.step, m.step).unwrap();
    }
    // The same as the study with rho_inf = 0.5 and the moment set from the start.
    let mut doc = study::Document::open(&file).unwrap();
    doc.set("analyses.motion.rho_inf", "0.5").unwrap();
    let st = doc.study().unwrap();
    let mut sim = Simulation::new(&st, "motion", &Options::default()).unwrap();
    sim.set_load("motor", mbs::LoadKind::Moment, [0.0, 0.0, 1.5]).unwrap();
    for _ in 0..10 {
        sim.step().unwrap();
    }
    assert_eq!(outputs(&mut inst), sim.read().unwrap().concat());
    // A missing resource: the instance says what it could not read.
    std::fs::remove_dir_all(resources.join("files")).unwrap();
    let err = Instance::new(&resources, None).err().unwrap().to_string();
    assert!(err.contains("cannot read"), "{err}");
}

#[test]
fn a_bad_fmu_table_is_located() {
    // A folder of its own: other tests write the slider-crank's example folder meanwhile.
    let file = example_as("slider_crank", "fmu-bad-table");
    let text =
        std::fs::read_to_string(&file).unwrap() + "\n[fmu]\nparameters = [\"rigid_bodies.crank.mas\", \"sensors\"]\n";
    let err = study::parse_and_validate(study::input::source::Source::from_text(&file, text))
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("fmu.parameters[0]") || err.contains("parameters"), "{err}");
    assert!(err.contains("names no value"), "{err}");
    assert!(err.contains("a parameter is a number"), "{err}");
}

#[test]
fn the_analysis_a_stepper_steps_is_the_named_dynamic_one_or_the_only_one() {
    let four_bar = study::load(&example("four_bar")).unwrap();
    let only = four_bar.dynamic_analysis(None).unwrap();
    assert_eq!(
        four_bar.analyses[four_bar.analysis(&only).unwrap()].kind_name(),
        "dynamic"
    );
    assert_eq!(four_bar.dynamic_analysis(Some(&only)).unwrap(), only);
    let not_dynamic = four_bar.dynamic_analysis(Some("at-rest")).unwrap_err().to_string();
    assert!(
        not_dynamic.contains("'at-rest' is of type 'equilibrium'"),
        "{not_dynamic}"
    );
    let unknown = four_bar.dynamic_analysis(Some("at-rst")).unwrap_err().to_string();
    assert!(unknown.contains("at-rest"), "did you mean: {unknown}");
}

/// The FMI 3.0 FMU of the same study: the same manifest and resources (one instance steps
/// both), a description of version 3.0 with the manifest's GUID as its instantiation token,
/// `Float64` variables by value reference, units declared, the outputs in the model
/// structure, the binary under `binaries/x86_64-linux`.
#[test]
fn the_fmi_3_description_names_the_same_variables() {
    // A file of its own beside the example's (another test appends to the example's).
    let example_file = example("controlled_arm");
    let file = example_file.with_file_name("arm_three.toml");
    let text =
        std::fs::read_to_string(&example_file).unwrap() + "\n[fmu]\nparameters = [\"analyses.motion.rho_inf\"]\n";
    std::fs::write(&file, text).unwrap();
    let dir = scratch("fmu-3");
    let library = dir.join("lib.so");
    std::fs::write(&library, b"x").unwrap();
    let two = study::fmu::export(&file, None, FmiVersion::V2, &library, &dir.join("two.fmu")).unwrap();
    let e = study::fmu::export(&file, None, FmiVersion::V3, &library, &dir.join("three.fmu")).unwrap();
    assert_eq!(e.version, FmiVersion::V3);
    assert_eq!(e.variables, two.variables);
    let entries = unzip(&std::fs::read(dir.join("three.fmu")).unwrap());
    let get = |n: &str| entries.iter().find(|(name, _)| name == n).map(|(_, d)| d.clone());
    assert!(get("binaries/x86_64-linux/arm_three.so").is_some());
    assert!(get("binaries/linux64/arm_three.so").is_none());
    let manifest: Manifest = serde_json::from_slice(&get("resources/flexmbs-fmu.json").unwrap()).unwrap();
    let xml = String::from_utf8(get("modelDescription.xml").unwrap()).unwrap();
    assert!(xml.contains(r#"fmiVersion="3.0""#), "{xml}");
    assert!(xml.contains(&format!(r#"instantiationToken="{}""#, manifest.guid)));
    assert!(!xml.contains("ScalarVariable") && !xml.contains("guid="));
    assert!(xml.contains(r#"<CoSimulation modelIdentifier="arm_three""#));
    let floats = xml.matches("<Float64 ").count();
    assert_eq!(floats, manifest.variables.len() + 1, "the variables and time");
    let n = manifest.variables.len();
    assert!(xml.contains(&format!(
        r#"<Float64 name="time" valueReference="{n}" description="time of the analysis" causality="independent""#
    )));
    assert!(xml.contains(r#"<Unit name="s"/>"#));
    for (vr, v) in manifest.variables.iter().enumerate() {
        let line = xml
            .lines()
            .find(|l| l.contains(&format!(r#"valueReference="{vr}" "#)) && l.contains("<Float64 "))
            .unwrap_or_else(|| panic!("variable {vr} in {xml}"));
        assert!(line.contains(&format!(r#"causality="{}""#, v.causality())), "{line}");
        if let Some(u) = &v.unit {
            assert!(line.contains(&format!(r#"unit="{u}""#)), "{line}");
            assert!(xml.contains(&format!(r#"<Unit name="{u}"/>"#)));
        }
        let is_output = matches!(v.kind, VarKind::Output { .. });
        assert_eq!(xml.contains(&format!(r#"<Output valueReference="{vr}"/>"#)), is_output);
    }
    assert!(study::fmu::FmiVersion::parse("4").is_err());
    assert_eq!(study::fmu::FmiVersion::parse("3.0").unwrap(), FmiVersion::V3);
}

/// An actuator called `time` would be a second FMU variable of the name FMI gives the
/// independent variable: the export refuses it by the actuator's name.
#[test]
fn an_fmu_variable_called_time_is_refused() {
    let file = example_as("controlled_arm", "fmu-time-actuator");
    let text = std::fs::read_to_string(&file).unwrap()
        + "\n[[actuators]]\nname = \"time\"\njoint = \"motor-axis\"\nfunction = { type = \"constant-speed\", speed = 0.0 }\n";
    let doc = study::input::document::Document::from_text(&text, &file).unwrap();
    let dir = scratch("fmu-time-actuator-out");
    let library = dir.join("lib.so");
    std::fs::write(&library, b"the library").unwrap();
    let err = study::fmu::export_document(&doc, None, FmiVersion::V2, &library, &dir.join("arm.fmu"))
        .map(|_| ())
        .expect_err("an actuator called time is refused")
        .to_string();
    assert!(err.contains("independent variable is called 'time'"), "{err}");
    assert!(err.contains("actuator 'time'"), "{err}");
    assert!(!dir.join("arm.fmu").exists());
}

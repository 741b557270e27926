//! Stresses in study files: a load at a load point inside a reduced solid body in an
//! `equilibrium` analysis against the full FE static stress of the same part under the same
//! load (the static correction makes them agree), read through `stress` sensors at a node and
//! over a node set, which agree with the mechanism's VTU stress fields of the same state.

use crate::common::{material, rectangle, BeamPart};
use crate::vtu_array;
use std::path::PathBuf;
use study::output::observer::Recorder;

/// `text` written as `<name>.toml` in a scratch folder and run, in memory and into its
/// results folder (for the VTU files).
fn run(name: &str, text: &str) -> (Recorder, Result<study::output::summary::Summary, String>, PathBuf) {
    let dir = crate::scratch(name);
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, text).unwrap();
    let study = study::load(&file).unwrap();
    let mut rec = Recorder::default();
    let summary = study::run(&study, &crate::options_in(&dir, None), &mut rec).map_err(|e| study::error::chain(&*e));
    (rec, summary, file)
}

const TIP: [f64; 3] = [2e2, -3e3, 1e3];

/// A clamped steel hex20 bar 1 x 0.1 x 0.1 m: its full FE static analysis under the tip force
/// `TIP` at the node (1, 0.05, 0.05), and the same part reduced with 2 modes, stress shapes and
/// a load point "tip" at that node, clamped at its root in a one-body mechanism with the same
/// force at the load point. `sensors`: extra `[[sensors]]` text.
fn study(sensors: &str) -> String {
    let [fx, fy, fz] = TIP;
    let steel = material("steel", 210e9, 0.3, 7850.0);
    format!(
        r#"
{steel}
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
load_points = [{{ name = "tip", node_at = [1.0, 0.05, 0.05] }}]

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
force = [{fx}, {fy}, {fz}]

{sensors}

[[analyses]]
type = "static"
name = "full"
part = "bar"
supports = [{{ at = "root" }}]
loads = [{{ node_at = [1.0, 0.05, 0.05], force = [{fx}, {fy}, {fz}] }}]

[[analyses]]
type = "equilibrium"
name = "reduced"
"#
    )
}

/// The point field `name` of the one VTU file in the results folder of `analysis`.
fn vtu_field(file: &std::path::Path, analysis: &str, name: &str) -> Vec<f64> {
    let dir = file.parent().unwrap().join("results").join(analysis);
    let vtu = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "vtu"))
        .max()
        .unwrap_or_else(|| panic!("no VTU file in {}", dir.display()));
    vtu_array(&std::fs::read_to_string(vtu).unwrap(), name).unwrap_or_else(|| panic!("no point field {name}"))
}

#[test]
fn a_load_at_a_load_point_gives_the_full_models_stress_through_stress_sensors() {
    // First the full model alone, for its ten most stressed nodes.
    let (_, summary, file) = run("stress-full", &study(""));
    summary.unwrap();
    let full = vtu_field(&file, "full", "von_mises");
    let mut order: Vec<usize> = (0..full.len()).collect();
    order.sort_by(|&a, &b| full[b].total_cmp(&full[a]));
    let hot = &order[..10];
    let mut sensors: String = hot
        .iter()
        .map(|k| format!("[[sensors]]\nname = \"n{k}\"\ntype = \"stress\"\nof = \"bar\"\nnode = {k}\n\n"))
        .collect();
    sensors.push_str("[[sensors]]\nname = \"top\"\ntype = \"stress\"\nof = \"bar\"\nset = \"y1\"\n");
    let (rec, summary, file) = run("stress-reduced", &study(&sensors));
    summary.unwrap();
    let full = vtu_field(&file, "full", "von_mises");
    let reduced_vtu = vtu_field(&file, "reduced", "von_mises");
    let tensor_vtu = vtu_field(&file, "reduced", "stress");
    let principal_vtu = vtu_field(&file, "reduced", "max_principal");
    let value = |name: &str, c: usize| *crate::setup::column(&rec, "reduced", name, c).last().unwrap();
    let mut worst: f64 = 0.0;
    for &k in hot {
        let vm = value(&format!("n{k}"), 6);
        worst = worst.max((vm - full[k]).abs() / full[k]);
        // The sensor and the VTU field are the same recovery of the same state; the VTU
        // text keeps about 10 significant digits.
        assert!(
            (vm - reduced_vtu[k]).abs() <= 1e-8 * vm,
            "node {k}: sensor {vm}, VTU {}",
            reduced_vtu[k]
        );
        for c in 0..6 {
            let s = value(&format!("n{k}"), c);
            assert!((s - tensor_vtu[6 * k + c]).abs() <= 1e-8 * vm, "node {k} component {c}");
        }
        assert!((value(&format!("n{k}"), 7) - principal_vtu[k]).abs() <= 1e-8 * vm);
    }
    // The required accuracy: 1 % at the ten most stressed nodes. With the attachment modes
    // the reduced static response to a load at the point is exact in the linear theory; what
    // remains is the geometric nonlinearity of the equilibrium (tip deflection 6e-4 m on 1 m)
    // and the Newton tolerance.
    assert!(worst < 1e-2, "worst von Mises error at the ten hot nodes {worst:.3e}");
    eprintln!(
        "stress at the ten most stressed nodes, reduced (2 modes + static correction) vs full: worst {worst:.3e}"
    );
    // The maximum over the node set: value and node against the VTU field over the same set.
    let top = value("top", 0);
    let node = value("top", 1) as usize;
    assert!((top - reduced_vtu[node]).abs() <= 1e-8 * top);
    let study = study::load(&file).unwrap();
    let set = study.parts[0].base.mesh.node_set("y1").unwrap();
    let best = set.iter().map(|n| reduced_vtu[n.index()]).fold(0.0, f64::max);
    assert!(
        (top - best).abs() <= 1e-8 * top,
        "max over y1: sensor {top}, VTU {best}"
    );
}

/// A stress sensor on a body reduced without stress shapes, or at a node it does not have, is
/// refused when the study runs, naming the sensor's key.
#[test]
fn stress_sensors_name_what_is_wrong() {
    let text = study("[[sensors]]\nname = \"s\"\ntype = \"stress\"\nof = \"bar\"\nnode = 100000\n");
    let (_, summary, _) = run("stress-bad-node", &text);
    let e = summary.unwrap_err();
    assert!(e.contains("sensors[0].node") && e.contains("mesh nodes"), "{e}");
    let text = study("[[sensors]]\nname = \"s\"\ntype = \"stress\"\nof = \"bar\"\nset = \"nowhere\"\n");
    let (_, summary, _) = run("stress-bad-set", &text);
    let e = summary.unwrap_err();
    assert!(e.contains("no node set 'nowhere'"), "{e}");
    let text = study("").replace("at = \"bar.tip\"", "at = \"bar.tap\"");
    // Refused when the study is validated (the part declares its load points), at the key.
    let dir = crate::scratch("stress-bad-point");
    let file = dir.join("stress-bad-point.toml");
    std::fs::write(&file, text).unwrap();
    let Err(e) = study::load(&file) else {
        panic!("a load at an unknown load point was accepted")
    };
    let e = e.to_string();
    assert!(
        e.contains("loads[0].at") && e.contains("no interface or load point 'tap'") && e.contains("'tip'"),
        "{e}"
    );
}

/// A load at a load point inside a body is changed between steps by `Simulation::set_load`
/// as a load at a node is: doubling the force after three steps gives, to the bit, the run of
/// a file whose load doubles between the third and the fourth step by its time function.
#[test]
fn set_load_changes_a_load_at_a_load_point_between_steps() {
    let dynamic = "[[analyses]]\ntype = \"dynamic\"\nname = \"shake\"\nt_end = 0.002\ndt = 1e-4\n";
    let sensor = "[[sensors]]\nname = \"top\"\ntype = \"stress\"\nof = \"bar\"\nset = \"y1\"\n";
    let simulation = |name: &str, function: &str| {
        let [fx, fy, fz] = TIP;
        let force = format!("force = [{fx}, {fy}, {fz}]\n");
        let text = study(sensor).replace(&force, &format!("{force}{function}")) + dynamic;
        let dir = crate::scratch(name);
        let file = dir.join(format!("{name}.toml"));
        std::fs::write(&file, text).unwrap();
        let study = study::load(&file).unwrap();
        study::Simulation::new(&study, "shake", &crate::options_in(&dir, None)).unwrap()
    };
    // The factor is 1 up to the third step's end (3e-4 s) and 2 from the fourth's (4e-4 s).
    let table = "function = { type = \"table\", t = [0.0, 3e-4, 4e-4, 1.0], value = [1.0, 1.0, 2.0, 2.0] }\n";
    let mut a = simulation("set-load-point-a", "");
    let mut b = simulation("set-load-point-b", "");
    let mut d = simulation("set-load-point-d", table);
    assert!(a.load_names().contains(&"tip-force"), "{:?}", a.load_names());
    for _ in 0..3 {
        for s in [&mut a, &mut b, &mut d] {
            s.step().unwrap();
        }
    }
    b.set_load("tip-force", mbs::LoadKind::Force, TIP.map(|x| 2.0 * x))
        .unwrap();
    for _ in 0..10 {
        for s in [&mut a, &mut b, &mut d] {
            s.step().unwrap();
        }
        assert_eq!(b.read().unwrap(), d.read().unwrap(), "t = {}", b.time());
    }
    // And the change acts: the unchanged run is far below (about half the stress).
    let (va, vb) = (a.sensor("top").unwrap()[0], b.sensor("top").unwrap()[0]);
    assert!(vb > 1.5 * va, "{va} {vb}");
    // A load point has a force and a moment; an unknown name and a bad value are named.
    b.set_load("tip-force", mbs::LoadKind::Moment, [0.0, 0.0, 0.0]).unwrap();
    let e = b.set_load("tip-forse", mbs::LoadKind::Force, TIP).unwrap_err();
    assert!(e.to_string().contains("tip-force"), "{e}");
    let e = b
        .set_load("tip-force", mbs::LoadKind::Force, [f64::NAN, 0.0, 0.0])
        .unwrap_err();
    assert!(e.to_string().contains("non-finite"), "{e}");
}

/// The hot spot of a dynamic analysis (peak von Mises over every node and output time) is the
/// same, to the bit, whether every output time writes a VTU frame (every node's stresses) or
/// none (the bounded search of the largest von Mises).
#[test]
fn the_hot_spot_of_a_run_is_the_same_with_and_without_vtu_frames() {
    // 100 output times: more than one batch of the search (the last one partial).
    let dynamic = "[[analyses]]\ntype = \"dynamic\"\nname = \"shake\"\nt_end = 0.01\ndt = 1e-4\n";
    let hot = |name: &str, output: &str| {
        let text = study("") + dynamic + output;
        let (_, summary, _) = run(name, &text);
        let summary = summary.unwrap();
        let a = summary.analyses.iter().find(|a| a.name == "shake").unwrap();
        a.results["hot_spots"][0].clone()
    };
    let framed = hot("hot-spot-vtu", "\n[output]\nvtu_every = 1\n");
    let tracked = hot("hot-spot-track", "");
    assert!(framed["von_mises_Pa"].as_f64().unwrap() > 1e6, "{framed}");
    assert_eq!(framed, tracked);
}

/// A largest-von-Mises sensor in a dynamic run (its rows completed a batch of output times at
/// a time) gives at every output time the largest von Mises stress over its node set of that
/// time's VTU frame (every node's stresses) and its node; and the same values, to the bit, as
/// the same run stepped by a `Simulation`, which records each row alone. 100 output times:
/// more than one batch, the last one partial.
#[test]
fn a_largest_von_mises_sensor_gives_every_output_times_maximum() {
    let sensor = "[[sensors]]\nname = \"top\"\ntype = \"stress\"\nof = \"bar\"\nset = \"y1\"\n";
    let dynamic = "[[analyses]]\ntype = \"dynamic\"\nname = \"shake\"\nt_end = 0.01\ndt = 1e-4\n";
    let text = study(sensor) + dynamic + "\n[output]\nvtu_every = 1\n";
    let (rec, summary, file) = run("stress-max-batches", &text);
    summary.unwrap();
    let values = crate::setup::column(&rec, "shake", "top", 0);
    let nodes = crate::setup::column(&rec, "shake", "top", 1);
    assert_eq!(values.len(), 101, "the start and 100 steps");
    let dir = file.parent().unwrap().join("results").join("shake");
    let mut frames: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "vtu"))
        .collect();
    frames.sort();
    assert_eq!(frames.len(), values.len());
    let study = study::load(&file).unwrap();
    let set = study.parts[0].base.mesh.node_set("y1").unwrap();
    for (k, frame) in frames.iter().enumerate() {
        let vm = vtu_array(&std::fs::read_to_string(frame).unwrap(), "von_mises").unwrap();
        let best = set.iter().map(|n| vm[n.index()]).fold(0.0, f64::max);
        // The VTU text keeps about 10 significant digits.
        assert!(
            (values[k] - best).abs() <= 1e-8 * best.max(1e-300),
            "output {k}: sensor {}, VTU {best}",
            values[k]
        );
        let node = nodes[k] as usize;
        assert!(
            (vm[node] - best).abs() <= 1e-8 * best.max(1e-300),
            "output {k}: node {node}"
        );
    }
    assert!(values.iter().fold(0.0f64, |m, v| m.max(*v)) > 1e6, "{values:?}");
    // The same run stepped, each row recorded alone: the same values to the bit.
    let mut sim = study::Simulation::new(&study, "shake", &crate::options_in(file.parent().unwrap(), None)).unwrap();
    assert_eq!(sim.sensor("top").unwrap(), [values[0], nodes[0]]);
    for k in 1..values.len() {
        sim.step().unwrap();
        let row = sim.sensor("top").unwrap();
        assert_eq!(row[0].to_bits(), values[k].to_bits(), "output {k}");
        assert_eq!(row[1], nodes[k], "output {k}");
    }
}

/// A modal analysis writes the stress of each mass-normalised mode shape: the first bending
/// mode of a clamped Euler-Bernoulli steel beam (L = 2 m, b x h = 0.02 x 0.04 m, bending
/// about the weak axis) has its largest fibre stress at the root, E c phi''(0) with
/// phi(x) = A [cosh bx - cos bx - s (sinh bx - sin bx)], b L = 1.875104, A = 1/sqrt(rho A_c L)
/// for unit modal mass: phi''(0) = 2 A b^2, c = b/2.
#[test]
fn a_modal_analysis_writes_the_stress_of_each_mode_shape() {
    let text = [
        material("steel", 210e9, 0.3, 7850.0),
        rectangle("bar", 0.02, 0.04),
        BeamPart {
            name: "beam",
            material: "steel",
            section: "bar",
            length: 2.0,
            elements: 40,
            theory: Some("euler-bernoulli"),
            orientation: Some([0.0, 1.0, 0.0]),
            interfaces: &[("root", "beam.start")],
            modes: None,
        }
        .toml(),
        r#"[[analyses]]
type = "modal"
name = "modes"
part = "beam"
modes = 2
supports = [{ at = "root" }]
"#
        .to_string(),
    ]
    .concat();
    let (_, summary, file) = run("modal-stress", &text);
    summary.unwrap();
    let vtu = file.parent().unwrap().join("results/modes/mode_001.vtu");
    let text = std::fs::read_to_string(&vtu).unwrap_or_else(|e| panic!("{}: {e}", vtu.display()));
    let von_mises = vtu_array(&text, "von_mises").expect("a von_mises point field");
    let peak = von_mises.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let (e, rho, l, b, h): (f64, f64, f64, f64, f64) = (210e9, 7850.0, 2.0, 0.02, 0.04);
    let beta = 1.875_104_068_711_961 / l;
    let a = 1.0 / (rho * b * h * l).sqrt();
    let exact = e * (b / 2.0) * 2.0 * a * beta * beta;
    // Measured 2.9e-5 with 40 cubic elements: the root moment of the FE mode converges at
    // O(h^2) ((beta h)^2 = 2e-3, with a small constant), and the consistent mass carries rotary
    // inertia the analytic shape leaves out. 2e-4 is that with a margin, ten times below a
    // wrong fibre distance or normalisation (which would be off by a factor).
    assert!(
        (peak - exact).abs() < 2e-4 * exact,
        "largest von Mises of mode 1: {peak:.6e} Pa against {exact:.6e} Pa ({:.2e})",
        peak / exact - 1.0
    );
}

/// A part from a deck numbered 101, 202, ... (`hex20_labels.inp`): the hot spot of the
/// summary and a stress sensor's error name its nodes by the deck's numbers, the 0-based
/// index beside them.
#[test]
fn hot_spots_and_stress_sensor_errors_name_nodes_by_the_decks_labels() {
    let deck = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fe-model/tests/data/import/hex20_labels.inp")
        .display()
        .to_string();
    let text = |sensors: &str| {
        format!(
            r#"
[[parts]]
name = "bar"
[parts.mesh]
file = "{deck}"
[[parts.interfaces]]
name = "root"
set = "clamp"
spider = "rbe2"
[[parts.interfaces]]
name = "tip"
set = "tip"
spider = "rbe3"
[parts.reduction]
modes = 2
stress_shapes = true

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
force = [0.0, -3e3, 1e3]
{sensors}
[[analyses]]
type = "equilibrium"
name = "reduced"
"#
        )
    };
    let (_, summary, _) = run("labels-hot-spot", &text(""));
    let summary = summary.unwrap();
    let hot = &summary.analyses[0].results["hot_spots"][0];
    let (index, label) = (hot["node"].as_u64().unwrap(), hot["node_label"].as_u64().unwrap());
    // The deck numbers node n as 100 n + n % 7 (make_unit_twins.py), in order of definition.
    let n = index + 1;
    assert_eq!(label, 100 * n + n % 7, "{hot}");
    // A stress sensor between nodes names the nearest by its label.
    let sensor = "[[sensors]]\nname = \"s\"\ntype = \"stress\"\nof = \"bar\"\nnode_at = [0.5, 0.1, 0.19]\n";
    let (_, summary, _) = run("labels-sensor", &text(sensor));
    let e = summary.unwrap_err();
    assert!(e.contains("the nearest, node 5506 (index 54)"), "{e}");
    // A stress sensor by the deck's label reads the node of that index, the hot spot.
    let pair = format!(
        "[[sensors]]\nname = \"by-index\"\ntype = \"stress\"\nof = \"bar\"\nnode = {index}\n\
         [[sensors]]\nname = \"by-label\"\ntype = \"stress\"\nof = \"bar\"\nlabel = {label}\n\
         [[sensors]]\nname = \"tip\"\ntype = \"stress\"\nof = \"bar\"\nset = \"tip\"\n"
    );
    let (rec, summary, _) = run("labels-by-label", &text(&pair));
    summary.unwrap();
    for c in 0..8 {
        let (by_index, by_label) = (
            crate::setup::column(&rec, "reduced", "by-index", c),
            crate::setup::column(&rec, "reduced", "by-label", c),
        );
        assert_eq!(by_index, by_label, "column {c}");
    }
    let vm = crate::setup::column(&rec, "reduced", "by-label", 6);
    let hot_vm = hot["von_mises_Pa"].as_f64().unwrap();
    assert!((vm[0] - hot_vm).abs() <= 1e-9 * hot_vm, "sensor {vm:?}, hot spot {hot}");
    // A sensor over a set of a deck's part gives the deck's label beside the node's index.
    let (node, node_label) = (
        crate::setup::column(&rec, "reduced", "tip", 1),
        crate::setup::column(&rec, "reduced", "tip", 2),
    );
    let n = node[0] as u64 + 1;
    assert_eq!(node_label[0], (100 * n + n % 7) as f64, "node {node:?}");
    // An index is not a label: the deck has no node 54.
    let sensor = "[[sensors]]\nname = \"s\"\ntype = \"stress\"\nof = \"bar\"\nlabel = 54\n";
    let (_, summary, _) = run("labels-unknown", &text(sensor));
    let e = summary.unwrap_err();
    assert!(e.contains("sensors[0].label"), "{e}");
    assert!(e.contains("part 'bar' has no node 54"), "{e}");
}

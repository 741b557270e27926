#![allow(non_snake_case)]

use crate::support::*;

/// The cantilever example prints, and writes, the tip deflection of beam theory (exact for
/// the Timoshenko element under a tip load) and the first bending frequency.
#[test]
fn cantilever_example_matches_beam_theory() {
    let dir = examples_copy("cantilever");
    let out = flexmbs(&dir, &["run", "cantilever.toml"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let results = dir.join("cantilever-results");

    // validation problem A2: tip force P along -z bends about y (Iy = b h^3/12), with shear.
    let (L, E, nu, rho, b, h, P): (f64, f64, f64, f64, f64, f64, f64) = (2.0, 210e9, 0.3, 7850.0, 0.02, 0.04, 100.0);
    let (A, Iy, Iz) = (b * h, b * h * h * h / 12.0, h * b * b * b / 12.0);
    let G = E / (2.0 * (1.0 + nu));
    let k = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu); // Cowper, as BeamSection::rectangle
    let tip = P * L.powi(3) / (3.0 * E * Iy) + P * L / (k * G * A);
    let uz = csv_value(&results.join("tip-load/interfaces.csv"), "tip", "uz [m]");
    assert_close(-uz, tip, 1e-9, "tip deflection");
    assert!(
        out.stdout
            .contains("interface 'tip': u = (0.000000e0, 0.000000e0, -1.190840e-2) m"),
        "{}",
        out.stdout
    );

    // validation problem A1: Euler-Bernoulli clamped-free, first mode about z; Timoshenko with
    // rotary inertia is a little lower (8e-5 here).
    let f1 = 1.875_104_07_f64.powi(2) * (E * Iz / (rho * A * L.powi(4))).sqrt() / (2.0 * std::f64::consts::PI);
    let f = csv_value(&results.join("clamped-modes/frequencies.csv"), "1", "frequency [Hz]");
    assert_close(f, f1, 2e-4, "first bending frequency");

    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(results.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "complete");
    assert_eq!(summary["analyses"][2]["results"]["coordinates"], 16);
    for file in [
        "summary.md",
        "tip-load/static.vtu",
        "tip-load/static.pvd",
        "tip-load/displacements.csv",
        "tip-load/reactions.csv",
        "clamped-modes/mode_006.vtu",
        "clamped-modes/modes.pvd",
        "reduce-beam/beam.rbody",
        "reduce-beam/fixed_interface_modes.csv",
        "reduce-beam/shapes.pvd",
        "reduce-beam/shape_016.vtu",
    ] {
        assert!(results.join(file).is_file(), "{file} is missing");
    }
    let (header, _) = read_csv(&results.join("tip-load/displacements.csv"));
    assert_eq!(header[5], "ux [m]", "CSV headers carry units");
}

/// The solid example: a gmsh tet10 bar with RBE2 and RBE3 interfaces, a hex20 box.
#[test]
fn solid_bar_example_runs() {
    let dir = examples_copy("solid_bar");
    let out = flexmbs(&dir, &["run", "solid_bar.toml"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let results = dir.join("solid_bar-results");
    // A coarse quadratic-tet bar (two tets across) with a rigid clamp is stiffer than beam
    // theory (P L^3/3EI + P L/kGA = 3.68e-5 m), by about 15 %.
    let (L, E, nu, a, P): (f64, f64, f64, f64, f64) = (1.0, 70e9, 0.33, 0.2, 1000.0);
    let I = a.powi(4) / 12.0;
    let beam = P * L.powi(3) / (3.0 * E * I) + P * L / (5.0 / 6.0 * E / (2.0 * (1.0 + nu)) * a * a);
    let uz = -csv_value(&results.join("bar-bending/interfaces.csv"), "tip", "uz [m]");
    assert!(
        uz > 0.75 * beam && uz < beam,
        "tip deflection {uz} against beam theory {beam}"
    );
    // Free-free modes: six rigid-body modes, then a bending pair (square section).
    let (_, rows) = read_csv(&results.join("block-free/frequencies.csv"));
    let f: Vec<f64> = rows.iter().map(|r| r[1].parse().unwrap()).collect();
    assert!(f[..6].iter().all(|x| x.abs() < 1.0), "rigid-body modes {f:?}");
    assert_close(f[7], f[6], 1e-6, "bending pair");
    assert!(f[6] > 800.0 && f[6] < 1050.0, "first bending frequency {}", f[6]);
    // The block has its two interfaces and the auxiliary one.
    let (_, rows) = read_csv(&results.join("reduce-block/interfaces.csv"));
    let names: Vec<&str> = rows.iter().map(|r| r[1].as_str()).collect();
    assert_eq!(names, ["root", "end", "auxiliary"]);
    assert!(results.join("reduce-bar/bar.rbody").is_file());
    assert!(out.stdout.contains("reduce 'reduce-bar'"), "{}", out.stdout);
}

/// The README's command: `flexmbs run` without a file runs the built-in slider-crank (C2)
/// into `./slider_crank-results/` and draws its deflection plot.
#[test]
fn run_without_a_file_runs_the_builtin_example() {
    let dir = scratch("builtin");
    let out = flexmbs(&dir, &["run", "--t-end", "0.02"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(
        out.stdout.contains("rod midpoint deflection: largest |w|"),
        "{}",
        out.stdout
    );
    let results = dir.join("slider_crank-results");
    assert!(results.join("slider-crank.png").is_file());
    assert!(results.join("run-up/rod-mid.csv").is_file());
}

#[test]
fn example_command_lists_and_writes_examples() {
    let dir = scratch("example-command");
    let out = flexmbs(&dir, &["example"]);
    assert_eq!(out.code, 0);
    assert!(
        out.stdout.contains("cantilever") && out.stdout.contains("solid_bar"),
        "{}",
        out.stdout
    );

    let out = flexmbs(&dir, &["example", "solid_bar", "mine"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(dir.join("mine/solid_bar.toml").is_file());
    assert!(dir.join("mine/meshes/bar_tet10.msh").is_file());
    let out = flexmbs(&dir, &["check", "mine/solid_bar.toml"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stdout.contains("valid: 2 parts, 4 analyses"), "{}", out.stdout);

    // Writing again over identical files is fine; over an edited one, refused.
    assert_eq!(flexmbs(&dir, &["example", "solid_bar", "mine"]).code, 0);
    std::fs::write(dir.join("mine/solid_bar.toml"), "# edited\n").unwrap();
    let out = flexmbs(&dir, &["example", "solid_bar", "mine"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("exists with other contents"), "{}", out.stderr);

    let out = flexmbs(&dir, &["example", "cantilevr"]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr
            .contains("unknown example 'cantilevr'; did you mean 'cantilever'?"),
        "{}",
        out.stderr
    );
}

#[test]
fn inspect_shows_a_reduced_body() {
    let dir = examples_copy("inspect");
    let out = flexmbs(&dir, &["reduce", "cantilever.toml", "--out", "bodies"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(dir.join("bodies/beam.rbody").is_file());
    let out = flexmbs(&dir, &["inspect", "bodies/beam.rbody", "--excitation-hz", "20"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    for text in [
        "reduced body 'beam'",
        "CB coordinates: 16 = 6 x 2 interfaces + 4 fixed-interface modes",
        "mass            1.256000e1 kg",
        "root",
        "tip",
        "Tx",
        "excitation up to 2.0000e1 Hz",
        "physical checks: passed",
    ] {
        assert!(out.stdout.contains(text), "missing '{text}' in\n{}", out.stdout);
    }
    // A generated mesh has no deck labels: the label column is blank.
    let row = |stdout: &str, name: &str| -> Vec<String> {
        let line = stdout
            .lines()
            .find(|l| {
                let mut w = l.split_whitespace();
                w.next().is_some_and(|k| k.parse::<usize>().is_ok()) && w.next() == Some(name)
            })
            .unwrap();
        line.split_whitespace().map(String::from).collect()
    };
    assert_eq!(row(&out.stdout, "root").len(), 6, "{}", out.stdout);
    // An interface on a deck node shows the deck's number beside the FE node.
    let mut body = reduction::file::read(&dir.join("bodies/beam.rbody")).unwrap();
    body.interfaces[0].node_label = Some(1001);
    reduction::file::write(&body, &dir.join("bodies/labelled.rbody")).unwrap();
    let out = flexmbs(&dir, &["inspect", "bodies/labelled.rbody"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let root = row(&out.stdout, &body.interfaces[0].name);
    assert_eq!(root[3], "1001", "{}", out.stdout);
    assert_eq!(root[2], body.interfaces[0].node.to_string(), "{}", out.stdout);
    // A copy with a negative modal stiffness and valid checksums: inspect names the problem,
    // a study refuses the file.
    let mut body = reduction::file::read(&dir.join("bodies/beam.rbody")).unwrap();
    let i = 12 + 12 * body.K_CB.nrows;
    body.K_CB.data[i] = -body.K_CB.data[i];
    reduction::file::write(&body, &dir.join("bodies/bad.rbody")).unwrap();
    // The report is printed in full, and the exit code says the checks failed.
    let out = flexmbs(&dir, &["inspect", "bodies/bad.rbody"]);
    assert_eq!(out.code, 1, "{}", out.stderr);
    assert!(
        out.stderr.contains("physical check") && out.stderr.contains("studies refuse it"),
        "{}",
        out.stderr
    );
    for text in [
        "physical checks: FAILED",
        "K_CB is indefinite",
        "contradicts K_CB and M_CB",
    ] {
        assert!(out.stdout.contains(text), "missing '{text}' in\n{}", out.stdout);
    }
    assert!(reduction::file::read(&dir.join("bodies/bad.rbody")).is_err());
    let out = flexmbs(&dir, &["inspect", "cantilever.toml"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("not a reduced-body file"), "{}", out.stderr);
    let out = flexmbs(&dir, &["inspect", "missing.rbody"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("missing.rbody"), "{}", out.stderr);
}

#[test]
fn export_fem_writes_an_mbdyn_file_that_a_study_reads_back() {
    let dir = examples_copy("export-fem");
    let out = flexmbs(&dir, &["reduce", "cantilever.toml", "--out", "bodies"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let out = flexmbs(
        &dir,
        &["export-fem", "bodies/beam.rbody", "beam.fem", "--reference", "root"],
    );
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stdout.contains("modal node at interface 'root'"), "{}", out.stdout);
    let text = std::fs::read_to_string(dir.join("beam.fem")).unwrap();
    assert!(text.starts_with("** MBDyn MODAL DATA FILE"));
    // The .fem file as a body of a study: its exposed nodes are the interfaces.
    std::fs::write(
        dir.join("fem.toml"),
        "[[bodies]]\nname = \"beam\"\nfile = \"beam.fem\"\n\n[[analyses]]\nname = \"modes\"\ntype = \"linearized\"\n",
    )
    .unwrap();
    let out = flexmbs(&dir, &["check", "fem.toml"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    // inspect reads it with the physical checks and what they measured.
    let out = flexmbs(&dir, &["inspect", "beam.fem"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    for text in [
        "MBDyn modal element file",
        "physical checks, measured",
        "closest interfaces",
        "physical checks: passed",
    ] {
        assert!(out.stdout.contains(text), "missing '{text}' in\n{}", out.stdout);
    }
    // Record 12 with the mass 12.5 times too small: inspect fails it (exit 1), a study
    // refuses it (exit 2), both naming the record.
    let at = text.find("** RECORD GROUP 12").unwrap();
    let start = at + text[at..].find('\n').unwrap() + 1;
    let end = start + text[start..].find('\n').unwrap();
    let mass: f64 = text[start..end].trim().parse().unwrap();
    let mut wrong = text.clone();
    wrong.replace_range(start..end, &format!("{:.17e}", mass / 12.5));
    std::fs::write(dir.join("beam.fem"), wrong).unwrap();
    let out = flexmbs(&dir, &["inspect", "beam.fem"]);
    assert_eq!(out.code, 1, "{}", out.stderr);
    assert!(
        out.stdout.contains("physical checks: FAILED") && out.stdout.contains("record 12 mass"),
        "{}",
        out.stdout
    );
    let out = flexmbs(&dir, &["check", "fem.toml"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains("bodies[0].file")
            && out.stderr.contains("beam.fem")
            && out.stderr.contains("record 12 mass"),
        "{}",
        out.stderr
    );
    // Usage errors name what is wrong.
    let out = flexmbs(
        &dir,
        &["export-fem", "bodies/beam.rbody", "x.fem", "--reference", "rot"],
    );
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.contains("no interface 'rot'") && out.stderr.contains("root"),
        "{}",
        out.stderr
    );
    let out = flexmbs(&dir, &["export-fem", "bodies/beam.rbody"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("export-fem needs"), "{}", out.stderr);
}

#[test]
fn reduce_command_selects_a_part() {
    let dir = examples_copy("reduce-part");
    let out = flexmbs(&dir, &["reduce", "solid_bar.toml", "--part", "block", "--out", "b"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(dir.join("b/block.rbody").is_file() && !dir.join("b/bar.rbody").exists());
    assert!(out.stderr.contains("reducing"), "progress on stderr: {}", out.stderr);
    let out = flexmbs(&dir, &["reduce", "solid_bar.toml", "--part", "blok"]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.contains("unknown part 'blok'; did you mean 'block'?"),
        "{}",
        out.stderr
    );
}

#[test]
fn usage_errors_exit_with_2() {
    let dir = scratch("usage");
    let out = flexmbs(&dir, &[]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("no command given"), "{}", out.stderr);
    let out = flexmbs(&dir, &["rnu"]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.contains("unknown command 'rnu'; did you mean `run`?"),
        "{}",
        out.stderr
    );
    let out = flexmbs(&dir, &["run", "--outt", "x", "a.toml"]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.contains("unknown option --outt; did you mean --out?"),
        "{}",
        out.stderr
    );
    let out = flexmbs(&dir, &["check", "nothing-here.toml"]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.contains("cannot read study file nothing-here.toml"),
        "{}",
        out.stderr
    );
    let out = flexmbs(&dir, &["--help"]);
    assert_eq!(out.code, 0);
    assert!(out.stdout.contains("flexmbs inspect FILE.rbody"));
}

/// An analysis that fails at run time stops the run with exit code 2, a message that points
/// at the analysis in the study file, and the results of the analyses before it kept.
#[test]
fn a_failing_analysis_keeps_earlier_results() {
    let dir = scratch("failing");
    let study = r#"
[[materials]]
name = "steel"
E = 210e9
nu = 0.3
rho = 7850.0

[[sections]]
name = "round"
shape = "circle"
d = 0.01

[[parts]]
name = "beam"
material = "steel"
[parts.beam]
kind = "straight"
from = [0.0, 0.0, 0.0]
to = [1.0, 0.0, 0.0]
elements = 4
section = "round"

[[analyses]]
type = "modal"
part = "beam"
modes = 8

[[analyses]]
type = "static"
name = "unsupported"
part = "beam"
loads = [{ at = "beam.end", force = [0.0, 0.0, 1.0] }]
"#;
    std::fs::write(dir.join("free.toml"), study).unwrap();
    let out = flexmbs(&dir, &["run", "free.toml"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr
            .contains("static analysis 'unsupported' (free.toml:28:1) failed"),
        "{}",
        out.stderr
    );
    assert!(out.stderr.contains("mechanism"), "{}", out.stderr);
    let results = dir.join("free-results");
    assert!(results.join("modal-beam/frequencies.csv").is_file());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(results.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "failed");
    assert_eq!(summary["analyses"][0]["status"], "done");
    assert_eq!(summary["analyses"][1]["status"], "failed");
}

/// `inspect` reads the stress shapes back from the file: a beam reduced without them says
/// "not kept"; with `stress_shapes = true` the section forces of each of its 20 elements are
/// kept (a beam has no solid nodes).
#[test]
fn inspect_says_whether_a_body_keeps_its_stress_shapes() {
    let dir = examples_copy("inspect-stress");
    let out = flexmbs(&dir, &["reduce", "cantilever.toml", "--out", "plain"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let out = flexmbs(&dir, &["inspect", "plain/beam.rbody"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stdout.contains("stress shapes: not kept"), "{}", out.stdout);
    let text = std::fs::read_to_string(dir.join("cantilever.toml")).unwrap().replace(
        "[parts.reduction]\nmodes = 4",
        "[parts.reduction]\nmodes = 4\nstress_shapes = true",
    );
    assert!(text.contains("stress_shapes = true"));
    std::fs::write(dir.join("stressed.toml"), text).unwrap();
    let out = flexmbs(&dir, &["reduce", "stressed.toml", "--out", "kept"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let out = flexmbs(&dir, &["inspect", "kept/beam.rbody"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(
        out.stdout
            .contains("stress shapes: kept, solid stresses on 0 nodes, section forces of 20 beams"),
        "{}",
        out.stdout
    );
}

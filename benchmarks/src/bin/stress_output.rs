//! What the stress output of a large solid body costs against the dynamic run that produces
//! its states.
//!
//! A clamped steel bar 1 x 0.1 x 0.1 m of hex8 bricks (default 90 x 10 x 10: 11 011 nodes,
//! 33 033 dofs), RBE2 interface on x = 0 (clamped), RBE3 interface on x = 1, reduced with 20
//! fixed-interface modes and its stress shapes; a step force of 10 kN along -z at the tip,
//! 1000 generalized-alpha steps of 0.1 ms (8 periods of the first bending mode), a sensor row
//! at every step. Timed, each the minimum of `REPEAT` runs:
//!
//! * the dynamic run alone (tip displacement sensor);
//! * the same run with a `stress` sensor giving the largest von Mises stress over every node
//!   of the body at every step (`mbs::SensorKind::MaxVonMises`: `solve_dynamic` finds it 64
//!   rows at a time, `reduction::VonMisesMaximum::maxima`); the two runs alternate, wall and
//!   CPU time (both threads) each;
//! * the recovery alone over the 1000 states of the run: every node's tensor in global axes,
//!   von Mises and largest principal stress (`reduction::StressShapes::node_stresses`, what a
//!   VTU frame holds); every node's von Mises and their maximum (the brute-force maximum); the
//!   bounded search of one state at a time (`VonMisesMaximum::maximum`) and the batched one
//!   (`VonMisesMaximum::maxima`), whose maxima are checked equal to the brute-force ones, bit
//!   for bit, as is the run's sensor column;
//! * the writing of the three VTU stress fields (tensor, von Mises, largest principal) per
//!   frame: a frame of the body with and without them (`study::output::vtu::write_vtu`, ASCII), the
//!   difference. That is output I/O, paid per VTU frame (`vtu_every`), not per sensor row.
//!
//! Usage: `cargo run --release -p flexmbs-benchmarks --bin stress_output [nx ny nz]`.

#![allow(non_snake_case)]

use flexmbs_benchmarks::cpu_seconds;
use mbs::{solve_dynamic, DynamicSettings, Integrator, SensorKind, System};
use nalgebra::{Matrix3, Vector3};
use reduction::{reduce, CbSettings, ModeSelection, VonMisesMaximum, VonMisesReference};
use std::time::Instant;
use study::output::vtu::{motion_fields, stress_fields, write_vtu, PointField, VtuMesh};

const REPEAT: usize = 3;
const STEPS: usize = 1000;
/// VTU frames written for the per-frame figure (each way).
const FRAMES: usize = 5;

/// The minimum over `REPEAT` runs of `f`'s wall time \[s\], and its last result.
fn timed<T>(f: impl FnMut() -> T) -> (f64, T) {
    let (wall, _, last) = timed_cpu(f);
    (wall, last)
}

/// The minima over `REPEAT` runs of `f`'s wall time and CPU time (both threads) \[s\], and
/// its last result.
fn timed_cpu<T>(mut f: impl FnMut() -> T) -> (f64, f64, T) {
    let (mut wall, mut cpu) = (f64::INFINITY, f64::INFINITY);
    let mut last = None;
    for _ in 0..REPEAT {
        let (t, c) = (Instant::now(), cpu_seconds());
        last = Some(f());
        cpu = cpu.min(cpu_seconds() - c);
        wall = wall.min(t.elapsed().as_secs_f64());
    }
    (wall, cpu, last.expect("REPEAT > 0"))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<usize> = std::env::args().skip(1).map(|a| a.parse()).collect::<Result<_, _>>()?;
    let div = match args.as_slice() {
        [x, y, z] => [*x, *y, *z],
        [] => [90, 10, 10],
        _ => return Err("give nx ny nz, or nothing".into()),
    };
    let load_before = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let (fe, [root, tip]) = models::steel_bar(div)?;
    let dofs = 3 * fe.mesh.nodes.len();
    let mut settings = CbSettings::new(ModeSelection::Count(20));
    settings.stress_shapes = true;
    let t = Instant::now();
    let body = reduce(&fe, "bar", &[("root".into(), root), ("tip".into(), tip)], &settings)?;
    let t_reduce = t.elapsed().as_secs_f64();
    let nodes = body.stress.as_ref().ok_or("no stress shapes")?.node_count();

    let build = |stress: bool| -> Result<System, Box<dyn std::error::Error>> {
        let (mut m, b, ids) = models::clamped_with_tip_force(&body, Vector3::new(0.0, 0.0, -1e4));
        m.add_sensor("tip", SensorKind::NodeDisplacement { node: ids[1] });
        if stress {
            m.add_sensor(
                "hot",
                SensorKind::MaxVonMises {
                    body: b,
                    nodes: (0..nodes).collect(),
                },
            );
        }
        Ok(System::new(&m)?)
    };
    let settings = DynamicSettings::new(1e-4, STEPS as f64 * 1e-4, 0.9);
    // The runs alternate, without and with the sensor, so that both see the same load.
    let (plain, stressed) = (build(false)?, build(true)?);
    let (mut t_plain, mut c_plain, mut t_stress, mut c_stress) =
        (f64::INFINITY, f64::INFINITY, f64::INFINITY, f64::INFINITY);
    let mut last = None;
    for _ in 0..REPEAT {
        for (sys, wall, cpu) in [
            (&plain, &mut t_plain, &mut c_plain),
            (&stressed, &mut t_stress, &mut c_stress),
        ] {
            let (t, c) = (Instant::now(), cpu_seconds());
            let traj = solve_dynamic(sys, sys.initial_state(), &settings).map_err(|e| e.error.to_string())?;
            *cpu = cpu.min(cpu_seconds() - c);
            *wall = wall.min(t.elapsed().as_secs_f64());
            last = Some(traj);
        }
    }
    let traj = last.expect("REPEAT > 0");

    // The states of the run: the body's CB coordinates and frame rotation at every step.
    let sys = build(false)?;
    let body_id = mbs::BodyId(0);
    let mut integ = Integrator::new(&sys, sys.initial_state(), settings.clone())?;
    let mut states: Vec<(Vec<f64>, Matrix3<f64>)> = Vec::with_capacity(STEPS);
    let mut t_kinematics = 0.0;
    for _ in 0..STEPS {
        integ.step()?;
        let t = Instant::now();
        let (kin, _) = sys.body_kinematics(integ.state(), body_id)?.ok_or("a flexible body")?;
        t_kinematics += t.elapsed().as_secs_f64();
        states.push((kin.q_jj.clone(), kin.R_j));
    }
    let se = sys.superelement(body_id).ok_or("no superelement")?;
    let shapes = se.stress_shapes().ok_or("no stress shapes")?;
    let all: Vec<usize> = (0..nodes).collect();

    let (t_full, _) = timed(|| {
        states
            .iter()
            .map(|(q, R)| shapes.node_stresses(q, R).principal[0])
            .sum::<f64>()
    });
    let (t_brute, brute) = timed(|| {
        states
            .iter()
            .map(|(q, _)| {
                let vm = shapes.von_mises(q);
                all.iter()
                    .map(|&k| (k, vm[k]))
                    .max_by(|a, b| a.1.total_cmp(&b.1))
                    .expect("nodes")
            })
            .collect::<Vec<_>>()
    });
    let t = Instant::now();
    let search = VonMisesMaximum::new(shapes, &all);
    let t_setup = t.elapsed().as_secs_f64();
    let (t_bounded, (bounded, (reference, per_state))) = timed(|| {
        let mut reference = VonMisesReference::default();
        let mut per_state = Vec::with_capacity(STEPS);
        let maxima = states
            .iter()
            .map(|(q, _)| {
                let before = reference.evaluations();
                let m = search.maximum(shapes, q, &mut reference).expect("nodes");
                per_state.push(reference.evaluations() - before);
                m
            })
            .collect::<Vec<_>>();
        (maxima, (reference, per_state))
    });
    for (k, (b, s)) in brute.iter().zip(&bounded).enumerate() {
        if b.0 != s.0 || b.1.to_bits() != s.1.to_bits() {
            return Err(format!("step {k}: bounded maximum {s:?} differs from every node's {b:?}").into());
        }
    }
    // The batched search (what the run's sensor uses): all states at once.
    let refs: Vec<&[f64]> = states.iter().map(|(q, _)| q.as_slice()).collect();
    let (t_batched, c_batched, (batched, batched_evaluations)) = timed_cpu(|| search.maxima(shapes, &refs));
    for (k, (b, s)) in brute.iter().zip(&batched).enumerate() {
        let s = s.ok_or("no maximum")?;
        if b.0 != s.0 || b.1.to_bits() != s.1.to_bits() {
            return Err(format!("step {k}: batched maximum {s:?} differs from every node's {b:?}").into());
        }
    }
    // The sensor column of the run: the same maxima.
    let peak = bounded.iter().map(|m| m.1).fold(0.0, f64::max);
    let sensor_peak = traj.sensors.rows.iter().map(|r| r[3]).fold(0.0, f64::max);
    if peak.to_bits() != sensor_peak.to_bits() {
        return Err(format!("the sensor's peak {sensor_peak} differs from the recovery's {peak}").into());
    }

    // A VTU frame of the body, with and without the stress fields.
    let vtu = VtuMesh::from_model(&fe, &[]);
    let (q, R) = states.last().expect("steps");
    let st = shapes.node_stresses(q, R);
    let n_points = vtu.points.len();
    let u: Vec<f64> = (0..3 * n_points).map(|k| 1e-4 * (k as f64).sin()).collect();
    let tensor: Vec<f64> = st.tensor.iter().flatten().copied().collect();
    let mut base = Vec::from(motion_fields(&u, &u));
    base.push(PointField {
        name: "velocity",
        components: 3,
        values: &u,
    });
    let dir = std::env::temp_dir().join(format!("flexmbs-stress-output-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let path = dir.join("frame.vtu");
    let (t_vtu_base, _) = timed(|| (0..FRAMES).try_for_each(|_| write_vtu(&path, &vtu, &base)));
    base.extend(stress_fields(&tensor, &st.von_mises, &st.principal));
    let (t_vtu_stress, _) = timed(|| (0..FRAMES).try_for_each(|_| write_vtu(&path, &vtu, &base)));
    let size = std::fs::metadata(&path)?.len();
    std::fs::remove_dir_all(&dir)?;

    let load_after = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!(
        "stress output: hex8 bar {}x{}x{}, {dofs} dofs, {nodes} nodes with stresses, {} CB coordinates",
        div[0],
        div[1],
        div[2],
        body.n_coordinates()
    );
    println!("reduction with stress shapes: {t_reduce:.2} s");
    println!(
        "dynamic run, {STEPS} steps, no stress output: {t_plain:.3} s wall, {c_plain:.3} CPU-s (minima of {REPEAT})"
    );
    println!(
        "the same with the largest von Mises over every node at every step: {t_stress:.3} s wall, {c_stress:.3} CPU-s (minima of {REPEAT}); stress output share {:.3} s wall ({:.2}x the run), {:.3} CPU-s ({:.2}x the run)",
        t_stress - t_plain,
        (t_stress - t_plain) / t_plain,
        c_stress - c_plain,
        (c_stress - c_plain) / c_plain
    );
    println!("recovery alone over the {STEPS} states (minimum of {REPEAT}; the body's kinematics from each state, which every stress output needs first: {t_kinematics:.3} s once):");
    println!("  every node's tensor, von Mises, largest principal (a VTU frame's values): {t_full:.3} s");
    println!("  largest von Mises by every node's: {t_brute:.3} s");
    println!(
        "  largest von Mises by the bounded search: {t_bounded:.3} s (set-up {t_setup:.3} s once), equal to every node's at all {STEPS} states; peak {peak:.4e} Pa"
    );
    println!(
        "  largest von Mises by the batched search (single-precision screen, {} states a product): {t_batched:.3} s wall, {c_batched:.3} CPU-s, equal to every node's at all {STEPS} states; {:.1} nodes evaluated exactly per state",
        64,
        batched_evaluations as f64 / STEPS as f64
    );
    println!(
        "  the bounded search evaluated {:.0} nodes per state on average ({} of {STEPS} states every node)",
        reference.evaluations() as f64 / STEPS as f64,
        reference.refreshes()
    );
    let mut sorted = per_state.clone();
    sorted.sort_unstable();
    let heavy = sorted.iter().rev().take(STEPS / 10).sum::<usize>();
    println!(
        "  nodes evaluated per state: median {}, 90th percentile {}, largest {}; the 10 % heaviest states hold {:.0} % of the evaluations",
        sorted[STEPS / 2],
        sorted[9 * STEPS / 10],
        sorted[STEPS - 1],
        100.0 * heavy as f64 / reference.evaluations() as f64
    );
    println!(
        "VTU frame of the body ({n_points} points, {:.1} MB with stresses): {:.1} ms without the stress fields, {:.1} ms with them: {:.1} ms per frame for the stress fields (output I/O)",
        size as f64 / 1e6,
        1e3 * t_vtu_base / FRAMES as f64,
        1e3 * t_vtu_stress / FRAMES as f64,
        1e3 * (t_vtu_stress - t_vtu_base) / FRAMES as f64
    );
    println!(
        "load average before: {}, after: {}",
        load_before.split_whitespace().take(3).collect::<Vec<_>>().join(" "),
        load_after.split_whitespace().take(3).collect::<Vec<_>>().join(" ")
    );
    Ok(())
}

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
//!   of the body at every step (`mbs::SensorKind::MaxVonMises`: the mechanism's stress
//!   output, every node's tensor, von Mises and largest principal stress in global axes);
//! * the recovery alone, 1000 times at the final state (kinematics and every node's stresses).
//!
//! Usage: `cargo run --release -p flexmbs-benchmarks --bin stress_output [nx ny nz]`.

#![allow(non_snake_case)]

use fe_model::{add_interface_on_set, box_mesh, solid_model, CellKind, IsotropicMaterial, MassKind, SpiderKind};
use mbs::{solve_dynamic, DynamicSettings, Model, SensorKind, Support, System};
use nalgebra::{Isometry3, Vector3};
use reduction::{reduce, CbSettings, ModeSelection};
use std::time::Instant;
use superelement::{FrameChoice, MassVariant};

const REPEAT: usize = 3;
const STEPS: usize = 1000;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<usize> = std::env::args().skip(1).map(|a| a.parse()).collect::<Result<_, _>>()?;
    let div = match args.as_slice() {
        [x, y, z] => [*x, *y, *z],
        [] => [90, 10, 10],
        _ => return Err("give nx ny nz, or nothing".into()),
    };
    let load_before = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let mesh = box_mesh::box_mesh(CellKind::Hex8, [1.0, 0.1, 0.1], div)?;
    let mut fe = solid_model(
        mesh,
        IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0)?,
        MassKind::Consistent,
    )?;
    let root = add_interface_on_set(&mut fe, "root", "x0", None, SpiderKind::Rbe2)?;
    let tip = add_interface_on_set(&mut fe, "tip", "x1", None, SpiderKind::Rbe3)?;
    let dofs = 3 * fe.mesh.nodes.len();
    let mut settings = CbSettings::new(ModeSelection::Count(20));
    settings.stress_shapes = true;
    let t = Instant::now();
    let body = reduce(&fe, "bar", &[("root".into(), root), ("tip".into(), tip)], &settings)?;
    let t_reduce = t.elapsed().as_secs_f64();
    let nodes = body.stress.as_ref().ok_or("no stress shapes")?.node_count();

    let build = |stress: bool| -> Result<System, Box<dyn std::error::Error>> {
        let mut m = Model::new("bar");
        let ids: Vec<_> = body
            .interfaces
            .iter()
            .map(|i| m.add_node(&i.name, Vector3::from(i.position)))
            .collect();
        let b = m.add_flexible_body(
            body.clone(),
            ids.clone(),
            Isometry3::identity(),
            FrameChoice::CenterOfMass,
            MassVariant::Exact,
        );
        m.add_support(Support::clamp(ids[0]));
        m.add_dead_force(ids[1], Vector3::new(0.0, 0.0, -1e4));
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
    let run = |stress: bool| -> Result<(f64, mbs::State, System), Box<dyn std::error::Error>> {
        let sys = build(stress)?;
        let mut best = f64::INFINITY;
        let mut last = None;
        for _ in 0..REPEAT {
            let t = Instant::now();
            let traj = solve_dynamic(&sys, sys.initial_state(), &settings).map_err(|e| e.error.to_string())?;
            best = best.min(t.elapsed().as_secs_f64());
            last = Some(traj.final_state);
        }
        Ok((best, last.expect("REPEAT > 0"), sys))
    };
    let (t_plain, _, _) = run(false)?;
    let (t_stress, state, sys) = run(true)?;
    let se = sys.superelement(mbs::BodyId(0)).ok_or("no superelement")?;
    let shapes = se.stress_shapes().ok_or("no stress shapes")?;
    let bs = sys.flexible_body_state(mbs::BodyId(0), &state).ok_or("no body state")?;
    let mut t_recover = f64::INFINITY;
    let mut peak = 0.0f64;
    for _ in 0..REPEAT {
        let t = Instant::now();
        for _ in 0..STEPS {
            let kin = se.kinematics(&bs)?;
            let st = shapes.node_stresses(&kin.q_jj, &kin.R_j);
            peak = peak.max(st.von_mises.iter().copied().fold(0.0, f64::max));
        }
        t_recover = t_recover.min(t.elapsed().as_secs_f64());
    }
    let load_after = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!(
        "stress output: hex8 bar {}x{}x{}, {dofs} dofs, {nodes} nodes with stresses, {} CB coordinates",
        div[0],
        div[1],
        div[2],
        body.n_coordinates()
    );
    println!("reduction with stress shapes: {t_reduce:.2} s");
    println!("dynamic run, {STEPS} steps, no stress output: {t_plain:.3} s (minimum of {REPEAT})");
    println!(
        "the same with the largest von Mises over every node at every step: {t_stress:.3} s (minimum of {REPEAT})"
    );
    println!("stress output share: {:.3} s", t_stress - t_plain);
    println!("recovery alone, {STEPS} times every node: {t_recover:.3} s (minimum of {REPEAT}); peak von Mises {peak:.4e} Pa");
    println!(
        "load average before: {}, after: {}",
        load_before.split_whitespace().take(3).collect::<Vec<_>>().join(" "),
        load_after.split_whitespace().take(3).collect::<Vec<_>>().join(" ")
    );
    Ok(())
}

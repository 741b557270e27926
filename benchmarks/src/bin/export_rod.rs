//! Writes the slider-crank rod's solid mesh and its assembled free-free $\mathbf K$, $\mathbf M$
//! (Matrix Market, our free-dof numbering) for the Exudyn script, so that both programs
//! reduce the same FE matrices.
//!
//! `cargo run --release -p flexmbs-benchmarks --bin export_rod -- --out DIR [--kind hex20]
//! [--along 24] [--across 2]` writes in DIR: `K.mtx`, `M.mtx`, `dofs.txt` (node and direction
//! 0..2 of each free dof, one line per row of K), `nodes.txt` (x y z per node), `sets.txt`
//! (the end-face node sets `x0`, `x1` and the axis nodes `axis` = start, middle, end) and
//! `params.txt` (the mechanism, `name value` per line).

#![allow(non_snake_case)]

use fe_model::{assemble, DofMap, SystemPattern};
use flexmbs_benchmarks::{axis_node, rod_fe_model, Args, BenchError, SliderCrank};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::from_env()?;
    let out = PathBuf::from(args.text("out").ok_or_else(|| BenchError::Argument {
        arg: "--out".into(),
        why: "the output directory is required".into(),
    })?);
    std::fs::create_dir_all(&out)?;
    let p = SliderCrank::C2;
    let mesh = args.rod_mesh()?;
    let fe = rod_fe_model(&p, p.rod, mesh)?;
    let dofs = DofMap::new(&fe)?;
    let pattern = SystemPattern::new(&fe, &dofs);
    let km = assemble(&fe, &pattern)?;
    reduction::write_matrix_market(&out.join("K.mtx"), km.K.as_ref())?;
    reduction::write_matrix_market(&out.join("M.mtx"), km.M.as_ref())?;
    let mut map = vec![(0usize, 0usize); dofs.n_free()];
    for node in 0..fe.mesh.nodes.len() {
        for k in 0..6 {
            if let Some(d) = dofs.free_dof(fe_model::NodeId(node as u32), k) {
                map[d.index()] = (node, k);
            }
        }
    }
    let mut text = String::new();
    for (node, k) in &map {
        writeln!(text, "{node} {k}")?;
    }
    std::fs::write(out.join("dofs.txt"), &text)?;
    text.clear();
    for x in &fe.mesh.nodes {
        writeln!(text, "{:.17e} {:.17e} {:.17e}", x.x, x.y, x.z)?;
    }
    std::fs::write(out.join("nodes.txt"), &text)?;
    text.clear();
    for set in ["x0", "x1"] {
        let nodes = fe.node_set(set, "export")?;
        let list: Vec<String> = nodes.iter().map(|n| n.index().to_string()).collect();
        writeln!(text, "{set} {}", list.join(" "))?;
    }
    let coords: Vec<[f64; 3]> = fe.mesh.nodes.iter().map(|x| [x.x, x.y, x.z]).collect();
    let axis = [0.0, p.rod / 2.0, p.rod]
        .iter()
        .map(|&x| axis_node(&coords, x, p.rod).map(|i| i.to_string()))
        .collect::<Result<Vec<_>, _>>()?;
    writeln!(text, "axis {}", axis.join(" "))?;
    std::fs::write(out.join("sets.txt"), &text)?;
    text.clear();
    let [Ix, Iy, Iz] = p.crank_inertia;
    for (k, v) in [
        ("crank", p.crank),
        ("rod", p.rod),
        ("speed", p.speed),
        ("side", p.side()),
        ("E", p.E),
        ("nu", p.nu),
        ("rho", p.rho),
        ("diameter", p.diameter),
        ("crank_mass", p.crank_mass),
        ("crank_Ixx", Ix),
        ("crank_Iyy", Iy),
        ("crank_Izz", Iz),
    ] {
        writeln!(text, "{k} {v:.17e}")?;
    }
    std::fs::write(out.join("params.txt"), &text)?;
    println!(
        "rod mesh {:?} {} x {} x {}: {} nodes, {} free dofs, K nnz {}; written to {}",
        mesh.kind,
        mesh.along,
        mesh.across,
        mesh.across,
        fe.mesh.nodes.len(),
        dofs.n_free(),
        km.K.compute_nnz(),
        out.display()
    );
    Ok(())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("export_rod: {e}");
            ExitCode::from(2)
        }
    }
}

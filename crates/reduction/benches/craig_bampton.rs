//! Whole Craig-Bampton reduction of a generated solid block, as a user runs it: hex8 box
//! mesh, RBE2 interfaces on the two end faces, 20 fixed-interface modes, through
//! `reduction::reduce` (factorisation of K_ii, 12 constraint-mode solves, Krylov-Schur, the
//! projections and the inertia invariants). Prints wall time per stage and the peak RSS.
//!
//! `cargo bench -p reduction --bench craig_bampton -- --bench` runs 50k and 200k dofs
//! (`REDUCTION_CB_SIZES=50k,200k,600k` to choose); without `--bench` (as `cargo test --benches`
//! runs it) a 3k-dof block, so CI checks that it runs.

use fe_model::{
    add_interface_on_set, box_mesh, solid_model, CellKind, DofMap, IsotropicMaterial, MassKind, SpiderKind,
};
use reduction::{reduce, CbSettings, ModeSelection};
use std::time::Instant;

fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map(|kb| kb / 1024.0)
        .unwrap_or(f64::NAN)
}

fn main() {
    let full = std::env::args().any(|a| a == "--bench");
    let sizes: Vec<String> = match std::env::var("REDUCTION_CB_SIZES") {
        Ok(s) => s.split(',').map(|x| x.trim().to_string()).collect(),
        Err(_) if full => vec!["50k".into(), "200k".into()],
        Err(_) => vec!["3k".into()],
    };
    println!(
        "reduction/benches/craig_bampton: hex8 block, RBE2 interfaces on both end faces, 20 modes; load average {}",
        std::fs::read_to_string("/proc/loadavg").unwrap_or_default().trim()
    );
    for size in sizes {
        // Elements (ex, ey, ez): dofs ~ 3 (ex+1)(ey+1)(ez+1).
        let (ex, ey, ez) = match size.as_str() {
            "3k" => (12, 8, 8),
            "50k" => (30, 23, 23),
            "200k" => (48, 37, 37),
            "600k" => (70, 53, 53),
            other => {
                eprintln!("unknown size {other} (3k, 50k, 200k, 600k)");
                std::process::exit(2);
            }
        };
        let t0 = Instant::now();
        let mesh = box_mesh(
            CellKind::Hex8,
            [2.0 * ex as f64 / ez as f64, ey as f64 / ez as f64, 1.0],
            [ex, ey, ez],
        )
        .unwrap();
        let steel = IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).unwrap();
        let mut model = solid_model(mesh, steel, MassKind::Consistent).unwrap();
        let a = add_interface_on_set(&mut model, "root", "x0", None, SpiderKind::Rbe2).unwrap();
        let b = add_interface_on_set(&mut model, "tip", "x1", None, SpiderKind::Rbe2).unwrap();
        let n_free = DofMap::new(&model).unwrap().n_free();
        let t_model = t0.elapsed();
        let t1 = Instant::now();
        let body = reduce(
            &model,
            "block",
            &[("root".into(), a), ("tip".into(), b)],
            &CbSettings {
                modes: ModeSelection::Count(20),
                keep_mesh_shapes: false,
                auxiliary_node: None,
            },
        )
        .unwrap();
        let t_reduce = t1.elapsed();
        println!(
            "{size:>5}: {ex} x {ey} x {ez} hex8, {n_free} free dofs: model {:.2} s, reduce (factor + Psi + 20 modes + projections + invariants) {:.2} s, peak RSS {:.0} MB, f1 = {:.1} Hz",
            t_model.as_secs_f64(),
            t_reduce.as_secs_f64(),
            peak_rss_mb(),
            body.fixed_interface_omega[0] / (2.0 * std::f64::consts::PI)
        );
    }
}

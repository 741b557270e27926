//! Arc-length continuation through a limit point and snap-through (the von Mises truss), and
//! linearised buckling of a column of N superelements against Euler's load.

use crate::fixtures::cantilever;
use mbs::{
    buckling, solve_static, solve_static_with, ArcLengthSettings, Model, SensorKind, Spring, StaticMethod,
    StaticSettings, Support, System,
};
use nalgebra::Vector3;
use reduction::ModeSelection;

/// Half span, rise and spring stiffness of the two-bar truss.
const B: f64 = 1.0;
const H: f64 = 0.2;
const K: f64 = 1000.0;

/// Load factor of the exact equilibrium at apex deflection `v` (downwards) under the load
/// `-p0` along y: each bar of length L(v) = sqrt(B^2 + (H - v)^2) is compressed by
/// K (L0 - L); the vertical equilibrium of the apex gives lambda p0 = 2 K (L0 - L)(H - v)/L.
fn lambda_exact(v: f64, p0: f64) -> f64 {
    let l0 = (B * B + H * H).sqrt();
    let l = (B * B + (H - v) * (H - v)).sqrt();
    2.0 * K * (l0 - l) * (H - v) / (l * p0)
}

/// The limit point of the exact curve: the maximum of lambda on 0 < v < H (golden section).
fn limit_point(p0: f64) -> (f64, f64) {
    let (mut a, mut b) = (0.0, H);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..200 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if lambda_exact(c, p0) > lambda_exact(d, p0) {
            b = d;
        } else {
            a = c;
        }
    }
    let v = 0.5 * (a + b);
    (v, lambda_exact(v, p0))
}

/// The truss: apex on a vertical slider, two springs to clamped ground nodes, dead load
/// (0, -p0, 0) at the apex. Sensor "apex": its displacement.
fn truss(p0: f64) -> System {
    let mut m = Model::new("von Mises truss");
    let top = m.add_node("apex", Vector3::new(0.0, H, 0.0));
    for (name, x) in [("left", -B), ("right", B)] {
        let g = m.add_node(name, Vector3::new(x, 0.0, 0.0));
        m.add_support(Support::clamp(g));
        m.springs.push(Spring {
            name: format!("bar {name}"),
            a: top,
            b: Some(g),
            ground_point: Vector3::zeros(),
            stiffness: K,
            damping: 0.0,
            rest_length: None,
        });
    }
    m.add_support(Support::slider(top, Vector3::y()));
    m.add_dead_force(top, Vector3::new(0.0, -p0, 0.0));
    m.add_sensor("apex", SensorKind::NodeDisplacement { node: top });
    System::new(&m).unwrap()
}

#[test]
fn arc_length_follows_the_von_mises_truss_through_snap_through() {
    // p0 twice the limit load: the limit point is at lambda = 0.5 and lambda = 1 is reached
    // only on the far branch, after the snap-through (v > 2H).
    let (_, p_lim) = limit_point(1.0);
    let p0 = 2.0 * p_lim;
    let (v_lim, lambda_lim) = limit_point(p0);
    let sys = truss(p0);
    // Steps of at most 0.03 (in v/size and lambda) sample the extrema of the curve closely.
    let settings = ArcLengthSettings {
        max_length: 0.03,
        ..ArcLengthSettings::new(0.02, 1.0, 1000)
    };
    let sol = solve_static_with(&sys, sys.initial_state(), &StaticMethod::ArcLength(settings)).unwrap();
    let apex = sol.sensors.series("apex").unwrap();
    let path: Vec<(f64, f64)> = sol.sensors.times.iter().zip(apex).map(|(&l, d)| (-d[1], l)).collect();
    eprintln!(
        "{} steps, {} rejected; limit point exact (v, lambda) = ({v_lim:.5}, {lambda_lim:.6})",
        path.len(),
        sol.rejected.len()
    );
    // Every converged point lies on the exact curve (to the Newton tolerance).
    let mut worst = 0.0f64;
    for &(v, l) in &path {
        worst = worst.max((l - lambda_exact(v, p0)).abs());
    }
    let lmax = path.iter().filter(|p| p.0 < H).map(|p| p.1).fold(f64::MIN, f64::max);
    let lmin = path.iter().map(|p| p.1).fold(f64::MAX, f64::min);
    let last = *path.last().unwrap();
    eprintln!("max |lambda - exact| = {worst:.2e}; path lambda in [{lmin:.4}, {lmax:.4}]; end {last:?}");
    assert!(worst < 1e-8, "{worst}");
    // It passes the limit point (lambda rises to it on the near branch, v < H, and comes
    // down; the curve is flat there, so steps of 0.03 land within 2 % of it), goes through the
    // unstable branch, where the load reverses (the exact minimum is -lambda_lim at
    // v = 2H - v_lim), and ends on the far branch at lambda = 1.
    assert!(
        lmax <= lambda_lim + 1e-9 && lmax > 0.98 * lambda_lim,
        "{lmax} vs {lambda_lim}"
    );
    assert!(lmin < -0.98 * lambda_lim, "{lmin}");
    assert!((last.1 - 1.0).abs() < 1e-12 && last.0 > 2.0 * H, "{last:?}");
    // Newton converges quadratically in the steps (residual history of a late step).
    let r = &sol.steps[sol.steps.len() / 2].residuals;
    eprintln!("residuals of a middle step: {r:?}");
    assert!(r.len() <= 6, "{r:?}");
}

#[test]
fn load_stepping_stops_at_the_limit_point() {
    // Under load control the same truss cannot pass the limit point on its branch: Newton with
    // load stepping either fails there or jumps to the far branch (v > 2H); it never returns a
    // point of the unstable branch between.
    let (_, p_lim) = limit_point(1.0);
    let sys = truss(2.0 * p_lim);
    let settings = StaticSettings {
        min_increment: 1e-3,
        ..StaticSettings::new(10)
    };
    match solve_static(&sys, sys.initial_state(), &settings) {
        Err(e) => {
            let lam = e.partial.sensors.times.last().copied().unwrap_or(0.0);
            eprintln!("load stepping stopped: {} (last lambda {lam})", e.error);
            assert!(lam <= 0.5 + 1e-9);
        }
        Ok(sol) => {
            let d = sol.sensors.series("apex").unwrap();
            for (l, d) in sol.sensors.times.iter().zip(d) {
                let v = -d[1];
                assert!(
                    !(H..=2.0 * H).contains(&v),
                    "lambda {l}: v = {v} on the unstable branch"
                );
            }
        }
    }
}

#[test]
fn column_buckling_load_approaches_euler() {
    // Clamped-free column, L = 1, square 10 mm steel: Euler P_cr = pi^2 EI / (4 L^2).
    let (E, side): (f64, f64) = (2.1e11, 0.01);
    let EI = E * side.powi(4) / 12.0;
    let p_euler = std::f64::consts::PI.powi(2) * EI / 4.0;
    let mut errors = Vec::new();
    for n in [1, 2, 4, 8] {
        let (mut model, nodes) = cantilever(n, 1.0, side, E, 7800.0, ModeSelection::StaticOnly, 2);
        // A tenth of Euler's load in compression: the reference state of the linearisation.
        let p = 0.1 * p_euler;
        model.add_dead_force(nodes[n], Vector3::new(-p, 0.0, 0.0));
        let sys = System::new(&model).unwrap();
        let unloaded = sys.initial_state();
        let sol = solve_static(&sys, unloaded.clone(), &StaticSettings::new(1)).unwrap();
        let b = buckling(&sys, &unloaded, &sol.state, 1.0).unwrap();
        let p_cr = b.load_factors[0] * p;
        let err = (p_cr - p_euler) / p_euler;
        eprintln!(
            "N = {n}: P_cr = {p_cr:.5} N (Euler {p_euler:.5}), error {err:.3e}; next factors {:?}",
            &b.load_factors[..4.min(b.load_factors.len())]
        );
        // Square section: the first load is double (two bending planes).
        assert!((b.load_factors[1] - b.load_factors[0]).abs() < 1e-6 * b.load_factors[0]);
        errors.push(err);
    }
    // Each superelement carries the prestress through its frame rotation only (a chord),
    // so the chain converges like a chain of co-rotational beams: error O(1/N^2), from above.
    for w in errors.windows(2) {
        assert!(w[1] > 0.0 && w[0] / w[1] > 3.0, "errors {errors:?}");
    }
    assert!(errors[3] < 5e-3, "{errors:?}");
}

//! Linearised analysis about static states.

use crate::fixtures::cantilever;
use mbs::{solve_static, spectrum, StaticSettings, System};
use nalgebra::Vector3;
use reduction::ModeSelection;

const E: f64 = 2.1e11;
const RHO: f64 = 7800.0;
const SIDE: f64 = 0.01;

/// First bending frequency of the clamped-free Euler-Bernoulli beam (A1), L = 1.
fn omega_1() -> f64 {
    let EI = E * SIDE.powi(4) / 12.0;
    let rhoA = RHO * SIDE * SIDE;
    1.87510407f64.powi(2) * (EI / rhoA).sqrt()
}

#[test]
fn cantilever_frequencies_match_euler_bernoulli() {
    let (model, _) = cantilever(4, 1.0, SIDE, E, RHO, ModeSelection::Count(2), 4);
    let sys = System::new(&model).unwrap();
    let sp = spectrum(&sys, &sys.initial_state()).unwrap();
    let w1 = omega_1();
    let w2 = 4.69409113f64.powi(2) / 1.87510407f64.powi(2) * w1;
    eprintln!(
        "first frequencies {:?} rad/s; Euler-Bernoulli {w1:.4}, {w2:.4}",
        &sp.omega[..6]
    );
    // Square section: each bending frequency twice. 4 superelements of 4 consistent-mass
    // elements with 2 fixed-interface modes each reproduce the 16-element beam, whose first
    // two frequencies are within 1e-5 and 1e-4 of the continuum.
    for (w, exact) in [
        (sp.omega[0], w1),
        (sp.omega[1], w1),
        (sp.omega[2], w2),
        (sp.omega[3], w2),
    ] {
        assert!((w - exact).abs() < 2e-4 * exact, "{w} vs {exact}");
    }
    // No damping: the state-space eigenvalues are ±i omega (to the accuracy of the
    // nonsymmetric eigensolver on the 2n system, ~1e-7 relative here).
    let (re, im) = sp.state_space[0];
    assert!(
        re.abs() < 1e-5 * w1 && (im - sp.omega[0]).abs() < 1e-6 * w1,
        "{re} {im}"
    );
}

#[test]
fn axial_preload_changes_the_bending_frequency() {
    // Tension stiffens, compression softens (geometric stiffness of the superelements, in K).
    let first = |P: f64| {
        let (mut model, nodes) = cantilever(4, 1.0, SIDE, E, RHO, ModeSelection::Count(1), 4);
        model.add_dead_force(nodes[4], Vector3::new(P, 0.0, 0.0));
        let sys = System::new(&model).unwrap();
        let sol = solve_static(&sys, sys.initial_state(), &StaticSettings::new(1)).unwrap();
        spectrum(&sys, &sol.state).unwrap().omega[0]
    };
    // Euler buckling load of the cantilever: pi^2 EI / (4 L^2) = 90 N; use a third of it.
    let P = 30.0;
    let (wt, w0, wc) = (first(P), first(0.0), first(-P));
    eprintln!("first frequency: tension {wt:.4}, none {w0:.4}, compression {wc:.4}");
    // Rayleigh estimate: w^2 changes by about P/P_cr of w^2 * 0.8; here +-15 % in w^2.
    assert!(wt > w0 * 1.03 && wc < w0 * 0.97, "{wt} {w0} {wc}");
}

/// Independent 2x2 reference: modes of K x = w^2 M x with M = diag(m1, m2), K symmetric, by the
/// closed form of the characteristic polynomial; returns (w^2, x) ascending, x mass-normalised.
fn two_dof_modes(m: [f64; 2], K: [[f64; 2]; 2]) -> [(f64, [f64; 2]); 2] {
    // det(K - l M) = m1 m2 l^2 - (K11 m2 + K22 m1) l + det K
    let (a, b, c) = (
        m[0] * m[1],
        -(K[0][0] * m[1] + K[1][1] * m[0]),
        K[0][0] * K[1][1] - K[0][1] * K[1][0],
    );
    let d = (b * b - 4.0 * a * c).sqrt();
    let roots = [(-b - d) / (2.0 * a), (-b + d) / (2.0 * a)];
    roots.map(|l| {
        // Row 1 of (K - l M) x = 0.
        let x = [-K[0][1], K[0][0] - l * m[0]];
        let x = if x[0] == 0.0 && x[1] == 0.0 {
            [K[1][1] - l * m[1], -K[1][0]]
        } else {
            x
        };
        let s = (m[0] * x[0] * x[0] + m[1] * x[1] * x[1]).sqrt();
        (l, [x[0] / s, x[1] / s])
    })
}

/// The shares of carriers, and of nodes with the bodies' interiors, joint springs and joint
/// geometry, sum to 1; the carriers' kinetic energies sum to phi^T M phi, their strain
/// energies (without the joint geometry) to phi^T K phi minus the geometry.
fn check_sums(modes: &[mbs::ModeEnergy]) {
    // The node split of a soft mode's strain energy differences terms of the stiffest parts:
    // its round-off is relative to the largest strain scale of the system, not of the mode
    // (the turning arm's pendulum mode: 2e-9 of its own 4.0 against 7e8 for the beam modes).
    let system_k = modes
        .iter()
        .flat_map(|m| m.carriers.iter().map(|c| c.strain.abs()).chain([m.strain.abs()]))
        .fold(0.0f64, f64::max);
    for (i, m) in modes.iter().enumerate() {
        let sum = |f: &dyn Fn(&mbs::CarrierEnergy) -> f64| m.carriers.iter().map(f).sum::<f64>();
        let scale = |f: &dyn Fn(&mbs::CarrierEnergy) -> f64, total: f64| {
            m.carriers.iter().map(|c| f(c).abs()).sum::<f64>().max(total.abs())
        };
        let (scale_k, scale_m) = (scale(&|c| c.strain, m.strain), scale(&|c| c.kinetic, m.kinetic));
        assert!(
            (sum(&|c| c.kinetic) - m.kinetic).abs() <= 1e-9 * scale_m,
            "mode {i}: kinetic {} vs phi^T M phi {}",
            sum(&|c| c.kinetic),
            m.kinetic
        );
        assert!((sum(&|c| c.strain) - m.strain).abs() <= 1e-9 * scale_k, "mode {i}");
        if m.kinetic.abs() > 0.0 {
            assert!((sum(&|c| c.kinetic_share) - 1.0).abs() < 1e-9, "mode {i}");
        }
        if m.strain.abs() > 1e-9 * scale_k {
            assert!((sum(&|c| c.strain_share) - 1.0).abs() < 1e-9, "mode {i}");
        }
        // Node ports + interiors + joint-coordinate carriers: the same totals (Derivation of
        // `mode_energies`).
        let off_node = |f: &dyn Fn(&mbs::CarrierEnergy) -> f64| {
            m.carriers
                .iter()
                .map(|c| match c.carrier {
                    mbs::EnergyCarrier::JointSpring { .. } | mbs::EnergyCarrier::JointGeometry => f(c),
                    _ => 0.0,
                })
                .sum::<f64>()
        };
        let nk =
            m.nodes.iter().map(|n| n.kinetic).sum::<f64>() + sum(&|c| c.interior_kinetic) + off_node(&|c| c.kinetic);
        let ns = m.nodes.iter().map(|n| n.strain).sum::<f64>() + sum(&|c| c.interior_strain) + off_node(&|c| c.strain);
        assert!(
            (nk - m.kinetic).abs() <= 1e-9 * scale_m,
            "mode {i}: nodes {nk} vs {}",
            m.kinetic
        );
        assert!(
            (ns - m.strain).abs() <= 1e-9 * scale_k + 1e-14 * system_k,
            "mode {i}: nodes {ns} vs {}",
            m.strain
        );
    }
}

/// Two oscillators on x sliders: A light (`m1`) and stiff (`k1`, damper `c1`) at x = 0, B heavy
/// (`m2`) and soft (`k2`) at x = 3, coupled by a weak spring `kc` along x.
fn two_oscillators(m1: f64, k1: f64, c1: f64, m2: f64, k2: f64, kc: f64) -> mbs::Model {
    let mut model = mbs::Model::new("two oscillators");
    let a = model.add_node("A", Vector3::new(0.0, 0.0, 0.0));
    let b = model.add_node("B", Vector3::new(3.0, 0.0, 0.0));
    let spring = |name: &str, a, b, ground: Vector3<f64>, k, c| mbs::Spring {
        name: name.into(),
        a,
        b,
        ground_point: ground,
        stiffness: k,
        damping: c,
        rest_length: None,
    };
    model
        .springs
        .push(spring("spring A", a, None, Vector3::new(-1.0, 0.0, 0.0), k1, c1));
    model
        .springs
        .push(spring("spring B", b, None, Vector3::new(4.0, 0.0, 0.0), k2, 0.0));
    model
        .springs
        .push(spring("coupling", a, Some(b), Vector3::zeros(), kc, 0.0));
    model.point_masses.push(mbs::PointMass {
        name: String::new(),
        node: a,
        mass: m1,
    });
    model.point_masses.push(mbs::PointMass {
        name: String::new(),
        node: b,
        mass: m2,
    });
    model.add_support(mbs::Support::slider(a, Vector3::x()));
    model.add_support(mbs::Support::slider(b, Vector3::x()));
    model
}

#[test]
fn weakly_coupled_spring_masses_are_labelled_by_their_mass_and_node() {
    // A: light (1 kg) and stiff (1e4 N/m), B: heavy (100 kg) and soft (1 N/m), coupled by a weak
    // spring (0.01 N/m). Frequencies 100 and 0.1 rad/s.
    let (m1, k1, m2, k2, kc) = (1.0, 1e4, 100.0, 1.0, 0.01);
    let model = two_oscillators(m1, k1, 0.0, m2, k2, kc);
    let sys = System::new(&model).unwrap();
    let modes = mbs::mode_energies(&sys, &sys.initial_state()).unwrap();
    check_sums(&modes);
    let exact = two_dof_modes([m1, m2], [[k1 + kc, -kc], [-kc, k2 + kc]]);
    assert_eq!(modes.len(), 2);
    for (mode, (l, x)) in modes.iter().zip(exact) {
        eprintln!("{:.6} rad/s: {}", mode.omega, mode.label);
        assert!(
            (mode.omega_squared - l).abs() < 1e-9 * l,
            "{} vs {l}",
            mode.omega_squared
        );
        assert!(!mode.rigid_body);
        // No damping: zeta = 0 to the accuracy of the state-space eigensolver.
        assert!(mode.damping_ratio.unwrap().abs() < 1e-8);
        // Energies of the reference mode, element by element: k x^2 and m x^2.
        let x = if (mode.shape[0] - x[0]).abs() < 1e-6 {
            x
        } else {
            [-x[0], -x[1]]
        };
        let reference = [
            ("spring A", k1 * x[0] * x[0], 0.0),
            ("spring B", k2 * x[1] * x[1], 0.0),
            ("coupling", kc * (x[0] - x[1]).powi(2), 0.0),
        ];
        for (name, strain, _) in reference {
            let c = mode
                .carriers
                .iter()
                .find(|c| c.carrier == mbs::EnergyCarrier::Spring(name.into()))
                .unwrap();
            assert!((c.strain - strain).abs() < 1e-8 * l, "{name}: {} vs {strain}", c.strain);
        }
        for (index, mass, xi) in [(0, m1, x[0]), (1, m2, x[1])] {
            let c = mode
                .carriers
                .iter()
                .find(|c| matches!(c.carrier, mbs::EnergyCarrier::PointMass { index: i, .. } if i == index))
                .unwrap();
            assert!((c.kinetic - mass * xi * xi).abs() < 1e-9, "{}", c.kinetic);
        }
    }
    // The soft heavy oscillator first, the stiff light one second; each mode carries more than
    // 99.9 % of its kinetic energy in its own mass and node.
    assert!(
        modes[0]
            .label
            .starts_with("point mass 1 on node B (100 % kinetic), node B"),
        "{}",
        modes[0].label
    );
    assert!(
        modes[1]
            .label
            .starts_with("point mass 0 on node A (100 % kinetic), node A"),
        "{}",
        modes[1].label
    );
    assert!(modes[0].nodes[1].kinetic_share > 0.999 && modes[1].nodes[0].kinetic_share > 0.999);
    // Plain serde data.
    let json = serde_json::to_string(&modes).unwrap();
    let back: Vec<mbs::ModeEnergy> = serde_json::from_str(&json).unwrap();
    assert_eq!(back, modes);
}

#[test]
fn two_cantilevers_modes_are_labelled_by_their_beam_and_tip() {
    // Cantilevers of length 1 and 0.5 (first frequencies 4x apart), each two superelements,
    // clamped at x = 0; each first bending pair must be labelled by its own beam and tip node.
    let mut model = mbs::Model::new("two cantilevers");
    let mut tips = Vec::new();
    for (name, L, y) in [("long", 1.0, 0.0), ("short", 0.5, 1.0)] {
        let nodes: Vec<_> = (0..3)
            .map(|i| model.add_node(&format!("{name} {i}"), Vector3::new(L * i as f64 / 2.0, y, 0.0)))
            .collect();
        for i in 0..2 {
            let a = model.nodes[nodes[i].index()].position;
            let b = model.nodes[nodes[i + 1].index()].position;
            let body =
                crate::fixtures::beam_body(&format!("{name}{i}"), a, b, 4, SIDE, E, RHO, ModeSelection::Count(2));
            model.add_flexible_body(
                body,
                vec![nodes[i], nodes[i + 1]],
                nalgebra::Isometry3::identity(),
                superelement::FrameChoice::CenterOfMass,
                superelement::MassVariant::Exact,
            );
        }
        model.add_support(mbs::Support::clamp(nodes[0]));
        tips.push(format!("{name} 2"));
    }
    let sys = System::new(&model).unwrap();
    let modes = mbs::mode_energies(&sys, &sys.initial_state()).unwrap();
    check_sums(&modes);
    for m in &modes[..4] {
        eprintln!("{:.3} rad/s, zeta {:?}: {}", m.omega, m.damping_ratio, m.label);
    }
    let w1 = omega_1();
    // Square sections: each bending frequency twice. The long beam's first pair (w1), then the
    // short beam's (4 w1), below the long beam's second pair (6.27 w1).
    for (k, (beam, tip, w)) in [(0, ("long", &tips[0], w1)), (2, ("short", &tips[1], 4.0 * w1))] {
        for m in &modes[k..k + 2] {
            assert!((m.omega - w).abs() < 1e-3 * w, "{} vs {w}", m.omega);
            let c = m
                .carriers
                .iter()
                .max_by(|a, b| a.kinetic_share.total_cmp(&b.kinetic_share))
                .unwrap();
            assert!(m.label.starts_with(beam), "{}", m.label);
            assert!(m.label.ends_with(&format!("node {tip}")), "{}", m.label);
            assert!(matches!(&c.carrier, mbs::EnergyCarrier::Body(n) if n.starts_with(beam)));
            // The other beam carries nothing (uncoupled but for round-off).
            let other: f64 = m
                .carriers
                .iter()
                .filter(|c| !matches!(&c.carrier, mbs::EnergyCarrier::Body(n) if n.starts_with(beam)))
                .map(|c| c.kinetic_share.abs() + c.strain_share.abs())
                .sum();
            assert!(other < 1e-8, "{other}");
        }
    }
}

#[test]
fn mode_energies_of_a_loaded_turning_arm_add_up() {
    // A rigid arm on a revolute joint carries node P at 0.4 m; a flexible beam hangs from P to a
    // free tip T; gravity and a joint rate. P's J depends on the joint angle, so the port split
    // includes C dV/dq and M dA/dq and the joints' geometric term is non-zero: node and
    // carrier totals must still agree, the carriers' strain equals phi^T K phi less the geometry.
    let mut model = mbs::Model::new("arm");
    let o = model.add_node("O", Vector3::zeros());
    let h = model.add_node("H", Vector3::zeros());
    let p = model.add_node("P", Vector3::new(0.4, 0.0, 0.0));
    let t = model.add_node("T", Vector3::new(0.4, -0.5, 0.0));
    model.add_support(mbs::Support::clamp(o));
    let joint = model.add_joint("hinge", o, h, mbs::JointKind::Revolute { axis: Vector3::z() });
    model.add_rigid_body(crate::fixtures::rigid(
        "arm",
        h,
        vec![p],
        0.5,
        Vector3::new(0.2, 0.0, 0.0),
        [1e-4, 7e-3, 7e-3],
    ));
    let a = model.nodes[p.index()].position;
    let b = model.nodes[t.index()].position;
    let beam = crate::fixtures::beam_body("beam", a, b, 4, SIDE, E, RHO, ModeSelection::Count(2));
    model.add_flexible_body(
        beam,
        vec![p, t],
        nalgebra::Isometry3::identity(),
        superelement::FrameChoice::CenterOfMass,
        superelement::MassVariant::Exact,
    );
    model.gravity = Vector3::new(0.0, -9.81, 0.0);
    model.initial.push(mbs::InitialCondition::JointRate {
        joint,
        coordinate: 0,
        rate: 3.0,
    });
    let sys = System::new(&model).unwrap();
    let modes = mbs::mode_energies(&sys, &sys.initial_state()).unwrap();
    assert_eq!(modes.len(), sys.n_dof());
    check_sums(&modes);
    for m in &modes[..3] {
        eprintln!("{:.3} rad/s: {}", m.omega, m.label);
    }
    let geometry = |m: &mbs::ModeEnergy| {
        m.carriers
            .iter()
            .find(|c| c.carrier == mbs::EnergyCarrier::JointGeometry)
            .map_or(0.0, |c| c.strain_share)
    };
    let largest = modes.iter().map(|m| geometry(m).abs()).fold(0.0, f64::max);
    eprintln!("largest joint-geometry share {largest:.3e}");
    assert!(largest > 1e-8, "{largest}");
    // The pendulum mode (lowest) swings the arm: labelled by a body, with P or T. About this
    // moving state its omega^2 is negative (the instantaneous spectrum of a turning arm), so the
    // label starts with the UNSTABLE notice.
    let label = modes[0]
        .label
        .split_once("1/s), ")
        .map_or(modes[0].label.as_str(), |(_, l)| l);
    assert!(
        label.starts_with("arm") || label.starts_with("beam"),
        "{}",
        modes[0].label
    );
}

#[test]
fn mode_energies_of_a_moving_slider_crank_add_up() {
    // A moving state of a driven mechanism: node and carrier totals agree.
    let (model, _, _) = crate::fixtures::slider_crank(2, ModeSelection::Count(2), 150.0);
    let sys = System::new(&model).unwrap();
    let modes = mbs::mode_energies(&sys, &sys.initial_state()).unwrap();
    assert_eq!(modes.len(), sys.n_dof());
    check_sums(&modes);
    for m in modes.iter().take(3) {
        eprintln!("{:.3} rad/s: {}", m.omega, m.label);
    }

    // The elastic modes of the rod are labelled by a rod segment.
    let first_elastic = modes.iter().find(|m| !m.rigid_body && m.omega > 1.0).unwrap();
    assert!(first_elastic.label.starts_with("rod"), "{}", first_elastic.label);
}

#[test]
fn free_mass_is_a_rigid_body_mode_and_damping_ratio_is_exact() {
    // B without its spring or coupling: a free mass on its slider, one zero (rigid-body) mode.
    // A with a damper c = 2 zeta sqrt(k m): damped eigenvalue -zeta w +- i w sqrt(1 - zeta^2).
    let (m1, k1, zeta): (f64, f64, f64) = (2.0, 800.0, 0.05);
    let c1 = 2.0 * zeta * (k1 * m1).sqrt();
    let model = two_oscillators(m1, k1, c1, 50.0, 0.0, 0.0);
    let sys = System::new(&model).unwrap();
    let modes = mbs::mode_energies(&sys, &sys.initial_state()).unwrap();
    check_sums(&modes);
    assert_eq!(modes.len(), 2);
    let (free, spring) = (&modes[0], &modes[1]);
    eprintln!("{} / {}: zeta {:?}", free.label, spring.label, spring.damping_ratio);
    assert!(free.rigid_body && free.damping_ratio.is_none() && free.omega_squared.abs() < 1e-9);
    assert!(
        free.label.starts_with("point mass 1 on node B (100 % kinetic), node B"),
        "{}",
        free.label
    );
    let w = (k1 / m1).sqrt();
    assert!(!spring.rigid_body && (spring.omega - w).abs() < 1e-10 * w);
    assert!(
        (spring.damping_ratio.unwrap() - zeta).abs() < 1e-10,
        "{:?}",
        spring.damping_ratio
    );
    let (re, im) = spring.damped_eigenvalue.unwrap();
    assert!((re + zeta * w).abs() < 1e-9 * w && (im - w * (1.0 - zeta * zeta).sqrt()).abs() < 1e-9 * w);
    assert!(
        spring
            .label
            .starts_with("point mass 0 on node A (100 % kinetic), node A"),
        "{}",
        spring.label
    );
    // Strain energy of the spring mode, all in spring A: phi^T K phi = w^2 (mass-normalised).
    assert!((spring.strain - w * w).abs() < 1e-9 * w * w);
}

/// An inverted pendulum (gravity reversed on the fixture pendulum: the bob 1 m above the
/// hinge) is an unstable equilibrium: the state space has the real eigenvalue
/// s = sqrt(m g d / (I_G + m d^2)) = sqrt(9.81 / 1.01) = 3.1165 1/s, and its mode is reported
/// unstable with that growth rate (it was reported as a stable 0 Hz mode); the hanging
/// pendulum has no growing eigenvalue.
#[test]
fn an_inverted_pendulum_is_reported_unstable() {
    let (mut model, _) = crate::fixtures::pendulum(1.0, 1.0, 0.01);
    let rate = (9.81f64 / 1.01).sqrt();
    let sys = mbs::System::new(&model).unwrap();
    let state = sys.initial_state();
    assert!(mbs::spectrum(&sys, &state).unwrap().growing().is_empty());
    assert!(mbs::mode_energies(&sys, &state).unwrap().iter().all(|m| !m.unstable));
    model.gravity = -model.gravity;
    let sys = mbs::System::new(&model).unwrap();
    let state = sys.initial_state();
    let growing = mbs::spectrum(&sys, &state).unwrap().growing();
    // One real eigenvalue; the dense eigensolver is exact to ~1e-14 on this 1-unknown model.
    assert_eq!(growing.len(), 1, "{growing:?}");
    assert!(
        (growing[0].0 - rate).abs() < 1e-10 && growing[0].1.abs() < 1e-10,
        "{growing:?}"
    );
    let modes = mbs::mode_energies(&sys, &state).unwrap();
    let m = &modes[0];
    assert!(m.unstable && m.frequency_hz == 0.0, "{m:?}");
    assert!((m.growth_rate.unwrap() - rate).abs() < 1e-10, "{:?}", m.growth_rate);
    assert!(
        m.label.starts_with("UNSTABLE (diverges at 3.1165e0 1/s)"),
        "{}",
        m.label
    );
}

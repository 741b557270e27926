use nalgebra::Vector3;
use reduction::ModeSelection;
use superelement::testing::*;
use superelement::*;
fn main() {
    let (_m, _i, body) = fixtures::straight_beam(nalgebra::Point3::new(0.1, -0.2, 0.05), nalgebra::Point3::new(1.0, 0.3, 0.45), 4, ModeSelection::StaticOnly, false);
    let se = Superelement::new(&body, FrameChoice::CenterOfMass, MassVariant::Lumped, Damping::none()).unwrap();
    let mut spec = StateSpec::moving(170.0, 11);
    spec.spin = 0.0;
    spec.deformation = 0.3;
    let (state, acc) = test_state(&se, &spec);
    let ev = se.evaluate(&state, &acc, &Vector3::zeros()).unwrap();
    let mut base = state.clone();
    base.frame = ev.frame;
    let n = se.n_coordinates();
    let ev2 = se.evaluate(&base, &acc, &Vector3::zeros()).unwrap();
    println!("frame iters {} {}", ev.frame_iterations, ev2.frame_iterations);
    println!("dr {:e}", (ev.frame.r - ev2.frame.r).norm());
    let r0: Vec<f64> = ev2.residual.clone();
    let mut a = acc.clone(); a[7] += 1.0;
    let r1 = se.evaluate(&base, &a, &Vector3::zeros()).unwrap().residual;
    for i in 0..n { println!("{i} {:.6e} {:.6e}", r1[i]-r0[i], ev2.mass[(i,7)]); }
}

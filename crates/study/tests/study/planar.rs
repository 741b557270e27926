//! Planar parts and bodies in study files (`planar` in `[parts.reduction]` and `[[bodies]]`,
//! the `planar` support), on the planar slider-crank of
//! `benchmarks/studies/slider_crank_beam_rod_planar.toml`.

use study::output::observer::Recorder;

/// The benchmark's planar slider-crank study, to `t_end`, with `edit` applied to its text.
fn text(t_end: f64, edit: impl Fn(String) -> String) -> String {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../benchmarks/studies/slider_crank_beam_rod_planar.toml");
    let text = std::fs::read_to_string(file).unwrap();
    let text = text.replace(
        "t_end = 0.16755160819145562   # four revolutions",
        &format!("t_end = {t_end:?}"),
    );
    edit(text)
}

/// `text` as `<name>.toml` in `dir`, loaded.
fn load(dir: &std::path::Path, name: &str, text: &str) -> Result<study::Study, String> {
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, text).unwrap();
    study::load(&file).map_err(|e| e.to_string())
}

/// A wrong type is refused at its file, line and key; the key reaches the reduction (the 2
/// modes of the round rod are its first two in-plane bending modes, where the 3D reduction's
/// are one in-plane and one out-of-plane mode of the same frequency) and the cache key (a
/// body reduced in 3D is not reused for the planar part); its bodies are planar unless they
/// say otherwise.
#[test]
fn the_planar_key_reaches_the_reduction_the_cache_and_the_bodies() {
    let dir = crate::scratch("planar-key");
    let wrong = text(0.01, |t| t.replace("planar = true ", "planar = 3 "));
    let e = load(&dir, "wrong", &wrong).unwrap_err();
    let line = wrong.lines().position(|l| l.starts_with("planar = 3")).unwrap() + 1;
    assert!(e.contains(&format!("wrong.toml:{line}:")), "{e}");
    assert!(e.contains("parts[0].reduction.planar"), "{e}");
    assert!(e.contains("expected a boolean"), "{e}");
    let wrong = text(0.01, |t| {
        t.replace("name = \"r1\"\n", "name = \"r1\"\nplanar = \"yes\"\n")
    });
    let e = load(&dir, "wrong-body", &wrong).unwrap_err();
    assert!(e.contains("bodies[1].planar"), "{e}");

    let planar = load(&dir, "planar", &text(0.01, |t| t)).unwrap();
    let spatial = load(
        &dir,
        "spatial",
        &text(0.01, |t| t.replace("planar = true ", "planar = false")),
    )
    .unwrap();
    assert!(planar.parts[0].reduction.as_ref().unwrap().planar);
    assert!(!spatial.parts[0].reduction.as_ref().unwrap().planar);
    assert!(planar.mechanism.bodies.iter().all(|b| b.planar));
    assert!(spatial.mechanism.bodies.iter().all(|b| !b.planar));
    let one_in_3d = load(
        &dir,
        "one-in-3d",
        &text(0.01, |t| {
            t.replace("name = \"r1\"\n", "name = \"r1\"\nplanar = false\n")
        }),
    )
    .unwrap();
    assert!(one_in_3d.mechanism.bodies[0].planar && !one_in_3d.mechanism.bodies[1].planar);

    let cache = dir.join("cache");
    let reduce = |study: &study::Study| study::reduce_part(study, &study.parts[0], &cache, &mut ()).unwrap();
    let (p, s) = (reduce(&planar), reduce(&spatial));
    assert!(!p.from_cache && !s.from_cache);
    assert_ne!(p.file, s.file);
    assert!(reduce(&planar).from_cache);
    let (wp, ws) = (&p.body.fixed_interface_omega, &s.body.fixed_interface_omega);
    // The round rod: the 3D pair is degenerate; the planar second mode is the second bending
    // mode (about 2.7 times the first for a beam clamped at both ends).
    // The degenerate pair splits only by the eigensolver's convergence and the mesh's round-off
    // (1e-6 is far above both, far below a physical split); the planar first mode is the 3D
    // in-plane one from the same eigenproblem, equal to the solver's tolerance, 1e-9 with margin.
    assert!((ws[1] - ws[0]).abs() < 1e-6 * ws[0], "{ws:?}");
    assert!((wp[0] - ws[0]).abs() < 1e-9 * ws[0], "{wp:?} {ws:?}");
    assert!(wp[1] > 2.5 * wp[0], "{wp:?}");
    let shapes = &p.body.mesh.as_ref().unwrap().shapes;
    for j in 12..shapes.ncols {
        for r in (0..shapes.nrows).filter(|r| reduction::OUT_OF_PLANE_DOFS.contains(&(r % 6))) {
            assert_eq!(shapes.get(r, j), 0.0);
        }
    }
}

/// Without the support of the node between the segments, a planar body could leave the
/// plane there: refused at the body, naming the node.
#[test]
fn a_planar_body_on_a_node_that_can_leave_the_plane_is_refused_at_the_body() {
    let dir = crate::scratch("planar-unsupported");
    let text = text(0.01, |t| {
        t.replace(
            "[[supports]]\nat = \"r0.b\"                 # the node between the segments: nothing else keeps it in the plane\ntype = \"planar\"\naxis = [0.0, 0.0, 1.0]\n",
            "",
        )
    });
    let study = load(&dir, "unsupported", &text).unwrap();
    let options = crate::options_in(&dir, None);
    let e = study::run_with(&study, &options, &mut Recorder::default())
        .map_err(|e| study::error::chain(&*e))
        .unwrap_err();
    assert!(e.contains("bodies[0]") && e.contains("body 'r0' is planar"), "{e}");
    assert!(e.contains("neither supported nor the child of a joint"), "{e}");
}

/// The planar run against the same study with the bodies evaluated in 3D (`planar = false` on
/// each body: the same planar parts and supports, so the same unknowns): the planar evaluation
/// is the in-plane block of the 3D one, so Newton takes the same iterations and the midpoint
/// deflection agrees to round-off over a quarter revolution (asserted to 1e-9 of the peak).
#[test]
fn the_planar_slider_crank_study_agrees_with_its_bodies_evaluated_in_3d() {
    let dir = crate::scratch("planar-run");
    let t_end = 0.25 * 2.0 * std::f64::consts::PI / 150.0;
    let run = |name: &str, text: String| {
        let study = load(&dir, name, &text).unwrap();
        let options = crate::options_in(&dir.join(name), None);
        let mut rec = Recorder::default();
        study::run_with(&study, &options, &mut rec)
            .map_err(|e| study::error::chain(&*e))
            .unwrap();
        crate::setup::column(&rec, "run", "rod-mid", 0)
    };
    let planar = run("planar", text(t_end, |t| t));
    let spatial = run(
        "spatial",
        text(t_end, |t| {
            t.replace("name = \"r0\"\n", "name = \"r0\"\nplanar = false\n")
                .replace("name = \"r1\"\n", "name = \"r1\"\nplanar = false\n")
        }),
    );
    let peak = spatial.iter().fold(0.0f64, |m, w| m.max(w.abs()));
    let worst = planar
        .iter()
        .zip(&spatial)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    eprintln!("planar against 3D: midpoint {worst:.3e} m of {peak:.3e} m");
    assert!(peak > 1e-4, "{peak}");
    assert!(worst < 1e-9 * peak, "{worst:.3e} of {peak:.3e}");
}

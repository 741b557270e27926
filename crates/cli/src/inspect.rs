//! `flexmbs inspect FILE`: what a reduced body (`.rbody`, or an MBDyn `.fem` file) holds, for
//! a person checking it before using it in a study: size, interfaces, mass data,
//! fixed-interface frequencies and modal effective masses (`reduction::diagnostics`), and the
//! physical checks every body passes before use (`reduction::checks`), with what they measured.

use std::fmt::Write as _;
use std::path::Path;
use study::error::{BoxError, ResultExt};

/// What `inspect` found: the report, and how many physical checks failed (the command then
/// exits with 1 after printing the report).
#[derive(Debug)]
pub struct Inspection {
    pub report: String,
    pub failed_checks: usize,
}

/// The report of `inspect`. `excitation_hz`: the highest frequency a study will excite; the
/// diagnostics then check that the kept modes reach `factor` times it.
pub fn inspect(path: &Path, excitation_hz: Option<f64>, factor: f64) -> Result<Inspection, BoxError> {
    // Read without the physical checks so that a refused file can still be looked at; the
    // checks are reported below.
    let is_fem = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("fem"));
    let (body, notes, record_problems) = if is_fem {
        reduction::mbdyn::read_mbdyn_fem_unchecked(path, None)
            .context(|| format!("cannot inspect {}", path.display()))?
    } else {
        let body = reduction::file::read_unchecked(path).context(|| format!("cannot inspect {}", path.display()))?;
        (body, Vec::new(), Vec::new())
    };
    let size = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "reduced body '{}' ({}, {:.1} kB, {})",
        body.name,
        path.display(),
        size as f64 / 1e3,
        if is_fem {
            "MBDyn modal element file".to_string()
        } else {
            format!("format version {}", body.format_version)
        }
    );
    for note in &notes {
        let _ = writeln!(s, "note: {note}");
    }
    let _ = writeln!(
        s,
        "CB coordinates: {} = 6 x {} interfaces + {} fixed-interface modes",
        body.n_coordinates(),
        body.interfaces.len(),
        body.n_modes
    );
    let _ = writeln!(
        s,
        "mode shapes on the mesh: {}",
        match &body.mesh {
            Some(m) => format!("kept, on {} nodes", m.nodes.len()),
            None => "not kept".into(),
        }
    );
    let _ = writeln!(
        s,
        "stress shapes: {}",
        match &body.stress {
            Some(st) => {
                let solids = st.solid_node.iter().filter(|&&b| b).count();
                format!(
                    "kept, solid stresses on {solids} nodes, section forces of {} beams",
                    st.beams.len()
                )
            }
            None => "not kept".into(),
        }
    );
    if !body.load_points.is_empty() {
        let _ = writeln!(
            s,
            "load points (static correction, {} attachment modes among the modes):",
            body.attachment_modes
        );
        for p in &body.load_points {
            let _ = writeln!(
                s,
                "  {:<16} FE node {:>8} at ({:.6e}, {:.6e}, {:.6e}) m",
                p.name, p.node, p.position[0], p.position[1], p.position[2]
            );
        }
    }
    let i = &body.inertia;
    let _ = writeln!(s, "\nmass data");
    let _ = writeln!(s, "  mass            {:.6e} kg", i.mass);
    let _ = writeln!(
        s,
        "  centre of mass  ({:.6e}, {:.6e}, {:.6e}) m",
        i.center_of_mass[0], i.center_of_mass[1], i.center_of_mass[2]
    );
    let _ = writeln!(s, "  inertia about the centre of mass [kg m^2]:");
    for row in &i.inertia_com {
        let _ = writeln!(s, "    {:>14.6e} {:>14.6e} {:>14.6e}", row[0], row[1], row[2]);
    }
    let _ = writeln!(s, "\ninterfaces");
    let _ = writeln!(
        s,
        "  {:>3}  {:<16} {:>8} {:>8} {:>14} {:>14} {:>14}",
        "#", "name", "FE node", "label", "x [m]", "y [m]", "z [m]"
    );
    for (k, p) in body.interfaces.iter().enumerate() {
        let aux = if body.auxiliary_interface == Some(k) {
            "  (auxiliary, at the centre of mass)"
        } else {
            ""
        };
        // The node's number in the part's mesh file; blank for generated meshes and added nodes.
        let label = p.node_label.map(|l| l.to_string()).unwrap_or_default();
        let _ = writeln!(
            s,
            "  {:>3}  {:<16} {:>8} {:>8} {:>14.6e} {:>14.6e} {:>14.6e}{aux}",
            k, p.name, p.node, label, p.position[0], p.position[1], p.position[2]
        );
    }
    let _ = writeln!(s, "\nfixed-interface modes and effective masses");
    if body.n_modes == 0 {
        let _ = writeln!(s, "  none kept: static (constraint) modes only");
    }
    let d = reduction::diagnostics(&body, excitation_hz, factor);
    let _ = write!(s, "{d}");
    let failed_checks = checks_report(&mut s, &body, record_problems);
    Ok(Inspection {
        report: s,
        failed_checks,
    })
}

/// The physical checks of `body` (with the problems of its file's records, `record_problems`)
/// into `s`: what they measured, then passed or the problems; the number of problems.
fn checks_report(
    s: &mut String,
    body: &reduction::ReducedBody,
    record_problems: Vec<reduction::PhysicsProblem>,
) -> usize {
    let (body_problems, measured) = reduction::checks::examine(body);
    let problems: Vec<_> = record_problems.into_iter().chain(body_problems).collect();
    let _ = write!(s, "\nphysical checks, measured:\n{measured}");
    if problems.is_empty() {
        let _ = writeln!(
            s,
            "physical checks: passed (symmetric K_CB and M_CB, positive masses, K_CB positive semi-definite with only rigid motions free, metadata consistent with the matrices, distinct interfaces)"
        );
    } else {
        let _ = writeln!(s, "physical checks: FAILED, studies refuse this file:");
        for p in &problems {
            let _ = writeln!(s, "  - {p}");
        }
    }
    problems.len()
}

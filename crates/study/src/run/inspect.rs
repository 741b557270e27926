//! `flexmbs inspect FILE` and Python's `flexmbs.inspect`: what a reduced body (`.rbody`, an
//! MBDyn `.fem` file, or matrices from another code: Matrix Market K and M with a node table,
//! reduced here as a study's `[bodies.matrices]` is) holds, for a person checking it before using it in a study: size,
//! interfaces, mass data, fixed-interface frequencies and modal effective masses
//! (`reduction::diagnostics`), and the physical checks every body passes before use
//! (`reduction::checks`), with what they measured.

use crate::error::{BoxError, ResultExt};
use crate::input::schema::MatricesFile;
use reduction::{PhysicsProblem, ReducedBody};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What `inspect` is given.
#[derive(Debug)]
pub enum Source<'a> {
    /// A reduced-body file (`.rbody`) or an MBDyn modal element file (`.fem`).
    File(&'a Path),
    /// Matrices from another code, as a study's `[bodies.matrices]` gives them (paths
    /// relative to the current folder).
    Matrices(&'a MatricesFile),
}

/// What `inspect` found: the report, and how many physical checks failed (the command then
/// exits with 1 after printing the report).
#[derive(Debug)]
pub struct Inspection {
    pub report: String,
    pub failed_checks: usize,
}

/// A body as read, before the checks of every body: where it comes from, the notes on what
/// was approximated, the problems of its input as written, the input checks that could not be
/// made and what the input checks measured.
struct Read {
    body: ReducedBody,
    path: PathBuf,
    format: String,
    notes: Vec<String>,
    problems: Vec<PhysicsProblem>,
    not_checked: Vec<String>,
    measured: String,
}

impl Read {
    fn body(body: ReducedBody, path: &Path, format: String) -> Read {
        Read {
            body,
            path: path.to_path_buf(),
            format,
            notes: Vec::new(),
            problems: Vec::new(),
            not_checked: Vec::new(),
            measured: String::new(),
        }
    }
}

/// Reads `source` without the physical checks, so that a refused body can still be looked at.
fn read(source: &Source<'_>) -> Result<Read, BoxError> {
    match source {
        Source::File(path) if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("fem")) => {
            let fem = reduction::mbdyn::read_mbdyn_fem_unchecked(path, None)
                .context(|| format!("cannot inspect {}", path.display()))?;
            Ok(Read {
                notes: fem.notes,
                problems: fem.problems,
                not_checked: fem.not_checked,
                ..Read::body(fem.body, path, "MBDyn modal element file".into())
            })
        }
        Source::File(path) => {
            let body =
                reduction::file::read_unchecked(path).context(|| format!("cannot inspect {}", path.display()))?;
            let format = format!("format version {}", body.format_version);
            Ok(Read::body(body, path, format))
        }
        Source::Matrices(m) => {
            let path = Path::new(&m.stiffness);
            let name = path
                .file_stem()
                .map_or_else(|| "matrices".to_string(), |s| s.to_string_lossy().into_owned());
            let i = crate::input::matrices::inspect_matrices(&name, m, Path::new(""))
                .map_err(|(key, message)| format!("cannot inspect {} ({key}): {message}", path.display()))?;
            let format = format!(
                "Matrix Market K, mass {}, node table {}, reduced here",
                m.mass,
                i.node_table.display()
            );
            Ok(Read {
                problems: i.node_table_problems,
                measured: i.cloud.to_string(),
                ..Read::body(i.body, path, format)
            })
        }
    }
}

/// The report of `inspect`. `excitation_hz`: the highest frequency a study will excite; the
/// diagnostics then check that the kept modes reach `factor` times it.
pub fn inspect(source: &Source<'_>, excitation_hz: Option<f64>, factor: f64) -> Result<Inspection, BoxError> {
    let read = read(source)?;
    let (body, path) = (&read.body, read.path.as_path());
    let size = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "reduced body '{}' ({}, {:.1} kB, {})",
        body.name,
        path.display(),
        size as f64 / 1e3,
        read.format
    );
    for note in &read.notes {
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
    let d = reduction::diagnostics(body, excitation_hz, factor);
    let _ = write!(s, "{d}");
    let failed_checks = checks_report(&mut s, read);
    Ok(Inspection {
        report: s,
        failed_checks,
    })
}

/// The physical checks of the body of `read` (with the problems of its input as written)
/// into `s`: what they measured, the checks that could not be made, then passed or the
/// problems; the number of problems.
fn checks_report(s: &mut String, read: Read) -> usize {
    let (body_problems, measured) = reduction::checks::examine(&read.body);
    let problems: Vec<_> = read.problems.into_iter().chain(body_problems).collect();
    let _ = write!(s, "\nphysical checks, measured:\n{}{measured}", read.measured);
    for reason in &read.not_checked {
        let _ = writeln!(s, "physical checks: not made: {reason}");
    }
    if problems.is_empty() {
        let _ = writeln!(
            s,
            "physical checks: passed (symmetric K_CB and M_CB, positive masses, K_CB positive semi-definite with only rigid motions free, metadata consistent with the matrices, distinct interfaces)"
        );
    } else {
        let _ = writeln!(s, "physical checks: FAILED, studies refuse this body:");
        for p in &problems {
            let _ = writeln!(s, "  - {p}");
        }
    }
    problems.len()
}

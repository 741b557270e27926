//! Executes a validated [`Study`] analysis by analysis, writing each one's results as soon
//! as it is done (`crate::output`), and reduces parts through the cache (`crate::cache`).
//!
//! Progress goes to stderr, what the analyses found to stdout (and into `summary.md`).

use crate::error::{BoxError, Context, ResultExt};
use crate::output::{
    default_results_dir, num, prepare_analysis_dir, AnalysisSummary, Csv, PartSummary, Status, Summary,
};
use crate::part::{Built, InterfaceTarget, LoadSpec, Part, SupportSpec};
use crate::study::{Analysis, AnalysisSpec, Solver, Study, DENSE_AUTO_LIMIT};
use crate::vtu::{six_dof_fields, write_pvd, write_vtu, PointField, VtuMesh};
use fe_model::{DofMap, ModalSolution, NodeId, DOF_NAMES};
use reduction::{CbSettings, ReducedBody};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Where results and cached bodies go.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Results folder (default: `<study dir>/<study stem>-results`).
    pub out: Option<PathBuf>,
    /// Reduced-body cache (default: `<study dir>/.flexmbs-cache`).
    pub cache: Option<PathBuf>,
    /// Ends every dynamic analysis at this time if it is earlier (`--t-end`, for short runs).
    pub t_end: Option<f64>,
}

impl Options {
    pub fn results_dir(&self, study: &Study) -> PathBuf {
        self.out
            .clone()
            .unwrap_or_else(|| default_results_dir(&study.source.path))
    }
    pub fn cache_dir(&self, study: &Study) -> PathBuf {
        self.cache
            .clone()
            .unwrap_or_else(|| study.source.dir().join(".flexmbs-cache"))
    }
}

/// What one analysis produced, for the summary.
struct Outcome {
    free_dofs: usize,
    report: Vec<String>,
    results: serde_json::Value,
    files: Vec<String>,
    /// A solver that stopped after writing part of its results.
    failure: Option<String>,
}

fn part_summary(p: &Part) -> PartSummary {
    PartSummary {
        name: p.name.clone(),
        description: p.description.clone(),
        nodes: p.base.node_count(),
        elements: p.base.elements.len(),
        interfaces: p.interfaces.iter().map(|i| i.name.clone()).collect(),
    }
}

/// Runs every analysis of `study`. Stops at the first that fails, after writing the
/// summary with the failure.
pub fn run(study: &Study, options: &Options) -> Result<Summary, BoxError> {
    let start = Instant::now();
    let out = options.results_dir(study);
    std::fs::create_dir_all(&out).context(|| format!("cannot create the results folder {}", out.display()))?;
    let cache = options.cache_dir(study);
    let mut summary = Summary {
        flexmbs_version: env!("CARGO_PKG_VERSION").to_string(),
        study: study.source.path.display().to_string(),
        title: study.title.clone(),
        status: "running".into(),
        parts: study.parts.iter().map(part_summary).collect(),
        analyses: study
            .analyses
            .iter()
            .map(|a| AnalysisSummary {
                name: a.name.clone(),
                kind: a.kind_name().into(),
                part: a
                    .part
                    .map_or_else(|| "(mechanism)".to_string(), |p| study.parts[p].name.clone()),
                status: Status::Pending,
                seconds: None,
                free_dofs: None,
                report: Vec::new(),
                results: serde_json::Value::Null,
                files: Vec::new(),
                error: None,
            })
            .collect(),
        total_seconds: 0.0,
    };
    let write_summary = |s: &Summary| {
        s.write(&out)
            .context(|| format!("cannot write the summary into {}", out.display()))
    };
    write_summary(&summary)?;
    let n = study.analyses.len();
    if n == 0 {
        eprintln!("flexmbs: the study has no [[analyses]]: nothing to run");
    }
    let mut mechanism: Option<crate::mechanism_run::BuiltMechanism> = None;
    for (i, a) in study.analyses.iter().enumerate() {
        let of = match a.part {
            Some(p) => format!("part '{}'", study.parts[p].name),
            None => "the mechanism".to_string(),
        };
        eprintln!(
            "flexmbs: [{}/{n}] {} analysis '{}' of {of}",
            i + 1,
            a.kind_name(),
            a.name
        );
        let t = Instant::now();
        let result = match &a.spec {
            AnalysisSpec::Mbs(spec) => {
                let mut spec = spec.clone();
                if let (crate::study::MbsAnalysis::Dynamic { t_end, .. }, Some(limit)) = (&mut spec, options.t_end) {
                    *t_end = t_end.min(limit);
                }
                run_mbs(study, a, &spec, &out, &cache, &mut mechanism)
            }
            _ => run_analysis(study, a, &out, &cache),
        };
        let entry = &mut summary.analyses[i];
        entry.seconds = Some(t.elapsed().as_secs_f64());
        summary.total_seconds = start.elapsed().as_secs_f64();
        match result {
            Ok(o) => {
                println!("{} '{}' ({of}):", a.kind_name(), a.name);
                for line in &o.report {
                    println!("  {line}");
                }
                entry.status = Status::Done;
                entry.free_dofs = Some(o.free_dofs);
                entry.report = o.report;
                entry.results = o.results;
                entry.files = o.files;
                if let Some(failure) = o.failure {
                    // The solver stopped: what it computed is written; the run fails here.
                    entry.status = Status::Failed;
                    entry.error = Some(failure.clone());
                    summary.status = "failed".into();
                    write_summary(&summary)?;
                    return Err(format!(
                        "{} analysis '{}' ({}): {failure} in {}",
                        a.kind_name(),
                        a.name,
                        study.location(&a.path),
                        out.join(&a.name).display()
                    )
                    .into());
                }
                write_summary(&summary)?;
            }
            Err(e) => {
                entry.status = Status::Failed;
                entry.error = Some(
                    crate::error::report(&*e)
                        .trim_start_matches("flexmbs: error: ")
                        .to_string(),
                );
                summary.status = "failed".into();
                write_summary(&summary)?;
                return Err(Box::new(Context {
                    message: format!(
                        "{} analysis '{}' ({}) failed; the results of the analyses before it are in {}",
                        a.kind_name(),
                        a.name,
                        study.location(&a.path),
                        out.display()
                    ),
                    source: e,
                }));
            }
        }
    }
    summary.status = "complete".into();
    summary.total_seconds = start.elapsed().as_secs_f64();
    write_summary(&summary)?;
    eprintln!(
        "flexmbs: {n} analyses done in {:.2} s; results in {}",
        summary.total_seconds,
        out.display()
    );
    Ok(summary)
}

/// An analysis of the mechanism; the mechanism is built (and its bodies reduced) once.
fn run_mbs(
    study: &Study,
    a: &Analysis,
    spec: &crate::study::MbsAnalysis,
    out: &Path,
    cache: &Path,
    mechanism: &mut Option<crate::mechanism_run::BuiltMechanism>,
) -> Result<Outcome, BoxError> {
    let dir = out.join(&a.name);
    prepare_analysis_dir(&dir).context(|| format!("cannot prepare the results folder {}", dir.display()))?;
    if mechanism.is_none() {
        *mechanism = Some(crate::mechanism_run::build(study, cache)?);
    }
    let Some(built) = mechanism.as_ref() else {
        return Err("the mechanism could not be built".into());
    };
    let o = crate::mechanism_run::run_analysis(study, spec, built, &dir, &a.name)?;
    Ok(Outcome {
        free_dofs: o.free_dofs,
        report: o.report,
        results: o.results,
        files: o.files,
        failure: o.failure,
    })
}

fn run_analysis(study: &Study, a: &Analysis, out: &Path, cache: &Path) -> Result<Outcome, BoxError> {
    let dir = out.join(&a.name);
    prepare_analysis_dir(&dir).context(|| format!("cannot prepare the results folder {}", dir.display()))?;
    let Some(part) = a.part.map(|p| &study.parts[p]) else {
        return Err(format!("analysis '{}' has no part", a.name).into());
    };
    let mut files = Files {
        dir: dir.clone(),
        prefix: a.name.clone(),
        list: Vec::new(),
    };
    let mut o = match &a.spec {
        AnalysisSpec::Static { supports, loads } => run_static(part, supports, loads, &mut files)?,
        AnalysisSpec::Modal {
            modes,
            solver,
            supports,
        } => run_modal(part, *modes, *solver, supports, &mut files)?,
        AnalysisSpec::Reduce => run_reduce(part, cache, &mut files)?,
        AnalysisSpec::Mbs(_) => return Err(format!("analysis '{}' runs on the mechanism", a.name).into()),
    };
    o.files = files.list;
    Ok(o)
}

/// The files of one analysis: written into its folder, listed relative to the results folder.
struct Files {
    dir: PathBuf,
    prefix: String,
    list: Vec<String>,
}

impl Files {
    fn path(&mut self, name: &str) -> PathBuf {
        self.list.push(format!("{}/{name}", self.prefix));
        self.dir.join(name)
    }
    fn csv(&mut self, name: &str, csv: &Csv) -> Result<(), BoxError> {
        let p = self.path(name);
        csv.write(&p).context(|| format!("cannot write {}", p.display()))
    }
    fn vtu(&mut self, name: &str, mesh: &VtuMesh, fields: &[PointField<'_>]) -> Result<(), BoxError> {
        let p = self.path(name);
        write_vtu(&p, mesh, fields).context(|| format!("cannot write {}", p.display()))
    }
    /// A field of six dofs per node, as the point fields "displacement" and "rotation".
    fn six_dof_vtu(&mut self, name: &str, mesh: &VtuMesh, values: &[[f64; 6]]) -> Result<(), BoxError> {
        let (u, r) = six_dof_fields(values);
        let fields = [
            PointField {
                name: "displacement",
                components: 3,
                values: &u,
            },
            PointField {
                name: "rotation",
                components: 3,
                values: &r,
            },
        ];
        self.vtu(name, mesh, &fields)
    }
    fn pvd(&mut self, name: &str, entries: &[(f64, String)]) -> Result<(), BoxError> {
        let p = self.path(name);
        write_pvd(&p, entries).context(|| format!("cannot write {}", p.display()))
    }
}

/// The spider of each solid interface, for drawing (the auxiliary spider on every node is
/// left out: it would hide the mesh).
fn spiders(part: &Part, built: &Built) -> Vec<(NodeId, Vec<NodeId>)> {
    part.interfaces
        .iter()
        .zip(&built.interfaces)
        .filter_map(|(spec, (_, node))| match &spec.target {
            InterfaceTarget::Spider { surface, .. } => Some((*node, surface.clone())),
            InterfaceTarget::BeamNode(_) => None,
        })
        .collect()
}

fn tag(built: &Built, node: NodeId) -> u64 {
    built
        .model
        .mesh
        .node_tags
        .get(node.index())
        .copied()
        .unwrap_or(node.0 as u64 + 1)
}

/// `x` with 7 significant digits; `-0` printed as `0`.
fn sci(x: f64) -> String {
    format!("{:.6e}", x + 0.0)
}

fn vec_text(v: &[f64]) -> String {
    format!("({})", v.iter().map(|x| sci(*x)).collect::<Vec<_>>().join(", "))
}

fn free_dofs(part: &Part, built: &Built) -> Result<usize, BoxError> {
    Ok(DofMap::new(&built.model)
        .context(|| format!("part '{}': cannot number the dofs", part.name))?
        .n_free())
}

fn run_static(
    part: &Part,
    supports: &[SupportSpec],
    loads: &[LoadSpec],
    files: &mut Files,
) -> Result<Outcome, BoxError> {
    let built = part
        .build(supports, false)
        .context(|| format!("part '{}': cannot build the FE model", part.name))?;
    let n_free = free_dofs(part, &built)?;
    let loads = Part::nodal_loads(&built, loads);
    let s = fe_model::solve_static(&built.model, &loads)
        .context(|| format!("part '{}': static solution failed", part.name))?;
    let nodes = &built.model.mesh.nodes;

    let mut csv = Csv::new(&[
        "node", "tag", "x [m]", "y [m]", "z [m]", "ux [m]", "uy [m]", "uz [m]", "rx [rad]", "ry [rad]", "rz [rad]",
    ]);
    let mut max = (0.0, 0usize);
    for (i, u) in s.displacements.iter().enumerate() {
        let norm = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
        if norm > max.0 {
            max = (norm, i);
        }
        let mut row = vec![i.to_string(), tag(&built, NodeId(i as u32)).to_string()];
        row.extend([nodes[i].x, nodes[i].y, nodes[i].z].map(num));
        row.extend(u.map(num));
        csv.row(&row);
    }
    files.csv("displacements.csv", &csv)?;

    let mut csv = Csv::new(&[
        "node", "tag", "Fx [N]", "Fy [N]", "Fz [N]", "Mx [N m]", "My [N m]", "Mz [N m]",
    ]);
    let mut total = [0.0; 6];
    for (node, r) in &s.reactions {
        let mut row = vec![node.index().to_string(), tag(&built, *node).to_string()];
        row.extend(r.map(num));
        csv.row(&row);
        // Moments about the origin: M + x x F.
        let x = nodes[node.index()].coords;
        let m = nalgebra::Vector3::new(r[3], r[4], r[5]) + x.cross(&nalgebra::Vector3::new(r[0], r[1], r[2]));
        for k in 0..3 {
            total[k] += r[k];
            total[3 + k] += m[k];
        }
    }
    files.csv("reactions.csv", &csv)?;

    let mut csv = Csv::new(&[
        "interface",
        "node",
        "ux [m]",
        "uy [m]",
        "uz [m]",
        "rx [rad]",
        "ry [rad]",
        "rz [rad]",
    ]);
    let mut report = vec![format!(
        "solved {n_free} dofs, relative residual {:.1e}",
        s.relative_residual
    )];
    report.push(format!(
        "largest displacement |u| = {:.6e} m at node {} ({:.4}, {:.4}, {:.4})",
        max.0,
        tag(&built, NodeId(max.1 as u32)),
        nodes[max.1].x,
        nodes[max.1].y,
        nodes[max.1].z
    ));
    let mut interfaces = Vec::new();
    for (name, node) in &built.interfaces {
        let u = s.displacements[node.index()];
        let mut row = vec![name.clone(), node.index().to_string()];
        row.extend(u.map(num));
        csv.row(&row);
        report.push(format!(
            "interface '{name}': u = {} m, theta = {} rad",
            vec_text(&u[..3]),
            vec_text(&u[3..])
        ));
        interfaces.push(json!({ "name": name, "u": &u[..3], "theta": &u[3..] }));
    }
    files.csv("interfaces.csv", &csv)?;
    report.push(format!(
        "sum of reactions: F = {} N, M = {} N m about the origin",
        vec_text(&total[..3]),
        vec_text(&total[3..])
    ));
    // Equilibrium check of the whole part: the reactions (spider supports included, see
    // fe_model::statics::support_reactions) must balance the applied forces.
    let applied: f64 = loads.iter().map(|l| l.force.norm()).sum();
    let sum_f = nalgebra::Vector3::new(total[0], total[1], total[2])
        + loads.iter().map(|l| l.force).sum::<nalgebra::Vector3<f64>>();
    if applied > 0.0 && sum_f.norm() > 1e-6 * applied {
        report.push(format!(
            "warning: the reactions do not balance the applied forces (out of balance {:.3e} N)",
            sum_f.norm()
        ));
    }

    let mesh = VtuMesh::from_model(&built.model, &spiders(part, &built));
    files.six_dof_vtu("static.vtu", &mesh, &s.displacements)?;
    files.pvd("static.pvd", &[(0.0, "static.vtu".into())])?;
    Ok(Outcome {
        free_dofs: n_free,
        report,
        results: json!({
            "max_displacement_m": max.0,
            "max_displacement_node": tag(&built, NodeId(max.1 as u32)),
            "relative_residual": s.relative_residual,
            "interfaces": interfaces,
        }),
        files: Vec::new(),
        failure: None,
    })
}

fn run_modal(
    part: &Part,
    modes: usize,
    solver: Solver,
    supports: &[SupportSpec],
    files: &mut Files,
) -> Result<Outcome, BoxError> {
    let built = part
        .build(supports, false)
        .context(|| format!("part '{}': cannot build the FE model", part.name))?;
    let n_free = free_dofs(part, &built)?;
    let dense = match solver {
        Solver::Dense => true,
        Solver::Sparse => false,
        Solver::Auto => n_free <= DENSE_AUTO_LIMIT,
    };
    // The sparse solver needs fewer modes than dofs; so many modes only fit a small model.
    let dense = dense || modes >= n_free;
    let modes = modes.min(n_free);
    let t = Instant::now();
    let (solution, method): (ModalSolution, &str) = if dense {
        (
            fe_model::modal_dense(&built.model, modes)
                .context(|| format!("part '{}': dense modal analysis failed", part.name))?,
            "dense",
        )
    } else {
        let (s, _residuals) = reduction::modal_sparse(&built.model, modes, reduction::Shift::Auto)
            .context(|| format!("part '{}': sparse modal analysis failed", part.name))?;
        (s, "sparse shift-invert")
    };
    let f = solution.frequencies_hz();
    let mut csv = Csv::new(&["mode", "frequency [Hz]", "omega [rad/s]"]);
    for (k, (hz, w)) in f.iter().zip(&solution.omega).enumerate() {
        csv.row(&[(k + 1).to_string(), num(*hz), num(*w)]);
    }
    files.csv("frequencies.csv", &csv)?;
    let mesh = VtuMesh::from_model(&built.model, &spiders(part, &built));
    let mut entries = Vec::new();
    for (k, shape) in solution.shapes.iter().enumerate() {
        let name = format!("mode_{:03}.vtu", k + 1);
        files.six_dof_vtu(&name, &mesh, shape)?;
        entries.push(((k + 1) as f64, name));
    }
    files.pvd("modes.pvd", &entries)?;
    let mut report = vec![format!(
        "{} modes of {n_free} dofs ({method}, {:.3} s), mass-normalised shapes in modes.pvd",
        f.len(),
        t.elapsed().as_secs_f64()
    )];
    // Rigid-body modes come out at round-off level, a few millionths of the elastic ones.
    let highest = f.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    for (k, hz) in f.iter().enumerate() {
        let rigid = if hz.abs() < 1e-4 * highest {
            "  (rigid-body mode)"
        } else {
            ""
        };
        report.push(format!("mode {:>3}: {:>14} Hz{rigid}", k + 1, sci(*hz)));
    }
    Ok(Outcome {
        free_dofs: n_free,
        report,
        results: json!({ "solver": method, "frequencies_hz": f }),
        files: Vec::new(),
        failure: None,
    })
}

/// A part reduced through the cache.
pub struct Reduced {
    pub body: ReducedBody,
    pub built: Built,
    /// The cache file.
    pub file: PathBuf,
    pub from_cache: bool,
    pub free_dofs: usize,
}

/// Reduces `part` (which has a reduction), or reads it from the cache when the same mesh and
/// settings were reduced before (`crate::cache`).
pub fn reduce_part(part: &Part, cache: &Path) -> Result<Reduced, BoxError> {
    let Some(reduction) = &part.reduction else {
        return Err(format!("part '{}' has no [parts.reduction]", part.name).into());
    };
    let built = part
        .build(&[], reduction.auxiliary_node)
        .context(|| format!("part '{}': cannot build the FE model", part.name))?;
    let n_free = free_dofs(part, &built)?;
    let key = crate::cache::key(part, &built, reduction)
        .context(|| format!("part '{}': cannot hash its inputs", part.name))?;
    let file = crate::cache::path(cache, &part.name, &key);
    if file.is_file() {
        match reduction::file::read(&file) {
            Ok(body) if body.name == part.name => {
                eprintln!(
                    "flexmbs: part '{}': reduced body found in the cache ({}): same mesh and settings, not reducing again",
                    part.name,
                    file.display()
                );
                return Ok(Reduced {
                    body,
                    built,
                    file,
                    from_cache: true,
                    free_dofs: n_free,
                });
            }
            Ok(_) => eprintln!(
                "flexmbs: warning: cache file {} holds another body; reducing again",
                file.display()
            ),
            Err(e) => eprintln!("flexmbs: warning: cannot use the cached body ({e}); reducing again"),
        }
    }
    let modes = match reduction.modes {
        reduction::ModeSelection::StaticOnly => "static modes only".to_string(),
        reduction::ModeSelection::Count(m) => format!("{m} fixed-interface modes"),
        reduction::ModeSelection::CutoffHz(f) => format!("fixed-interface modes below {f} Hz"),
    };
    eprintln!(
        "flexmbs: part '{}': reducing {n_free} dofs to {} interfaces{} and {modes}{} ...",
        part.name,
        built.interfaces.len(),
        if built.auxiliary.is_some() {
            " + the auxiliary node"
        } else {
            ""
        },
        if reduction.geometric_stiffening {
            ", with geometric stiffening"
        } else {
            ""
        }
    );
    let t = Instant::now();
    let mut settings = CbSettings::new(reduction.modes);
    settings.keep_mesh_shapes = reduction.keep_mesh_shapes;
    settings.auxiliary_node = built.auxiliary;
    settings.geometric_stiffening = reduction.geometric_stiffening;
    // A spinner on stderr naming the stage (hidden when stderr is not a terminal).
    let bar = indicatif::ProgressBar::with_draw_target(None, indicatif::ProgressDrawTarget::stderr());
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let mut progress = |stage: reduction::Stage| {
        let what = match stage {
            reduction::Stage::Assembling => "assembling K and M".to_string(),
            reduction::Stage::Factorising { internal_dofs } => format!("factorising K_ii ({internal_dofs} dofs)"),
            reduction::Stage::ConstraintModes { count } => format!("{count} constraint modes"),
            reduction::Stage::EigenIteration { converged, wanted, .. } => {
                format!("fixed-interface modes: {converged} of {wanted} converged")
            }
            reduction::Stage::Projecting => "projecting K_CB, M_CB".to_string(),
            reduction::Stage::Invariants => "inertia invariants".to_string(),
            _ => return,
        };
        bar.set_message(format!("part '{}': {what}", part.name));
    };
    let body = reduction::reduce_with_progress(
        &built.model,
        &part.name,
        &built.interfaces,
        &settings,
        fe_model::FillOrdering::Auto,
        &mut progress,
    )
    .context(|| format!("part '{}': Craig-Bampton reduction failed", part.name))?;
    bar.finish_and_clear();
    eprintln!(
        "flexmbs: part '{}': reduced in {:.2} s to {} coordinates ({} interfaces, {} modes)",
        part.name,
        t.elapsed().as_secs_f64(),
        body.n_coordinates(),
        body.interfaces.len(),
        body.n_modes
    );
    std::fs::create_dir_all(cache).context(|| format!("cannot create the cache folder {}", cache.display()))?;
    reduction::file::write(&body, &file).context(|| format!("part '{}': cannot write the reduced body", part.name))?;
    eprintln!(
        "flexmbs: part '{}': saved to the cache as {}",
        part.name,
        file.display()
    );
    Ok(Reduced {
        body,
        built,
        file,
        from_cache: false,
        free_dofs: n_free,
    })
}

fn run_reduce(part: &Part, cache: &Path, files: &mut Files) -> Result<Outcome, BoxError> {
    let r = reduce_part(part, cache)?;
    let body = &r.body;
    let name = format!("{}.{}", part.name, reduction::file::EXTENSION);
    let target = files.path(&name);
    std::fs::copy(&r.file, &target).context(|| format!("cannot copy {} to {}", r.file.display(), target.display()))?;

    let mut csv = Csv::new(&["index", "name", "node", "x [m]", "y [m]", "z [m]"]);
    for (k, i) in body.interfaces.iter().enumerate() {
        let mut row = vec![k.to_string(), i.name.clone(), i.node.to_string()];
        row.extend(i.position.map(num));
        csv.row(&row);
    }
    files.csv("interfaces.csv", &csv)?;

    let d = reduction::diagnostics(body, None, 3.0);
    let mut header = vec!["mode", "frequency [Hz]", "generalized mass [-]"];
    let labels: Vec<String> = reduction::diagnostics::DIRECTIONS
        .iter()
        .map(|d| format!("effective mass {d} [% of rigid]"))
        .collect();
    header.extend(labels.iter().map(String::as_str));
    let mut csv = Csv::new(&header);
    for m in &d.modes {
        let mut row = vec![m.mode.to_string(), num(m.frequency_hz), num(m.generalized_mass)];
        row.extend(m.effective_fraction.map(|x| num(100.0 * x)));
        csv.row(&row);
    }
    files.csv("fixed_interface_modes.csv", &csv)?;

    let i = &body.inertia;
    let mut csv = Csv::new(&["quantity", "value", "unit"]);
    csv.row(&["mass".into(), num(i.mass), "kg".into()]);
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        csv.row(&[format!("center of mass {axis}"), num(i.center_of_mass[k]), "m".into()]);
    }
    for (a, ra) in ["x", "y", "z"].iter().enumerate() {
        for (b, rb) in ["x", "y", "z"].iter().enumerate() {
            csv.row(&[
                format!("inertia about center of mass J{ra}{rb}"),
                num(i.inertia_com[a][b]),
                "kg m^2".into(),
            ]);
        }
    }
    files.csv("mass.csv", &csv)?;

    // The CB shapes on the mesh: the constraint modes, then the fixed-interface modes.
    if let Some(shapes) = &body.mesh {
        let n_nodes = shapes.nodes.len();
        if n_nodes == r.built.model.node_count() {
            let mesh = VtuMesh::from_model(&r.built.model, &spiders(part, &r.built));
            let mut csv = Csv::new(&["shape", "file", "kind", "interface", "dof", "frequency [Hz]"]);
            let mut entries = Vec::new();
            for c in 0..shapes.shapes.ncols {
                let values: Vec<[f64; 6]> = (0..n_nodes)
                    .map(|n| std::array::from_fn(|k| shapes.shapes.get(6 * n + k, c)))
                    .collect();
                let file = format!("shape_{:03}.vtu", c + 1);
                files.six_dof_vtu(&file, &mesh, &values)?;
                let nb = 6 * body.interfaces.len();
                let row = if c < nb {
                    vec![
                        (c + 1).to_string(),
                        file.clone(),
                        "constraint mode".into(),
                        body.interfaces[c / 6].name.clone(),
                        DOF_NAMES[c % 6].into(),
                        String::new(),
                    ]
                } else {
                    let k = c - nb;
                    vec![
                        (c + 1).to_string(),
                        file.clone(),
                        "fixed-interface mode".into(),
                        String::new(),
                        String::new(),
                        num(body.fixed_interface_omega[k] / (2.0 * std::f64::consts::PI)),
                    ]
                };
                csv.row(&row);
                entries.push(((c + 1) as f64, file));
            }
            files.csv("shapes.csv", &csv)?;
            files.pvd("shapes.pvd", &entries)?;
        }
    }

    let f: Vec<f64> = body
        .fixed_interface_omega
        .iter()
        .map(|w| w / (2.0 * std::f64::consts::PI))
        .collect();
    let mut report = vec![
        format!(
            "{} CB coordinates = 6 x {} interfaces + {} fixed-interface modes, from {} dofs{}",
            body.n_coordinates(),
            body.interfaces.len(),
            body.n_modes,
            r.free_dofs,
            if r.from_cache { " (from the cache)" } else { "" }
        ),
        format!(
            "mass {:.6e} kg, centre of mass {} m",
            i.mass,
            vec_text(&i.center_of_mass)
        ),
    ];
    if !f.is_empty() {
        report.push(format!(
            "fixed-interface frequencies [Hz]: {}",
            f.iter().map(|x| sci(*x)).collect::<Vec<_>>().join(", ")
        ));
    }
    report.push(format!("reduced body: {}/{name}", files.prefix));
    for w in &d.warnings {
        report.push(format!("warning: {w}"));
    }
    Ok(Outcome {
        free_dofs: r.free_dofs,
        report,
        results: json!({
            "coordinates": body.n_coordinates(),
            "interfaces": body.interfaces.iter().map(|i| i.name.clone()).collect::<Vec<_>>(),
            "modes_kept": body.n_modes,
            "fixed_interface_frequencies_hz": f,
            "mass_kg": i.mass,
            "center_of_mass_m": i.center_of_mass,
            "from_cache": r.from_cache,
            "cache_file": r.file.display().to_string(),
        }),
        files: Vec::new(),
        failure: None,
    })
}

/// `flexmbs reduce`: reduces every part with a `[parts.reduction]`, or the one named, and
/// copies the bodies into the results folder. Returns the files written.
pub fn reduce_command(study: &Study, only: Option<&str>, options: &Options) -> Result<Vec<PathBuf>, BoxError> {
    let parts: Vec<&Part> = match only {
        Some(name) => {
            let part = &study.parts[study.part(name)?];
            if part.reduction.is_none() {
                return Err(format!(
                    "part '{name}' has no [parts.reduction] in {} (parts that do: {})",
                    study.source.path.display(),
                    reducible(study)
                )
                .into());
            }
            vec![part]
        }
        None => study.parts.iter().filter(|p| p.reduction.is_some()).collect(),
    };
    if parts.is_empty() {
        return Err(format!(
            "no part of {} has a [parts.reduction]: nothing to reduce",
            study.source.path.display()
        )
        .into());
    }
    let out = options.results_dir(study);
    std::fs::create_dir_all(&out).context(|| format!("cannot create the results folder {}", out.display()))?;
    let cache = options.cache_dir(study);
    let mut written = Vec::new();
    for part in parts {
        let r = reduce_part(part, &cache)?;
        let target = out.join(format!("{}.{}", part.name, reduction::file::EXTENSION));
        std::fs::copy(&r.file, &target)
            .context(|| format!("cannot copy {} to {}", r.file.display(), target.display()))?;
        println!(
            "part '{}': {} coordinates ({} interfaces, {} modes) -> {}",
            part.name,
            r.body.n_coordinates(),
            r.body.interfaces.len(),
            r.body.n_modes,
            target.display()
        );
        written.push(target);
    }
    Ok(written)
}

fn reducible(study: &Study) -> String {
    let names: Vec<&str> = study
        .parts
        .iter()
        .filter(|p| p.reduction.is_some())
        .map(|p| p.name.as_str())
        .collect();
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
    }
}

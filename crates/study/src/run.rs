//! Executes a validated [`Study`] analysis by analysis, every result to an [`Observer`] as
//! soon as it is computed, and reduces parts through the cache (`crate::cache`). The
//! analyses of parts (static, modal, reduce) are here; those of the mechanism in
//! `crate::mechanism`.

use crate::error::{AnalysisFailed, BoxError, ResultExt, SolverStopped};
use crate::input::part::{Built, InterfaceTarget, LoadSpec, Part, SupportSpec};
use crate::input::validate::{Analysis, AnalysisSpec, Solver, Study, DENSE_AUTO_LIMIT};
use crate::output::folder::ResultsFolder;
use crate::output::observer::{AnalysisInfo, Cell, Observer, Progress, Series, Table};
use crate::output::summary::{default_results_dir, AnalysisSummary, PartSummary, Status, Summary};
use crate::output::vtu::{six_dof_fields, PointField, VtuMesh};
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
    /// Files in the results folder that flexmbs did not write: refuse (default) or keep
    /// (`--foreign-files keep`; `crate::output::folder`).
    pub foreign: crate::output::folder::ForeignFiles,
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
    /// A solver that stopped after writing part of its results.
    failure: Option<SolverStopped>,
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

/// The analysis `a` (number `index` of the study) as the observer sees it.
pub fn analysis_info(study: &Study, index: usize) -> AnalysisInfo {
    let a = &study.analyses[index];
    AnalysisInfo {
        index,
        count: study.analyses.len(),
        name: a.name.clone(),
        kind: a.kind_name().into(),
        of: match a.part {
            Some(p) => format!("part '{}'", study.parts[p].name),
            None => "the mechanism".to_string(),
        },
    }
}

/// The summary of `study` before anything ran: every analysis pending.
pub fn pending_summary(study: &Study) -> Summary {
    Summary {
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
    }
}

/// Runs every analysis of `study` into a results folder (`options.out`, or beside the study
/// file), with `observer` seeing every result too. Stops at the first analysis that fails,
/// after writing the summary with the failure.
pub fn run(study: &Study, options: &Options, observer: &mut dyn Observer) -> Result<Summary, BoxError> {
    // Refused before the results folder is made.
    if study.analyses.is_empty() {
        return Err(nothing_to_run(study));
    }
    let names: Vec<String> = study.analyses.iter().map(|a| a.name.clone()).collect();
    let mut folder = ResultsFolder::open(&options.results_dir(study), &names, options.foreign)?;
    run_with(study, options, &mut (&mut folder, observer))
}

/// Runs analysis `index` of `study` alone into its results folder (the other analyses'
/// files are left as they are), every result to `observer` too. When its `start` names
/// another analysis, that one (and the chain of `start`s behind it) runs first and writes
/// its results too ([`Runner::run_one`]).
pub fn run_only(
    study: &Study,
    options: &Options,
    index: usize,
    observer: &mut dyn Observer,
) -> Result<Summary, BoxError> {
    let names: Vec<String> = study.analyses.iter().map(|a| a.name.clone()).collect();
    let mut folder = ResultsFolder::open(&options.results_dir(study), &names, options.foreign)?;
    let obs: &mut dyn Observer = &mut (&mut folder, observer);
    let mut runner = Runner::new(study, options);
    obs.summary(&runner.summary)?;
    runner.run_one(index, obs)?;
    runner.finish(obs)
}

/// Runs every analysis of `study`, every result to `obs` only (no results folder unless
/// `obs` writes one); the cache of reduced bodies is used as in [`run`].
pub fn run_with(study: &Study, options: &Options, obs: &mut dyn Observer) -> Result<Summary, BoxError> {
    let n = study.analyses.len();
    if n == 0 {
        return Err(nothing_to_run(study));
    }
    let mut runner = Runner::new(study, options);
    obs.summary(&runner.summary)?;
    for i in 0..n {
        runner.run_one(i, obs)?;
    }
    runner.finish(obs)
}

/// The error for a study without analyses.
pub fn nothing_to_run(study: &Study) -> BoxError {
    format!(
        "{}: the study has no [[analyses]], so there is nothing to run; add one \
         (`type = \"static\"`, `\"modal\"`, `\"reduce\"`, `\"equilibrium\"`, `\"dynamic\"`, \
         `\"linearized\"` or `\"buckling\"`, docs/study-file.md)",
        study.source.path.display()
    )
    .into()
}

/// A study being run analysis by analysis; the mechanism is built once, at its first
/// analysis, and kept for the next.
pub struct Runner<'s> {
    study: &'s Study,
    options: Options,
    start: Instant,
    pub summary: Summary,
    mechanism: Option<crate::mechanism::BuiltMechanism>,
    /// The final state of each analysis of the mechanism that ended in one (for `start`).
    states: Vec<Option<mbs::State>>,
}

impl<'s> Runner<'s> {
    pub fn new(study: &'s Study, options: &Options) -> Self {
        Self {
            study,
            options: options.clone(),
            start: Instant::now(),
            summary: pending_summary(study),
            mechanism: None,
            states: vec![None; study.analyses.len()],
        }
    }

    /// The final state of analysis `i`, once it has run (equilibrium and dynamic analyses).
    pub fn state(&self, i: usize) -> Option<&mbs::State> {
        self.states[i].as_ref()
    }

    /// The mechanism, built (its bodies reduced through the cache) at the first call.
    pub fn mechanism(&mut self, obs: &mut dyn Observer) -> Result<&crate::mechanism::BuiltMechanism, BoxError> {
        if self.mechanism.is_none() {
            let cache = self.options.cache_dir(self.study);
            self.mechanism = Some(crate::mechanism::build(self.study, &cache, obs)?);
        }
        self.mechanism
            .as_ref()
            .ok_or_else(|| "the mechanism could not be built".into())
    }

    /// Runs analysis `i`; a failure is recorded in the summary and returned with the
    /// analysis it belongs to. An analysis whose `start` names one that has not run yet runs
    /// that one first (and its own `start`, down the chain), with its results recorded as
    /// usual: running one analysis alone needs no earlier run.
    pub fn run_one(&mut self, i: usize, obs: &mut dyn Observer) -> Result<(), BoxError> {
        let study = self.study;
        let a = &study.analyses[i];
        // The analysis whose final state is the start, run now when it has not run.
        let mut prerequisite = None;
        if let Some(k) = a.start {
            if self.states[k].is_none() && self.summary.analyses[k].status == crate::output::summary::Status::Pending {
                self.run_one(k, obs)?;
                prerequisite = Some(k);
            }
        }
        let info = analysis_info(study, i);
        obs.begin(&info)?;
        let t = Instant::now();
        let cache = self.options.cache_dir(study);
        // (t_end of the study, the --t-end it was cut to) when the option shortened the run.
        let mut shortened = None;
        let result = match &a.spec {
            AnalysisSpec::Mbs(spec) => {
                let mut spec = spec.clone();
                let mut refused = None;
                if let (crate::input::validate::MbsAnalysis::Dynamic { t_end, dt, .. }, Some(limit)) =
                    (&mut spec, self.options.t_end)
                {
                    if limit < *dt {
                        refused = Some(format!(
                            "--t-end {limit} s is shorter than one time step of analysis '{}' (dt = {dt} s)",
                            a.name
                        ));
                    }
                    if limit < *t_end {
                        shortened = Some((*t_end, limit));
                        *t_end = limit;
                    }
                }
                let start: Result<Option<mbs::State>, BoxError> = match (refused, a.start) {
                    (Some(refusal), _) => Err(refusal.into()),
                    (None, start) => match start {
                        Some(k) => self.states[k].clone().map(Some).ok_or_else(|| {
                            format!(
                                "analysis '{}' starts from '{}', which ended in no state",
                                a.name, study.analyses[k].name
                            )
                            .into()
                        }),
                        None => Ok(None),
                    },
                };
                let mut final_state = None;
                let result = match (start, self.mechanism(obs)) {
                    (Ok(start), Ok(built)) => crate::mechanism::run_analysis(study, &spec, built, start.as_ref(), obs)
                        .map(|o| {
                            final_state = o.final_state;
                            Outcome {
                                free_dofs: o.free_dofs,
                                report: o.report,
                                results: o.results,
                                failure: o.failure,
                            }
                        }),
                    (Err(e), _) | (_, Err(e)) => Err(e),
                };
                self.states[i] = final_state;
                result
            }
            _ => run_analysis(study, a, &cache, obs),
        };
        let result = result.map(|mut o| {
            if let Some(k) = prerequisite {
                o.report.insert(
                    0,
                    format!(
                        "started from the final state of '{}', which was run first for it",
                        study.analyses[k].name
                    ),
                );
            }
            if let Some((requested, limit)) = shortened {
                o.report.insert(
                    0,
                    format!("shortened by --t-end: run to t = {limit} s instead of the study's t_end = {requested} s"),
                );
                if let Some(r) = o.results.as_object_mut() {
                    r.insert("t_end_study".into(), json!(requested));
                    r.insert("t_end_option".into(), json!(limit));
                }
            }
            o
        });
        let files = obs.take_files();
        let summary = &mut self.summary;
        let entry = &mut summary.analyses[i];
        entry.seconds = Some(t.elapsed().as_secs_f64());
        entry.files = files;
        summary.total_seconds = self.start.elapsed().as_secs_f64();
        let where_ = || match &self.options.out {
            Some(out) => out.display().to_string(),
            None => self.options.results_dir(study).display().to_string(),
        };
        match result {
            Ok(o) => {
                entry.status = Status::Done;
                entry.free_dofs = Some(o.free_dofs);
                entry.report = o.report;
                entry.results = o.results;
                if let Some(failure) = o.failure {
                    // The solver stopped: what it computed is written; the run fails here.
                    entry.status = Status::Failed;
                    entry.error = Some(crate::error::chain(&failure));
                    summary.status = failed_status();
                    let entry = entry.clone();
                    // The failure is the message; a summary that cannot be written (a full
                    // disk) must not replace it.
                    let _ = obs.end(&info, &entry);
                    let _ = obs.summary(summary);
                    return Err(Box::new(AnalysisFailed {
                        analysis: a.name.clone(),
                        message: format!(
                            "{} analysis '{}' ({}) stopped; what it computed is in {}/{}",
                            a.kind_name(),
                            a.name,
                            study.location(&a.path),
                            where_(),
                            a.name
                        ),
                        source: Box::new(failure),
                    }));
                }
                let entry = entry.clone();
                obs.end(&info, &entry)?;
                obs.summary(summary)?;
                Ok(())
            }
            Err(e) => {
                entry.status = Status::Failed;
                entry.error = Some(crate::error::chain(&*e));
                summary.status = failed_status();
                let entry = entry.clone();
                let _ = obs.end(&info, &entry);
                let _ = obs.summary(summary);
                Err(Box::new(AnalysisFailed {
                    analysis: a.name.clone(),
                    message: format!(
                        "{} analysis '{}' ({}) failed; the results of the analyses before it are in {}",
                        a.kind_name(),
                        a.name,
                        study.location(&a.path),
                        where_()
                    ),
                    source: e,
                }))
            }
        }
    }

    /// Marks the run complete and hands the summary out.
    pub fn finish(mut self, obs: &mut dyn Observer) -> Result<Summary, BoxError> {
        self.summary.status = "complete".into();
        self.summary.total_seconds = self.start.elapsed().as_secs_f64();
        obs.summary(&self.summary)?;
        Ok(self.summary)
    }
}

/// The summary status of a run that stopped: `interrupted` after Ctrl-C, else `failed`.
fn failed_status() -> String {
    if crate::interrupt::requested() {
        "interrupted".into()
    } else {
        "failed".into()
    }
}

fn run_analysis(study: &Study, a: &Analysis, cache: &Path, obs: &mut dyn Observer) -> Result<Outcome, BoxError> {
    let Some(part) = a.part.map(|p| &study.parts[p]) else {
        return Err(format!("analysis '{}' has no part", a.name).into());
    };
    let o = match &a.spec {
        AnalysisSpec::Static { supports, loads } => run_static(part, supports, loads, obs)?,
        AnalysisSpec::Modal {
            modes,
            solver,
            supports,
        } => run_modal(part, *modes, *solver, supports, obs)?,
        AnalysisSpec::Reduce => run_reduce(study, part, cache, &a.name, obs)?,
        AnalysisSpec::Mbs(_) => return Err(format!("analysis '{}' runs on the mechanism", a.name).into()),
    };
    Ok(o)
}

/// Stress tensor (6 components), von Mises stress and largest principal stress per node \[Pa\].
pub type StressFields = (Vec<[f64; 6]>, Vec<f64>, Vec<f64>);

/// The stress fields of nodal displacements `values` of `model` at its nodes: the Voigt
/// tensor of the solids (averaged at the nodes, `fe_model::stress`; zero elsewhere), von Mises
/// and the largest principal stress. Beam nodes carry no tensor; their von Mises and largest
/// principal stress are the largest magnitude and value of the extreme-fibre axial stress over
/// the element ends at the node, for sections given by shape (nodal loads only: no load
/// along the elements).
pub fn stress_fields(model: &fe_model::FeModel, values: &[[f64; 6]]) -> Result<StressFields, BoxError> {
    let n = model.node_count();
    let mut tensor = vec![[0.0; 6]; n];
    let mut von_mises = vec![0.0; n];
    let mut principal = vec![0.0; n];
    if model.elements.iter().any(|e| e.solid().is_some()) {
        for (i, s) in fe_model::stress::nodal_stresses(model, values)?.iter().enumerate() {
            if let Some(s) = s {
                tensor[i] = *s;
                von_mises[i] = fe_model::von_mises(s);
                principal[i] = fe_model::principal_stresses(s)[0];
            }
        }
    }
    let mut ends = Vec::new();
    for (e, element) in model.elements.iter().enumerate() {
        let fe_model::Element::Beam2(beam) = element else {
            continue;
        };
        let Some(section) = model.sections.get(beam.section.0 as usize) else {
            continue;
        };
        let u_e: Vec<f64> = beam.nodes.iter().flat_map(|node| values[node.index()]).collect();
        let forces = fe_model::stress::beam_section_forces(model, e, &u_e, None)?;
        for (end, f) in forces.iter().enumerate() {
            if let Some(range) = section.fibre_stress_range(f) {
                ends.push((beam.nodes[end].index(), range));
            }
        }
    }
    for (i, x) in fe_model::stress::fibre_extremes_at_nodes(n, ends).iter().enumerate() {
        if let Some([magnitude, largest]) = x {
            von_mises[i] = *magnitude;
            principal[i] = *largest;
        }
    }
    Ok((tensor, von_mises, principal))
}

/// A field of six dofs per node as one frame with the point fields "displacement" and
/// "rotation", and with `stress` (from [`stress_fields`]) "stress", "von_mises" and
/// "max_principal".
fn six_dof_frame(
    obs: &mut dyn Observer,
    series: Series,
    key: f64,
    mesh: &VtuMesh,
    values: &[[f64; 6]],
    stress: Option<&StressFields>,
) -> Result<(), BoxError> {
    let (u, r) = six_dof_fields(values);
    let mut fields = vec![
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
    let tensor: Vec<f64> = stress
        .map(|s| s.0.iter().flatten().copied().collect())
        .unwrap_or_default();
    if let Some((_, von_mises, principal)) = stress {
        fields.push(PointField {
            name: "stress",
            components: 6,
            values: &tensor,
        });
        fields.push(PointField {
            name: "von_mises",
            components: 1,
            values: von_mises,
        });
        fields.push(PointField {
            name: "max_principal",
            components: 1,
            values: principal,
        });
    }
    obs.frame(series, key, mesh, &fields)
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
    obs: &mut dyn Observer,
) -> Result<Outcome, BoxError> {
    let built = part
        .build(supports, false)
        .context(|| format!("part '{}': cannot build the FE model", part.name))?;
    let n_free = free_dofs(part, &built)?;
    let loads = Part::nodal_loads(&built, loads);
    obs.progress(&Progress::Stage(format!(
        "part '{}': assembling and factorising K ({n_free} dofs)",
        part.name
    )));
    let s = fe_model::solve_static(&built.model, &loads)
        .context(|| format!("part '{}': static solution failed", part.name))?;
    obs.progress(&Progress::Finished);
    let nodes = &built.model.mesh.nodes;

    let mut csv = Table::new(
        "displacements",
        &[
            "node", "tag", "x [m]", "y [m]", "z [m]", "ux [m]", "uy [m]", "uz [m]", "rx [rad]", "ry [rad]", "rz [rad]",
        ],
    );
    let mut max = (0.0, 0usize);
    for (i, u) in s.displacements.iter().enumerate() {
        let norm = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
        if norm > max.0 {
            max = (norm, i);
        }
        let mut row = vec![Cell::from(i), Cell::Int(tag(&built, NodeId(i as u32)) as i64)];
        row.extend([nodes[i].x, nodes[i].y, nodes[i].z].map(Cell::Num));
        row.extend(u.map(Cell::Num));
        csv.row(row);
    }
    obs.table(&csv)?;

    let mut csv = Table::new(
        "reactions",
        &[
            "node", "tag", "Fx [N]", "Fy [N]", "Fz [N]", "Mx [N m]", "My [N m]", "Mz [N m]",
        ],
    );
    let mut total = [0.0; 6];
    for (node, r) in &s.reactions {
        let mut row = vec![Cell::from(node.index()), Cell::Int(tag(&built, *node) as i64)];
        row.extend(r.map(Cell::Num));
        csv.row(row);
        // Moments about the origin: M + x x F.
        let x = nodes[node.index()].coords;
        let m = nalgebra::Vector3::new(r[3], r[4], r[5]) + x.cross(&nalgebra::Vector3::new(r[0], r[1], r[2]));
        for k in 0..3 {
            total[k] += r[k];
            total[3 + k] += m[k];
        }
    }
    obs.table(&csv)?;

    let mut csv = Table::new(
        "interfaces",
        &[
            "interface",
            "node",
            "ux [m]",
            "uy [m]",
            "uz [m]",
            "rx [rad]",
            "ry [rad]",
            "rz [rad]",
        ],
    );
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
        let mut row = vec![Cell::from(name.clone()), Cell::from(node.index())];
        row.extend(u.map(Cell::Num));
        csv.row(row);
        report.push(format!(
            "interface '{name}': u = {} m, theta = {} rad",
            vec_text(&u[..3]),
            vec_text(&u[3..])
        ));
        interfaces.push(json!({ "name": name, "u": &u[..3], "theta": &u[3..] }));
    }
    obs.table(&csv)?;
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
    let stress = stress_fields(&built.model, &s.displacements)
        .context(|| format!("part '{}': cannot recover the stresses", part.name))?;
    let hot = stress
        .1
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map(|(i, v)| (i, *v))
        .unwrap_or((0, 0.0));
    if hot.1 > 0.0 {
        report.push(format!(
            "largest von Mises stress {:.6e} Pa at node {}",
            hot.1,
            tag(&built, NodeId(hot.0 as u32))
        ));
    }
    six_dof_frame(obs, Series::Static, 0.0, &mesh, &s.displacements, Some(&stress))?;
    Ok(Outcome {
        free_dofs: n_free,
        report,
        results: json!({
            "max_von_mises_Pa": hot.1,
            "max_von_mises_node": tag(&built, NodeId(hot.0 as u32)),
            "max_displacement_m": max.0,
            "max_displacement_node": tag(&built, NodeId(max.1 as u32)),
            "relative_residual": s.relative_residual,
            "interfaces": interfaces,
        }),
        failure: None,
    })
}

fn run_modal(
    part: &Part,
    modes: usize,
    solver: Solver,
    supports: &[SupportSpec],
    obs: &mut dyn Observer,
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
    obs.progress(&Progress::Stage(format!(
        "part '{}': {modes} modes of {n_free} dofs ({})",
        part.name,
        if dense { "dense" } else { "sparse shift-invert" }
    )));
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
    obs.progress(&Progress::Finished);
    // Rigid-body modes at 0 Hz and flagged, never negative (fe_model::ModalSolution).
    let f = solution.frequencies_hz();
    let rigid = solution.rigid_body_modes();
    let mut csv = Table::new(
        "frequencies",
        &["mode", "frequency [Hz]", "omega [rad/s]", "rigid body [-]"],
    );
    for (k, hz) in f.iter().enumerate() {
        csv.row(vec![
            Cell::from(k + 1),
            Cell::Num(*hz),
            Cell::Num(2.0 * std::f64::consts::PI * hz),
            Cell::from(usize::from(rigid[k])),
        ]);
    }
    obs.table(&csv)?;
    let mesh = VtuMesh::from_model(&built.model, &spiders(part, &built));
    for (k, shape) in solution.shapes.iter().enumerate() {
        // The stress of the mass-normalised shape: where each mode strains the part.
        let stress = stress_fields(&built.model, shape)
            .context(|| format!("part '{}': cannot recover the stresses of mode {}", part.name, k + 1))?;
        six_dof_frame(obs, Series::Modes, (k + 1) as f64, &mesh, shape, Some(&stress))?;
    }
    let mut report = vec![format!(
        "{} modes of {n_free} dofs ({method}, {:.3} s), mass-normalised shapes in modes.pvd",
        f.len(),
        t.elapsed().as_secs_f64()
    )];
    for (k, hz) in f.iter().enumerate() {
        let label = if rigid[k] { "  (rigid-body mode)" } else { "" };
        report.push(format!("mode {:>3}: {:>14} Hz{label}", k + 1, sci(*hz)));
    }
    Ok(Outcome {
        free_dofs: n_free,
        report,
        results: json!({ "solver": method, "frequencies_hz": f }),
        failure: None,
    })
}

/// A part reduced through the cache.
pub struct Reduced {
    /// Shared with the model and the system built from it (a large solid's shapes are
    /// hundreds of MB).
    pub body: std::sync::Arc<ReducedBody>,
    pub built: Built,
    /// The cache file.
    pub file: PathBuf,
    pub from_cache: bool,
    pub free_dofs: usize,
}

/// Reduces `part` of `study` (which has a reduction), or reads it from the cache when the
/// same mesh and settings were reduced before (`crate::cache`). A mode count the part cannot
/// give is located at its `reduction.modes` in the study file.
pub fn reduce_part(study: &Study, part: &Part, cache: &Path, obs: &mut dyn Observer) -> Result<Reduced, BoxError> {
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
        let recorded = crate::cache::lookup(&file, &key);
        if recorded.is_none() {
            obs.progress(&Progress::Warning(format!(
                "cache file {} does not record the inputs of this reduction (or was changed); reducing again",
                file.display()
            )));
        }
        match recorded.map(|bytes| reduction::file::from_bytes(&bytes, &file)) {
            None => {}
            Some(Ok(body)) if body.name == part.name => {
                obs.progress(&Progress::Info(format!(
                    "part '{}': reduced body found in the cache ({}): same mesh and settings, not reducing again",
                    part.name,
                    file.display()
                )));
                return Ok(Reduced {
                    body: body.into(),
                    built,
                    file,
                    from_cache: true,
                    free_dofs: n_free,
                });
            }
            Some(Ok(_)) => obs.progress(&Progress::Warning(format!(
                "cache file {} holds another body; reducing again",
                file.display()
            ))),
            Some(Err(e)) => obs.progress(&Progress::Warning(format!(
                "cannot use the cached body ({e}); reducing again"
            ))),
        }
    }
    let modes = match reduction.modes {
        reduction::ModeSelection::StaticOnly => "static modes only".to_string(),
        reduction::ModeSelection::Count(m) => format!("{m} fixed-interface modes"),
        reduction::ModeSelection::CutoffHz(f) => format!("fixed-interface modes below {f} Hz"),
    };
    obs.progress(&Progress::Info(format!(
        "part '{}': reducing {n_free} dofs to {} interfaces{} and {modes}{}{}{} ...",
        part.name,
        built.interfaces.len(),
        if built.auxiliary.is_some() {
            " + the auxiliary node"
        } else {
            ""
        },
        if reduction.inertia_correction {
            " + the static correction for the interfaces' inertia"
        } else {
            ""
        },
        if reduction.planar {
            ", planar (in-plane modes)"
        } else {
            ""
        },
        if reduction.geometric_stiffening {
            ", with geometric stiffening"
        } else {
            ""
        }
    )));
    let t = Instant::now();
    let mut settings = CbSettings::new(reduction.modes);
    settings.keep_mesh_shapes = reduction.keep_mesh_shapes;
    settings.auxiliary_node = built.auxiliary;
    settings.geometric_stiffening = reduction.geometric_stiffening;
    settings.inertia_correction = reduction.inertia_correction;
    settings.planar = reduction.planar;
    settings.stress_shapes = reduction.stress_shapes;
    settings.load_points = reduction.load_points.clone();
    settings.factor = reduction.factor;
    let mut progress = |stage: reduction::Stage| {
        let what = match stage {
            reduction::Stage::Assembling => "assembling K and M".to_string(),
            reduction::Stage::Factorising { internal_dofs } => format!("factorising K_ii ({internal_dofs} dofs)"),
            reduction::Stage::Factorised {
                factor_len, precision, ..
            } => format!(
                "K_ii factored: {:.1} M values, {:.2} GB in {} precision",
                factor_len as f64 / 1e6,
                (factor_len * precision.bytes()) as f64 / 1e9,
                precision.name()
            ),
            reduction::Stage::ConstraintModes { count } => format!("{count} constraint modes"),
            reduction::Stage::Solved {
                constraint_steps,
                applications,
                factor_solves,
            } if factor_solves > applications => {
                // A figure of the run, not a passing stage: kept in the log (a stage line only
                // shows on a terminal).
                obs.progress(&Progress::Info(format!(
                    "part '{}': refined solves with the single-precision factor: {constraint_steps} per constraint mode, {:.2} per Lanczos vector ({applications} vectors)",
                    part.name,
                    factor_solves as f64 / applications.max(1) as f64
                )));
                return;
            }
            reduction::Stage::EigenIteration { converged, wanted, .. } => {
                format!("fixed-interface modes: {converged} of {wanted} converged")
            }
            reduction::Stage::Projecting => "projecting K_CB, M_CB".to_string(),
            reduction::Stage::Invariants => "inertia invariants".to_string(),
            _ => return,
        };
        obs.progress(&Progress::Stage(format!("part '{}': {what}", part.name)));
    };
    let body = reduction::reduce_with_progress(
        &built.model,
        &part.name,
        &built.interfaces,
        &settings,
        fe_model::FillOrdering::Auto,
        &mut progress,
    )
    .map_err(|e| -> BoxError {
        // A mode count the part cannot give is the study's to change: located at the key.
        let message = if let reduction::ReductionError::TooManyModes { .. } = e {
            let at = part.path.key("reduction").key("modes");
            format!("{}: {at}: part '{}'", study.location(&at), part.name)
        } else {
            format!("part '{}': Craig-Bampton reduction failed", part.name)
        };
        Box::new(crate::error::Context {
            message,
            source: e.into(),
        })
    })?;
    obs.progress(&Progress::Finished);
    obs.progress(&Progress::Info(format!(
        "part '{}': reduced in {:.2} s to {} coordinates ({} interfaces, {} modes)",
        part.name,
        t.elapsed().as_secs_f64(),
        body.n_coordinates(),
        body.interfaces.len(),
        body.n_modes
    )));
    std::fs::create_dir_all(cache).context(|| format!("cannot create the cache folder {}", cache.display()))?;
    reduction::file::write(&body, &file).context(|| format!("part '{}': cannot write the reduced body", part.name))?;
    crate::cache::record(&file, &key).context(|| {
        format!(
            "part '{}': cannot record the cache key of {}",
            part.name,
            file.display()
        )
    })?;
    obs.progress(&Progress::Info(format!(
        "part '{}': saved to the cache as {}",
        part.name,
        file.display()
    )));
    Ok(Reduced {
        body: body.into(),
        built,
        file,
        from_cache: false,
        free_dofs: n_free,
    })
}

fn run_reduce(
    study: &Study,
    part: &Part,
    cache: &Path,
    analysis: &str,
    obs: &mut dyn Observer,
) -> Result<Outcome, BoxError> {
    let r = reduce_part(study, part, cache, obs)?;
    let body = &r.body;
    let name = format!("{}.{}", part.name, reduction::file::EXTENSION);
    obs.file(&name, &r.file)?;

    let mut csv = Table::new("interfaces", &["index", "name", "node", "x [m]", "y [m]", "z [m]"]);
    for (k, i) in body.interfaces.iter().enumerate() {
        let mut row = vec![Cell::from(k), Cell::from(i.name.clone()), Cell::Int(i64::from(i.node))];
        row.extend(i.position.map(Cell::Num));
        csv.row(row);
    }
    obs.table(&csv)?;

    let d = reduction::diagnostics(body, None, 3.0);
    let mut header = vec!["mode", "frequency [Hz]", "generalized mass [-]"];
    let labels: Vec<String> = reduction::diagnostics::DIRECTIONS
        .iter()
        .map(|d| format!("effective mass {d} [% of rigid]"))
        .collect();
    header.extend(labels.iter().map(String::as_str));
    let mut csv = Table::new("fixed_interface_modes", &header);
    for m in &d.modes {
        let mut row = vec![
            Cell::from(m.mode),
            Cell::Num(m.frequency_hz),
            Cell::Num(m.generalized_mass),
        ];
        row.extend(m.effective_fraction.map(|x| Cell::Num(100.0 * x)));
        csv.row(row);
    }
    obs.table(&csv)?;

    let i = &body.inertia;
    let mut csv = Table::new("mass", &["quantity", "value", "unit"]);
    csv.row(vec!["mass".into(), Cell::Num(i.mass), "kg".into()]);
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        csv.row(vec![
            format!("center of mass {axis}").into(),
            Cell::Num(i.center_of_mass[k]),
            "m".into(),
        ]);
    }
    for (a, ra) in ["x", "y", "z"].iter().enumerate() {
        for (b, rb) in ["x", "y", "z"].iter().enumerate() {
            csv.row(vec![
                format!("inertia about center of mass J{ra}{rb}").into(),
                Cell::Num(i.inertia_com[a][b]),
                "kg m^2".into(),
            ]);
        }
    }
    obs.table(&csv)?;

    // The CB shapes on the mesh: the constraint modes, then the fixed-interface modes.
    if let Some(shapes) = &body.mesh {
        let n_nodes = shapes.nodes.len();
        if n_nodes == r.built.model.node_count() {
            let mesh = VtuMesh::from_model(&r.built.model, &spiders(part, &r.built));
            let mut csv = Table::new(
                "shapes",
                &["shape", "file", "kind", "interface", "dof", "frequency [Hz]"],
            );
            for c in 0..shapes.shapes.ncols {
                let values: Vec<[f64; 6]> = (0..n_nodes)
                    .map(|n| std::array::from_fn(|k| shapes.shapes.get(6 * n + k, c)))
                    .collect();
                let file = format!("shape_{:03}.vtu", c + 1);
                six_dof_frame(obs, Series::Shapes, (c + 1) as f64, &mesh, &values, None)?;
                let nb = 6 * body.interfaces.len();
                let row = if c < nb {
                    vec![
                        Cell::from(c + 1),
                        Cell::from(file),
                        "constraint mode".into(),
                        body.interfaces[c / 6].name.clone().into(),
                        DOF_NAMES[c % 6].into(),
                        Cell::Empty,
                    ]
                } else {
                    let k = c - nb;
                    vec![
                        Cell::from(c + 1),
                        Cell::from(file),
                        "fixed-interface mode".into(),
                        Cell::Empty,
                        Cell::Empty,
                        Cell::Num(body.fixed_interface_omega[k] / (2.0 * std::f64::consts::PI)),
                    ]
                };
                csv.row(row);
            }
            obs.table(&csv)?;
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
    report.push(format!("reduced body: {analysis}/{name}"));
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
        failure: None,
    })
}

/// A reduced body copied into the results folder by [`reduce_command`].
#[derive(Clone, Debug)]
pub struct ReducedFile {
    pub part: String,
    pub coordinates: usize,
    pub interfaces: usize,
    pub modes: usize,
    pub path: PathBuf,
}

/// `flexmbs reduce`: reduces every part with a `[parts.reduction]`, or the one named, and
/// copies the bodies into the results folder.
pub fn reduce_command(
    study: &Study,
    only: Option<&str>,
    options: &Options,
    obs: &mut dyn Observer,
) -> Result<Vec<ReducedFile>, BoxError> {
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
    if out.as_os_str().is_empty() {
        return Err(
            "the output folder is '' (an empty path): name a folder, e.g. --out bodies, or --out . for the current one"
                .into(),
        );
    }
    std::fs::create_dir_all(&out).context(|| format!("cannot create the results folder {}", out.display()))?;
    let cache = options.cache_dir(study);
    let mut written = Vec::new();
    for part in parts {
        let r = reduce_part(study, part, &cache, obs)?;
        let target = out.join(format!("{}.{}", part.name, reduction::file::EXTENSION));
        std::fs::copy(&r.file, &target)
            .context(|| format!("cannot copy {} to {}", r.file.display(), target.display()))?;
        written.push(ReducedFile {
            part: part.name.clone(),
            coordinates: r.body.n_coordinates(),
            interfaces: r.body.interfaces.len(),
            modes: r.body.n_modes,
            path: target,
        });
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

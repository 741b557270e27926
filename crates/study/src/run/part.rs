//! The analyses of parts: static, modal and reduce, on the FE model of one part.

use super::outcome::Outcome;
use super::reduce::{free_dofs, reduce_part, Reduced};
use crate::error::{BoxError, ResultExt};
use crate::input::part::{Built, InterfaceTarget, LoadSpec, Part, SupportSpec};
use crate::input::validate::{Analysis, AnalysisSpec, Solver, Study, DENSE_AUTO_LIMIT};
use crate::mesh::VtuMesh;
use crate::output::observer::{Cell, Observer, Progress, Series, Table};
use crate::output::vtu::{self, motion_fields, six_dof_fields};
use fe_model::{ModalSolution, NodeId, DOF_NAMES};
use serde_json::json;
use std::path::Path;
use std::time::Instant;

pub fn run_analysis(study: &Study, a: &Analysis, cache: &Path, obs: &mut dyn Observer) -> Result<Outcome, BoxError> {
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
/// "max_principal"; and as a shape of the part on the results page, with the labels of the
/// mesh nodes in their file.
fn six_dof_frame(
    obs: &mut dyn Observer,
    series: Series,
    key: f64,
    (mesh, labels): (&VtuMesh, &[u64]),
    values: &[[f64; 6]],
    stress: Option<&StressFields>,
) -> Result<(), BoxError> {
    let (u, r) = six_dof_fields(values);
    let mut fields = Vec::from(motion_fields(&u, &r));
    let tensor: Vec<f64> = stress
        .map(|s| s.0.iter().flatten().copied().collect())
        .unwrap_or_default();
    if let Some((_, von_mises, principal)) = stress {
        fields.extend(vtu::stress_fields(&tensor, von_mises, principal));
    }
    obs.frame(series, key, mesh, &fields)?;
    obs.view(&crate::output::view::ViewEvent::PartField {
        series,
        key,
        mesh,
        labels,
        values,
        stress: stress.map(|s| s.0.as_slice()),
    });
    Ok(())
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

/// An interface node's deck label (its number in the part's mesh file), empty without one.
fn label_cell(label: Option<u64>) -> Cell {
    label.map_or(Cell::Empty, |l| {
        i64::try_from(l).map_or_else(|_| Cell::Text(l.to_string()), Cell::Int)
    })
}

/// `x` with 7 significant digits; `-0` printed as `0`.
fn sci(x: f64) -> String {
    format!("{:.6e}", x + 0.0)
}

fn vec_text(v: &[f64]) -> String {
    format!("({})", v.iter().map(|x| sci(*x)).collect::<Vec<_>>().join(", "))
}

/// The FE model of `part` on `supports` and its number of free dofs.
fn build_part(part: &Part, supports: &[SupportSpec]) -> Result<(Built, usize), BoxError> {
    let built = part
        .build(supports)
        .context(|| format!("part '{}': cannot build the FE model", part.name))?;
    let n_free = free_dofs(part, &built)?;
    Ok((built, n_free))
}

fn run_static(
    part: &Part,
    supports: &[SupportSpec],
    loads: &[LoadSpec],
    obs: &mut dyn Observer,
) -> Result<Outcome, BoxError> {
    let (built, n_free) = build_part(part, supports)?;
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

    let total = reactions(obs, &built, &s.reactions)?;

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
            "node label",
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
        row.push(label_cell(part.deck_label(node.index())));
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
    let labels = &built.model.mesh.node_tags;
    six_dof_frame(
        obs,
        Series::Static,
        0.0,
        (&mesh, labels),
        &s.displacements,
        Some(&stress),
    )?;
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
        final_state: None,
    })
}

/// The table of the support reactions of a static solution on `built`, and their sum: the
/// forces, then the moments about the origin.
fn reactions(obs: &mut dyn Observer, built: &Built, reactions: &[(NodeId, [f64; 6])]) -> Result<[f64; 6], BoxError> {
    let nodes = &built.model.mesh.nodes;
    let mut csv = Table::new(
        "reactions",
        &[
            "node", "tag", "Fx [N]", "Fy [N]", "Fz [N]", "Mx [N m]", "My [N m]", "Mz [N m]",
        ],
    );
    let mut total = [0.0; 6];
    for (node, r) in reactions {
        let mut row = vec![Cell::from(node.index()), Cell::Int(tag(built, *node) as i64)];
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
    Ok(total)
}

fn run_modal(
    part: &Part,
    modes: usize,
    solver: Solver,
    supports: &[SupportSpec],
    obs: &mut dyn Observer,
) -> Result<Outcome, BoxError> {
    let (built, n_free) = build_part(part, supports)?;
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
        let labels = &built.model.mesh.node_tags;
        six_dof_frame(
            obs,
            Series::Modes,
            (k + 1) as f64,
            (&mesh, labels),
            shape,
            Some(&stress),
        )?;
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
        final_state: None,
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

    let mut csv = Table::new(
        "interfaces",
        &["index", "name", "node", "x [m]", "y [m]", "z [m]", "node label"],
    );
    for (k, i) in body.interfaces.iter().enumerate() {
        let mut row = vec![Cell::from(k), Cell::from(i.name.clone()), Cell::Int(i64::from(i.node))];
        row.extend(i.position.map(Cell::Num));
        row.push(label_cell(i.node_label));
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
    cb_shapes(obs, part, &r)?;

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
        final_state: None,
    })
}

/// The CB shapes of the reduced part `r` on its mesh, each a frame, with the table that says
/// what each is: the constraint modes, then the fixed-interface modes.
fn cb_shapes(obs: &mut dyn Observer, part: &Part, r: &Reduced) -> Result<(), BoxError> {
    let body = &r.body;
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
                let labels = &r.built.model.mesh.node_tags;
                six_dof_frame(obs, Series::Shapes, (c + 1) as f64, (&mesh, labels), &values, None)?;
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
    Ok(())
}

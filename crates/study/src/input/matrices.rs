#![allow(non_snake_case)]
//! A flexible body reduced from matrices exported by another FE code: `[bodies.matrices]`,
//! stiffness and mass in Matrix Market files, a node table and a dof table
//! (`reduction::reduce_external_dofs`).
//!
//! # Tables
//!
//! * **Nodes**: one line per node, `x y z` (m), whitespace- or comma-separated; node `k` is
//!   the `k`-th data line (0-based). Blank lines and lines starting with `#` are skipped.
//! * **Dofs** (optional): one line per row of the matrices, `node dof`, with `dof` one of
//!   `ux uy uz rx ry rz` (or 0-5). Without it every node has `dofs_per_node` (3 or 6) dofs in
//!   node order.

use crate::input::schema::MatricesFile;
use reduction::checks::NodeCloud;
use reduction::{CbSettings, ModeSelection, PhysicsProblem, ReducedBody};
use std::path::Path;

/// The data lines of a table: (1-based line, fields).
fn table(path: &Path) -> Result<Vec<(usize, Vec<String>)>, String> {
    let text = fe_model::input::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    Ok(text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
        .map(|(k, l)| {
            (
                k + 1,
                l.split(|c: char| c.is_whitespace() || c == ',')
                    .filter(|f| !f.is_empty())
                    .map(str::to_string)
                    .collect(),
            )
        })
        .collect())
}

/// The matrices and tables of `[bodies.matrices]` as read.
struct Inputs {
    nodes_path: std::path::PathBuf,
    nodes: Vec<[f64; 3]>,
    /// The table's line of each node.
    node_lines: Vec<usize>,
    K: faer::sparse::SparseColMat<usize, f64>,
    M: faer::sparse::SparseColMat<usize, f64>,
    dofs: Vec<(usize, usize)>,
}

/// Reads the matrices and tables of `m` (paths relative to `dir`) and reduces the body
/// `name`. Errors name the file and line, or the key at fault (`Err((key, message))`).
pub fn reduce_matrices(name: &str, m: &MatricesFile, dir: &Path) -> Result<ReducedBody, (&'static str, String)> {
    let inputs = read_inputs(m, dir)?;
    check_node_table(name, &inputs)?;
    let body = reduce(name, m, &inputs)?;
    // The reduced body passes the checks of every body; its interface problems are the
    // `interfaces` key's.
    match reduction::check_body(&body, &dir.join(&m.stiffness)) {
        Ok(_) => Ok(body),
        Err(e) => {
            let interfaces_at_fault = matches!(&e, reduction::BodyCheckError::Refused { problems, .. }
                if problems.iter().all(|p| matches!(p, PhysicsProblem::Coincident { .. } | PhysicsProblem::DuplicateName { .. })));
            Err((
                if interfaces_at_fault { "interfaces" } else { "stiffness" },
                e.to_string(),
            ))
        }
    }
}

/// A body reduced from matrices for `flexmbs inspect`, before any refusal: the body (not yet
/// checked), the node table's problems (against $\mathbf K$ and against the mass of
/// $\mathbf M$) and the node cloud measured.
#[derive(Clone, Debug)]
pub struct Inspected {
    pub body: ReducedBody,
    pub node_table: std::path::PathBuf,
    pub node_table_problems: Vec<PhysicsProblem>,
    pub cloud: NodeCloud,
}

/// [`reduce_matrices`] without refusing the body for its physical problems (`flexmbs
/// inspect` reports them): errors only when the files cannot be read or reduced.
pub fn inspect_matrices(name: &str, m: &MatricesFile, dir: &Path) -> Result<Inspected, (&'static str, String)> {
    let inputs = read_inputs(m, dir)?;
    let (node_table_problems, cloud) = node_table_problems(&inputs);
    let body = reduce(name, m, &inputs)?;
    Ok(Inspected {
        body,
        node_table: inputs.nodes_path,
        node_table_problems,
        cloud,
    })
}

/// The node table, the matrices and the dof list of `m`.
fn read_inputs(m: &MatricesFile, dir: &Path) -> Result<Inputs, (&'static str, String)> {
    let nodes_path = dir.join(&m.nodes);
    let mut nodes = Vec::new();
    let mut node_lines = Vec::new();
    for (line, fields) in table(&nodes_path).map_err(|e| ("nodes", e))? {
        let xyz: Vec<f64> = fields
            .iter()
            .filter_map(|f| f.parse::<f64>().ok())
            .filter(|v| v.is_finite())
            .collect();
        if fields.len() != 3 || xyz.len() != 3 {
            return Err((
                "nodes",
                format!(
                    "{}:{line}: expected 'x y z', found '{}'",
                    nodes_path.display(),
                    fields.join(" ")
                ),
            ));
        }
        nodes.push([xyz[0], xyz[1], xyz[2]]);
        node_lines.push(line);
    }
    let K = reduction::read_matrix_market(&dir.join(&m.stiffness)).map_err(|e| ("stiffness", e.to_string()))?;
    let M = reduction::read_matrix_market(&dir.join(&m.mass)).map_err(|e| ("mass", e.to_string()))?;
    let dofs = dof_list(m, dir, nodes.len())?;
    Ok(Inputs {
        nodes_path,
        nodes,
        node_lines,
        K,
        M,
        dofs,
    })
}

/// The dof of each matrix row: from the dof table, or `dofs_per_node` in node order.
fn dof_list(m: &MatricesFile, dir: &Path, n_nodes: usize) -> Result<Vec<(usize, usize)>, (&'static str, String)> {
    match (&m.dofs, m.dofs_per_node) {
        (Some(_), Some(_)) => Err(("dofs", "give `dofs` (a table) or `dofs_per_node`, not both".into())),
        (None, None) => Err((
            "dofs",
            "missing key `dofs` (a table 'node dof' per matrix row) or `dofs_per_node` (3 or 6)".into(),
        )),
        (None, Some(k)) => {
            if k != 3 && k != 6 {
                return Err((
                    "dofs_per_node",
                    format!("must be 3 (solids) or 6 (beams, shells), got {k}"),
                ));
            }
            Ok((0..n_nodes * k).map(|d| (d / k, d % k)).collect())
        }
        (Some(file), None) => {
            let path = dir.join(file);
            let mut dofs = Vec::new();
            for (line, fields) in table(&path).map_err(|e| ("dofs", e))? {
                let names = ["ux", "uy", "uz", "rx", "ry", "rz"];
                let parsed = match fields.as_slice() {
                    [n, d] => n.parse::<usize>().ok().zip(
                        names
                            .iter()
                            .position(|x| x.eq_ignore_ascii_case(d))
                            .or_else(|| d.parse::<usize>().ok().filter(|&k| k < 6)),
                    ),
                    _ => None,
                };
                match parsed {
                    Some((n, _)) if n >= n_nodes => {
                        return Err((
                            "dofs",
                            format!(
                                "{}:{line}: node {n} is not in the node table ({n_nodes} nodes, 0-based)",
                                path.display(),
                            ),
                        ))
                    }
                    Some(d) => dofs.push(d),
                    None => {
                        return Err((
                            "dofs",
                            format!(
                                "{}:{line}: expected 'node dof' (dof: ux uy uz rx ry rz), found '{}'",
                                path.display(),
                                fields.join(" ")
                            ),
                        ))
                    }
                }
            }
            Ok(dofs)
        }
    }
}

/// The Craig-Bampton reduction of `inputs` with the interfaces and modes of `m`.
fn reduce(name: &str, m: &MatricesFile, inputs: &Inputs) -> Result<ReducedBody, (&'static str, String)> {
    let nodes = &inputs.nodes;
    let mut interfaces = Vec::new();
    for (iname, &node) in &m.interfaces {
        if node >= nodes.len() {
            return Err((
                "interfaces",
                format!(
                    "interface '{iname}': node {node} is not in the node table ({} nodes, 0-based)",
                    nodes.len()
                ),
            ));
        }
        interfaces.push((iname.clone(), node));
    }
    let modes = match (m.modes, m.cutoff_hz) {
        (Some(n), None) => ModeSelection::Count(n),
        (None, Some(f)) => ModeSelection::CutoffHz(f),
        _ => return Err(("modes", "give `modes` (a count) or `cutoff_hz`, one of them".into())),
    };
    let mut settings = CbSettings::new(modes);
    settings.keep_mesh_shapes = false;
    reduction::reduce_external_dofs(
        nodes,
        inputs.K.as_ref(),
        inputs.M.as_ref(),
        &inputs.dofs,
        name,
        &interfaces,
        &settings,
    )
    .map_err(|e| ("stiffness", format!("cannot reduce the matrices: {e}")))
}

/// The node table against the rigid motions of $\mathbf K$
/// (`reduction::checks::node_table_problems`) and against the mass of $\mathbf M$
/// (`reduction::checks::NodeCloud`), and the node cloud.
fn node_table_problems(inputs: &Inputs) -> (Vec<PhysicsProblem>, NodeCloud) {
    let mut problems = reduction::checks::node_table_problems(&inputs.nodes, inputs.K.as_ref(), &inputs.dofs);
    let cloud = NodeCloud::new(&inputs.nodes, inputs.M.as_ref(), &inputs.dofs);
    problems.extend(cloud.problem());
    (problems, cloud)
}

/// The node table's problems ([`node_table_problems`]) as the error of the `nodes` key,
/// located at the table's line of the node most at fault when a problem has one.
fn check_node_table(name: &str, inputs: &Inputs) -> Result<(), (&'static str, String)> {
    let (problems, _) = node_table_problems(inputs);
    let Some(first) = problems.first() else {
        return Ok(());
    };
    let path = &inputs.nodes_path;
    let at = match first {
        PhysicsProblem::RigidMotionStrained { node, .. } => {
            format!("{}:{}: node {node}", path.display(), inputs.node_lines[*node])
        }
        _ => path.display().to_string(),
    };
    let error = reduction::BodyCheckError::NodeTable {
        body: name.to_string(),
        file: path.to_path_buf(),
        problems,
    };
    Err(("nodes", format!("{at}: {error}")))
}

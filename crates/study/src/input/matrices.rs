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

/// Reads the matrices and tables of `m` (paths relative to `dir`) and reduces the body
/// `name`. Errors name the file and line, or the key at fault (`Err((key, message))`).
pub fn reduce_matrices(name: &str, m: &MatricesFile, dir: &Path) -> Result<ReducedBody, (&'static str, String)> {
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
    let dofs: Vec<(usize, usize)> = match (&m.dofs, m.dofs_per_node) {
        (Some(_), Some(_)) => return Err(("dofs", "give `dofs` (a table) or `dofs_per_node`, not both".into())),
        (None, None) => {
            return Err((
                "dofs",
                "missing key `dofs` (a table 'node dof' per matrix row) or `dofs_per_node` (3 or 6)".into(),
            ))
        }
        (None, Some(k)) => {
            if k != 3 && k != 6 {
                return Err((
                    "dofs_per_node",
                    format!("must be 3 (solids) or 6 (beams, shells), got {k}"),
                ));
            }
            (0..nodes.len() * k).map(|d| (d / k, d % k)).collect()
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
                    Some((n, _)) if n >= nodes.len() => {
                        return Err((
                            "dofs",
                            format!(
                                "{}:{line}: node {n} is not in the node table ({} nodes, 0-based)",
                                path.display(),
                                nodes.len()
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
            dofs
        }
    };
    check_node_table(name, &nodes_path, &node_lines, &nodes, K.as_ref(), &dofs)?;
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
    let body = reduction::reduce_external_dofs(&nodes, K.as_ref(), M.as_ref(), &dofs, name, &interfaces, &settings)
        .map_err(|e| ("stiffness", format!("cannot reduce the matrices: {e}")))?;
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

/// The node table (`path`, node `k` on line `lines[k]`) against the rigid motions of `K`
/// (`reduction::checks::node_table_problems`), each problem's node named by its line.
fn check_node_table(
    name: &str,
    path: &Path,
    lines: &[usize],
    nodes: &[[f64; 3]],
    K: faer::sparse::SparseColMatRef<'_, usize, f64>,
    dofs: &[(usize, usize)],
) -> Result<(), (&'static str, String)> {
    let problems = reduction::checks::node_table_problems(nodes, K, dofs);
    let Some(PhysicsProblem::RigidMotionStrained { node, .. }) = problems.first() else {
        return Ok(());
    };
    let error = reduction::BodyCheckError::NodeTable {
        body: name.to_string(),
        file: path.to_path_buf(),
        problems: problems.clone(),
    };
    Err((
        "nodes",
        format!("{}:{}: node {node}: {error}", path.display(), lines[*node]),
    ))
}

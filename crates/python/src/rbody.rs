//! `flexmbs.ReducedBody`: a Craig-Bampton reduced body ([`reduction::ReducedBody`]) from a
//! `.rbody` file or a reduction, with its data as numpy arrays.
//!
//! Arrays are copies (a script may change them freely; the body does not change). Matrices
//! keep the library's shapes: $\mathbf K_{CB}$, $\mathbf M_{CB}$ are $n\times n$ with
//! $n = 6N + m$ CB coordinates $[\mathbf u_1, \boldsymbol\theta_1, \dots, \mathbf u_N,
//! \boldsymbol\theta_N, \boldsymbol\eta]$ (FE model axes).

#![allow(non_snake_case)]

use crate::errors::{chain, with_attributes, ReducedBodyFileError};
use crate::signature::{Class, Member::*};
use numpy::ndarray::{Array2, Array3, ShapeBuilder};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use reduction::{DenseMatrix, ReductionError};
use std::path::PathBuf;

/// A reduced flexible body: interfaces, reduced matrices, mass data, fixed-interface modes.
///
/// `ReducedBody.load(path)` reads a `.rbody` file (as written by `flexmbs reduce`, the
/// results of a study, or `save`); every array property returns a fresh numpy array.
#[pyclass(module = "flexmbs", name = "ReducedBody", frozen)]
#[derive(Clone)]
pub struct ReducedBody {
    pub(crate) body: reduction::ReducedBody,
}

/// A dense library matrix as a numpy array of its shape.
fn matrix<'py>(py: Python<'py>, m: &DenseMatrix) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_vec((m.nrows, m.ncols).f(), m.data.clone())
        .expect("a DenseMatrix holds nrows * ncols values")
        .into_pyarray(py)
}

/// A `ReductionError` about a file as `ReducedBodyFileError` with its `path`.
pub(crate) fn file_error(py: Python<'_>, e: ReductionError, fallback: PathBuf) -> PyErr {
    let path = match &e {
        ReductionError::BodyFile { path, .. } => path.clone(),
        _ => fallback,
    };
    let path = PyString::new(py, &path.display().to_string()).into_any().unbind();
    with_attributes::<ReducedBodyFileError>(py, chain(&e), &[("path", path)])
}

/// `ReducedBody` as the type stubs declare it.
pub(crate) const STUB: Class = Class {
    name: "ReducedBody",
    bases: "",
    members: &[
        Static("load", "(path: _Path) -> \"ReducedBody\""),
        Method("save", "(self, path: _Path) -> None"),
        Property("name", "str"),
        Property("format_version", "int"),
        Property("n_modes", "int"),
        Property("n_coordinates", "int"),
        Property("interfaces", "List[Dict[str, Any]]"),
        Property("interface_names", "List[str]"),
        Property("K_CB", "_Array"),
        Property("M_CB", "_Array"),
        Property("mass", "float"),
        Property("center_of_mass", "_Array"),
        Property("inertia", "_Array"),
        Property("invariants", "Dict[str, _Array]"),
        Property("fixed_interface_omega", "_Array"),
        Property("fixed_interface_frequencies", "_Array"),
        Property("mesh_nodes", "Optional[_Array]"),
        Property("cb_basis", "Optional[_Array]"),
        Property("mode_shapes", "Optional[_Array]"),
        Property("geometric_stiffness", "Optional[_Array]"),
        Method("__eq__", "(self, other: object) -> bool"),
    ],
};

#[pymethods]
impl ReducedBody {
    /// Reads a reduced-body file. Raises `ReducedBodyFileError` (with `.path`) when the file is
    /// missing, damaged (checksums), of a newer format version or not a reduced body.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let body = py
            .detach(|| reduction::file::read(&path))
            .map_err(|e| file_error(py, e, path.clone()))?;
        Ok(Self { body })
    }

    /// Writes the body to `path` (atomically: a temporary file, then a rename). Reading it back
    /// gives the same body bit for bit.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| reduction::file::write(&self.body, &path))
            .map_err(|e| file_error(py, e, path.clone()))
    }

    /// The body's name (its part's name).
    #[getter]
    fn name(&self) -> &str {
        &self.body.name
    }

    /// Format version of the reduced-body data.
    #[getter]
    fn format_version(&self) -> u32 {
        self.body.format_version
    }

    /// Number $m$ of fixed-interface modes.
    #[getter]
    fn n_modes(&self) -> usize {
        self.body.n_modes
    }

    /// Number $n = 6N + m$ of CB coordinates.
    #[getter]
    fn n_coordinates(&self) -> usize {
        self.body.n_coordinates()
    }

    /// Interfaces in the order of the CB coordinates: a list of dicts with `name`, `node` (the
    /// FE node index), `node_label` (the node's number in the part's mesh file; None for
    /// generated meshes and for spider and auxiliary nodes) and `position` (undeformed, FE
    /// axes, m; numpy array of 3).
    #[getter]
    fn interfaces<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.body
            .interfaces
            .iter()
            .map(|i| {
                let d = PyDict::new(py);
                d.set_item("name", &i.name)?;
                d.set_item("node", i.node)?;
                d.set_item("node_label", i.node_label)?;
                d.set_item("position", PyArray1::from_slice(py, &i.position))?;
                Ok(d)
            })
            .collect()
    }

    /// Names of the interfaces, in the order of the CB coordinates.
    #[getter]
    fn interface_names(&self) -> Vec<String> {
        self.body.interfaces.iter().map(|i| i.name.clone()).collect()
    }

    /// $\mathbf K_{CB} = \mathbf V^T\mathbf K\mathbf V$ ($n\times n$, N/m, N, N m by coordinate).
    #[getter]
    fn K_CB<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix(py, &self.body.K_CB)
    }

    /// $\mathbf M_{CB} = \mathbf V^T\mathbf M\mathbf V$ ($n\times n$, kg, kg m, kg m^2 by coordinate).
    #[getter]
    fn M_CB<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix(py, &self.body.M_CB)
    }

    /// Total mass [kg].
    #[getter]
    fn mass(&self) -> f64 {
        self.body.inertia.mass
    }

    /// Centre of mass of the undeformed body, FE axes [m] (numpy array of 3).
    #[getter]
    fn center_of_mass<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.body.inertia.center_of_mass)
    }

    /// Inertia tensor about the centre of mass, FE axes [kg m^2] (3x3).
    #[getter]
    fn inertia<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let I = self.body.inertia.inertia_com;
        Array2::from_shape_fn((3, 3), |(i, j)| I[i][j]).into_pyarray(py)
    }

    /// The mass-field invariants as a dict of arrays: `S_t` (3 x n), `S_r` (3 x n), `S_x`
    /// (9 x n), `S_bar` (9 x n x n, entry 3k+l is the integral of rho S_k^T S_l), `Phi_com`
    /// (6 x n, the CB modes at the centre of mass).
    #[getter]
    fn invariants<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let inv = &self.body.inertia;
        let d = PyDict::new(py);
        d.set_item("S_t", matrix(py, &inv.S_t))?;
        d.set_item("S_r", matrix(py, &inv.S_r))?;
        d.set_item("S_x", matrix(py, &inv.S_x))?;
        let n = self.body.n_coordinates();
        let bar = Array3::from_shape_fn((inv.S_bar.len(), n, n), |(k, i, j)| inv.S_bar[k].get(i, j));
        d.set_item("S_bar", bar.into_pyarray(py))?;
        d.set_item("Phi_com", matrix(py, &self.body.Phi_com))?;
        Ok(d)
    }

    /// Circular frequencies of the kept fixed-interface modes [rad/s], ascending.
    #[getter]
    fn fixed_interface_omega<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.body.fixed_interface_omega)
    }

    /// Frequencies of the kept fixed-interface modes [Hz], ascending.
    #[getter]
    fn fixed_interface_frequencies<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let f: Vec<f64> = self
            .body
            .fixed_interface_omega
            .iter()
            .map(|w| w / (2.0 * std::f64::consts::PI))
            .collect();
        PyArray1::from_vec(py, f)
    }

    /// Reference coordinates of the FE nodes (n_nodes x 3) [m], or `None` when the body was
    /// reduced without mesh shapes.
    #[getter]
    fn mesh_nodes<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        let mesh = self.body.mesh.as_ref()?;
        Some(Array2::from_shape_fn((mesh.nodes.len(), 3), |(i, j)| mesh.nodes[i][j]).into_pyarray(py))
    }

    /// The CB basis on the mesh (6 n_nodes x n: rows node by node, [ux, uy, uz, rx, ry, rz]),
    /// or `None` without mesh shapes. Columns 0..6N are the constraint modes, 6N.. the
    /// fixed-interface modes.
    #[getter]
    fn cb_basis<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        let mesh = self.body.mesh.as_ref()?;
        Some(matrix(py, &mesh.shapes))
    }

    /// The fixed-interface mode shapes on the mesh (n_nodes x 6 x m: node, dof slot
    /// [ux, uy, uz, rx, ry, rz], mode), mass-normalised like the library's modes, or `None`
    /// without mesh shapes.
    #[getter]
    fn mode_shapes<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray3<f64>>> {
        let mesh = self.body.mesh.as_ref()?;
        let first = 6 * self.body.interfaces.len();
        let shape = (mesh.nodes.len(), 6, self.body.n_modes);
        Some(Array3::from_shape_fn(shape, |(a, s, k)| mesh.shapes.get(6 * a + s, first + k)).into_pyarray(py))
    }

    /// The reduced geometric stiffness matrices G_k (n x n x n, index k first), or `None` when
    /// the body was reduced without geometric stiffening.
    #[getter]
    fn geometric_stiffness<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray3<f64>>> {
        let G = self.body.geometric_stiffness.as_ref()?;
        let n = self.body.n_coordinates();
        Some(Array3::from_shape_fn((G.len(), n, n), |(k, i, j)| G[k].get(i, j)).into_pyarray(py))
    }

    fn __repr__(&self) -> String {
        format!(
            "ReducedBody(name={:?}, interfaces={:?}, n_modes={}, mass={:.6e} kg)",
            self.body.name,
            self.interface_names(),
            self.body.n_modes,
            self.body.inertia.mass
        )
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.body == other.body
    }
}

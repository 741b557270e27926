//! Stress shapes of a reduced body ([`StressShapes`]): the stress of every CB vector, computed
//! on the FE elements once at reduction time, so that a body's stress at any state is the
//! product $\boldsymbol\sigma = \boldsymbol\Sigma\mathbf q^{jj}$ of the stored shapes with its
//! elastic coordinates (recovery: `superelement::recovery`). Linear in the elastic field,
//! like the reduced body itself (the floating frame carries the large motion).

#![allow(non_snake_case)]

use crate::error::ReductionError;
use crate::reduced_body::{combine, BeamStressElement, DenseMatrix, StressShapes};
use faer::MatRef;
use fe_model::stress::{averaged_nodal_stresses, beam_section_forces};
use fe_model::{Element, FeModel};
use rayon::prelude::*;

/// The stress shapes of the basis `S_full` ($6 n_{nodes} \times n$, every node's six slots):
/// solid stresses at the nodes ([`fe_model::stress::averaged_nodal_stresses`]) and beam section
/// forces at both ends of every beam ([`fe_model::stress::beam_section_forces`]).
///
/// # Errors
/// [`ReductionError::Fe`] or [`ReductionError::InvalidFeModel`] for an element whose geometry or properties cannot give stresses.
pub fn stress_shapes(model: &FeModel, S_full: MatRef<'_, f64>) -> Result<StressShapes, ReductionError> {
    let n = S_full.ncols();
    let basis = DenseMatrix::from_faer(S_full);
    let has_solids = model.elements.iter().any(|e| e.solid().is_some());
    let (nodal, solid_node) = if has_solids {
        let (sigma, count) = averaged_nodal_stresses(model, &basis.data, n)?;
        (
            Some(DenseMatrix {
                nrows: 6 * model.node_count(),
                ncols: n,
                data: sigma,
            }),
            count.iter().map(|&c| c > 0).collect(),
        )
    } else {
        (None, Vec::new())
    };
    let beams: Vec<BeamStressElement> =
        model
            .elements
            .iter()
            .enumerate()
            .filter_map(|(e, element)| match element {
                Element::Beam2(b) => Some((e, b)),
                _ => None,
            })
            .map(|(e, b)| {
                let section = model.sections.get(b.section.0 as usize).cloned().ok_or_else(|| {
                    ReductionError::InvalidFeModel {
                        what: format!("element {e}: beam section {} does not exist", b.section.0),
                    }
                })?;
                Ok(BeamStressElement {
                    element: e as u32,
                    nodes: [b.nodes[0].0, b.nodes[1].0],
                    section,
                })
            })
            .collect::<Result<_, ReductionError>>()?;
    let rows = 12 * beams.len();
    // Column by column in parallel: each CB vector's section forces on every beam.
    let columns: Vec<Vec<f64>> = (0..n)
        .into_par_iter()
        .map(|k| {
            let mut col = Vec::with_capacity(rows);
            for b in &beams {
                let u_e: Vec<f64> = b
                    .nodes
                    .iter()
                    .flat_map(|&node| (0..6).map(move |s| S_full[(6 * node as usize + s, k)]))
                    .collect();
                let s = beam_section_forces(model, b.element as usize, &u_e, None)?;
                col.extend(s.iter().flatten());
            }
            Ok(col)
        })
        .collect::<Result<_, ReductionError>>()?;
    Ok(StressShapes {
        nodal,
        solid_node,
        beams,
        beam_forces: DenseMatrix {
            nrows: rows,
            ncols: n,
            data: columns.into_iter().flatten().collect(),
        },
    })
}

/// The stresses of a body at its mesh nodes in global axes: the Voigt tensor $[xx, yy, zz, xy,
/// yz, zx]$ (zero where none), von Mises and the largest principal stress \[Pa\]. Beam nodes
/// carry no tensor: their von Mises and largest principal stress are the largest magnitude and
/// the largest value of the extreme-fibre axial stress over the element ends at the node
/// ([`fe_model::BeamSection::fibre_stress_range`]; the shear stresses of the section are not
/// included). Nodes without stress (spider nodes) hold 0.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeStresses {
    pub tensor: Vec<[f64; 6]>,
    pub von_mises: Vec<f64>,
    pub principal: Vec<f64>,
}

impl StressShapes {
    /// The number of mesh nodes the shapes cover (solid nodes, beam nodes).
    pub fn node_count(&self) -> usize {
        self.solid_node.len().max(
            self.beams
                .iter()
                .flat_map(|b| b.nodes)
                .max()
                .map_or(0, |m| m as usize + 1),
        )
    }

    /// [`NodeStresses`] for CB coordinates `q` ($\boldsymbol\sigma = \boldsymbol\Sigma\mathbf q$ in
    /// body axes), turned into global axes by `R` ($\mathbf R\boldsymbol\sigma\mathbf R^T$).
    /// One matrix-vector product for every node's tensor; von Mises and the principal stresses
    /// are invariant under the rotation and are taken from the body-axes tensor.
    ///
    /// # Panics
    /// If `q` does not have one value per column (a caller's bug).
    pub fn node_stresses(&self, q: &[f64], R: &nalgebra::Matrix3<f64>) -> NodeStresses {
        let n_nodes = self.node_count();
        let mut out = NodeStresses {
            tensor: vec![[0.0; 6]; n_nodes],
            von_mises: vec![0.0; n_nodes],
            principal: vec![0.0; n_nodes],
        };
        self.for_each_solid_node(q, |i, s| {
            (out.tensor[i], out.von_mises[i], out.principal[i]) = solid_values(s, R);
        });
        for (i, x) in self.beam_extremes(q, n_nodes).iter().enumerate() {
            if let Some([magnitude, largest]) = x {
                out.von_mises[i] = *magnitude;
                out.principal[i] = *largest;
            }
        }
        out
    }

    /// [`Self::node_stresses`] at mesh node `node` only (tensor in global axes, von Mises,
    /// largest principal stress), the same values to the bit: one node's rows of
    /// $\boldsymbol\Sigma$, and the section forces of the beams ending at the node. For a
    /// sensor at one node.
    ///
    /// # Panics
    /// If `q` does not have one value per column or `node` is not below the node count (a
    /// caller's bug).
    pub fn node_stress(&self, node: usize, q: &[f64], R: &nalgebra::Matrix3<f64>) -> ([f64; 6], f64, f64) {
        let n_nodes = self.node_count();
        assert!(node < n_nodes, "a node of the body");
        assert_eq!(q.len(), self.n_coordinates(), "one coordinate per column");
        let mut out = ([0.0; 6], 0.0, 0.0);
        if let (Some(S), true) = (&self.nodal, self.solid_node.get(node).copied().unwrap_or(false)) {
            let mut s = [0.0; 6];
            for (j, &qj) in q.iter().enumerate() {
                if qj != 0.0 {
                    for (c, sc) in s.iter_mut().enumerate() {
                        *sc += S.data[j * S.nrows + 6 * node + c] * qj;
                    }
                }
            }
            out = solid_values(&s, R);
        }
        let mut ranges = Vec::new();
        let F = &self.beam_forces;
        for (b, beam) in self.beams.iter().enumerate() {
            for end in (0..2).filter(|&end| beam.nodes[end] as usize == node) {
                let mut f = [0.0; 6];
                for (c, fc) in f.iter_mut().enumerate() {
                    for (j, &qj) in q.iter().enumerate() {
                        if qj != 0.0 {
                            *fc += F.data[j * F.nrows + 12 * b + 6 * end + c] * qj;
                        }
                    }
                }
                ranges.extend(beam.section.fibre_stress_range(&f).map(|r| (0, r)));
            }
        }
        if let Some([magnitude, largest]) = fe_model::stress::fibre_extremes_at_nodes(1, ranges)[0] {
            out.1 = magnitude;
            out.2 = largest;
        }
        out
    }

    /// The number of CB coordinates the shapes are combined with (their columns).
    pub fn n_coordinates(&self) -> usize {
        self.nodal.as_ref().map_or(self.beam_forces.ncols, |S| S.ncols)
    }

    /// The von Mises stress of every mesh node for CB coordinates `q`, as
    /// [`NodeStresses::von_mises`] of [`Self::node_stresses`] but without the rotation to global
    /// axes (von Mises is invariant under it) and without principal stresses: the cheap path of
    /// a largest-von-Mises output at every step.
    ///
    /// # Panics
    /// If `q` does not have one value per column (a caller's bug).
    pub fn von_mises(&self, q: &[f64]) -> Vec<f64> {
        let n_nodes = self.node_count();
        let mut vm = vec![0.0; n_nodes];
        self.for_each_solid_node(q, |i, s| vm[i] = fe_model::von_mises(s));
        for (i, x) in self.beam_extremes(q, n_nodes).iter().enumerate() {
            if let Some([magnitude, _]) = x {
                vm[i] = *magnitude;
            }
        }
        vm
    }

    /// Calls `f(i, sigma_i)` with the body-axes stress of every solid node `i` below the node
    /// count ($\boldsymbol\sigma = \boldsymbol\Sigma\mathbf q$, one matrix-vector product).
    fn for_each_solid_node(&self, q: &[f64], mut f: impl FnMut(usize, &[f64; 6])) {
        let Some(S) = &self.nodal else {
            return;
        };
        let sigma = combine(S, q);
        for ((i, s), _) in sigma
            .chunks_exact(6)
            .enumerate()
            .zip(&self.solid_node)
            .filter(|(_, &solid)| solid)
        {
            f(i, s.try_into().expect("6 components"));
        }
    }

    /// The largest magnitude and the largest value of the beams' extreme-fibre axial stress at
    /// every node below `n_nodes` (`None` at nodes without a beam end).
    fn beam_extremes(&self, q: &[f64], n_nodes: usize) -> Vec<Option<[f64; 2]>> {
        if self.beams.is_empty() {
            return Vec::new();
        }
        let forces = self.beam_section_forces(q);
        let ends = self.beams.iter().zip(&forces).flat_map(|(b, forces)| {
            forces.iter().enumerate().filter_map(move |(end, f)| {
                let node = b.nodes[end] as usize;
                let range = b.section.fibre_stress_range(f)?;
                (node < n_nodes).then_some((node, range))
            })
        });
        fe_model::stress::fibre_extremes_at_nodes(n_nodes, ends)
    }
}

/// The tensor in global axes ($\mathbf R\boldsymbol\sigma\mathbf R^T$), von Mises and largest
/// principal stress of the body-axes stress `s` (both invariant under the rotation, taken from
/// `s`).
fn solid_values(s: &[f64; 6], R: &nalgebra::Matrix3<f64>) -> ([f64; 6], f64, f64) {
    let g = R * fe_model::stress::tensor(s) * R.transpose();
    (
        [g[(0, 0)], g[(1, 1)], g[(2, 2)], g[(0, 1)], g[(1, 2)], g[(2, 0)]],
        fe_model::von_mises(s),
        fe_model::principal_stresses(s)[0],
    )
}

/// The largest von Mises stress over a node set of a body at one state, and where it occurs:
/// a bounded search whose result equals the brute-force maximum over every node of the set
/// (value bit for bit, node the last of equal maxima in set order, as `Iterator::max_by`), at a
/// fraction of its cost when the state changes little between calls (the output times of a
/// run).
///
/// The bound (theory guide, results, (10.3)): the von Mises stress is a seminorm of the nodal
/// stress, $v(\boldsymbol\sigma) =
/// \lVert\mathbf M^{1/2}\boldsymbol\sigma\rVert$ (Voigt vector, $\mathbf M^{1/2}$ =
/// $\sqrt{3/2}$ times the deviatoric projector on the normal part, $\sqrt3$ on the shear part),
/// so that at node $i$, with $\mathbf A_i = \mathbf M^{1/2}\boldsymbol\Sigma_i$ and a
/// reference state $\mathbf q^{ref}$ whose stresses $v_i^{ref}$ are known,
/// $$v_i(\mathbf q) \le b_i = v_i^{ref} + c_i\lVert\mathbf T(\mathbf q - \mathbf q^{ref})\rVert + \tau_i,
/// \qquad c_i = \lVert\mathbf A_i\mathbf T^{-1}\rVert_2,$$
/// for any invertible $\mathbf T$ ($c_i$ the spectral norm, computed per node at the first call). The CB
/// coordinates mix units and cancel each other's stress (an interface displacement and the
/// modes that bend back), so $\mathbf T$ whitens them by the stress they cause over the whole
/// set: $\mathbf T = \boldsymbol\Lambda^{1/2}\mathbf V^T$ from $\sum_i\mathbf A_i^T\mathbf A_i =
/// \mathbf V\boldsymbol\Lambda\mathbf V^T$ (eigenvalues floored at $10^{-12}$ of the largest), so
/// that $\lVert\mathbf T\mathbf d\rVert$ is the root-sum-square over the set of the von Mises
/// stress of a change $\mathbf d$. And $\tau_i =
/// 10^{-12}\lVert\boldsymbol\Sigma_i\rVert_F(\lVert\mathbf q\rVert + \lVert\mathbf
/// q^{ref}\rVert)$ covering the round-off of both evaluations (about $(n+10)\,\epsilon$ times
/// the same factor). [`Self::maximum`] evaluates the node that was the maximum at the last call,
/// whose stress $v^*$ bounds the maximum from below, then every node with $b_i \ge v^*$: the
/// nodes left out cannot reach the maximum nor tie with it. The reference need not be one
/// state for all nodes: every node keeps the state it was last evaluated at (its epoch, one per
/// call), so that the nodes near the maximum, evaluated at most calls, have tight bounds, and
/// the nodes far below it keep an old reference for many calls
/// ([`VonMisesReference`]; the nodes of epochs older than the last 64 are evaluated again).
/// The zero state is a reference too ($v_i(\mathbf 0) = 0$): a node's bound is the smaller of
/// its epoch's and $c_i\lVert\mathbf T\mathbf q\rVert + 10^{-12}\lVert\boldsymbol\Sigma_i\rVert_F
/// \lVert\mathbf q\rVert$. And a change $\mathbf d$ of whitened coordinates splits into its
/// part along $\mathbf u$, the whitened direction of the first nonzero state, and the rest:
/// $\lVert\mathbf A_i\mathbf T^{-1}\mathbf d\rVert \le |\mathbf u^T\mathbf d|\,w_i + c_i\lVert\mathbf d -
/// \mathbf u\mathbf u^T\mathbf d\rVert$ with $w_i$ the node's von Mises stress of $\mathbf
/// T^{-1}\mathbf u$ (plus its round-off margin), used where smaller than $c_i\lVert\mathbf
/// d\rVert$. Many candidates are evaluated on rayon's threads.
/// Beam nodes (extreme-fibre stress of
/// [`StressShapes::von_mises`]) are evaluated at every call.
///
/// The node blocks $\boldsymbol\Sigma_i$ of the set are copied node by node (each $6\times n$
/// block contiguous), so that a node's evaluation reads one block; the products are summed in
/// the order of [`StressShapes::von_mises`], so that the values are the same to the bit.
#[derive(Clone, Debug)]
pub struct VonMisesMaximum {
    /// The node set (mesh node indices), in the caller's order.
    nodes: Vec<usize>,
    /// $n$, the number of CB coordinates.
    n: usize,
    /// Per set entry $k$: $\boldsymbol\Sigma_i$ stored coordinate-major (`6 * n * k + 6 * j +
    /// c`), zero for entries without solid stress.
    blocks: Vec<f64>,
    /// Per set entry: whether the node has solid stress.
    solid: Vec<bool>,
    /// The whitening and the bounds of the search of one state at a time ([`Self::maximum`]),
    /// made at its first call: a run's maxima ([`Self::maxima`]) do not need them.
    whitened: std::sync::OnceLock<Whitened>,
    /// Per set entry: $\lVert\boldsymbol\Sigma_i\rVert_F$ (0 without solid stress).
    frobenius: Vec<f64>,
    /// Per set entry: whether a beam ends at the node (its value is the beam's).
    beam: Vec<bool>,
    /// The screening copy of [`Self::maxima`]: per chunk of [`SCREEN_CHUNK`] set entries,
    /// $\tilde{\mathbf A}_i$ = the single-precision $\mathbf M^{1/2}\boldsymbol\Sigma_i$ of its
    /// entries as one column-major $6C\times n$ matrix (row $cC + l$: component $c$ of the
    /// chunk's entry $l$; zero for entries without solid stress, for beam entries and for the
    /// last chunk's padding).
    screen: Vec<f32>,
    /// Per chunk of the screening copy: the largest over its entries of the rounding of the
    /// copy $\lVert\tilde{\mathbf A}_i - \mathbf A_i\rVert_F$, of $\lVert\tilde{\mathbf
    /// A}_i\rVert_F$ and of $\lVert\boldsymbol\Sigma_i\rVert_F$ (the chunk's margin).
    screen_chunk_factors: Vec<[f64; 3]>,
    /// The set entries where a beam ends (evaluated exactly at every state).
    beam_entries: Vec<usize>,
}

/// The whitening of the CB coordinates of a [`VonMisesMaximum`] and the nodes' bounds in it.
#[derive(Clone, Debug)]
struct Whitened {
    /// $\mathbf T$, the whitening of the coordinates ($n\times n$).
    T: nalgebra::DMatrix<f64>,
    /// $\mathbf T^{-1}$.
    T_inv: nalgebra::DMatrix<f64>,
    /// Per set entry: $c_i$ (0 without solid stress).
    c: Vec<f64>,
}

/// The reference states of a [`VonMisesMaximum`], kept between calls: every set entry's von
/// Mises stress at the last state it was evaluated at (its *epoch*), the whitened coordinates
/// $\mathbf T\mathbf q_e$ of the live epochs, and the set entry of the last maximum. Empty
/// (`Default`) before the first call. Any reference gives the exact maximum; a near one gives
/// it cheaply.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VonMisesReference {
    /// Live epochs, oldest first, the first with id `front`.
    epochs: std::collections::VecDeque<Epoch>,
    front: u64,
    /// Per set entry: its epoch id and its von Mises stress there.
    epoch_of: Vec<u64>,
    von_mises: Vec<f64>,
    last: usize,
    /// Node evaluations and calls that evaluated every node, so far.
    evaluations: usize,
    refreshes: usize,
    /// $\mathbf u$, the unit whitened direction of the first nonzero state ($\mathbf T\mathbf
    /// q/\lVert\mathbf T\mathbf q\rVert$; empty before), and per set entry the von Mises stress
    /// of $\mathbf T^{-1}\mathbf u$ with its round-off margin: a change along $\mathbf u$ is
    /// bounded by it rather than by $c_i$.
    direction: Vec<f64>,
    along: Vec<f64>,
}

/// One state at which some set entries were last evaluated.
#[derive(Clone, Debug, Default, PartialEq)]
struct Epoch {
    /// $\mathbf T\mathbf q_e$.
    tq: Vec<f64>,
    /// $\lVert\mathbf q_e\rVert$.
    q_norm: f64,
    /// The set entries at this epoch.
    count: usize,
}

impl VonMisesReference {
    /// The number of node evaluations over every call so far (the brute force makes the set's
    /// size per call).
    pub fn evaluations(&self) -> usize {
        self.evaluations
    }

    /// The number of calls that evaluated every node.
    pub fn refreshes(&self) -> usize {
        self.refreshes
    }
}

/// At most this many epochs are kept; the entries of older ones are evaluated again.
const MAX_EPOCHS: usize = 64;

/// From this many candidates on, [`VonMisesMaximum::maximum`] evaluates them on rayon's threads.
const PARALLEL_CANDIDATES: usize = 512;

/// Set entries per chunk of the screening copy ([`VonMisesMaximum::maxima`]): a chunk's
/// $6C\times n$ single-precision rows (196 kB at $n$ = 32) and its product with a batch of
/// [`SCREEN_BATCH`] states stay in a core's second-level cache.
const SCREEN_CHUNK: usize = 256;

/// States screened by one product in [`VonMisesMaximum::maxima`].
const SCREEN_BATCH: usize = 64;

/// $\mathbf M^{1/2}$ of the von Mises seminorm in Voigt order: $\sqrt{3/2}$ times the deviatoric
/// projector on the normal stresses, $\sqrt3$ on the shear stresses.
fn von_mises_root() -> nalgebra::Matrix6<f64> {
    let mut m = nalgebra::Matrix6::zeros();
    let a = 1.5f64.sqrt();
    for r in 0..3 {
        for c in 0..3 {
            m[(r, c)] = a * (if r == c { 1.0 } else { 0.0 } - 1.0 / 3.0);
        }
        m[(3 + r, 3 + r)] = 3.0f64.sqrt();
    }
    m
}

impl VonMisesMaximum {
    /// The search over `nodes` (mesh node indices below [`StressShapes::node_count`]) of a body
    /// with stress shapes `shapes`.
    ///
    /// # Panics
    /// If a node is not below the node count (a caller's bug: `mbs::System::new` checks the
    /// nodes of stress sensors).
    pub fn new(shapes: &StressShapes, nodes: &[usize]) -> Self {
        let count = shapes.node_count();
        assert!(nodes.iter().all(|&i| i < count), "nodes of the body");
        let n = shapes.n_coordinates();
        let mut beam_node = vec![false; count];
        for b in &shapes.beams {
            for &i in &b.nodes {
                beam_node[i as usize] = true;
            }
        }
        let solid: Vec<bool> = nodes
            .iter()
            .map(|&i| shapes.nodal.is_some() && shapes.solid_node.get(i).copied().unwrap_or(false))
            .collect();
        // The blocks, coordinate-major, zero for entries without solid stress.
        let mut blocks = vec![0.0; 6 * n * nodes.len()];
        if let Some(S) = &shapes.nodal {
            blocks
                .par_chunks_mut(6 * n)
                .zip(nodes.par_iter().zip(&solid))
                .for_each(|(block, (&i, &solid))| {
                    if solid {
                        for j in 0..n {
                            block[6 * j..6 * j + 6]
                                .copy_from_slice(&S.data[j * S.nrows + 6 * i..j * S.nrows + 6 * i + 6]);
                        }
                    }
                });
        }
        let root = von_mises_root();
        let A = |k: usize| {
            let S = nalgebra::DMatrix::from_column_slice(6, n, &blocks[6 * n * k..6 * n * (k + 1)]);
            root * S
        };
        let frobenius: Vec<f64> = blocks
            .par_chunks(6 * n)
            .map(|b| b.iter().map(|x| x * x).sum::<f64>().sqrt())
            .collect();
        // The screening copy, chunk by chunk: A_i in single precision, component-major within
        // the chunk, and per entry the norm of the copy and its rounding.
        let chunks = nodes.len().div_ceil(SCREEN_CHUNK);
        let rows = 6 * SCREEN_CHUNK;
        let mut screen = vec![0.0f32; chunks * rows * n];
        let mut screen_norm = vec![0.0; nodes.len()];
        let mut screen_rounding = vec![0.0; nodes.len()];
        screen
            .par_chunks_mut(rows * n)
            .zip(screen_norm.par_chunks_mut(SCREEN_CHUNK))
            .zip(screen_rounding.par_chunks_mut(SCREEN_CHUNK))
            .enumerate()
            .for_each(|(chunk, ((block, norm), rounding))| {
                for l in 0..norm.len() {
                    let k = chunk * SCREEN_CHUNK + l;
                    // Beam entries are evaluated at every state; their zero rows screen as 0.
                    if !solid[k] || beam_node[nodes[k]] {
                        continue;
                    }
                    let a = A(k);
                    let (mut f, mut e) = (0.0, 0.0);
                    for j in 0..n {
                        for c in 0..6 {
                            let x = a[(c, j)];
                            let x32 = x as f32;
                            block[j * rows + c * SCREEN_CHUNK + l] = x32;
                            f += f64::from(x32) * f64::from(x32);
                            e += (f64::from(x32) - x) * (f64::from(x32) - x);
                        }
                    }
                    norm[l] = f.sqrt();
                    rounding[l] = e.sqrt();
                }
            });
        Self {
            nodes: nodes.to_vec(),
            n,
            blocks,
            solid,
            whitened: std::sync::OnceLock::new(),
            beam: nodes.iter().map(|&i| beam_node[i]).collect(),
            screen_chunk_factors: (0..chunks)
                .map(|c| {
                    let r = c * SCREEN_CHUNK..((c + 1) * SCREEN_CHUNK).min(nodes.len());
                    let largest = |x: &[f64]| x.iter().copied().fold(0.0, f64::max);
                    [
                        largest(&screen_rounding[r.clone()]),
                        largest(&screen_norm[r.clone()]),
                        largest(&frobenius[r]),
                    ]
                })
                .collect(),
            screen,
            beam_entries: (0..nodes.len()).filter(|&k| beam_node[nodes[k]]).collect(),
            frobenius,
        }
    }

    /// $\mathbf A_i = \mathbf M^{1/2}\boldsymbol\Sigma_i$ of set entry `k` ($6\times n$).
    fn A(&self, k: usize) -> nalgebra::OMatrix<f64, nalgebra::U6, nalgebra::Dyn> {
        let n = self.n;
        von_mises_root() * nalgebra::DMatrix::from_column_slice(6, n, &self.blocks[6 * n * k..6 * n * (k + 1)])
    }

    /// The whitening of the coordinates and every entry's $c_i$ ([`Self::maximum`]).
    fn whitened(&self) -> &Whitened {
        self.whitened.get_or_init(|| {
            let (n, solid) = (self.n, &self.solid);
            // The whitening T = Lambda^1/2 V^T of G = sum_i A_i^T A_i = V Lambda V^T.
            let G = (0..self.nodes.len())
                .into_par_iter()
                .filter(|&k| solid[k])
                .map(|k| self.A(k).tr_mul(&self.A(k)))
                .reduce(|| nalgebra::DMatrix::zeros(n, n), |a, b| a + b);
            let eigen = nalgebra::SymmetricEigen::new(G);
            let largest = eigen.eigenvalues.max();
            // Directions of (nearly) no stress keep a floor, so that T is invertible; their
            // columns of A_i T^-1 stay bounded by 1 (|A v| <= sqrt(lambda) <= sqrt(floor)).
            let floor = if largest > 0.0 { 1e-12 * largest } else { 1.0 };
            let scale = eigen.eigenvalues.map(|l| l.max(floor).sqrt());
            let V = eigen.eigenvectors;
            let T = nalgebra::DMatrix::from_diagonal(&scale) * V.transpose();
            let T_inv = V * nalgebra::DMatrix::from_diagonal(&scale.map(|s| 1.0 / s));
            let c = (0..self.nodes.len())
                .into_par_iter()
                .map(|k| {
                    if !solid[k] {
                        return 0.0;
                    }
                    // c_i = |A_i T^-1|_2: the largest eigenvalue of B B^T (6 x 6).
                    let B = self.A(k) * &T_inv;
                    nalgebra::SymmetricEigen::new(&B * B.transpose())
                        .eigenvalues
                        .max()
                        .max(0.0)
                        .sqrt()
                })
                .collect();
            Whitened { T, T_inv, c }
        })
    }

    /// The node set.
    pub fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    /// The solid von Mises stress of set entry `k` (0 without solid stress), summed as
    /// [`StressShapes::von_mises`] sums it.
    fn solid(&self, k: usize, q: &[f64]) -> f64 {
        if !self.solid[k] {
            return 0.0;
        }
        let block = &self.blocks[6 * self.n * k..6 * self.n * (k + 1)];
        let mut s = [0.0; 6];
        for (col, &qj) in block.chunks_exact(6).zip(q) {
            if qj != 0.0 {
                for (sc, a) in s.iter_mut().zip(col) {
                    *sc += a * qj;
                }
            }
        }
        fe_model::von_mises(&s)
    }

    /// The largest von Mises stress over the set for CB coordinates `q` and the mesh node where
    /// it occurs (the last of equal maxima in set order), `None` for an empty set; `shapes` are
    /// those the search was built from (for the beams), `reference` the states kept between
    /// calls (type docs).
    ///
    /// # Panics
    /// If `q` does not have one value per CB coordinate (a caller's bug).
    pub fn maximum(&self, shapes: &StressShapes, q: &[f64], reference: &mut VonMisesReference) -> Option<(usize, f64)> {
        assert_eq!(q.len(), self.n, "one value per CB coordinate");
        let size = self.nodes.len();
        if size == 0 {
            return None;
        }
        let beams = self
            .beam
            .iter()
            .any(|&b| b)
            .then(|| shapes.beam_extremes(q, shapes.node_count()));
        let value = |k: usize| match &beams {
            Some(x) if self.beam[k] => x[self.nodes[k]].map_or_else(|| self.solid(k, q), |[magnitude, _]| magnitude),
            _ => self.solid(k, q),
        };
        let q_norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        let w = self.whitened();
        let tq = &w.T * nalgebra::DVector::from_column_slice(q);
        let r = reference;
        let usable = q_norm.is_finite() && r.epoch_of.len() == size && !r.epochs.is_empty();
        if !usable {
            let (k, vm) = self.restart(r, (0..size).map(value).collect(), q_norm, &tq);
            return Some((self.nodes[k], vm));
        }
        let tq_norm = tq.norm();
        if (r.along.len() != size || r.direction.len() != self.n) && tq_norm > 0.0 && tq_norm.is_finite() {
            self.set_direction(r, &tq, tq_norm);
        }
        let directed = r.along.len() == size && r.direction.len() == self.n;
        // A change d in whitened coordinates: its component along u and the norm of the rest.
        let split = |d: &[f64]| -> (f64, f64) {
            if !directed {
                return (0.0, f64::INFINITY);
            }
            let a: f64 = d.iter().zip(&r.direction).map(|(x, u)| x * u).sum();
            let rest = d
                .iter()
                .zip(&r.direction)
                .map(|(x, u)| (x - a * u) * (x - a * u))
                .sum::<f64>()
                .sqrt();
            (a.abs(), rest)
        };
        // This call's epoch; the distance to and the round-off margin of every live one.
        let now = r.front + r.epochs.len() as u64;
        let (distance, slack): (Vec<f64>, Vec<f64>) = r
            .epochs
            .iter()
            .map(|e| {
                let d = tq.iter().zip(&e.tq).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt();
                (d, 1e-12 * (q_norm + e.q_norm))
            })
            .unzip();
        let parts: Vec<(f64, f64)> = r
            .epochs
            .iter()
            .map(|e| split(&tq.iter().zip(&e.tq).map(|(a, b)| a - b).collect::<Vec<_>>()))
            .collect();
        let zero_parts = split(tq.as_slice());
        r.epochs.push_back(Epoch {
            tq: tq.as_slice().to_vec(),
            q_norm,
            count: 0,
        });
        let k0 = r.last.min(size - 1);
        let lower = value(k0);
        // Every entry's bound: the smaller of its epoch's (10.3) and the zero state's ($v_i(\mathbf
        // 0) = 0$: $c_i\lVert\mathbf T\mathbf q\rVert$, tight where the body passes through
        // zero stress), each widened by its round-off margin. The candidates are the entries whose
        // bound reaches the lower bound, and those of the oldest epochs when there are too many.
        let zero_slack = 1e-12 * q_norm;
        let stale = r.front + r.epochs.len().saturating_sub(MAX_EPOCHS) as u64;
        let candidates: Vec<usize> = (0..size)
            .filter(|&k| {
                let e = (r.epoch_of[k] - r.front) as usize;
                k == k0 || self.beam[k] || r.epoch_of[k] < stale || !lower.is_finite() || {
                    let along = r.along.get(k).copied().unwrap_or(0.0);
                    let change = |d: f64, (a, rest): (f64, f64)| (w.c[k] * d).min(a * along + w.c[k] * rest);
                    (r.von_mises[k] + change(distance[e], parts[e]) + self.frobenius[k] * slack[e])
                        .min(change(tq_norm, zero_parts) + self.frobenius[k] * zero_slack)
                        >= lower
                }
            })
            .collect();
        let mut best: Option<(usize, f64)> = None;
        let evaluated = candidates.len();
        // The candidates' values, in parallel when there are many (each summed as one node's
        // alone, the same to the bit; few are cheaper on one thread).
        let values: Vec<f64> = if evaluated >= PARALLEL_CANDIDATES {
            candidates
                .par_iter()
                .with_min_len(PARALLEL_CANDIDATES / 2)
                .map(|&k| if k == k0 { lower } else { value(k) })
                .collect()
        } else {
            candidates
                .iter()
                .map(|&k| if k == k0 { lower } else { value(k) })
                .collect()
        };
        for (k, vm) in candidates.into_iter().zip(values) {
            if best.is_none_or(|b| vm.total_cmp(&b.1).is_ge()) {
                best = Some((k, vm));
            }
            // The entry now has this call's epoch.
            let e = (r.epoch_of[k] - r.front) as usize;
            r.epochs[e].count -= 1;
            r.epoch_of[k] = now;
            r.von_mises[k] = vm;
            let last = r.epochs.len() - 1;
            r.epochs[last].count += 1;
        }
        r.evaluations += evaluated;
        if evaluated == size {
            r.refreshes += 1;
        }
        while r.epochs.front().is_some_and(|e| e.count == 0) {
            r.epochs.pop_front();
            r.front += 1;
        }
        let (k, vm) = best.expect("the lower bound's entry is a candidate");
        r.last = k;
        Some((self.nodes[k], vm))
    }

    /// [`Self::maximum`] without a usable reference: every node's value `von_mises` taken,
    /// and the state (when finite) becomes the reference's one epoch. The maximum's entry and
    /// value.
    fn restart(
        &self,
        r: &mut VonMisesReference,
        von_mises: Vec<f64>,
        q_norm: f64,
        tq: &nalgebra::DVector<f64>,
    ) -> (usize, f64) {
        let size = von_mises.len();
        let (k, vm) = last_maximum((0..size).map(|k| (k, von_mises[k])));
        r.evaluations += size;
        r.refreshes += 1;
        if q_norm.is_finite() {
            let front = r.front + r.epochs.len() as u64 + 1;
            *r = VonMisesReference {
                epochs: [Epoch {
                    tq: tq.as_slice().to_vec(),
                    q_norm,
                    count: size,
                }]
                .into(),
                front,
                epoch_of: vec![front; size],
                von_mises,
                last: k,
                evaluations: r.evaluations,
                refreshes: r.refreshes,
                direction: std::mem::take(&mut r.direction),
                along: std::mem::take(&mut r.along),
            };
        }
        (k, vm)
    }

    /// The reference's whitened direction $\mathbf u = \mathbf T\mathbf q / \lVert\mathbf
    /// T\mathbf q\rVert$ and every node's von Mises stress along it, $w_i$.
    fn set_direction(&self, r: &mut VonMisesReference, tq: &nalgebra::DVector<f64>, tq_norm: f64) {
        let w = self.whitened();
        let size = self.nodes.len();
        let u = tq / tq_norm;
        let y = &w.T_inv * &u;
        let y_norm = y.norm();
        r.along = (0..size)
            .into_par_iter()
            .map(|k| self.solid(k, y.as_slice()) + 1e-12 * self.frobenius[k] * y_norm)
            .collect();
        r.direction = u.as_slice().to_vec();
    }
}

impl VonMisesMaximum {
    /// [`Self::maximum`] at each of `states` (CB coordinates), computed together: the same
    /// node and value at every state, to the bit, without a reference (any order of states).
    ///
    /// A batch of states is screened by one matrix product in single precision, which reads
    /// the set's stress shapes once for the batch rather than once per state (the search of
    /// [`Self::maximum`] is bound by those reads): $\hat{\mathbf y}_i = \tilde{\mathbf
    /// A}_i\tilde{\mathbf q}$ and $\hat v_i = \lVert\hat{\mathbf y}_i\rVert$ (in double
    /// precision from the single-precision products), with $\tilde{\mathbf A}_i$,
    /// $\tilde{\mathbf q}$ the single-precision $\mathbf A_i = \mathbf M^{1/2}\boldsymbol\Sigma_i$
    /// and $\mathbf q$. The exact von Mises stress $v_i = \lVert\mathbf A_i\mathbf q\rVert$
    /// differs from $\hat v_i$ by at most
    /// $$m_i = \lVert\tilde{\mathbf A}_i - \mathbf A_i\rVert_F\lVert\mathbf q\rVert +
    /// \lVert\tilde{\mathbf A}_i\rVert_F\,\big(\lVert\tilde{\mathbf q} - \mathbf q\rVert +
    /// \gamma_n\lVert\tilde{\mathbf q}\rVert\big) + \tau_i,$$
    /// $\gamma_n = nu/(1 - nu)$ ($u = 2^{-24}$) the bound of an $n$-term single-precision dot
    /// product in any summation order, applied row by row, and $\tau_i$ the round-off of the
    /// double-precision evaluation and of $\hat v_i$ (the margin of [`Self::maximum`], plus
    /// underflow). Each chunk of 256 entries takes the largest of its entries'
    /// margins, $m_C \ge m_i$. With $L = \max_i(\hat v_i - m_C) \le \max_i v_i$, only the
    /// entries with $\hat v_i + m_C \ge L$ can reach or tie the maximum; they (usually a
    /// handful) and the beam entries are evaluated exactly as [`Self::maximum`] evaluates
    /// them. States the
    /// screen cannot bound (not finite, or so large that single precision would overflow) are
    /// evaluated entry by entry.
    ///
    /// Returns the maxima and the number of exact entry evaluations they took (the set's size
    /// per state would be every entry's).
    ///
    /// # Panics
    /// If a state does not have one value per CB coordinate (a caller's bug).
    pub fn maxima(&self, shapes: &StressShapes, states: &[&[f64]]) -> (Vec<Option<(usize, f64)>>, usize) {
        assert!(states.iter().all(|q| q.len() == self.n), "one value per CB coordinate");
        let size = self.nodes.len();
        if size == 0 {
            return (vec![None; states.len()], 0);
        }
        let mut out = vec![None; states.len()];
        let mut evaluations = 0;
        let largest_norm = self.screen_chunk_factors.iter().map(|f| f[1]).fold(0.0, f64::max);
        let (screened, direct): (Vec<usize>, Vec<usize>) = (0..states.len()).partition(|&s| {
            let q = states[s];
            let q_norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            // Every product and partial sum stays far below f32::MAX (3.4e38).
            q_norm.is_finite() && q.iter().all(|x| x.abs() < 1e30) && largest_norm * q_norm < 1e30
        });
        for s in direct {
            out[s] = self.maximum(shapes, states[s], &mut VonMisesReference::default());
            evaluations += size;
        }
        for batch in screened.chunks(SCREEN_BATCH) {
            let found = self.screened_maxima(shapes, &batch.iter().map(|&s| states[s]).collect::<Vec<_>>());
            for (&s, (m, count)) in batch.iter().zip(found) {
                out[s] = Some(m);
                evaluations += count;
            }
        }
        (out, evaluations)
    }

    /// [`Self::maxima`] of up to [`SCREEN_BATCH`] states that the screen can bound, each with
    /// its number of exact evaluations.
    fn screened_maxima(&self, shapes: &StressShapes, states: &[&[f64]]) -> Vec<((usize, f64), usize)> {
        let (n, size, b) = (self.n, self.nodes.len(), states.len());
        let u = f64::from(f32::EPSILON) / 2.0;
        let gamma = n as f64 * u / (1.0 - n as f64 * u);
        // Q~ (n x b, column-major) and per state ||q||, ||q~ - q||, ||q~||.
        let mut qt = vec![0.0f32; n * b];
        let norms: Vec<[f64; 3]> = states
            .iter()
            .enumerate()
            .map(|(s, q)| {
                let (mut a, mut d, mut t) = (0.0, 0.0, 0.0);
                for (j, &x) in q.iter().enumerate() {
                    let x32 = x as f32;
                    qt[s * n + j] = x32;
                    a += x * x;
                    d += (f64::from(x32) - x) * (f64::from(x32) - x);
                    t += f64::from(x32) * f64::from(x32);
                }
                [a.sqrt(), d.sqrt(), t.sqrt()]
            })
            .collect();
        let rows = 6 * SCREEN_CHUNK;
        let arch = pulp::Arch::new();
        // Underflow: each of the 2n operations of a single-precision dot product may lose up to
        // half the smallest subnormal; six components.
        let underflow = 6f64.sqrt() * 2.0 * n as f64 * 2f64.powi(-150);
        // Per chunk and state: the chunk's lower bound and its candidates (entry, upper bound),
        // in set order. One margin per chunk, from the chunk's largest factors: the margins are
        // about 1e-6 of the stresses, so a uniform one keeps few more candidates and leaves the
        // pass over the nodes a plain vector loop.
        let per_chunk: Vec<Vec<ChunkScreen>> = self
            .screen
            .par_chunks(rows * n)
            .zip(&self.screen_chunk_factors)
            .enumerate()
            .map_init(
                || (vec![0.0f32; rows * SCREEN_BATCH], vec![0.0f64; SCREEN_CHUNK]),
                |(w, v), (chunk, (A, &[rounding, norm, frobenius]))| {
                    let w = &mut w[..rows * b];
                    faer::linalg::matmul::matmul(
                        faer::MatMut::from_column_major_slice_mut(w, rows, b),
                        faer::Accum::Replace,
                        MatRef::from_column_major_slice(A, rows, n),
                        MatRef::from_column_major_slice(&qt, n, b),
                        1.0f32,
                        faer::Par::Seq,
                    );
                    let first = chunk * SCREEN_CHUNK;
                    let len = SCREEN_CHUNK.min(size - first);
                    let v = &mut v[..len];
                    (0..b)
                        .map(|s| {
                            let y = &w[s * rows..(s + 1) * rows];
                            // v_hat^2 of every entry of the chunk, and the largest, in the
                            // vector instructions the machine has.
                            let largest = arch.dispatch(SquaredNorms { y, v: &mut *v }).sqrt();
                            let [q_norm, q_rounding, qt_norm] = norms[s];
                            let margin = 1.01
                                * (rounding * q_norm
                                    + norm * (q_rounding + gamma * qt_norm)
                                    + 1e-12 * frobenius * q_norm
                                    + 1e-15 * largest
                                    + underflow);
                            // The chunk's lower bound, and the entries that can reach it with
                            // both margins (a superset of those reaching the set's bound).
                            let lower = largest - margin;
                            let floor = (lower - margin).max(0.0);
                            let floor = floor * floor;
                            let candidates = v
                                .iter()
                                .enumerate()
                                .filter(|&(_, &sq)| sq >= floor)
                                .map(|(l, &sq)| (first + l, sq.sqrt() + margin))
                                .collect();
                            (lower, candidates)
                        })
                        .collect()
                },
            )
            .collect();
        (0..b)
            .into_par_iter()
            .map(|s| {
                let q = states[s];
                let lower = per_chunk.iter().map(|c| c[s].0).fold(f64::NEG_INFINITY, f64::max);
                let beams = self
                    .beam
                    .iter()
                    .any(|&x| x)
                    .then(|| shapes.beam_extremes(q, shapes.node_count()));
                let value = |k: usize| match &beams {
                    Some(x) if self.beam[k] => {
                        x[self.nodes[k]].map_or_else(|| self.solid(k, q), |[magnitude, _]| magnitude)
                    }
                    _ => self.solid(k, q),
                };
                let mut count = 0;
                // The screened candidates and the beam entries (their screen rows are zero), in
                // set order.
                let mut candidates: Vec<usize> = per_chunk
                    .iter()
                    .flat_map(|c| &c[s].1)
                    .filter(|&&(_, upper)| upper >= lower)
                    .map(|&(k, _)| k)
                    .collect();
                if !self.beam_entries.is_empty() {
                    candidates.extend(&self.beam_entries);
                    candidates.sort_unstable();
                    candidates.dedup();
                }
                let (k, vm) = last_maximum(candidates.into_iter().map(|k| {
                    count += 1;
                    (k, value(k))
                }));
                ((self.nodes[k], vm), count)
            })
            .collect()
    }
}

/// One chunk's screen of one state: its lower bound of the maximum and its candidates (set
/// entry, upper bound of its value), in set order.
type ChunkScreen = (f64, Vec<(usize, f64)>);

/// The squared norms $\hat v_l^2 = \sum_c y_{cC + l}^2$ of a chunk's entries from its
/// single-precision products `y` (component-major, [`SCREEN_CHUNK`] rows a component) into
/// `v` (one per entry), returning the largest: plain loops that `pulp` compiles for the vector
/// instructions of the machine (the release target is baseline x86-64).
struct SquaredNorms<'a> {
    y: &'a [f32],
    v: &'a mut [f64],
}

impl pulp::WithSimd for SquaredNorms<'_> {
    type Output = f64;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> f64 {
        let Self { y, v } = self;
        let len = v.len();
        v.fill(0.0);
        for c in 0..6 {
            for (vl, &x) in v.iter_mut().zip(&y[c * SCREEN_CHUNK..c * SCREEN_CHUNK + len]) {
                *vl += f64::from(x) * f64::from(x);
            }
        }
        v.iter().copied().fold(0.0, f64::max)
    }
}

/// The last of the largest values (`Iterator::max_by` with `total_cmp`) and its index.
fn last_maximum(values: impl Iterator<Item = (usize, f64)>) -> (usize, f64) {
    values.max_by(|a, b| a.1.total_cmp(&b.1)).expect("a node")
}

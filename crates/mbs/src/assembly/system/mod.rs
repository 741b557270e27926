//! [`System`]: a checked [`Model`] turned into independent coordinates, elements and a sparse
//! pattern; [`State`]: the coordinates, velocities and accelerations at one instant.
//!
//! The equations in the independent coordinates are (theory guide §8)
//! $$\mathbf F(\mathbf q, \dot{\mathbf q}, \ddot{\mathbf q}, t) = \sum_c\mathbf J_c^T\mathbf r_c + \mathbf r_\eta + \mathbf r_{joint} = \mathbf 0,$$
//! with $\mathbf r_c$ the residual of all elements at node $c$ evaluated at the node motion
//! $\mathbf V_c = \mathbf J_c\dot{\mathbf q}$, $\mathbf A_c = \mathbf J_c\ddot{\mathbf q} + \dot{\mathbf J}_c\dot{\mathbf q}$; the same
//! sums over the prescribed columns are the reactions (formed when a sensor reads them).
//! Their derivatives $\hat{\mathbf M} =
//! \partial\mathbf F/\partial\ddot{\mathbf q}$, $\hat{\mathbf C} = \partial\mathbf F/\partial\dot{\mathbf q}$,
//! $\hat{\mathbf K} = \partial\mathbf F/\partial\mathbf q$ are assembled into one sparse pattern
//! ([`crate::assembly::coordinates`] gives the formulas).
//!
//! Style R9: the pattern, the element-to-slot maps and the symbolic LU are built once in
//! [`System::new`]; each Newton iteration refills values only (`evaluate_into`). Style R8: the
//! per-element outputs (every element function writes into its reused output), each
//! superelement's workspace ([`superelement::Superelement::evaluate_into`]), the node motions
//! and their derivatives (the coordinate maps reuse their column buffers), the element
//! matrices, the iteration matrix and its factorisation live in the analysis' `Workspace`, so
//! an iteration allocates nothing up to [`DENSE_MAX`] unknowns (dense LU in a preallocated
//! buffer, [`LinearSolver`]) and only in faer's numeric sparse LU above. The motions of the
//! nodes driven by time alone are kept while the time stays (`System::update_motions`).

#![allow(non_snake_case)]

mod initial_state;
pub mod momentum;
pub mod recovery;
pub mod sensors;

use crate::assembly::body::{
    load_element, point_mass_element, rigid_element, spring_element, user_force_element, ElementOutput, FlexBuffer,
    FlexibleElement, LoadElement, RigidElement, SpringElement,
};
use crate::assembly::coordinates::{
    scalar_values, unknown, values, CoordinateMap, Motion, MotionCache, NodeDerivatives, Slot, Values,
};
use crate::assembly::dense_lu::{self, SMALL_LU_MAX};
use crate::assembly::force_law::BoundLaw;
use crate::assembly::initial::InitialPlan;
use crate::assembly::joint_forces::JointForces;
use crate::assembly::topology::{self, RootRotation, Topology};
use crate::error::{Entity, ModelError, SolveError};
use crate::model::force_law::{ForceLaw, LawBuffer};
use crate::model::time_function::CompiledFunction;
use crate::model::user_force::{UserBuffer, UserForce};
use crate::model::{Body, BodyId, InitialCondition, JointId, LoadAxes, LoadKind, Model, NodeId, SensorKind};
use crate::node::NodeMotion;
use crate::state::State;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::lu::partial_pivoting::{factor as lu_factor, solve as lu_solve};
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Mat, Par};
use nalgebra::{UnitQuaternion, Vector3};
use rayon::prelude::*;
use std::sync::Arc;
use superelement::{so3, Frame, Superelement};

/// A joint spring on its scalar: (scalar, $k$, $c$, $x_0$, $f_0$).
pub(crate) type JointSpringScalar = (usize, f64, f64, f64, f64);

/// One element of the assembly: what it is and where it acts.
#[derive(Clone, Debug)]
pub(crate) enum ElementKind {
    Flexible(usize),
    Rigid(usize),
    PointMass(usize, f64),
    Spring(usize),
    Load(usize),
    /// A [`UserForce`] (index into `System::user_forces`).
    User(usize),
}

#[derive(Clone, Debug)]
pub(crate) struct ElementRef {
    pub kind: ElementKind,
    /// Node ports, 6 rows each.
    pub nodes: Vec<usize>,
    /// Unknown dof of each modal coordinate (flexible bodies).
    pub modal: Vec<usize>,
}

/// Sparse structure of $\hat{\mathbf M}$, $\hat{\mathbf C}$, $\hat{\mathbf K}$ and the maps that scatter into it.
#[derive(Clone, Debug)]
pub(crate) struct Pattern {
    pub symbolic: SymbolicSparseColMat<usize>,
    pub lu: Option<SymbolicLu<usize>>,
    /// Per element: its unknown dofs (sorted), the position of each node's unknown column among
    /// them, the position of each modal dof, and the slots of the dense local block (column major).
    pub elem_dofs: Vec<Vec<usize>>,
    pub elem_pos: Vec<Vec<Vec<usize>>>,
    pub elem_modal_pos: Vec<Vec<usize>>,
    pub elem_slots: Vec<Vec<usize>>,
    /// Per node: slots of (unknown column i, unknown column k) for the geometric term.
    pub node_slots: Vec<Vec<usize>>,
    /// Per node: (position among its columns, unknown) of each unknown column.
    pub node_unknown_cols: Vec<Vec<(usize, usize)>>,
    /// Slot of each joint spring's diagonal entry (when its coordinate is unknown).
    pub joint_spring_slots: Vec<Option<usize>>,
}

impl Pattern {
    /// The sparse pattern of the elements, the nodes' own blocks, the joint springs and the
    /// joint forces, with the symbolic LU and the slots of each (the joint forces bound to it).
    fn build(
        model: &Model,
        topo: &Topology,
        elements: &[ElementRef],
        joint_springs: &[JointSpringScalar],
        joint_forces: &mut JointForces,
        law: Option<&mut BoundLaw>,
    ) -> Result<Self, ModelError> {
        let map = &topo.map;
        let n = map.n_dof;
        let node_unknown: Vec<Vec<usize>> = map
            .chains
            .iter()
            .map(|c| c.cols.iter().copied().filter(|&id| id < n).collect())
            .collect();
        let mut sets: Vec<Vec<usize>> = Vec::new();
        for e in elements {
            let mut s: Vec<usize> = e.nodes.iter().flat_map(|&a| node_unknown[a].iter().copied()).collect();
            s.extend(&e.modal);
            s.sort_unstable();
            s.dedup();
            sets.push(s);
        }
        let n_elem_sets = sets.len();
        for (c, u) in node_unknown.iter().enumerate() {
            if !map.chains[c].root {
                sets.push(u.clone());
            }
        }
        sets.extend(joint_forces.pattern_sets(topo));
        if let Some(law) = law.as_deref() {
            sets.extend(law.pattern_sets(&node_unknown));
        }
        let symbolic = Pattern::structure(n, &sets);
        let lu = if n > 0 {
            Some(
                SymbolicLu::try_new(symbolic.as_ref())
                    .map_err(|e| invalid(None, "system".into(), format!("symbolic LU failed: {e:?}")))?,
            )
        } else {
            None
        };
        let mut pattern = Pattern {
            symbolic,
            lu,
            elem_dofs: Vec::new(),
            elem_pos: Vec::new(),
            elem_modal_pos: Vec::new(),
            elem_slots: Vec::new(),
            node_slots: vec![Vec::new(); model.nodes.len()],
            node_unknown_cols: map
                .chains
                .iter()
                .map(|ch| ch.cols.iter().copied().enumerate().filter(|&(_, id)| id < n).collect())
                .collect(),
            joint_spring_slots: Vec::new(),
        };
        for (e, dofs) in elements.iter().zip(sets.iter().take(n_elem_sets)) {
            let find = |d: usize| dofs.binary_search(&d).expect("dof of the element");
            let pos = e
                .nodes
                .iter()
                .map(|&a| node_unknown[a].iter().map(|&d| find(d)).collect())
                .collect();
            let modal_pos = e.modal.iter().map(|&d| find(d)).collect();
            let slots = dofs
                .iter()
                .flat_map(|&c| dofs.iter().map(move |&r| (r, c)))
                .map(|(r, c)| pattern.slot(r, c))
                .collect();
            pattern.elem_dofs.push(dofs.clone());
            pattern.elem_pos.push(pos);
            pattern.elem_modal_pos.push(modal_pos);
            pattern.elem_slots.push(slots);
        }
        for (c, u) in node_unknown.iter().enumerate() {
            if !map.chains[c].root {
                pattern.node_slots[c] = u
                    .iter()
                    .flat_map(|&k| u.iter().map(move |&i| (i, k)))
                    .map(|(i, k)| pattern.slot(i, k))
                    .collect();
            }
        }
        pattern.joint_spring_slots = joint_springs
            .iter()
            .map(|&(s, ..)| match map.scalars[s].slot {
                Slot::Unknown(d) => Some(pattern.slot(d, d)),
                Slot::Prescribed(_) => None,
            })
            .collect();
        joint_forces.bind(topo, |r, c| pattern.slot(r, c));
        if let Some(law) = law {
            law.bind(&node_unknown, |r, c| pattern.slot(r, c));
        }
        Ok(pattern)
    }

    /// The CSC structure holding every $\text{set}\times\text{set}$ block and the diagonal.
    fn structure(n: usize, sets: &[Vec<usize>]) -> SymbolicSparseColMat<usize> {
        fe_model::pattern::block_structure(n, sets)
    }

    /// Position of entry (r, c) in the values array.
    pub(crate) fn slot(&self, r: usize, c: usize) -> usize {
        let cp = self.symbolic.col_ptr();
        let rows = &self.symbolic.row_idx()[cp[c]..cp[c + 1]];
        cp[c] + rows.binary_search(&r).expect("entry in the pattern")
    }

    pub(crate) fn nnz(&self) -> usize {
        self.symbolic.row_idx().len()
    }
}

/// Dense $\hat{\mathbf M}$, $\hat{\mathbf C}$, $\hat{\mathbf K}$ and $\mathbf F$ (for tests and the
/// linearised analysis).
#[derive(Clone, Debug)]
pub struct Matrices {
    pub F: Vec<f64>,
    pub M: Mat<f64>,
    pub C: Mat<f64>,
    pub K: Mat<f64>,
}

/// Kinematic data of one node: $\mathbf J_c$ over its unknown columns and its derivatives.
#[derive(Clone, Debug)]
pub struct NodeKinematics {
    pub motion: NodeMotion,
    /// Unknown dof of each column.
    pub dofs: Vec<usize>,
    /// $\mathbf J_c$, $6\times$ `dofs.len()`.
    pub J: Mat<f64>,
    /// $\partial\mathbf V_c/\partial\mathbf q$, $\partial\mathbf A_c/\partial\mathbf q$, $\partial\mathbf A_c/\partial\dot{\mathbf q}$.
    pub DV: Mat<f64>,
    pub DA: Mat<f64>,
    pub DAd: Mat<f64>,
}

/// Buffers of one analysis: created once, refilled by every evaluation. A clone carries the
/// factorisation and the caches too, so that an integrator cloned to go back to a step
/// continues bit for bit as the original ([`crate::Integrator`] is `Clone`).
#[derive(Clone)]
pub(crate) struct Workspace {
    pub motions: Vec<Motion>,
    /// Which of `motions` are current ([`System::update_motions`]).
    pub motion_cache: MotionCache,
    pub nodes: Vec<NodeMotion>,
    pub derivs: Vec<NodeDerivatives>,
    pub node_res: Vec<[f64; 6]>,
    pub F: Vec<f64>,
    pub reactions: Vec<f64>,
    pub M: Vec<f64>,
    pub C: Vec<f64>,
    pub K: Vec<f64>,
    pub presc_rate: Vec<f64>,
    pub presc_acc: Vec<f64>,
    /// $\|\mathbf J^T\mathbf f_{inertia}\| + \|\mathbf J^T\mathbf f_{internal}\| + \|\mathbf J^T\mathbf f_{external}\|$:
    /// the force scale of the convergence test.
    pub scale: f64,
    /// Round-off floor of $\|\mathbf F\|$ (absolute): see [`System::residual_floor`].
    pub floor: f64,
    /// Iteration-matrix values and the last numeric LU.
    pub S: Vec<f64>,
    /// Per element (order of `System::elements`): its output and reused buffers.
    pub elems: Vec<ElementBuffer>,
    /// Per node: the inertia, internal and external parts of its residual.
    pub parts: Vec<[[f64; 6]; 3]>,
    /// The generalised inertia, internal and external forces ($\mathbf J^T$ of `parts`).
    pub gparts: [Vec<f64>; 3],
    /// The factorisation of `S` ([`System::factor`]), kept for more solves ([`System::solve_factored`]).
    pub factor: Factor,
    /// Scratch of [`System::inertia_floor`]: $\hat{\mathbf M}\mathbf v$.
    pub momentum: Vec<f64>,
    /// The force law's inputs, values and Jacobians ([`System::with_force_law`]).
    pub law: Option<LawBuffer>,
}

/// A joint limit as a stop of a dynamic run ([`crate::assembly::joint_forces`], stops that a
/// step resolves): a spring of stiffness $k$ on the coordinate's inertia $m$.
#[derive(Clone, Debug)]
pub(crate) struct Stop {
    /// Index in `Model::joint_limits`.
    pub index: usize,
    pub name: String,
    pub joint: String,
    pub stiffness: f64,
    pub inertia: f64,
}

impl Stop {
    /// $\omega = \sqrt{k/m}$ [rad/s].
    pub fn frequency(&self) -> f64 {
        (self.stiffness / self.inertia).sqrt()
    }
}

/// Up to this many unknowns the iteration matrix is factorised densely (LU with partial
/// pivoting, in place in a preallocated buffer): for small systems the sparse LU's bookkeeping
/// and allocations cost more than the $O(n^3)$ arithmetic. Measured with callgrind on the chain
/// bench (`cargo bench -p mbs --bench step -- chain N 10 dense|sparse`, 6 unknowns per
/// superelement; instructions of factorisations and solves in 13 steps, dense / sparse): 24
/// unknowns 0.9M / 3.4M, 48 3.1M / 9.9M, 96 13.9M / 19.4M, 192 65.8M / 40.5M. The chain's
/// banded matrix favours the sparse LU more than most mechanisms do; the crossover there is
/// near 115 unknowns.
pub const DENSE_MAX: usize = 96;

/// How [`System`] factorises its iteration matrices (style: a switch is an enum).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LinearSolver {
    /// Dense LU up to [`DENSE_MAX`] unknowns, sparse LU (symbolic analysis reused) above.
    #[default]
    Auto,
    /// Always the dense LU with partial pivoting ([`crate::assembly::dense_lu`] up to
    /// [`crate::assembly::dense_lu::SMALL_LU_MAX`] unknowns, faer `lu_in_place` above).
    Dense,
    /// Always the sparse LU on the system pattern (faer, symbolic analysis from [`System::new`]).
    Sparse,
}

/// The factorisation of the last iteration matrix (or none yet).
pub(crate) enum Factor {
    /// No unknowns, or not factorised yet.
    None,
    /// Sparse LU of `A` (the matrix on the system pattern, refilled from `S`).
    Sparse {
        A: SparseColMat<usize, f64>,
        lu: Option<Box<Lu<usize, f64>>>,
    },
    /// Dense LU of a small matrix in place ([`crate::assembly::dense_lu`], up to
    /// [`crate::assembly::dense_lu::SMALL_LU_MAX`] unknowns): `LU` the factors column major, `piv` the
    /// row interchanges.
    Small {
        LU: Vec<f64>,
        piv: Vec<usize>,
        factored: bool,
    },
    /// Dense LU in place (faer): `LU` holds $\mathbf L$ (unit lower) and $\mathbf U$, `perm` the row
    /// permutation; `mem` the scratch of the factorisation and the solves, sized once.
    Dense {
        LU: Mat<f64>,
        perm: Vec<usize>,
        perm_inv: Vec<usize>,
        mem: MemBuffer,
        /// Right-hand sides `mem` has room for (it grows, once, for more).
        rhs_cols: usize,
        factored: bool,
    },
}

/// The factors are copied; the dense LU's scratch memory is allocated anew at its size (its
/// contents are not read before they are written).
impl Clone for Factor {
    fn clone(&self) -> Self {
        match self {
            Factor::None => Factor::None,
            Factor::Sparse { A, lu } => Factor::Sparse {
                A: A.clone(),
                lu: lu.clone(),
            },
            Factor::Small { LU, piv, factored } => Factor::Small {
                LU: LU.clone(),
                piv: piv.clone(),
                factored: *factored,
            },
            Factor::Dense {
                LU,
                perm,
                perm_inv,
                mem: _,
                rhs_cols,
                factored,
            } => Factor::Dense {
                LU: LU.clone(),
                perm: perm.clone(),
                perm_inv: perm_inv.clone(),
                mem: MemBuffer::new(dense_scratch(LU.nrows(), *rhs_cols)),
                rhs_cols: *rhs_cols,
                factored: *factored,
            },
        }
    }
}

/// Scratch of the dense LU and of its solve for `k` right-hand sides.
fn dense_scratch(n: usize, k: usize) -> StackReq {
    StackReq::any_of(&[
        lu_factor::lu_in_place_scratch::<usize, f64>(n, n, Par::Seq, Default::default()),
        lu_solve::solve_in_place_scratch::<usize, f64>(n, k, Par::Seq),
    ])
}

/// One element's output and the buffers it is computed in (sized once per analysis).
/// Below this many elements the element loops run on the calling thread: handing a few
/// evaluations of 10-20 µs to rayon's pool costs more in wake-ups than it saves. Measured on
/// 2 cores (`cargo bench -p mbs --bench step`): slider-crank step 273 µs in parallel against
/// 54 µs serial; chains break even near 32 superelements, and at 512 the parallel loop is
/// 1.6x faster.
const PARALLEL_ELEMENTS: usize = 32;

#[derive(Clone)]
pub(crate) struct ElementBuffer {
    pub out: ElementOutput,
    pub flex: Option<FlexBuffer>,
    pub user: Option<UserBuffer>,
    /// $\hat{\mathbf M}_e$, $\hat{\mathbf C}_e$, $\hat{\mathbf K}_e$ on the element's unknowns (column major).
    pub local: [Vec<f64>; 3],
    /// The element matrices times one unknown's port column, all element rows
    /// (`System::local_matrices`).
    pub y: [Vec<f64>; 3],
    /// The ports' unknown columns of $\mathbf J$ (`System::local_matrices`).
    pub ports: Vec<(usize, usize, [f64; 6])>,
}

/// A model ready for analysis.
#[derive(Clone, Debug)]
pub struct System {
    pub(crate) model: Model,
    pub(crate) topo: Topology,
    pub(crate) flexible: Vec<FlexibleElement>,
    pub(crate) rigid: Vec<RigidElement>,
    pub(crate) springs: Vec<SpringElement>,
    pub(crate) loads: Vec<LoadElement>,
    /// (scalar, stiffness, damping, rest, preload).
    pub(crate) joint_springs: Vec<JointSpringScalar>,
    /// Limits and actuators on joint coordinates.
    pub(crate) joint_forces: JointForces,
    /// How each of `model.initial` acts ([`crate::assembly::initial`]).
    pub(crate) initial_plan: Vec<InitialPlan>,
    /// Drivers not zero at $t = 0$ and the nodes assembled with them (`initial::driver_starts`).
    pub(crate) driver_starts: Vec<crate::assembly::initial::DriverStart>,
    /// The consistent start and how it was made (`initial_state.rs`).
    pub(crate) start: Option<(State, crate::assembly::initial::StartReport)>,
    pub(crate) drivers: Vec<CompiledFunction>,
    /// User-defined forces ([`System::with_user_forces`]).
    pub(crate) user_forces: Vec<Arc<dyn UserForce>>,
    /// The force law evaluated in every iteration ([`System::with_force_law`]).
    pub(crate) force_law: Option<BoundLaw>,
    pub(crate) elements: Vec<ElementRef>,
    pub(crate) pattern: Pattern,
    /// Flexible element of each body (or `None`).
    /// Scale of each unknown for the increment test: the model size for lengths, 1 for
    /// angles, body size times the square root of its mass for modal coordinates.
    pub(crate) dof_scale: Vec<f64>,
    /// Dense or sparse factorisation of the iteration matrices.
    pub(crate) linear_solver: LinearSolver,
    /// Per sensor of `model.sensors`: the bounded search of a largest-von-Mises sensor
    /// (`None` for other sensors).
    pub(crate) stress_maxima: Vec<Option<StressMaximum>>,
    /// Whether a sensor reads the reactions (`Reaction`, `DriverEffort`): without one the
    /// evaluations leave `Workspace::reactions` at zero.
    pub(crate) reactions_read: bool,
    /// Per element: whether evaluations compute it. Without a sensor of the reactions a rigid
    /// body, point mass, spring or load on nodes without unknowns (a driven crank) is skipped:
    /// its forces reach the prescribed coordinates only.
    pub(crate) evaluated: Vec<bool>,
}

/// The bounded search of a largest-von-Mises sensor ([`reduction::VonMisesMaximum`]) and its
/// reference state, kept between output times. The reference only makes the search cheap: any
/// reference gives the same maximum, so clones and concurrent runs on one system may share or
/// copy it freely.
#[derive(Debug)]
pub(crate) struct StressMaximum {
    pub search: Arc<reduction::VonMisesMaximum>,
    pub reference: std::sync::Mutex<reduction::VonMisesReference>,
}

impl Clone for StressMaximum {
    fn clone(&self) -> Self {
        let reference = self.reference.lock().unwrap_or_else(|e| e.into_inner()).clone();
        Self {
            search: Arc::clone(&self.search),
            reference: std::sync::Mutex::new(reference),
        }
    }
}

fn finite(v: f64) -> bool {
    v.is_finite()
}

impl System {
    /// Checks the model and builds the coordinates, elements and sparse pattern.
    pub fn new(model: &Model) -> Result<Self, ModelError> {
        Self::with_user_forces(model, Vec::new())
    }

    /// [`Self::new`] with user-defined forces acting on the model's nodes
    /// ([`crate::model::user_force`]); a node id out of range is [`ModelError::UnknownNode`].
    pub fn with_user_forces(model: &Model, user_forces: Vec<Arc<dyn UserForce>>) -> Result<Self, ModelError> {
        Self::build(model, user_forces, None)
    }

    /// [`Self::new`] with a force law evaluated in every Newton iteration, its Jacobians in the
    /// iteration matrix ([`crate::model::force_law`]); ports that name no actuator, load or
    /// joint coordinate of the model, or a follower load, are [`ModelError::InvalidValue`].
    pub fn with_force_law(model: &Model, law: Arc<dyn ForceLaw>) -> Result<Self, ModelError> {
        Self::build(model, Vec::new(), Some(law))
    }

    /// The force law of [`Self::with_force_law`], if there is one.
    pub fn force_law(&self) -> Option<&Arc<dyn ForceLaw>> {
        self.force_law.as_ref().map(|l| &l.law)
    }

    fn build(
        model: &Model,
        user_forces: Vec<Arc<dyn UserForce>>,
        law: Option<Arc<dyn ForceLaw>>,
    ) -> Result<Self, ModelError> {
        topology::check_references(model)?;
        let topo = topology::build(model)?;
        let Bodies {
            flexible,
            rigid,
            size,
            modal_scale,
        } = body_elements(model, &topo)?;
        check_point_masses(model)?;
        let springs = spring_elements(model)?;
        let mut loads = load_elements(model)?;
        let joint_springs = joint_spring_scalars(model, &topo)?;
        let drivers = compile_drivers(model)?;
        check_initial_coordinates(model, &topo)?;
        topology::held_coordinates(model, &topo)?;
        let mut joint_forces = JointForces::new(model, &topo)?;
        let mut force_law = law.map(|l| BoundLaw::new(l, model, &topo)).transpose()?;
        if let Some(law) = &force_law {
            // The law gives these loads' and actuators' whole values.
            for l in law.loads() {
                loads[l].value = Vector3::zeros();
            }
            for a in law.actuators() {
                joint_forces.set_by_law(a);
            }
        }
        let initial_plan = crate::assembly::initial::plan(model, &topo)?;
        let driver_starts = crate::assembly::initial::driver_starts(model, &topo, &drivers)?;

        check_stress_sensors(model, &flexible)?;
        check_reaction_sensors(model, &topo)?;
        let reactions_read = model.sensors.iter().any(|s| {
            // The energy balance reads the drivers' efforts and the user forces' outputs.
            matches!(
                s.kind,
                SensorKind::Reaction { .. } | SensorKind::DriverEffort { .. } | SensorKind::EnergyBalance
            )
        });
        let stress_maxima = stress_maxima(model, &flexible);
        let elements = element_refs(model, &topo.map, &flexible, &rigid, &springs, &loads, &user_forces)?;
        let pattern = Pattern::build(
            model,
            &topo,
            &elements,
            &joint_springs,
            &mut joint_forces,
            force_law.as_mut(),
        )?;
        let evaluated = elements
            .iter()
            .zip(&pattern.elem_dofs)
            .map(|(e, dofs)| {
                let passive = matches!(
                    e.kind,
                    ElementKind::Rigid(_) | ElementKind::PointMass(..) | ElementKind::Spring(_) | ElementKind::Load(_)
                );
                reactions_read || !passive || !dofs.is_empty()
            })
            .collect();
        let dof_scale = dof_scales(&topo, size, &modal_scale);
        let mut system = Self {
            model: model.clone(),
            topo,
            flexible,
            rigid,
            springs,
            loads,
            joint_springs,
            joint_forces,
            initial_plan,
            driver_starts,
            start: None,
            drivers,
            user_forces,
            force_law,
            elements,
            pattern,
            dof_scale,
            linear_solver: LinearSolver::Auto,
            stress_maxima,
            reactions_read,
            evaluated,
        };
        system.start = Some(system.consistent_start()?);
        Ok(system)
    }

    /// The model this system was built from.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// Sets the value $\mathbf f_0$ of load `load` (index in `Model::loads`) in its axes: the
    /// load is $x(t)\,\mathbf f_0$ from now on (a follower's in the node's axes at the start,
    /// as `Model::loads` gives it). For loads that change between time steps.
    pub fn set_load_value(&mut self, load: usize, value: Vector3<f64>) -> Result<(), ModelError> {
        if !value.iter().all(|x| x.is_finite()) {
            return Err(ModelError::InvalidValue {
                entity: format!("load {load}"),
                what: "non-finite value".into(),
                id: Some(Entity::Load(load)),
            });
        }
        if self
            .force_law
            .as_ref()
            .is_some_and(|law| law.loads().any(|l| l == load))
        {
            return Err(ModelError::InvalidValue {
                entity: format!("load {load}"),
                what: "its value is set by the force law".into(),
                id: Some(Entity::Load(load)),
            });
        }
        let (Some(l), Some(e)) = (self.model.loads.get_mut(load), self.loads.get_mut(load)) else {
            return Err(ModelError::InvalidValue {
                entity: format!("load {load}"),
                what: format!("there are {} loads", self.model.loads.len()),
                id: None,
            });
        };
        l.value = value;
        e.value = if e.follower {
            self.model.nodes[l.node.index()].orientation.inverse() * value
        } else {
            value
        };
        Ok(())
    }

    /// Sets the force or the moment (`kind`) $\mathbf f_0$ of body load `load` (index in
    /// `Model::body_loads`, a load at a load point inside a flexible body): the load is
    /// $x(t)\,\mathbf f_0$ from now on, in its axes as `Model::body_loads` gives it (a
    /// follower's inertial at the initial configuration, turning with the floating frame).
    /// For loads that change between time steps, as [`Self::set_load_value`].
    pub fn set_body_load_value(&mut self, load: usize, kind: LoadKind, value: Vector3<f64>) -> Result<(), ModelError> {
        let Some(l) = self.model.body_loads.get(load) else {
            return Err(ModelError::InvalidValue {
                entity: format!("body load {load}"),
                what: format!("there are {} loads at load points", self.model.body_loads.len()),
                id: None,
            });
        };
        if !value.iter().all(|x| x.is_finite()) {
            return Err(ModelError::InvalidValue {
                entity: format!("load {load} on body '{}'", self.model.bodies[l.body.index()].name()),
                what: "non-finite value".into(),
                id: Some(Entity::BodyLoad(load)),
            });
        }
        let body = l.body.index();
        // The position of the load among its body's (`body_loads` keeps them in model order).
        let k = self.model.body_loads[..load]
            .iter()
            .filter(|m| m.body.index() == body)
            .count();
        let f = self
            .flexible
            .iter_mut()
            .find(|f| f.body == body)
            .expect("body loads are on flexible bodies (System::new)");
        let (point_load, _) = &mut f.loads[k];
        // The initial body axes, as `body_loads` turns a follower into them.
        let R0 = self.model.nodes[f.nodes[0]].orientation * f.offsets[0];
        let local = if point_load.follower {
            R0.inverse() * value
        } else {
            value
        };
        let l = &mut self.model.body_loads[load];
        match kind {
            LoadKind::Force => {
                l.force = value;
                point_load.force = local;
            }
            LoadKind::Moment => {
                l.moment = value;
                point_load.moment = local;
            }
        }
        Ok(())
    }

    /// Holds actuator `actuator` (index in `Model::actuators`) at the effort `effort` [N on a
    /// length, N m on an angle] in place of its time function or PID law from the next step
    /// on, or releases it to its law with `None` ([`crate::assembly::joint_forces`], held effort). For
    /// controllers that close the loop outside the model, between time steps.
    pub fn set_actuator_effort(&mut self, actuator: usize, effort: Option<f64>) -> Result<(), ModelError> {
        let entity = || match self.model.actuators.get(actuator) {
            Some(a) => format!("actuator '{}'", a.name),
            None => format!("actuator {actuator}"),
        };
        self.joint_forces
            .hold(actuator, effort)
            .map_err(|what| ModelError::InvalidValue {
                entity: entity(),
                what,
                id: Some(Entity::Actuator(actuator)),
            })
    }

    /// The effort actuator `actuator` is held at by [`System::set_actuator_effort`] (`None`:
    /// its law acts, or there is no such actuator).
    pub fn held_actuator_effort(&self, actuator: usize) -> Option<f64> {
        self.joint_forces.held(actuator)
    }

    /// The effort $u$ of every actuator at `state` (N on a length, N m on an angle).
    pub fn actuator_efforts(&self, state: &State) -> Vec<f64> {
        let map = &self.topo.map;
        let (s, pr, pa) = self.driven(state);
        let x = values(&s, &pr, &pa);
        let value = |sc: usize| value_and_rate(map, &x, sc);
        let mut efforts = self.joint_forces.efforts(&value, s.time, &state.controls);
        if let Some(law) = &self.force_law {
            // The law's efforts (NaN, which the sensors refuse, when it fails).
            let mut motions = vec![Motion::ground(); self.model.nodes.len()];
            map.motions_into(&x, &mut motions);
            let mut buf = law.buffer();
            let ok = law
                .evaluate(&self.topo, (&x, &motions), s.time, false, &mut buf)
                .is_ok();
            for (a, u) in law.efforts(&buf.u) {
                if self.joint_forces.held(a).is_none() {
                    efforts[a] = if ok { u } else { f64::NAN };
                }
            }
        }
        efforts
    }

    /// Number of unknowns $\dim\dot{\mathbf q}$.
    pub fn n_dof(&self) -> usize {
        self.topo.map.n_dof
    }

    /// What each unknown is ("node 'tip' translation x", "joint 'crank' angle", ...).
    pub fn dof_labels(&self) -> &[String] {
        &self.topo.map.dof_labels
    }

    /// Round-off floor of $\|\mathbf F\|$: $10\,\varepsilon\big(\sum_b(\|\mathbf K_{CB,b}\|_\infty R_b)^2 +
    /// \sum_s(k_s R_s)^2\big)^{1/2}$, with $R$ the largest distance of the element's nodes from the
    /// origin plus its size.
    ///
    /// The elastic forces are computed from $\mathbf u_k = \mathbf R_j^T(\mathbf r_k - \mathbf r_j) - \mathbf x_k$,
    /// whose round-off is $\varepsilon R$; times the stiffness this is the smallest residual a
    /// converged state can have. For a stiff slender body under a small load it can exceed a
    /// relative tolerance (the elastica's axial stiffness is $10^5$ times its bending stiffness),
    /// so Newton's test is $\|\mathbf F\| \le \mathrm{tol}\cdot f_{scale} + \mathrm{floor}$. The factor 10
    /// covers the few roundings of the subtraction, the product and the rotations.
    pub fn residual_floor(&self, nodes: &[NodeMotion]) -> f64 {
        let mut sum = 0.0;
        for f in &self.flexible {
            let R = f.nodes.iter().map(|&n| nodes[n].r.norm()).fold(0.0, f64::max) + f.size;
            sum += (f.k_norm * R).powi(2);
        }
        for s in &self.springs {
            let R = nodes[s.a].r.norm() + s.b.map_or(s.ground.norm(), |b| nodes[b].r.norm());
            sum += (s.k * R).powi(2);
        }
        10.0 * f64::EPSILON * sum.sqrt()
    }

    /// Round-off floor of the inertia forces of a time step of size $h$:
    /// $10\,\varepsilon\,\|\hat{\mathbf M}\mathbf v\|/h$, with $\hat{\mathbf M}$ the mass matrix of the
    /// workspace's last evaluation with tangents.
    ///
    /// The accelerations of a step are differences of velocities over the step, so their
    /// round-off is $\varepsilon|\mathbf v|/h$ and that of the inertia forces $\varepsilon\|\hat{\mathbf M}\mathbf v\|/h$:
    /// the generalised momentum over the step, in the units of $\mathbf F$ row by row. A body
    /// coasting force-free (a rotor at constant speed about a principal axis, a drifting mass)
    /// has zero inertia, internal and external forces, so $f_{scale}$ vanishes and only this
    /// floor lets Newton stop at round-off. The factor 10 covers the few roundings of the
    /// update, the rotations and the gyroscopic terms ($\varepsilon|\mathbf J\boldsymbol\omega||\boldsymbol\omega|$,
    /// below the momentum term while $|\boldsymbol\omega| h < 1$).
    pub(crate) fn inertia_floor(&self, ws: &mut Workspace, v: &[f64], h: f64) -> f64 {
        let cp = self.pattern.symbolic.col_ptr();
        let rows = self.pattern.symbolic.row_idx();
        let p = &mut ws.momentum;
        p.clear();
        p.resize(v.len(), 0.0);
        for (c, &vc) in v.iter().enumerate() {
            for k in cp[c]..cp[c + 1] {
                p[rows[k]] += ws.M[k] * vc;
            }
        }
        10.0 * f64::EPSILON * p.iter().map(|x| x * x).sum::<f64>().sqrt() / h
    }

    /// $\max_i |\delta q_i|/s_i$ with the unknowns' scales $s_i$ (model size for lengths, 1 for
    /// angles, body size $\times\sqrt{m}$ for modal coordinates).
    pub fn increment_norm(&self, dq: &[f64]) -> f64 {
        dq.iter()
            .zip(&self.dof_scale)
            .map(|(d, s)| d.abs() / s)
            .fold(0.0, f64::max)
    }

    /// Number of stored entries of the sparse system matrices.
    pub fn nnz(&self) -> usize {
        self.pattern.nnz()
    }

    /// The consistent start at $t = 0$ ([`crate::assembly::initial`]): the initial
    /// configuration with the drivers' and initial values, closed loops assembled, and the
    /// rates solved from the drivers' and initial rates (every flexible body moving rigidly,
    /// without strain rate); accelerations zero (the dynamic solver computes consistent ones),
    /// controllers at rest.
    pub fn initial_state(&self) -> State {
        match &self.start {
            Some((s, _)) => s.clone(),
            None => unreachable!("System::new makes the start"),
        }
    }

    /// How [`Self::initial_state`] was made: the drivers' values and rates at $t = 0$, the
    /// initial conditions, the rates solved and the positions assembled.
    pub fn start_report(&self) -> &crate::assembly::initial::StartReport {
        match &self.start {
            Some((_, r)) => r,
            None => unreachable!("System::new makes the start"),
        }
    }

    /// [`Self::initial_state`] at rest: the same configuration with every unknown's rate
    /// zero (the drivers keep theirs). The explicit choice of a start at rest.
    pub fn initial_state_at_rest(&self) -> State {
        self.at_rest(&self.initial_state(), 0.0)
    }

    /// Restarts every controller's integral at zero at the state's time and configuration
    /// ([`crate::assembly::joint_forces`]).
    pub(crate) fn start_controls(&self, state: &mut State) {
        let (s, pr, pa) = self.driven(state);
        state.controls = self.joint_forces.start_controls(&values(&s, &pr, &pa), s.time);
    }

    /// Moves the controllers' integrals to the end of a converged step at `state`
    /// ([`crate::assembly::joint_forces`]); the integrator calls it for every accepted step.
    pub fn accept_step(&self, state: &mut State) {
        if self.joint_forces.n_actuators() == 0 {
            return;
        }
        let (s, pr, pa) = self.driven(state);
        self.joint_forces
            .accept(&values(&s, &pr, &pa), s.time, &mut state.controls);
    }

    /// Puts every PID actuator of `state` on the branch of its saturation that its linear
    /// law's value there lies on ([`crate::assembly::joint_forces`], saturation); returns
    /// whether a branch changed. The integrator calls it at the predictor and at each converged
    /// iterate, so that a step is solved on one smooth branch and ends on its own.
    pub fn settle_actuator_branches(&self, state: &mut State) -> bool {
        if self.joint_forces.n_actuators() == 0 {
            return false;
        }
        let map = &self.topo.map;
        let (s, pr, pa) = self.driven(state);
        let x = values(&s, &pr, &pa);
        let value = |sc: usize| value_and_rate(map, &x, sc);
        self.joint_forces.settle_branches(&value, s.time, &mut state.controls)
    }

    /// The joint limits on unknown coordinates as stops of a dynamic run, with the inertias of
    /// `ws` (evaluated with tangents): name, joint, stiffness, inertia ([`Stop`]).
    pub(crate) fn stops(&self, ws: &Workspace) -> Vec<Stop> {
        self.joint_forces
            .stops(&ws.M)
            .into_iter()
            .map(|(index, stiffness, inertia)| {
                let l = &self.model.joint_limits[index];
                Stop {
                    index,
                    name: l.name.clone(),
                    joint: self
                        .model
                        .joints
                        .get(l.joint.index())
                        .map_or_else(String::new, |j| j.name.clone()),
                    stiffness,
                    inertia,
                }
            })
            .collect()
    }

    /// Whether joint limit `index` is penetrated at `state`.
    pub(crate) fn limit_penetrated(&self, index: usize, state: &State) -> bool {
        self.joint_forces.penetrated(index, &state.scalars)
    }

    /// Gives the free coordinates of independent node `n` the velocity $(\mathbf v, \boldsymbol\omega)$
    /// (projected on the free directions).
    pub(crate) fn set_root_velocity(&self, state: &mut State, n: usize, v: &Vector3<f64>, w: &Vector3<f64>) {
        let map = &self.topo.map;
        let Some(rc) = &self.topo.roots[n] else { return };
        for (s, e) in &rc.translation {
            if let Slot::Unknown(d) = map.scalars[*s].slot {
                state.velocity[d] = e.dot(v);
            }
        }
        match &rc.rotation {
            RootRotation::Free(r) => {
                let d = map.rotations[*r].dof;
                state.velocity[d..d + 3].copy_from_slice(w.as_slice());
            }
            RootRotation::Axes(axes) => {
                for (s, e) in axes {
                    if let Slot::Unknown(d) = map.scalars[*s].slot {
                        state.velocity[d] = e.dot(w);
                    }
                }
            }
        }
    }

    /// Moves independent node `node` to `position`, `orientation` (free directions only; the
    /// removed ones keep their values). For initial deformations and tests.
    pub fn set_node_pose(
        &self,
        state: &mut State,
        node: NodeId,
        position: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
    ) {
        let map = &self.topo.map;
        let n = node.index();
        let Some(rc) = &self.topo.roots[n] else { return };
        let nd = &self.model.nodes[n];
        for (s, e) in &rc.translation {
            if let Slot::Unknown(_) = map.scalars[*s].slot {
                state.scalars[*s] = e.dot(&(position - nd.position));
            }
        }
        if let RootRotation::Free(r) = &rc.rotation {
            state.rotations[*r] = orientation * nd.orientation.inverse();
        }
    }

    /// Sets the velocity of independent node `node` (free directions).
    pub fn set_node_velocity(&self, state: &mut State, node: NodeId, v: Vector3<f64>, omega: Vector3<f64>) {
        self.set_root_velocity(state, node.index(), &v, &omega);
    }

    /// Value of scalar coordinate `coordinate` of `joint`.
    pub fn joint_value(&self, state: &State, joint: JointId, coordinate: usize) -> f64 {
        state.scalars[self.topo.joint_scalars[joint.index()][coordinate]]
    }

    /// Sets a free joint coordinate's value and rate.
    pub fn set_joint(&self, state: &mut State, joint: JointId, coordinate: usize, value: f64, rate: f64) {
        let s = self.topo.joint_scalars[joint.index()][coordinate];
        if let Slot::Unknown(d) = self.topo.map.scalars[s].slot {
            state.scalars[s] = value;
            state.velocity[d] = rate;
        }
    }

    /// Rate of a joint coordinate (driven ones from their driver).
    pub fn joint_rate(&self, state: &State, joint: JointId, coordinate: usize) -> f64 {
        let s = self.topo.joint_scalars[joint.index()][coordinate];
        match self.topo.map.scalars[s].slot {
            Slot::Unknown(d) => state.velocity[d],
            Slot::Prescribed(p) => self.topo.map.prescribed[p]
                .0
                .map_or(0.0, |d| self.drivers[d].eval(state.time).1),
        }
    }

    /// Modal coordinates $\boldsymbol\eta$ and their rates $\dot{\boldsymbol\eta}$ of flexible
    /// body `body` (empty for a rigid body or a body without fixed-interface modes).
    pub fn modal_coordinates(&self, state: &State, body: BodyId) -> (Vec<f64>, Vec<f64>) {
        let Some(scalars) = self.topo.modal_scalars.get(body.index()) else {
            return (Vec::new(), Vec::new());
        };
        scalars
            .iter()
            .map(|&s| {
                let rate = match self.topo.map.scalars[s].slot {
                    Slot::Unknown(d) => state.velocity[d],
                    Slot::Prescribed(_) => 0.0,
                };
                (state.scalars[s], rate)
            })
            .unzip()
    }

    /// Re-guesses every flexible body's floating frame from the current node motions (by the
    /// rigid fit of its interfaces); use after moving nodes far by hand.
    pub fn reset_frames(&self, state: &mut State) {
        let motions = self.node_motions(state);
        state.frames = self.flexible.iter().map(|f| rigid_fit(f, &motions)).collect();
    }

    /// $\mathbf q \oplus \delta\mathbf q$: scalars added, rotations $\exp(\widetilde{\delta\boldsymbol\pi})\mathbf R$.
    pub fn retract(&self, state: &State, dq: &[f64]) -> State {
        let mut s = state.clone();
        self.retract_in_place(&mut s, state, dq);
        s
    }

    /// $\mathbf a \ominus \mathbf b$: the $\delta\mathbf q$ with $\mathbf b\oplus\delta\mathbf q = \mathbf a$
    /// (rotations $\log(\mathbf R_a\mathbf R_b^T)$).
    pub fn difference(&self, a: &State, b: &State) -> Vec<f64> {
        let map = &self.topo.map;
        let mut d = vec![0.0; map.n_dof];
        for (i, sc) in map.scalars.iter().enumerate() {
            if let Slot::Unknown(k) = sc.slot {
                d[k] = a.scalars[i] - b.scalars[i];
            }
        }
        for (i, r) in map.rotations.iter().enumerate() {
            let v = so3::log(&(a.rotations[i] * b.rotations[i].inverse()));
            d[r.dof..r.dof + 3].copy_from_slice(v.as_slice());
        }
        d
    }

    /// Rotates the three components of every rotation unknown of `v` from spatial to the body
    /// axes of the orientations `rotations` ($\mathbf R^T\mathbf v$, `to_body`) or back
    /// ($\mathbf R\mathbf v$); scalars are left alone.
    pub(crate) fn rotate_components(&self, rotations: &[UnitQuaternion<f64>], v: &mut [f64], to_body: bool) {
        for (i, r) in self.topo.map.rotations.iter().enumerate() {
            let d = r.dof;
            let x = Vector3::new(v[d], v[d + 1], v[d + 2]);
            let R = &rotations[i];
            let y = if to_body {
                R.inverse_transform_vector(&x)
            } else {
                R.transform_vector(&x)
            };
            v[d..d + 3].copy_from_slice(y.as_slice());
        }
    }

    /// `out` = `base` $\oplus$ `dq` (configuration only).
    pub(crate) fn retract_in_place(&self, out: &mut State, base: &State, dq: &[f64]) {
        let map = &self.topo.map;
        for (i, sc) in map.scalars.iter().enumerate() {
            if let Slot::Unknown(d) = sc.slot {
                out.scalars[i] = base.scalars[i] + dq[d];
            }
        }
        for (i, r) in map.rotations.iter().enumerate() {
            let d = r.dof;
            let mut q = so3::exp(&Vector3::new(dq[d], dq[d + 1], dq[d + 2])) * base.rotations[i];
            q.renormalize_fast();
            out.rotations[i] = q;
        }
    }

    /// Writes driven values into the state and their rates and accelerations into `pr`, `pa`.
    pub(crate) fn apply_drivers(&self, state: &mut State, pr: &mut [f64], pa: &mut [f64]) {
        for (p, &(driver, s)) in self.topo.map.prescribed.iter().enumerate() {
            let (x, xd, xdd) = driver.map_or((0.0, 0.0, 0.0), |d| self.drivers[d].eval(state.time));
            state.scalars[s] = x;
            pr[p] = xd;
            pa[p] = xdd;
        }
    }

    /// `state` with the drivers applied at its time, and the prescribed coordinates' values
    /// and rates there (read together by `coordinates::values`).
    fn driven(&self, state: &State) -> (State, Vec<f64>, Vec<f64>) {
        let np = self.topo.map.n_prescribed();
        let mut s = state.clone();
        let (mut pr, mut pa) = (vec![0.0; np], vec![0.0; np]);
        self.apply_drivers(&mut s, &mut pr, &mut pa);
        (s, pr, pa)
    }

    /// Motions of all nodes at `state` (drivers evaluated at its time).
    pub fn node_motions(&self, state: &State) -> Vec<NodeMotion> {
        let (s, pr, pa) = self.driven(state);
        let mut motions = vec![Motion::ground(); self.model.nodes.len()];
        self.topo.map.motions_into(&values(&s, &pr, &pa), &mut motions);
        motions.iter().map(NodeMotion::from).collect()
    }

    /// Every node's motion and its derivatives at `state`, with the drivers at its time (the
    /// shared first step of [`Self::node_kinematics`] and [`Self::generalized_force`]).
    fn motions_and_derivatives(&self, state: &State) -> (Vec<Motion>, Vec<NodeDerivatives>) {
        let map = &self.topo.map;
        let (s, pr, pa) = self.driven(state);
        let x = values(&s, &pr, &pa);
        let nn = self.model.nodes.len();
        let mut motions = vec![Motion::ground(); nn];
        map.motions_into(&x, &mut motions);
        let mut derivs = vec![NodeDerivatives::default(); nn];
        map.derivatives_into(&x, &motions, &mut derivs);
        (motions, derivs)
    }

    /// $\mathbf J_c$, $\partial\mathbf V_c/\partial\mathbf q$, $\partial\mathbf A_c/\partial\mathbf q$, $\partial\mathbf A_c/\partial\dot{\mathbf q}$
    /// of every node at `state` (drivers at its time). With zero accelerations,
    /// `motion.a`, `motion.alpha` are the convective term $\dot{\mathbf J}_c\dot{\mathbf q}$ (plus the
    /// drivers' accelerations).
    pub fn node_kinematics(&self, state: &State) -> Vec<NodeKinematics> {
        let map = &self.topo.map;
        let nn = self.model.nodes.len();
        let (motions, derivs) = self.motions_and_derivatives(state);
        (0..nn)
            .map(|c| {
                let d = &derivs[c];
                let u = d.unknown.len();
                let m = &motions[c];
                NodeKinematics {
                    motion: NodeMotion::from(m),
                    dofs: d.unknown.iter().map(|&k| map.chains[c].cols[k]).collect(),
                    J: Mat::from_fn(6, u, |i, j| m.col(d.unknown[j])[i]),
                    DV: Mat::from_fn(6, u, |i, j| d.DV[j][i]),
                    DA: Mat::from_fn(6, u, |i, j| d.DA[j][i]),
                    DAd: Mat::from_fn(6, u, |i, j| d.DAd[j][i]),
                }
            })
            .collect()
    }

    /// $\sum_c\mathbf J_c^T\mathbf f_c$ for given node forces, and the geometric term
    /// $\partial(\sum_c\mathbf J_c^T\mathbf f_c)/\partial\mathbf q$ at fixed $\mathbf f_c$ (dense; for tests).
    pub fn generalized_force(&self, state: &State, node_forces: &[[f64; 6]]) -> (Vec<f64>, Mat<f64>) {
        let map = &self.topo.map;
        let nn = self.model.nodes.len();
        let (motions, derivs) = self.motions_and_derivatives(state);
        let n = map.n_dof;
        let mut F = vec![0.0; n];
        let mut G = Mat::zeros(n, n);
        for c in 0..nn {
            for (k, &id) in map.chains[c].cols.iter().enumerate() {
                if id < n {
                    let col = motions[c].col(k);
                    F[id] += (0..6).map(|i| col[i] * node_forces[c][i]).sum::<f64>();
                }
            }
            let u: Vec<usize> = derivs[c].unknown.iter().map(|&k| map.chains[c].cols[k]).collect();
            map.geometric_term(c, &derivs[c], &node_forces[c], |i, k, g| G[(u[i], u[k])] += g);
        }
        (F, G)
    }

    pub(crate) fn workspace(&self) -> Workspace {
        let nn = self.model.nodes.len();
        let n = self.n_dof();
        let np = self.topo.map.n_prescribed();
        let nnz = self.pattern.nnz();
        Workspace {
            motions: vec![Motion::ground(); nn],
            motion_cache: self.topo.map.motion_cache(),
            nodes: Vec::with_capacity(nn),
            derivs: vec![NodeDerivatives::default(); nn],
            node_res: vec![[0.0; 6]; nn],
            F: vec![0.0; self.n_dof()],
            reactions: vec![0.0; np],
            M: vec![0.0; nnz],
            C: vec![0.0; nnz],
            K: vec![0.0; nnz],
            presc_rate: vec![0.0; np],
            presc_acc: vec![0.0; np],
            scale: 0.0,
            floor: 0.0,
            S: vec![0.0; nnz],
            elems: self
                .elements
                .iter()
                .enumerate()
                .map(|(ei, e)| {
                    let rows = 6 * e.nodes.len() + e.modal.len();
                    let s = self.pattern.elem_dofs[ei].len();
                    ElementBuffer {
                        out: ElementOutput::zeros(rows, true),
                        flex: match e.kind {
                            ElementKind::Flexible(i) => Some(self.flexible[i].buffer()),
                            _ => None,
                        },
                        user: match e.kind {
                            ElementKind::User(_) => Some(UserBuffer::new(e.nodes.len())),
                            _ => None,
                        },
                        local: [vec![0.0; s * s], vec![0.0; s * s], vec![0.0; s * s]],
                        y: [vec![0.0; rows], vec![0.0; rows], vec![0.0; rows]],
                        ports: Vec::with_capacity(
                            e.nodes
                                .iter()
                                .map(|&a| self.topo.map.chains[a].cols.iter().filter(|&&c| c < n).count())
                                .sum(),
                        ),
                    }
                })
                .collect(),
            parts: vec![[[0.0; 6]; 3]; nn],
            gparts: [
                vec![0.0; self.n_dof()],
                vec![0.0; self.n_dof()],
                vec![0.0; self.n_dof()],
            ],
            factor: self.empty_factor(),
            momentum: Vec::with_capacity(self.n_dof()),
            law: self.force_law.as_ref().map(BoundLaw::buffer),
        }
    }

    /// An empty factorisation of the kind [`Self::linear_solver`] picks for this system.
    fn empty_factor(&self) -> Factor {
        let n = self.n_dof();
        if n == 0 {
            return Factor::None;
        }
        let dense = match self.linear_solver {
            LinearSolver::Auto => n <= DENSE_MAX,
            LinearSolver::Dense => true,
            LinearSolver::Sparse => false,
        };
        if dense && n <= SMALL_LU_MAX {
            Factor::Small {
                LU: vec![0.0; n * n],
                piv: vec![0; n],
                factored: false,
            }
        } else if dense {
            // Two right-hand sides: Newton's one and the arc-length's bordered pair.
            let rhs_cols = 2;
            Factor::Dense {
                LU: Mat::zeros(n, n),
                perm: vec![0; n],
                perm_inv: vec![0; n],
                mem: MemBuffer::new(dense_scratch(n, rhs_cols)),
                rhs_cols,
                factored: false,
            }
        } else {
            Factor::Sparse {
                A: SparseColMat::new(self.pattern.symbolic.clone(), vec![0.0; self.pattern.nnz()]),
                lu: None,
            }
        }
    }

    /// Chooses the factorisation of the iteration matrices (default [`LinearSolver::Auto`]);
    /// applies to the analyses started after the call.
    pub fn set_linear_solver(&mut self, choice: LinearSolver) {
        self.linear_solver = choice;
    }

    /// The factorisation in use ([`Self::set_linear_solver`]).
    pub fn linear_solver(&self) -> LinearSolver {
        self.linear_solver
    }

    /// Evaluates $\mathbf F$, the reactions and (with `tangents`) $\hat{\mathbf M}$, $\hat{\mathbf C}$,
    /// $\hat{\mathbf K}$ at `state`, loads and gravity scaled by `lambda`; updates the state's
    /// floating frames (warm starts) and its driven coordinates.
    pub(crate) fn evaluate_into(
        &self,
        state: &mut State,
        lambda: f64,
        tangents: bool,
        ws: &mut Workspace,
    ) -> Result<(), SolveError> {
        self.update_motions(state, ws);
        self.element_outputs(state, lambda, tangents, ws)?;
        if let (Some(law), Some(buf)) = (&self.force_law, ws.law.as_mut()) {
            let x = values(state, &ws.presc_rate, &ws.presc_acc);
            law.evaluate(&self.topo, (&x, &ws.motions), state.time, tangents, buf)?;
        }
        self.assemble_residual(state, lambda, ws);
        if tangents {
            self.assemble_tangents(state, lambda, ws);
        }
        self.store_frames(ws, state);
        Ok(())
    }

    /// Every element that is evaluated at `state` (loads and gravity scaled by `lambda`) into
    /// its buffer in `ws`, in parallel on large models.
    fn element_outputs(
        &self,
        state: &State,
        lambda: f64,
        tangents: bool,
        ws: &mut Workspace,
    ) -> Result<(), SolveError> {
        let gravity = self.model.gravity * lambda;
        let nodes = &ws.nodes;
        let eval = |((e, b), &evaluated): ((&ElementRef, &mut ElementBuffer), &bool)| {
            if !evaluated {
                return Ok(());
            }
            self.element_output(e, state, nodes, &gravity, lambda, tangents, b)
        };
        if self.elements.len() >= PARALLEL_ELEMENTS {
            self.elements
                .par_iter()
                .zip(ws.elems.par_iter_mut())
                .zip(self.evaluated.par_iter())
                .try_for_each(eval)?;
        } else {
            self.elements
                .iter()
                .zip(ws.elems.iter_mut())
                .zip(&self.evaluated)
                .try_for_each(eval)?;
        }
        Ok(())
    }

    /// $\mathbf F$, its inertia, internal and external parts, the reactions, the residual's
    /// scale and floor from the element outputs, the joint springs and the joint forces.
    fn assemble_residual(&self, state: &State, lambda: f64, ws: &mut Workspace) {
        let map = &self.topo.map;
        let n = map.n_dof;
        let x = values(state, &ws.presc_rate, &ws.presc_acc);
        // Node residuals and their parts.
        let nn = self.model.nodes.len();
        let parts = &mut ws.parts;
        parts.iter_mut().for_each(|p| *p = [[0.0; 6]; 3]);
        for r in ws.node_res.iter_mut() {
            *r = [0.0; 6];
        }
        ws.F.iter_mut().for_each(|f| *f = 0.0);
        ws.reactions.iter_mut().for_each(|f| *f = 0.0);
        let gparts = &mut ws.gparts;
        gparts.iter_mut().for_each(|g| g.iter_mut().for_each(|x| *x = 0.0));
        // Rows `6 ia..6 ia + 6` of `v` added to `acc`.
        let add_port = |acc: &mut [f64; 6], v: &[f64], ia: usize| {
            let v: &[f64; 6] = v[6 * ia..6 * ia + 6].try_into().expect("six rows per port");
            for i in 0..6 {
                acc[i] += v[i];
            }
        };
        for ((e, b), _) in self
            .elements
            .iter()
            .zip(&ws.elems)
            .zip(&self.evaluated)
            .filter(|(_, &evaluated)| evaluated)
        {
            let o = &b.out;
            for (ia, &a) in e.nodes.iter().enumerate() {
                add_port(&mut ws.node_res[a], &o.residual, ia);
                let pa = &mut parts[a];
                add_port(&mut pa[0], &o.inertia, ia);
                add_port(&mut pa[1], &o.internal, ia);
                add_port(&mut pa[2], &o.external, ia);
            }
            let base = 6 * e.nodes.len();
            for (i, &d) in e.modal.iter().enumerate() {
                ws.F[d] += o.residual[base + i];
                gparts[0][d] += o.inertia[base + i];
                gparts[1][d] += o.internal[base + i];
                gparts[2][d] += o.external[base + i];
            }
        }
        // The force law's loads, as external forces on their nodes; its efforts on their rows.
        let mut law_scale = 0.0;
        if let (Some(law), Some(buf)) = (&self.force_law, &ws.law) {
            let node_res = &mut ws.node_res;
            law_scale = law.add_forces(
                &buf.u,
                (state.time, lambda),
                |a| self.joint_forces.held(a).is_some(),
                &mut ws.F,
                |node, i, f| {
                    node_res[node][i] -= f;
                    parts[node][2][i] += f;
                },
            );
        }
        let dot = |col: &[f64; 6], r: &[f64; 6]| (0..6).map(|i| col[i] * r[i]).sum::<f64>();
        for c in 0..nn {
            let m = &ws.motions[c];
            let (res, pc) = (&ws.node_res[c], &parts[c]);
            for &(k, id) in &self.pattern.node_unknown_cols[c] {
                let col = m.col(k);
                ws.F[id] += dot(&col, res);
                for p in 0..3 {
                    gparts[p][id] += dot(&col, &pc[p]);
                }
            }
            if self.reactions_read {
                for (k, &id) in map.chains[c].cols.iter().enumerate().filter(|(_, &id)| id >= n) {
                    ws.reactions[id - n] += dot(&m.col(k), res);
                }
            }
        }
        for &(s, k, c, rest, preload) in &self.joint_springs {
            let (xv, xd, _) = scalar_values(map, &x, s);
            let f = preload + k * (xv - rest) + c * xd;
            match map.scalars[s].slot {
                Slot::Unknown(d) => {
                    ws.F[d] += f;
                    gparts[1][d] += f;
                }
                Slot::Prescribed(p) => ws.reactions[p] += f,
            }
        }
        let joint_force_scale = self.joint_forces.add_forces(
            &self.topo,
            &x,
            state.time,
            &state.controls,
            &mut ws.F,
            &mut ws.reactions,
        );
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        ws.scale = norm(&gparts[0]) + norm(&gparts[1]) + norm(&gparts[2]) + joint_force_scale + law_scale.sqrt();
        ws.floor = self.residual_floor(&ws.nodes);
    }

    /// $\hat{\mathbf M}$, $\hat{\mathbf C}$, $\hat{\mathbf K}$ from the elements' port matrices, the
    /// geometric terms of the node residuals, the joint springs and the joint forces.
    fn assemble_tangents(&self, state: &State, lambda: f64, ws: &mut Workspace) {
        let map = &self.topo.map;
        let nn = self.model.nodes.len();
        let x = values(state, &ws.presc_rate, &ws.presc_acc);
        map.derivatives_into(&x, &ws.motions, &mut ws.derivs);
        for v in [&mut ws.M, &mut ws.C, &mut ws.K] {
            v.iter_mut().for_each(|x| *x = 0.0);
        }
        let (motions, derivs) = (&ws.motions, &ws.derivs);
        let local = |(ei, b): (usize, &mut ElementBuffer)| {
            self.local_matrices(
                ei,
                &self.elements[ei],
                &b.out,
                motions,
                derivs,
                &mut b.local,
                &mut b.y,
                &mut b.ports,
            )
        };
        if self.elements.len() >= PARALLEL_ELEMENTS {
            ws.elems.par_iter_mut().enumerate().for_each(local);
        } else {
            ws.elems.iter_mut().enumerate().for_each(local);
        }
        for (ei, b) in ws.elems.iter().enumerate() {
            let [lm, lc, lk] = &b.local;
            for (&slot, ((m, c), k)) in self.pattern.elem_slots[ei].iter().zip(lm.iter().zip(lc).zip(lk)) {
                ws.M[slot] += m;
                ws.C[slot] += c;
                ws.K[slot] += k;
            }
        }
        for c in 0..nn {
            let slots = &self.pattern.node_slots[c];
            if slots.is_empty() {
                continue;
            }
            let u = ws.derivs[c].unknown.len();
            let Kv = &mut ws.K;
            map.geometric_term(c, &ws.derivs[c], &ws.node_res[c], |i, k, g| Kv[slots[k * u + i]] += g);
        }
        for (&(_, k, c, ..), slot) in self.joint_springs.iter().zip(&self.pattern.joint_spring_slots) {
            if let Some(slot) = slot {
                ws.K[*slot] += k;
                ws.C[*slot] += c;
            }
        }
        self.joint_forces
            .add_tangents(&self.topo, &x, state.time, &state.controls, &mut ws.K, &mut ws.C);
        if let (Some(law), Some(buf)) = (&self.force_law, ws.law.as_mut()) {
            law.add_tangents(
                buf,
                (state.time, lambda),
                |a| self.joint_forces.held(a).is_some(),
                &self.pattern.node_unknown_cols,
                (&ws.motions, &ws.derivs),
                &mut ws.K,
                &mut ws.C,
            );
        }
    }

    /// The drivers at the state's time into the state and the workspace, and the node motions
    /// (`ws.motions`, `ws.nodes`) at the state: the nodes driven by time alone are kept while
    /// the time stays ([`crate::assembly::coordinates::CoordinateMap::motions_update`]).
    pub(crate) fn update_motions(&self, state: &mut State, ws: &mut Workspace) {
        self.apply_drivers(state, &mut ws.presc_rate, &mut ws.presc_acc);
        let x = values(state, &ws.presc_rate, &ws.presc_acc);
        self.topo
            .map
            .motions_update(&x, state.time, &mut ws.motions, &mut ws.motion_cache);
        if ws.nodes.len() != ws.motions.len() {
            ws.nodes.clear();
            ws.nodes.extend(ws.motions.iter().map(NodeMotion::from));
            return;
        }
        for ((n, m), &changed) in ws.nodes.iter_mut().zip(&ws.motions).zip(&ws.motion_cache.changed) {
            if changed {
                *n = NodeMotion::from(m);
            }
        }
    }

    /// The flexible elements' new floating frames into the state (the next warm starts).
    fn store_frames(&self, ws: &Workspace, state: &mut State) {
        for (e, b) in self.elements.iter().zip(&ws.elems) {
            if let (ElementKind::Flexible(i), Some(f)) = (&e.kind, b.out.frame) {
                state.frames[*i] = f;
            }
        }
    }

    /// `source`, the failure of flexible body `body` (index in the model) at time `t`, under the
    /// body's name.
    pub(crate) fn body_error(&self, body: usize, t: f64, source: superelement::SuperelementError) -> SolveError {
        SolveError::Body {
            body: self.model.bodies[body].name().to_string(),
            id: crate::model::BodyId(body as u32),
            at: crate::error::At::Time(t),
            step: None,
            source: Box::new(source),
        }
    }

    /// One element's output at the node motions, into `buf.out` (flexible bodies evaluate in
    /// their reused superelement workspace).
    #[allow(clippy::too_many_arguments)]
    fn element_output(
        &self,
        e: &ElementRef,
        state: &State,
        nodes: &[NodeMotion],
        gravity: &Vector3<f64>,
        lambda: f64,
        tangents: bool,
        buf: &mut ElementBuffer,
    ) -> Result<(), SolveError> {
        let map = &self.topo.map;
        let out = &mut buf.out;
        match &e.kind {
            ElementKind::Flexible(i) => {
                let f = &self.flexible[*i];
                let modal = |k: usize| {
                    let s = f.modal[k];
                    let d = unknown(map.scalars[s].slot);
                    (state.scalars[s], state.velocity[d], state.acceleration[d])
                };
                let flex = buf.flex.as_mut().expect("flexible element buffer");
                f.element_into(
                    nodes,
                    modal,
                    state.frames[*i],
                    gravity,
                    (state.time, lambda),
                    tangents,
                    flex,
                    out,
                )
                .map_err(|source| self.body_error(f.body, state.time, source))?;
            }
            ElementKind::Rigid(i) => {
                rigid_element(&self.rigid[*i], &nodes[self.rigid[*i].node], gravity, tangents, out);
            }
            ElementKind::PointMass(node, m) => point_mass_element(*m, &nodes[*node], gravity, tangents, out),
            ElementKind::Spring(i) => {
                let s = &self.springs[*i];
                spring_element(s, &nodes[s.a], s.b.map(|b| &nodes[b]), tangents, out);
            }
            ElementKind::Load(i) => {
                let l = &self.loads[*i];
                load_element(l, &nodes[l.node], state.time, lambda, tangents, out);
            }
            ElementKind::User(i) => {
                let buffer = buf.user.as_mut().expect("user force buffer");
                let force = self.user_forces[*i].as_ref();
                user_force_element(force, *i, &e.nodes, nodes, state.time, lambda, tangents, buffer, out)?;
            }
        }
        Ok(())
    }

    /// The element's $\hat{\mathbf M}_e$, $\hat{\mathbf C}_e$, $\hat{\mathbf K}_e$ on its unknown dofs
    /// (column major), from its port tangents and the node kinematics (module docs of
    /// [`crate::assembly::coordinates`]): $\mathbf J^T\mathbf M\mathbf J$, $\mathbf J^T(\mathbf C\mathbf J + \mathbf M\,\partial\mathbf A/\partial\dot{\mathbf q})$,
    /// $\mathbf J^T(\mathbf K\mathbf J + \mathbf C\,\partial\mathbf V/\partial\mathbf q + \mathbf M\,\partial\mathbf A/\partial\mathbf q)$.
    ///
    /// Column by column of $\mathbf J$: the element matrices times one unknown's port column
    /// are formed over all element rows at once (`y`, axpys on the contiguous columns of
    /// $\mathbf M$, $\mathbf C$, $\mathbf K$, skipping the zero entries of the column, half of them in a
    /// planar mechanism), then projected on the row ports by $\mathbf J^T$ and read off on the
    /// modal rows.
    #[allow(clippy::too_many_arguments)]
    fn local_matrices(
        &self,
        ei: usize,
        e: &ElementRef,
        o: &ElementOutput,
        motions: &[Motion],
        derivs: &[NodeDerivatives],
        local: &mut [Vec<f64>; 3],
        y: &mut [Vec<f64>; 3],
        ports: &mut Vec<(usize, usize, [f64; 6])>,
    ) {
        let s = self.pattern.elem_dofs[ei].len();
        let [Ml, Cl, Kl] = local;
        for v in [&mut *Ml, &mut *Cl, &mut *Kl] {
            v.iter_mut().for_each(|x| *x = 0.0);
        }
        let pos = &self.pattern.elem_pos[ei];
        let mpos = &self.pattern.elem_modal_pos[ei];
        let N = e.nodes.len();
        let (M, C, K) = (&o.M, &o.C, &o.K);
        let ne = M.nrows();
        let [yM, yC, yK] = y;
        for v in [&mut *yM, &mut *yC, &mut *yK] {
            v.resize(ne, 0.0);
        }
        let dot6 = |a: &[f64; 6], b: &[f64]| {
            let b: &[f64; 6] = b.try_into().expect("six rows per port");
            (0..6).map(|i| a[i] * b[i]).sum::<f64>()
        };
        // The unknown columns of the ports, port by port: (local position, first row of the
        // port, J column), gathered once for all the columns below (a reused buffer).
        ports.clear();
        for (ia, &a) in e.nodes.iter().enumerate() {
            let d = &derivs[a];
            ports.extend(
                d.unknown
                    .iter()
                    .zip(&pos[ia])
                    .map(|(&k, &qa)| (qa, 6 * ia, motions[a].col(k))),
            );
        }
        let ports = &ports[..];
        // One column (local column `q`) of the element's M, C, K, given in element
        // coordinates, into the local matrices: J^T of each port's rows, the modal rows as they
        // are.
        let add_column = |[Ml, Cl, Kl]: [&mut [f64]; 3], q: usize, [m, c, k]: [&[f64]; 3]| {
            for &(qa, r, Ja) in ports {
                let at = q * s + qa;
                Ml[at] += dot6(&Ja, &m[r..r + 6]);
                Cl[at] += dot6(&Ja, &c[r..r + 6]);
                Kl[at] += dot6(&Ja, &k[r..r + 6]);
            }
            for (i, &qi) in mpos.iter().enumerate() {
                let at = q * s + qi;
                Ml[at] += m[6 * N + i];
                Cl[at] += c[6 * N + i];
                Kl[at] += k[6 * N + i];
            }
        };
        // Columns: node ports.
        for ib in 0..N {
            let b = e.nodes[ib];
            let d = &derivs[b];
            for (u, &k) in d.unknown.iter().enumerate() {
                let qb = pos[ib][u];
                let Jb = motions[b].col(k);
                let (DV, DA, DAd) = (&d.DV[u], &d.DA[u], &d.DAd[u]);
                for v in [&mut *yM, &mut *yC, &mut *yK] {
                    v.fill(0.0);
                }
                for j in 0..6 {
                    let (jb, dv, da, dad) = (Jb[j], DV[j], DA[j], DAd[j]);
                    if jb == 0.0 && dv == 0.0 && da == 0.0 && dad == 0.0 {
                        continue;
                    }
                    let c = 6 * ib + j;
                    let (mc, cc, kc) = (
                        &M.col_as_slice(c)[..ne],
                        &C.col_as_slice(c)[..ne],
                        &K.col_as_slice(c)[..ne],
                    );
                    let (yM, yC, yK) = (&mut yM[..ne], &mut yC[..ne], &mut yK[..ne]);
                    for i in 0..ne {
                        yM[i] += mc[i] * jb;
                        yC[i] += cc[i] * jb + mc[i] * dad;
                        yK[i] += kc[i] * jb + cc[i] * dv + mc[i] * da;
                    }
                }
                add_column([&mut *Ml, &mut *Cl, &mut *Kl], qb, [&yM[..], &yC[..], &yK[..]]);
            }
        }
        // Columns: modal coordinates.
        for (j, &qj) in mpos.iter().enumerate() {
            let c = 6 * N + j;
            let (mc, cc, kc) = (M.col_as_slice(c), C.col_as_slice(c), K.col_as_slice(c));
            add_column([&mut *Ml, &mut *Cl, &mut *Kl], qj, [mc, cc, kc]);
        }
    }

    /// $\mathbf F$ at `state` with loads scaled by `lambda` (updates the frames' warm starts).
    pub fn residual(&self, state: &mut State, lambda: f64) -> Result<Vec<f64>, SolveError> {
        let mut ws = self.workspace();
        self.evaluate_into(state, lambda, false, &mut ws)?;
        Ok(ws.F)
    }

    /// $\mathbf F$, $\hat{\mathbf M}$, $\hat{\mathbf C}$, $\hat{\mathbf K}$ (dense) at `state`.
    pub fn matrices(&self, state: &mut State, lambda: f64) -> Result<Matrices, SolveError> {
        let mut ws = self.workspace();
        self.evaluate_into(state, lambda, true, &mut ws)?;
        let n = self.n_dof();
        Ok(Matrices {
            F: ws.F.clone(),
            M: self.dense(&ws.M, n),
            C: self.dense(&ws.C, n),
            K: self.dense(&ws.K, n),
        })
    }

    pub(crate) fn dense(&self, values: &[f64], n: usize) -> Mat<f64> {
        let mut A = Mat::zeros(n, n);
        let cp = self.pattern.symbolic.col_ptr();
        let ri = self.pattern.symbolic.row_idx();
        for c in 0..n {
            for p in cp[c]..cp[c + 1] {
                A[(ri[p], c)] += values[p];
            }
        }
        A
    }

    /// Solves $\mathbf S\mathbf X = \mathbf B$ in place for the values `ws.S` on the system pattern;
    /// `b` holds the right-hand sides column after column (`b.len()` a multiple of `n_dof`):
    /// [`Self::factor`] then [`Self::solve_factored`].
    pub(crate) fn solve(&self, ws: &mut Workspace, b: &mut [f64]) -> Result<(), String> {
        self.factor(ws)?;
        self.solve_factored(ws, b)
    }

    /// Factorises `ws.S` into `ws.factor` (dense or sparse, [`LinearSolver`]); the factor stays
    /// for later solves (modified Newton reuses it across iterations and steps). The dense
    /// path allocates nothing; the sparse one allocates in faer's numeric LU.
    pub(crate) fn factor(&self, ws: &mut Workspace) -> Result<(), String> {
        let n = self.n_dof();
        match &mut ws.factor {
            Factor::None => Ok(()),
            Factor::Sparse { A, lu } => {
                *lu = None;
                A.val_mut().copy_from_slice(&ws.S);
                let f = Lu::try_new_with_symbolic(self.pattern.lu.clone().expect("symbolic LU for n > 0"), A.as_ref())
                    .map_err(|e| format!("{e:?}"))?;
                *lu = Some(Box::new(f));
                Ok(())
            }
            Factor::Small { LU, piv, factored } => {
                *factored = false;
                LU.fill(0.0);
                let cp = self.pattern.symbolic.col_ptr();
                let ri = self.pattern.symbolic.row_idx();
                for c in 0..n {
                    for p in cp[c]..cp[c + 1] {
                        LU[c * n + ri[p]] = ws.S[p];
                    }
                }
                dense_lu::factor(LU, n, piv)
                    .map_err(|i| format!("zero pivot at unknown {i} ({})", self.dof_labels()[i]))?;
                *factored = true;
                Ok(())
            }
            Factor::Dense {
                LU,
                perm,
                perm_inv,
                mem,
                factored,
                ..
            } => {
                *factored = false;
                LU.fill(0.0);
                let cp = self.pattern.symbolic.col_ptr();
                let ri = self.pattern.symbolic.row_idx();
                for c in 0..n {
                    for p in cp[c]..cp[c + 1] {
                        LU[(ri[p], c)] = ws.S[p];
                    }
                }
                lu_factor::lu_in_place(
                    LU.as_mut(),
                    perm,
                    perm_inv,
                    Par::Seq,
                    MemStack::new(mem),
                    Default::default(),
                );
                // faer's partial-pivoting LU does not stop at a zero pivot: refuse it here (the
                // sparse LU reports the same matrices as singular), naming the unknown.
                if let Some(i) = (0..n).find(|&i| LU[(i, i)] == 0.0 || !LU[(i, i)].is_finite()) {
                    return Err(format!("zero pivot at unknown {i} ({})", self.dof_labels()[i]));
                }
                *factored = true;
                Ok(())
            }
        }
    }

    /// Solves with the factorisation of the last [`Self::factor`], in place.
    pub(crate) fn solve_factored(&self, ws: &mut Workspace, b: &mut [f64]) -> Result<(), String> {
        let n = self.n_dof();
        if n == 0 {
            return Ok(());
        }
        if let Factor::Small { LU, piv, factored } = &ws.factor {
            if !*factored {
                return Err("no factorisation".into());
            }
            dense_lu::solve(LU, n, piv, b);
        } else {
            self.solve_faer(ws, b)?;
        }
        if b.iter().any(|x| !x.is_finite()) {
            return Err("non-finite solution".into());
        }
        Ok(())
    }

    /// [`Self::solve_factored`] with faer's dense or sparse LU.
    fn solve_faer(&self, ws: &mut Workspace, b: &mut [f64]) -> Result<(), String> {
        use faer::linalg::solvers::Solve;
        let n = self.n_dof();
        let k = b.len() / n;
        let rhs = faer::MatMut::from_column_major_slice_mut(b, n, k);
        match &mut ws.factor {
            Factor::None => return Ok(()),
            Factor::Sparse { lu, .. } => lu.as_ref().ok_or("no factorisation")?.solve_in_place(rhs),
            Factor::Small { .. } => unreachable!("solved above"),
            Factor::Dense {
                LU,
                perm,
                perm_inv,
                mem,
                rhs_cols,
                factored,
            } => {
                if !*factored {
                    return Err("no factorisation".into());
                }
                if k > *rhs_cols {
                    *mem = MemBuffer::new(dense_scratch(n, k));
                    *rhs_cols = k;
                }
                let P = faer::perm::PermRef::new_checked(perm, perm_inv, n);
                lu_solve::solve_in_place(LU.as_ref(), LU.as_ref(), P, rhs, Par::Seq, MemStack::new(mem));
            }
        }
        Ok(())
    }

    /// Combines the iteration matrix into `ws.S`: $\beta'\hat{\mathbf M} + \gamma'\hat{\mathbf C} +
    /// \hat{\mathbf K}$, and with `step` = (the spatial increment $\mathbf h$ of each rotation,
    /// the iterate of $t_{n+1}$) the exact derivative of the residual with respect to a spatial
    /// correction $\delta\mathbf h$ of the increment under the body-axis recursion of the
    /// integrator (`dynamic_solver` module docs): on each rotation's columns
    /// $\delta\boldsymbol\pi = \mathbf J_l(\mathbf h)\delta\mathbf h$ moves the rotation, and
    /// $\boldsymbol\omega_s = \mathbf R_{n+1}\boldsymbol\omega_b$, $\dot{\boldsymbol\omega}_s =
    /// \mathbf R_{n+1}\dot{\boldsymbol\omega}_b$ vary by $\gamma'\mathbf E\delta\mathbf h -
    /// \tilde{\boldsymbol\omega}_s\mathbf J_l\delta\mathbf h$ and $\beta'\mathbf E\delta\mathbf h -
    /// \tilde{\dot{\boldsymbol\omega}}_s\mathbf J_l\delta\mathbf h$, $\mathbf E = \exp(\tilde{\mathbf h})$, so the
    /// columns become $\hat{\mathbf K}\mathbf J_l + \hat{\mathbf C}(\gamma'\mathbf E - \tilde{\boldsymbol\omega}_s\mathbf J_l)
    /// \;+\; \hat{\mathbf M}(\beta'\mathbf E - \tilde{\dot{\boldsymbol\omega}}_s\mathbf J_l)$.
    pub(crate) fn iteration_matrix(&self, ws: &mut Workspace, beta: f64, gamma: f64, step: Option<(&[f64], &State)>) {
        for i in 0..ws.S.len() {
            ws.S[i] = beta * ws.M[i] + gamma * ws.C[i] + ws.K[i];
        }
        let Some((h, st)) = step else { return };
        let cp = self.pattern.symbolic.col_ptr();
        for r in &self.topo.map.rotations {
            let d = r.dof;
            let hv = Vector3::new(h[d], h[d + 1], h[d + 2]);
            let T = so3::left_jacobian(&hv);
            let E = so3::exp(&hv).to_rotation_matrix().into_inner();
            let W = so3::skew(&Vector3::new(st.velocity[d], st.velocity[d + 1], st.velocity[d + 2])) * T;
            let A = so3::skew(&Vector3::new(
                st.acceleration[d],
                st.acceleration[d + 1],
                st.acceleration[d + 2],
            )) * T;
            let len = cp[d + 1] - cp[d];
            for t in 0..len {
                let at = |v: &[f64]| [v[cp[d] + t], v[cp[d + 1] + t], v[cp[d + 2] + t]];
                let (k, c, m) = (at(&ws.K), at(&ws.C), at(&ws.M));
                for j in 0..3 {
                    let mut s = 0.0;
                    for i in 0..3 {
                        s += k[i] * T[(i, j)] + (gamma * c[i] + beta * m[i]) * E[(i, j)]
                            - c[i] * W[(i, j)]
                            - m[i] * A[(i, j)];
                    }
                    ws.S[cp[d + j] + t] = s;
                }
            }
        }
    }
}

/// The elements of the bodies and the model's size (spread of the nodes, flexible bodies and
/// centres of mass), with the scale of each body's modal coordinates.
struct Bodies {
    flexible: Vec<FlexibleElement>,
    rigid: Vec<RigidElement>,
    size: f64,
    modal_scale: Vec<f64>,
}

fn invalid(id: Option<Entity>, entity: String, what: String) -> ModelError {
    ModelError::InvalidValue { entity, what, id }
}

/// The flexible and rigid bodies checked (interfaces on their nodes, finite mass data) and
/// turned into elements.
fn body_elements(model: &Model, topo: &Topology) -> Result<Bodies, ModelError> {
    let mut flexible = Vec::new();
    let mut rigid = Vec::new();
    // Model size: spread of the nodes, flexible bodies and centres of mass.
    let centroid = model.nodes.iter().map(|n| n.position).sum::<Vector3<f64>>() / model.nodes.len().max(1) as f64;
    let mut size = model
        .nodes
        .iter()
        .map(|n| (n.position - centroid).norm())
        .fold(1e-3, f64::max);
    let mut modal_scale = vec![1.0; model.bodies.len()];
    for (bi, body) in model.bodies.iter().enumerate() {
        match body {
            Body::Flexible(f) => {
                let N = f.reduced.interfaces.len();
                if f.nodes.len() != N {
                    return Err(invalid(
                        Some(Entity::Body(BodyId(bi as u32))),
                        format!("body '{}'", f.name),
                        format!("{} nodes for {N} interfaces", f.nodes.len()),
                    ));
                }
                let superelement_error = |source| ModelError::Superelement {
                    body: f.name.clone(),
                    body_id: BodyId(bi as u32),
                    source,
                };
                let mut se = Superelement::shared(Arc::clone(&f.reduced), f.frame, f.mass, f.damping.clone())
                    .map_err(superelement_error)?;
                if f.planar {
                    // The model's confinement first: it names the node, whatever the body.
                    crate::assembly::planar::check_planar_body(model, bi, f)?;
                    se = se.into_planar().map_err(superelement_error)?;
                }
                let pos: Vec<Vector3<f64>> = f.reduced.interfaces.iter().map(|i| Vector3::from(i.position)).collect();
                let tolerance = 1e-6 * (1.0 + size_body(&pos));
                let mut offsets = Vec::with_capacity(N);
                for k in 0..N {
                    let node = &model.nodes[f.nodes[k].index()];
                    let x = f.placement.transform_point(&pos[k].into()).coords;
                    let distance = (x - node.position).norm();
                    if !(distance <= tolerance) {
                        return Err(ModelError::InterfaceMismatch {
                            body: f.name.clone(),
                            interface: k,
                            name: f.reduced.interfaces[k].name.clone(),
                            node: node.name.clone(),
                            distance,
                            tolerance,
                            body_id: BodyId(bi as u32),
                            node_id: f.nodes[k],
                        });
                    }
                    offsets.push(node.orientation.inverse() * f.placement.rotation);
                }
                size = size.max(2.0 * size_body(&pos));
                let K = se.k_cb();
                let k_norm = (0..K.nrows())
                    .map(|i| (0..K.ncols()).map(|j| K[(i, j)].abs()).sum::<f64>())
                    .fold(0.0, f64::max);
                modal_scale[bi] = size_body(&pos).max(1e-3) * f.reduced.inertia.mass.sqrt();
                let loads = body_loads(model, bi, &se, model.nodes[f.nodes[0].index()].orientation * offsets[0])?;
                flexible.push(FlexibleElement {
                    body: bi,
                    se,
                    nodes: f.nodes.iter().map(|n| n.index()).collect(),
                    offsets,
                    modal: topo.modal_scalars[bi].clone(),
                    k_norm,
                    size: 2.0 * size_body(&pos),
                    loads,
                });
            }
            Body::Rigid(r) => {
                let ok = r.mass >= 0.0
                    && finite(r.mass)
                    && r.center_of_mass.iter().all(|x| x.is_finite())
                    && r.inertia.iter().all(|x| x.is_finite());
                if !ok {
                    return Err(invalid(
                        Some(Entity::Body(BodyId(bi as u32))),
                        format!("rigid body '{}'", r.name),
                        "mass must be finite and >= 0, centre of mass and inertia finite".into(),
                    ));
                }
                size = size.max(r.center_of_mass.norm());
                rigid.push(RigidElement {
                    node: r.reference.index(),
                    mass: r.mass,
                    c: r.center_of_mass,
                    J: (r.inertia + r.inertia.transpose()) * 0.5,
                });
            }
        }
    }
    Ok(Bodies {
        flexible,
        rigid,
        size,
        modal_scale,
    })
}

/// Every point mass finite and not negative.
fn check_point_masses(model: &Model) -> Result<(), ModelError> {
    for (i, p) in model.point_masses.iter().enumerate() {
        if !(p.mass >= 0.0 && finite(p.mass)) {
            return Err(invalid(
                Some(Entity::PointMass(i)),
                p.label(i),
                format!("mass must be finite and >= 0, got {}", p.mass),
            ));
        }
    }
    Ok(())
}

/// The springs checked (finite, not negative, a direction at the start) as elements.
fn spring_elements(model: &Model) -> Result<Vec<SpringElement>, ModelError> {
    let mut springs = Vec::new();
    for (i, s) in model.springs.iter().enumerate() {
        if !(s.stiffness >= 0.0 && s.damping >= 0.0 && finite(s.stiffness) && finite(s.damping)) {
            return Err(invalid(
                Some(Entity::Spring(i)),
                format!("spring '{}'", s.name),
                "stiffness and damping must be finite and >= 0".into(),
            ));
        }
        let xa = model.nodes[s.a.index()].position;
        let xb = s.b.map_or(s.ground_point, |b| model.nodes[b.index()].position);
        let l = (xb - xa).norm();
        let l0 = s.rest_length.unwrap_or(l);
        // A spring whose ends coincide has no direction: with a rest length its force
        // k (l - l0) would act along the round-off of the end positions.
        if l0 > 0.0 && l <= 1e-9 * l0 {
            return Err(invalid(
                Some(Entity::Spring(i)),
                format!("spring '{}'", s.name),
                format!("its ends coincide (length {l:.3e} m) and its rest length is {l0} m: the direction of its force is undefined; place the ends apart (or give rest_length = 0)"),
            ));
        }
        springs.push(SpringElement {
            a: s.a.index(),
            b: s.b.map(|b| b.index()),
            ground: s.ground_point,
            k: s.stiffness,
            c: s.damping,
            l0,
        });
    }
    Ok(springs)
}

/// The node loads checked (finite) as elements, a follower's value in its node's axes.
fn load_elements(model: &Model) -> Result<Vec<LoadElement>, ModelError> {
    let mut loads = Vec::new();
    for (i, l) in model.loads.iter().enumerate() {
        let time = (l.time.compile(&format!("load {i}"))).map_err(|e| e.with_id(Entity::Load(i)))?;
        if !l.value.iter().all(|x| x.is_finite()) {
            return Err(invalid(
                Some(Entity::Load(i)),
                format!("load {i}"),
                "non-finite value".into(),
            ));
        }
        let node = &model.nodes[l.node.index()];
        let (follower, value) = match l.axes {
            LoadAxes::Dead => (false, l.value),
            LoadAxes::Follower => (true, node.orientation.inverse() * l.value),
        };
        loads.push(LoadElement {
            node: l.node.index(),
            moment: l.kind == LoadKind::Moment,
            follower,
            value,
            time,
        });
    }
    Ok(loads)
}

/// Each joint spring as (scalar, $k$, $c$, $x_0$, $f_0$).
fn joint_spring_scalars(model: &Model, topo: &Topology) -> Result<Vec<JointSpringScalar>, ModelError> {
    let mut joint_springs = Vec::new();
    for (i, js) in model.joint_springs.iter().enumerate() {
        let s = *topo.joint_scalars[js.joint.index()].get(js.coordinate).ok_or_else(|| {
            invalid(
                Some(Entity::JointSpring(i)),
                format!("joint spring {i}"),
                format!("joint coordinate {} does not exist", js.coordinate),
            )
        })?;
        joint_springs.push((s, js.stiffness, js.damping, js.rest, js.preload));
    }
    Ok(joint_springs)
}

/// The drivers' time functions.
fn compile_drivers(model: &Model) -> Result<Vec<CompiledFunction>, ModelError> {
    model
        .drivers
        .iter()
        .enumerate()
        .map(|(i, d)| (d.motion.compile(&format!("driver '{}'", d.name))).map_err(|e| e.with_id(Entity::Driver(i))))
        .collect::<Result<Vec<_>, _>>()
}

/// Every initial joint value or rate is on a free coordinate of its joint.
fn check_initial_coordinates(model: &Model, topo: &Topology) -> Result<(), ModelError> {
    let map = &topo.map;
    for (i, c) in model.initial.iter().enumerate() {
        if let InitialCondition::JointValue { joint, coordinate, .. }
        | InitialCondition::JointRate { joint, coordinate, .. } = c
        {
            let j = &model.joints[joint.index()];
            match topo.joint_scalars[joint.index()].get(*coordinate) {
                Some(&s) if matches!(map.scalars[s].slot, Slot::Unknown(_)) => {}
                // A driven coordinate's rate is a condition of the start, checked against the
                // driver's rate at t = 0.
                Some(&s)
                    if matches!(c, InitialCondition::JointRate { .. })
                        && matches!(map.scalars[s].slot, Slot::Prescribed(p) if map.prescribed[p].0.is_some()) => {}
                _ => {
                    return Err(invalid(
                        Some(Entity::InitialCondition(i)),
                        format!("initial condition on joint '{}'", j.name),
                        format!("coordinate {coordinate} is not a free coordinate of the joint"),
                    ))
                }
            }
        }
    }
    Ok(())
}

/// The search of each maximum-stress sensor (`None` for the other sensors).
fn stress_maxima(model: &Model, flexible: &[FlexibleElement]) -> Vec<Option<StressMaximum>> {
    model
        .sensors
        .iter()
        .map(|s| match &s.kind {
            SensorKind::MaxVonMises { body, nodes } => {
                let f = flexible.iter().find(|f| f.body == body.index())?;
                let shapes = f.se.stress_shapes()?;
                Some(StressMaximum {
                    search: Arc::new(reduction::VonMisesMaximum::new(shapes, nodes)),
                    reference: Default::default(),
                })
            }
            _ => None,
        })
        .collect()
}

/// One [`ElementRef`] per element, in the order of the assembly: flexible and rigid bodies,
/// point masses, springs, loads, user forces.
fn element_refs(
    model: &Model,
    map: &CoordinateMap,
    flexible: &[FlexibleElement],
    rigid: &[RigidElement],
    springs: &[SpringElement],
    loads: &[LoadElement],
    user_forces: &[Arc<dyn UserForce>],
) -> Result<Vec<ElementRef>, ModelError> {
    // Elements and the sparse pattern.
    let mut elements = Vec::new();
    for (i, f) in flexible.iter().enumerate() {
        let modal = f.modal.iter().map(|&s| unknown(map.scalars[s].slot)).collect();
        elements.push(ElementRef {
            kind: ElementKind::Flexible(i),
            nodes: f.nodes.clone(),
            modal,
        });
    }
    for (i, r) in rigid.iter().enumerate() {
        elements.push(ElementRef {
            kind: ElementKind::Rigid(i),
            nodes: vec![r.node],
            modal: vec![],
        });
    }
    for p in &model.point_masses {
        elements.push(ElementRef {
            kind: ElementKind::PointMass(p.node.index(), p.mass),
            nodes: vec![p.node.index()],
            modal: vec![],
        });
    }
    for (i, s) in springs.iter().enumerate() {
        let mut nodes = vec![s.a];
        nodes.extend(s.b);
        elements.push(ElementRef {
            kind: ElementKind::Spring(i),
            nodes,
            modal: vec![],
        });
    }
    for (i, l) in loads.iter().enumerate() {
        elements.push(ElementRef {
            kind: ElementKind::Load(i),
            nodes: vec![l.node],
            modal: vec![],
        });
    }
    for (i, u) in user_forces.iter().enumerate() {
        elements.push(ElementRef {
            kind: ElementKind::User(i),
            nodes: crate::model::user_force::check_nodes(u.as_ref(), i, model.nodes.len())?,
            modal: vec![],
        });
    }
    Ok(elements)
}

/// The scale of each unknown in the norms (`System::dof_scale`): the model size for a length,
/// 1 for an angle, the body's modal scale for a modal coordinate.
fn dof_scales(topo: &Topology, size: f64, modal_scale: &[f64]) -> Vec<f64> {
    topo.dims
        .iter()
        .map(|d| match d {
            topology::Dimension::Length => size,
            topology::Dimension::Angle => 1.0,
            topology::Dimension::Modal(b) => modal_scale[*b],
        })
        .collect()
}

/// Largest distance of the interface positions from their centroid.
fn size_body(pos: &[Vector3<f64>]) -> f64 {
    let c = pos.iter().sum::<Vector3<f64>>() / pos.len().max(1) as f64;
    pos.iter().map(|p| (p - c).norm()).fold(0.0, f64::max)
}

/// A first guess of a flexible body's frame from its nodes: the orientation of interface 0 and
/// the origin that fits the undeformed interface positions best (least squares, rotation fixed).
pub(super) fn rigid_fit(f: &FlexibleElement, motions: &[NodeMotion]) -> Frame {
    let R = motions[f.nodes[0]].R * f.offsets[0];
    let x = f.se.interface_positions();
    let mut r = Vector3::zeros();
    for (k, &n) in f.nodes.iter().enumerate() {
        r += motions[n].r - R * x[k];
    }
    Frame::new(r / f.nodes.len() as f64, R)
}

/// The loads of `model.body_loads` on flexible body `bi` (superelement `se`, initial body axes
/// `R0`): each checked (its load point exists, finite values), a follower turned into body axes.
fn body_loads(
    model: &Model,
    bi: usize,
    se: &Superelement,
    R0: UnitQuaternion<f64>,
) -> Result<Vec<(superelement::PointLoad, CompiledFunction)>, ModelError> {
    let mut out = Vec::new();
    for (i, l) in model
        .body_loads
        .iter()
        .enumerate()
        .filter(|(_, l)| l.body.index() == bi)
    {
        let entity = || format!("load {i} on body '{}'", model.bodies[bi].name());
        let invalid = |what: String| ModelError::InvalidValue {
            entity: entity(),
            what,
            id: Some(Entity::BodyLoad(i)),
        };
        if l.point >= se.load_points().len() {
            return Err(invalid(format!(
                "load point {} does not exist (the reduced body has {})",
                l.point,
                se.load_points().len()
            )));
        }
        if !l.force.iter().chain(l.moment.iter()).all(|x| x.is_finite()) {
            return Err(invalid("non-finite force or moment".into()));
        }
        let follower = l.axes == LoadAxes::Follower;
        let (force, moment) = if follower {
            (R0.inverse() * l.force, R0.inverse() * l.moment)
        } else {
            (l.force, l.moment)
        };
        let load = superelement::PointLoad {
            point: l.point,
            force,
            moment,
            follower,
        };
        let time = l.time.compile(&entity()).map_err(|e| e.with_id(Entity::BodyLoad(i)))?;
        out.push((load, time));
    }
    Ok(out)
}

/// Every reaction sensor is at an independent node that a support or a driver holds in some
/// direction: the reaction is the residual of its removed coordinates, which a node without
/// them does not have (a node that follows a joint or a body has no coordinates of its own; a
/// free node's reaction would be zero by definition, never what was meant).
fn check_reaction_sensors(model: &Model, topo: &Topology) -> Result<(), ModelError> {
    for (i, s) in model.sensors.iter().enumerate() {
        let SensorKind::Reaction { node } = s.kind else {
            continue;
        };
        let held = |sc: &usize| matches!(topo.map.scalars[*sc].slot, Slot::Prescribed(_));
        let why = match &topo.roots[node.index()] {
            None => "it follows a joint or a body (it has no coordinates of its own)",
            Some(rc) => {
                let rotation_held = match &rc.rotation {
                    RootRotation::Free(_) => false,
                    RootRotation::Axes(axes) => axes.iter().any(|(sc, _)| held(sc)),
                };
                if rc.translation.iter().any(|(sc, _)| held(sc)) || rotation_held {
                    continue;
                }
                "no support or driver holds it"
            }
        };
        return Err(ModelError::InvalidValue {
            entity: format!("sensor '{}'", s.name),
            what: format!(
                "node '{}' has no reaction: {why}; a reaction is measured at a supported or driven node",
                model.nodes[node.index()].name
            ),
            id: Some(Entity::Sensor(i)),
        });
    }
    Ok(())
}

/// Every stress sensor is on a flexible body reduced with stress shapes, at nodes it has.
fn check_stress_sensors(model: &Model, flexible: &[FlexibleElement]) -> Result<(), ModelError> {
    for (i, s) in model.sensors.iter().enumerate() {
        let (body, nodes): (BodyId, &[usize]) = match &s.kind {
            SensorKind::Stress { body, node } => (*body, std::slice::from_ref(node)),
            SensorKind::MaxVonMises { body, nodes } => (*body, nodes),
            _ => continue,
        };
        let invalid = |what: String| ModelError::InvalidValue {
            entity: format!("sensor '{}'", s.name),
            what,
            id: Some(Entity::Sensor(i)),
        };
        let name = model.bodies[body.index()].name();
        let Some(f) = flexible.iter().find(|f| f.body == body.index()) else {
            return Err(invalid(format!(
                "body '{name}' is rigid: stresses are measured on flexible bodies"
            )));
        };
        let Some(shapes) = f.se.stress_shapes() else {
            return Err(invalid(format!(
                "body '{name}' was reduced without stress shapes (reduce its part with `stress_shapes = true`)"
            )));
        };
        let count = shapes.node_count();
        if nodes.is_empty() {
            return Err(invalid("no nodes to measure".into()));
        }
        if let Some(k) = nodes.iter().find(|&&k| k >= count) {
            return Err(invalid(format!(
                "node {k} is not a node of body '{name}' ({count} mesh nodes)"
            )));
        }
    }
    Ok(())
}

/// The value and rate of scalar coordinate `sc` (the controllers' input).
fn value_and_rate(map: &CoordinateMap, x: &Values, sc: usize) -> (f64, f64) {
    let (v, d, _) = scalar_values(map, x, sc);
    (v, d)
}

//! Independent coordinates and the explicit map to every node's configuration, velocity and
//! acceleration: the Jacobian $\mathbf J$, the convective term $\dot{\mathbf J}\dot{\mathbf q}$ and
//! the derivatives of both that Newton's tangent needs (theory guide §8).
//!
//! # Coordinates
//!
//! The generalised coordinates $\mathbf q$ live on a Lie group: scalars (translations of
//! independent nodes along their free directions, joint angles and lengths, modal coordinates
//! $\boldsymbol\eta$) and rotations in SO(3) (independent node orientations, spherical joints).
//! Velocities are $\dot{\mathbf q} = [\dots, \dot s, \dots, \boldsymbol\omega, \dots]$ with *spatial*
//! angular velocities, and a rotation is varied and updated as $\mathbf R \leftarrow
//! \exp(\widetilde{\delta\boldsymbol\pi})\mathbf R$, the superelement's convention
//! (`superelement::so3`). Prescribed coordinates (supported directions, always zero, and driven
//! ones, $x(t)$) enter the maps like the others, with known value, rate and acceleration; their
//! columns of $\mathbf J$ give the reactions.
//!
//! # The map: a chain of elementary operations per node
//!
//! Each node is reached from its parent node (or from the ground frame) by a short list of
//! operations `Op` acting on a moving frame $\{\mathbf p, \mathbf R\}$ with velocity
//! $\{\mathbf v, \boldsymbol\omega\}$ and acceleration $\{\mathbf a, \boldsymbol\alpha\}$ (all inertial;
//! $\mathbf v$ is the velocity of the point $\mathbf p$):
//!
//! | op | configuration | velocity | acceleration |
//! |---|---|---|---|
//! | `Translate(â, s)`, $\mathbf n = \mathbf R\hat{\mathbf a}$ | $\mathbf p \mathrel{+}= s\mathbf n$ | $\mathbf v \mathrel{+}= \dot s\mathbf n + s\,\boldsymbol\omega\times\mathbf n$ | $\mathbf a \mathrel{+}= \ddot s\mathbf n + 2\dot s\,\boldsymbol\omega\times\mathbf n + s(\boldsymbol\alpha\times\mathbf n + \boldsymbol\omega\times(\boldsymbol\omega\times\mathbf n))$ |
//! | `Rotate(â, θ)`, $\mathbf n = \mathbf R\hat{\mathbf a}$ | $\mathbf R \leftarrow \exp(\theta\tilde{\mathbf n})\mathbf R$ | $\boldsymbol\omega \mathrel{+}= \dot\theta\mathbf n$ | $\boldsymbol\alpha \mathrel{+}= \ddot\theta\mathbf n + \dot\theta\,\boldsymbol\omega\times\mathbf n$ |
//! | `Offset(d, C)`, $\mathbf b = \mathbf R\mathbf d$ | $\mathbf p \mathrel{+}= \mathbf b$, $\mathbf R \leftarrow \mathbf R\mathbf C$ | $\mathbf v \mathrel{+}= \boldsymbol\omega\times\mathbf b$ | $\mathbf a \mathrel{+}= \boldsymbol\alpha\times\mathbf b + \boldsymbol\omega\times(\boldsymbol\omega\times\mathbf b)$ |
//! | `FreeRotation(k)` | $\mathbf R \leftarrow \mathbf R_k$ | $\boldsymbol\omega \leftarrow \boldsymbol\omega_k$ | $\boldsymbol\alpha \leftarrow \dot{\boldsymbol\omega}_k$ |
//!
//! An independent node is `Offset(r0)`, three `Translate`s along its support basis, its
//! rotation (`FreeRotation`, or three `Rotate`s of which the supported ones are zero), and
//! `Offset(0, R0)`; a joint appends its own operations to the parent node's frame (a revolute
//! joint is one `Rotate`), a rigid body an `Offset`. Every dependent coordinate is thus an
//! explicit function of the independent ones, and velocity and acceleration follow by
//! differentiating each row in time.
//!
//! The columns of $\mathbf J$ (node velocity $\mathbf V_c = [\mathbf v_c; \boldsymbol\omega_c] =
//! \sum_i\mathbf J_{c,i}\dot q_i$) are carried along: `Translate` appends $[\mathbf n; \mathbf 0]$ and
//! adds $s\,\mathbf J^\omega_i\times\mathbf n$ to the earlier columns, `Rotate` appends
//! $[\mathbf 0; \mathbf n]$, `Offset` adds $\mathbf J^\omega_i\times\mathbf b$, `FreeRotation` zeroes the
//! earlier $\mathbf J^\omega_i$ and appends $[\mathbf 0; \mathbf e_k]$. With $\ddot{\mathbf q} = 0$ the
//! acceleration is the convective term $\dot{\mathbf J}\dot{\mathbf q}$.
//!
//! # Derivatives for Newton
//!
//! The equations are $\mathbf F = \mathbf J^T\mathbf r(\mathbf x(\mathbf q), \mathbf V(\mathbf q,
//! \dot{\mathbf q}), \mathbf A(\mathbf q, \dot{\mathbf q}, \ddot{\mathbf q})) = 0$ with node residuals
//! $\mathbf r$ (theory guide §8: $\mathbf J^T(\mathbf M\mathbf J\ddot{\mathbf q} + \mathbf M\dot{\mathbf J}\dot{\mathbf q} +
//! \mathbf Q_v - \mathbf Q)$). Node variations are $\delta\mathbf x_c = \mathbf J_c\delta\mathbf q$, so
//!
//! $$\frac{\partial\mathbf F}{\partial\mathbf q} = \mathbf G_r + \mathbf J^T\Big(\mathbf K_t\mathbf J +
//! \mathbf C_t\frac{\partial\mathbf V}{\partial\mathbf q} + \mathbf M\frac{\partial\mathbf A}{\partial\mathbf q}\Big),
//! \quad \frac{\partial\mathbf F}{\partial\dot{\mathbf q}} = \mathbf J^T\Big(\mathbf C_t\mathbf J +
//! \mathbf M\frac{\partial\mathbf A}{\partial\dot{\mathbf q}}\Big),\quad
//! \frac{\partial\mathbf F}{\partial\ddot{\mathbf q}} = \mathbf J^T\mathbf M\mathbf J,$$
//!
//! with the geometric term of the joints $(\mathbf G_r)_{ik} = \sum_c\mathbf r_c\cdot\partial\mathbf J_{c,i}/\partial q_k$.
//! All derivatives come from one forward-mode pass per node and unknown column $k$: the
//! variation of every row of the table above in the direction $\delta q_k = 1$ (position
//! direction; it carries $\delta\mathbf J$ too) or $\delta\dot q_k = 1$ (rate direction). The
//! variation rules are the product rule on each row with $\delta\mathbf n = \delta\boldsymbol\pi\times\mathbf n$,
//! $\delta\mathbf b = \delta\boldsymbol\pi\times\mathbf b$, and for `Rotate` $\delta\boldsymbol\pi \mathrel{+}= \delta\theta\,\mathbf n$
//! (the axis is invariant under its own rotation, so $\mathbf J_r(\theta\hat{\mathbf a})\hat{\mathbf a} = \hat{\mathbf a}$).
//! Checked against central differences by `tests/unit/kinematics.rs` (maps, $\mathbf J$,
//! $\dot{\mathbf J}\dot{\mathbf q}$, $\partial\mathbf V/\partial\mathbf q$, $\partial\mathbf A/\partial\mathbf q$,
//! $\partial\mathbf A/\partial\dot{\mathbf q}$, $\mathbf G_r$) and `tests/unit/tangent.rs` (assembled).
//!
//! Independent nodes have constant $\mathbf J$ and no derivative terms; their tangents are written
//! down directly (`root` nodes).

#![allow(non_snake_case)]

use crate::node::NodeMotion;
use crate::state::State;
use nalgebra::{UnitQuaternion, Vector3};
use superelement::so3;

/// Where a scalar coordinate's value comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Slot {
    /// An unknown: index into the velocity vector $\dot{\mathbf q}$.
    Unknown(usize),
    /// Prescribed: index into the prescribed list (zero or driven).
    Prescribed(usize),
}

/// One elementary operation of a node's chain (module docs). `col` is the position of the
/// operation's coordinate among the node's columns.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Op {
    Translate {
        axis: Vector3<f64>,
        coord: usize,
        col: usize,
    },
    Rotate {
        axis: Vector3<f64>,
        coord: usize,
        col: usize,
    },
    Offset {
        d: Vector3<f64>,
        C: UnitQuaternion<f64>,
    },
    FreeRotation {
        rot: usize,
        col: usize,
    },
}

/// A scalar coordinate.
#[derive(Clone, Debug)]
pub(crate) struct Scalar {
    pub slot: Slot,
}

/// An SO(3) coordinate; its three velocity components are `dof..dof + 3`.
#[derive(Clone, Debug)]
pub(crate) struct Rotation {
    pub dof: usize,
}

/// How one node is reached.
#[derive(Clone, Debug)]
pub(crate) struct Chain {
    pub parent: Option<usize>,
    pub ops: Vec<Op>,
    /// Velocity-coordinate id of each column: `< n_dof` an unknown, else `n_dof + prescribed`.
    /// A node's columns start with its parent's (prefix property).
    pub cols: Vec<usize>,
    /// An independent node: $\mathbf J$ constant, all derivatives zero.
    pub root: bool,
}

/// The coordinates of a system and every node's chain.
#[derive(Clone, Debug)]
pub(crate) struct CoordinateMap {
    pub scalars: Vec<Scalar>,
    pub rotations: Vec<Rotation>,
    /// Number of unknowns (velocity components).
    pub n_dof: usize,
    /// Driver of each prescribed coordinate (`None`: held at zero) and its scalar.
    pub prescribed: Vec<(Option<usize>, usize)>,
    pub chains: Vec<Chain>,
    /// Nodes, parents first.
    pub order: Vec<usize>,
    /// Label of each unknown (for messages).
    pub dof_labels: Vec<String>,
}

/// Values of all coordinates at one instant.
#[derive(Clone, Copy)]
pub(crate) struct Values<'a> {
    pub scalars: &'a [f64],
    pub rotations: &'a [UnitQuaternion<f64>],
    pub vel: &'a [f64],
    pub acc: &'a [f64],
    pub presc_rate: &'a [f64],
    pub presc_acc: &'a [f64],
}

impl Values<'_> {
    #[inline]
    fn scalar(&self, map: &CoordinateMap, s: usize) -> (f64, f64, f64) {
        let x = self.scalars[s];
        match map.scalars[s].slot {
            Slot::Unknown(d) => (x, self.vel[d], self.acc[d]),
            Slot::Prescribed(p) => (x, self.presc_rate[p], self.presc_acc[p]),
        }
    }
}

/// Configuration, velocity, acceleration of a moving frame, with the columns of $\mathbf J$.
#[derive(Clone, Debug)]
pub struct Motion {
    pub p: Vector3<f64>,
    pub R: UnitQuaternion<f64>,
    pub v: Vector3<f64>,
    pub w: Vector3<f64>,
    pub a: Vector3<f64>,
    pub al: Vector3<f64>,
    pub Jv: Vec<Vector3<f64>>,
    pub Jw: Vec<Vector3<f64>>,
}

impl Default for Motion {
    fn default() -> Self {
        Self::ground()
    }
}

impl Motion {
    pub(crate) fn ground() -> Self {
        let z = Vector3::zeros();
        Self {
            p: z,
            R: UnitQuaternion::identity(),
            v: z,
            w: z,
            a: z,
            al: z,
            Jv: Vec::new(),
            Jw: Vec::new(),
        }
    }

    /// Back to the ground frame, keeping the column buffers' capacity.
    fn reset(&mut self) {
        self.reset_values();
        self.Jv.clear();
        self.Jw.clear();
    }

    /// Back to the ground frame's configuration, velocity and acceleration, keeping the columns.
    fn reset_values(&mut self) {
        let z = Vector3::zeros();
        (self.p, self.R, self.v, self.w, self.a, self.al) = (z, UnitQuaternion::identity(), z, z, z, z);
    }

    /// `self = other` without allocating once the column buffers have grown (the derived
    /// `clone_from` would allocate a fresh copy every time).
    fn copy_from(&mut self, other: &Motion) {
        (self.p, self.R, self.v, self.w, self.a, self.al) = (other.p, other.R, other.v, other.w, other.a, other.al);
        self.Jv.clone_from(&other.Jv);
        self.Jw.clone_from(&other.Jw);
    }

    /// Column $i$ of $\mathbf J_c$ as $[\mathbf J^v; \mathbf J^\omega]$.
    #[inline]
    pub(crate) fn col(&self, i: usize) -> [f64; 6] {
        let (v, w) = (self.Jv[i], self.Jw[i]);
        [v.x, v.y, v.z, w.x, w.y, w.z]
    }
}

/// Variation of a [`Motion`] in one direction (module docs).
#[derive(Clone, Debug)]
pub(crate) struct Tangent {
    pub dp: Vector3<f64>,
    pub dpi: Vector3<f64>,
    pub dv: Vector3<f64>,
    pub dw: Vector3<f64>,
    pub da: Vector3<f64>,
    pub dal: Vector3<f64>,
    /// $\delta\mathbf J$ (position directions only).
    pub dJv: Vec<Vector3<f64>>,
    pub dJw: Vec<Vector3<f64>>,
}

impl Tangent {
    fn zero(ncols: usize, with_J: bool) -> Self {
        let mut t = Self {
            dp: Vector3::zeros(),
            dpi: Vector3::zeros(),
            dv: Vector3::zeros(),
            dw: Vector3::zeros(),
            da: Vector3::zeros(),
            dal: Vector3::zeros(),
            dJv: Vec::new(),
            dJw: Vec::new(),
        };
        t.reset(ncols, with_J);
        t
    }

    /// The zero variation over `ncols` columns, reusing the buffers.
    fn reset(&mut self, ncols: usize, with_J: bool) {
        let z = Vector3::zeros();
        (self.dp, self.dpi, self.dv, self.dw, self.da, self.dal) = (z, z, z, z, z, z);
        let n = if with_J { ncols } else { 0 };
        self.dJv.clear();
        self.dJv.resize(n, z);
        self.dJw.clear();
        self.dJw.resize(n, z);
    }

    /// `self = other`, reusing the buffers.
    fn copy_from(&mut self, other: &Tangent) {
        (self.dp, self.dpi, self.dv, self.dw, self.da, self.dal) =
            (other.dp, other.dpi, other.dv, other.dw, other.da, other.dal);
        self.dJv.clone_from(&other.dJv);
        self.dJw.clone_from(&other.dJw);
    }
}

/// `(&v[a], &mut v[b])` for `a != b`.
fn pair_mut<T>(v: &mut [T], a: usize, b: usize) -> (&T, &mut T) {
    debug_assert_ne!(a, b);
    if a < b {
        let (lo, hi) = v.split_at_mut(b);
        (&lo[a], &mut hi[0])
    } else {
        let (lo, hi) = v.split_at_mut(a);
        (&hi[0], &mut lo[b])
    }
}

/// Direction of a tangent pass: the column whose coordinate is varied, in position or rate.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Dir {
    Position(usize),
    Rate(usize),
}

/// Applies one operation to the motion (the value pass); without `with_J` the columns of
/// $\mathbf J$ are left alone (an independent node's, constant, kept from an earlier pass) and
/// a held coordinate costs nothing.
pub(crate) fn apply(op: &Op, m: &mut Motion, map: &CoordinateMap, x: &Values, with_J: bool) {
    match op {
        Op::Translate { axis, coord, col } => {
            debug_assert!(!with_J || *col == m.Jv.len());
            let (s, sd, sdd) = x.scalar(map, *coord);
            if !with_J && s == 0.0 && sd == 0.0 && sdd == 0.0 {
                return;
            }
            let n = m.R * axis;
            // A held coordinate (a support's zero translation) only adds its column.
            if s != 0.0 || sd != 0.0 || sdd != 0.0 {
                let wn = m.w.cross(&n);
                m.p += n * s;
                m.a += n * sdd + wn * (2.0 * sd) + (m.al.cross(&n) + m.w.cross(&wn)) * s;
                m.v += n * sd + wn * s;
            }
            if !with_J {
                return;
            }
            if s != 0.0 {
                for k in 0..m.Jv.len() {
                    let c = m.Jw[k].cross(&n) * s;
                    m.Jv[k] += c;
                }
            }
            m.Jv.push(n);
            m.Jw.push(Vector3::zeros());
        }
        Op::Rotate { axis, coord, col } => {
            debug_assert!(!with_J || *col == m.Jv.len());
            let (th, thd, thdd) = x.scalar(map, *coord);
            if !with_J && th == 0.0 && thd == 0.0 && thdd == 0.0 {
                return;
            }
            let n = m.R * axis;
            if thd != 0.0 || thdd != 0.0 {
                m.al += n * thdd + m.w.cross(&n) * thd;
                m.w += n * thd;
            }
            if th != 0.0 {
                m.R = so3::exp(&(n * th)) * m.R;
            }
            if with_J {
                m.Jv.push(Vector3::zeros());
                m.Jw.push(n);
            }
        }
        Op::Offset { d, C } => {
            // The closing `Offset(0, R0)` of an independent node only turns the frame.
            if *d != Vector3::zeros() {
                let b = m.R * d;
                let wb = m.w.cross(&b);
                m.p += b;
                m.a += m.al.cross(&b) + m.w.cross(&wb);
                m.v += wb;
                if with_J {
                    for k in 0..m.Jv.len() {
                        let c = m.Jw[k].cross(&b);
                        m.Jv[k] += c;
                    }
                }
            }
            if *C != UnitQuaternion::identity() {
                m.R *= C;
            }
        }
        Op::FreeRotation { rot, col } => {
            debug_assert!(!with_J || *col == m.Jv.len());
            let d = map.rotations[*rot].dof;
            m.R = x.rotations[*rot];
            m.w = Vector3::new(x.vel[d], x.vel[d + 1], x.vel[d + 2]);
            m.al = Vector3::new(x.acc[d], x.acc[d + 1], x.acc[d + 2]);
            if !with_J {
                return;
            }
            for w in m.Jw.iter_mut() {
                *w = Vector3::zeros();
            }
            for i in 0..3 {
                m.Jv.push(Vector3::zeros());
                m.Jw.push(Vector3::ith(i, 1.0));
            }
        }
    }
}

/// Variation of one operation in direction `dir` (position or rate of the node column), given
/// the motion `m` *before* the operation.
fn apply_tangent(op: &Op, m: &Motion, t: &mut Tangent, dir: Dir, map: &CoordinateMap, x: &Values) {
    let with_J = matches!(dir, Dir::Position(_));
    let seed = |col: usize| -> (f64, f64) {
        match dir {
            Dir::Position(k) if k == col => (1.0, 0.0),
            Dir::Rate(k) if k == col => (0.0, 1.0),
            _ => (0.0, 0.0),
        }
    };
    match op {
        Op::Translate { axis, coord, col } => {
            let (s, sd, sdd) = x.scalar(map, *coord);
            let (ds, dsd) = seed(*col);
            let n = m.R * axis;
            let dn = t.dpi.cross(&n);
            let wn = m.w.cross(&n);
            let dwn = t.dw.cross(&n) + m.w.cross(&dn);
            t.dp += n * ds + dn * s;
            t.da += dn * sdd
                + wn * (2.0 * dsd)
                + dwn * (2.0 * sd)
                + (m.al.cross(&n) + m.w.cross(&wn)) * ds
                + (t.dal.cross(&n) + m.al.cross(&dn) + t.dw.cross(&wn) + m.w.cross(&dwn)) * s;
            t.dv += n * dsd + dn * sd + wn * ds + dwn * s;
            if with_J {
                for k in 0..t.dJv.len() {
                    let c = m.Jw[k].cross(&n) * ds + (t.dJw[k].cross(&n) + m.Jw[k].cross(&dn)) * s;
                    t.dJv[k] += c;
                }
                t.dJv.push(dn);
                t.dJw.push(Vector3::zeros());
            }
        }
        Op::Rotate { axis, coord, col } => {
            let (_, thd, thdd) = x.scalar(map, *coord);
            let (dth, dthd) = seed(*col);
            let n = m.R * axis;
            let dn = t.dpi.cross(&n);
            t.dal += dn * thdd + m.w.cross(&n) * dthd + (t.dw.cross(&n) + m.w.cross(&dn)) * thd;
            t.dw += n * dthd + dn * thd;
            t.dpi += n * dth;
            if with_J {
                t.dJv.push(Vector3::zeros());
                t.dJw.push(dn);
            }
        }
        Op::Offset { d, .. } => {
            let b = m.R * d;
            let db = t.dpi.cross(&b);
            let wb = m.w.cross(&b);
            let dwb = t.dw.cross(&b) + m.w.cross(&db);
            t.dp += db;
            t.dv += dwb;
            t.da += t.dal.cross(&b) + m.al.cross(&db) + t.dw.cross(&wb) + m.w.cross(&dwb);
            if with_J {
                for k in 0..t.dJv.len() {
                    let c = t.dJw[k].cross(&b) + m.Jw[k].cross(&db);
                    t.dJv[k] += c;
                }
            }
        }
        Op::FreeRotation { col, .. } => {
            let e = |k: usize| {
                if k >= *col && k < col + 3 {
                    Vector3::ith(k - col, 1.0)
                } else {
                    Vector3::zeros()
                }
            };
            match dir {
                Dir::Position(k) => {
                    t.dpi = e(k);
                    t.dw = Vector3::zeros();
                }
                Dir::Rate(k) => {
                    t.dpi = Vector3::zeros();
                    t.dw = e(k);
                }
            }
            t.dal = Vector3::zeros();
            if with_J {
                for w in t.dJw.iter_mut() {
                    *w = Vector3::zeros();
                }
                for _ in 0..3 {
                    t.dJv.push(Vector3::zeros());
                    t.dJw.push(Vector3::zeros());
                }
            }
        }
    }
}

/// Which node motions [`CoordinateMap::motions_update`] can keep: the nodes whose chains
/// (their own and their ancestors') read prescribed coordinates only are functions of time.
#[derive(Clone, Debug)]
pub(crate) struct MotionCache {
    time_only: Vec<bool>,
    /// The time of the motions (bits), `None` before the first pass.
    time: Option<u64>,
    /// Per node: recomputed by the last pass.
    pub changed: Vec<bool>,
}

/// Kinematic derivatives of one node, per unknown column (in the node's column order).
#[derive(Clone, Debug, Default)]
pub(crate) struct NodeDerivatives {
    /// Positions (in `cols`) of the unknown columns.
    pub unknown: Vec<usize>,
    /// $\partial\mathbf V/\partial q_k$ for each unknown column.
    pub DV: Vec<[f64; 6]>,
    /// $\partial\mathbf A/\partial q_k$.
    pub DA: Vec<[f64; 6]>,
    /// $\partial\mathbf A/\partial\dot q_k$.
    pub DAd: Vec<[f64; 6]>,
    /// Tangents in position directions per column (`None` for prescribed), kept for children.
    pub(crate) pos: Vec<Option<Tangent>>,
    /// Tangents in rate directions per column.
    pub(crate) rate: Vec<Option<Tangent>>,
    /// The moving frame of the node's chain before each operation (scratch of the tangent pass).
    work: Motion,
    /// `unknown`, `pos` and `rate` sized for the node's chain by an earlier call (and, for an
    /// independent node, its derivatives formed: they are constant like its columns).
    sized: bool,
}

fn six(a: &Vector3<f64>, b: &Vector3<f64>) -> [f64; 6] {
    [a.x, a.y, a.z, b.x, b.y, b.z]
}

impl CoordinateMap {
    /// Number of prescribed coordinates.
    pub(crate) fn n_prescribed(&self) -> usize {
        self.prescribed.len()
    }

    /// The value pass for every node (parents first): configuration, velocity,
    /// acceleration and $\mathbf J$ columns. Reuses the column buffers of `out` (no allocation
    /// after the first call).
    pub(crate) fn motions_into(&self, x: &Values, out: &mut [Motion]) {
        self.motion_pass(x, out, None);
    }

    /// An empty [`MotionCache`] for this map's nodes (the first [`Self::motions_update`]
    /// computes every node).
    pub(crate) fn motion_cache(&self) -> MotionCache {
        let mut time_only = vec![false; self.chains.len()];
        for &c in &self.order {
            let chain = &self.chains[c];
            let own = chain.ops.iter().all(|op| match op {
                Op::Translate { coord, .. } | Op::Rotate { coord, .. } => {
                    matches!(self.scalars[*coord].slot, Slot::Prescribed(_))
                }
                Op::FreeRotation { .. } => false,
                Op::Offset { .. } => true,
            });
            time_only[c] = own && chain.parent.is_none_or(|p| time_only[p]);
        }
        MotionCache {
            time_only,
            time: None,
            changed: vec![true; self.chains.len()],
        }
    }

    /// [`Self::motions_into`] at time `t` into the motions of the last call with the same
    /// `cache`, recomputing the nodes that hang on unknowns and, when `t` changed, those
    /// driven by time alone: within a time step a driven crank and what it carries are
    /// computed once. `cache.changed` tells which nodes were recomputed.
    pub(crate) fn motions_update(&self, x: &Values, t: f64, out: &mut [Motion], cache: &mut MotionCache) {
        let same_time = cache.time == Some(t.to_bits());
        for (changed, &time_only) in cache.changed.iter_mut().zip(&cache.time_only) {
            *changed = !(same_time && time_only);
        }
        // After a first pass the independent nodes' constant columns are in `out`.
        let keep_root_columns = cache.time.is_some();
        self.motion_pass(x, out, Some((&cache.changed, keep_root_columns)));
        cache.time = Some(t.to_bits());
    }

    /// The value pass of [`Self::motions_into`]; with `which` = (nodes, keep) only the nodes
    /// marked, and with `keep` the independent nodes' columns of $\mathbf J$ (constant) left as
    /// they are in `out` ([`Self::motions_update`]).
    fn motion_pass(&self, x: &Values, out: &mut [Motion], which: Option<(&[bool], bool)>) {
        let keep_root_columns = which.is_some_and(|(_, keep)| keep);
        for &c in &self.order {
            let chain = &self.chains[c];
            if which.is_some_and(|(w, _)| !w[c]) {
                continue;
            }
            let with_J = !(chain.root && keep_root_columns);
            let m = match chain.parent {
                Some(p) => {
                    let (parent, m) = pair_mut(out, p, c);
                    m.copy_from(parent);
                    m
                }
                None if with_J => {
                    out[c].reset();
                    &mut out[c]
                }
                None => {
                    out[c].reset_values();
                    &mut out[c]
                }
            };
            for op in &chain.ops {
                apply(op, m, self, x, with_J);
            }
        }
    }

    /// The tangent passes (module docs) for every node. `motions` from
    /// [`Self::motions_into`]. Reuses the buffers of `out` (no allocation after the first
    /// call: a node's columns and unknowns never change).
    pub(crate) fn derivatives_into(&self, x: &Values, motions: &[Motion], out: &mut [NodeDerivatives]) {
        for &c in &self.order {
            let chain = &self.chains[c];
            let ncols = chain.cols.len();
            let (parent, d) = match chain.parent {
                Some(p) => {
                    let (pd, d) = pair_mut(out, p, c);
                    (Some(pd), d)
                }
                None => (None, &mut out[c]),
            };
            if !d.sized {
                d.unknown.clear();
                d.unknown.extend((0..ncols).filter(|&k| chain.cols[k] < self.n_dof));
                d.pos.resize_with(ncols, || None);
                d.rate.resize_with(ncols, || None);
                d.sized = true;
            } else if chain.root {
                // Formed by an earlier call from the constant columns: nothing changed.
                continue;
            }
            d.DV.clear();
            d.DA.clear();
            d.DAd.clear();
            if chain.root {
                // J constant: a position variation moves the node along its column, a rate
                // variation changes its velocity by the column; nothing else.
                let m = &motions[c];
                for &k in &d.unknown {
                    let tp = d.pos[k].get_or_insert_with(|| Tangent::zero(ncols, true));
                    tp.reset(ncols, true);
                    tp.dp = m.Jv[k];
                    tp.dpi = m.Jw[k];
                    let tr = d.rate[k].get_or_insert_with(|| Tangent::zero(ncols, false));
                    tr.reset(ncols, false);
                    tr.dv = m.Jv[k];
                    tr.dw = m.Jw[k];
                    d.DV.push([0.0; 6]);
                    d.DA.push([0.0; 6]);
                    d.DAd.push([0.0; 6]);
                }
                continue;
            }
            let parent_cols = chain.parent.map_or(0, |p| self.chains[p].cols.len());
            match chain.parent {
                Some(p) => d.work.copy_from(&motions[p]),
                None => d.work.reset(),
            }
            for &k in &d.unknown {
                let tp = d.pos[k].get_or_insert_with(|| Tangent::zero(parent_cols, true));
                let tr = d.rate[k].get_or_insert_with(|| Tangent::zero(parent_cols, false));
                if k < parent_cols {
                    let pd = parent.expect("columns from a parent");
                    tp.copy_from(pd.pos[k].as_ref().expect("parent tangent of an unknown column"));
                    tr.copy_from(pd.rate[k].as_ref().expect("parent tangent of an unknown column"));
                } else {
                    tp.reset(parent_cols, true);
                    tr.reset(parent_cols, false);
                }
            }
            for op in &chain.ops {
                for &k in &d.unknown {
                    let tp = d.pos[k].as_mut().expect("tangent of an unknown column");
                    apply_tangent(op, &d.work, tp, Dir::Position(k), self, x);
                    let tr = d.rate[k].as_mut().expect("tangent of an unknown column");
                    apply_tangent(op, &d.work, tr, Dir::Rate(k), self, x);
                }
                apply(op, &mut d.work, self, x, true);
            }
            for &k in &d.unknown {
                let tp = d.pos[k].as_ref().expect("tangent of an unknown column");
                let tr = d.rate[k].as_ref().expect("tangent of an unknown column");
                d.DV.push(six(&tp.dv, &tp.dw));
                d.DA.push(six(&tp.da, &tp.dal));
                d.DAd.push(six(&tr.da, &tr.dal));
            }
        }
    }

    /// $(\mathbf G_r)_{ik} \mathrel{+}= \mathbf r_c\cdot\partial\mathbf J_{c,i}/\partial q_k$ for node `c` with
    /// residual `r`: calls `add(i, k, value)` with `i`, `k` positions in `d.unknown`.
    pub(crate) fn geometric_term(
        &self,
        c: usize,
        d: &NodeDerivatives,
        r: &[f64; 6],
        mut add: impl FnMut(usize, usize, f64),
    ) {
        if self.chains[c].root {
            return;
        }
        let f = Vector3::new(r[0], r[1], r[2]);
        let mo = Vector3::new(r[3], r[4], r[5]);
        for (uk, &k) in d.unknown.iter().enumerate() {
            let t = d.pos[k].as_ref().unwrap();
            for (ui, &i) in d.unknown.iter().enumerate() {
                let g = f.dot(&t.dJv[i]) + mo.dot(&t.dJw[i]);
                if g != 0.0 {
                    add(ui, uk, g);
                }
            }
        }
    }
}

impl From<&Motion> for NodeMotion {
    fn from(m: &Motion) -> Self {
        Self {
            r: m.p,
            R: m.R,
            v: m.v,
            omega: m.w,
            a: m.a,
            alpha: m.al,
        }
    }
}

/// The unknown index of a slot known to be unknown.
pub(crate) fn unknown(slot: Slot) -> usize {
    match slot {
        Slot::Unknown(d) => d,
        Slot::Prescribed(_) => unreachable!("modal and initial-condition coordinates are unknowns"),
    }
}

pub(crate) fn values<'a>(s: &'a State, pr: &'a [f64], pa: &'a [f64]) -> Values<'a> {
    Values {
        scalars: &s.scalars,
        rotations: &s.rotations,
        vel: &s.velocity,
        acc: &s.acceleration,
        presc_rate: pr,
        presc_acc: pa,
    }
}

pub(crate) fn scalar_values(map: &CoordinateMap, x: &Values, s: usize) -> (f64, f64, f64) {
    let v = x.scalars[s];
    match map.scalars[s].slot {
        Slot::Unknown(d) => (v, x.vel[d], x.acc[d]),
        Slot::Prescribed(p) => (v, x.presc_rate[p], x.presc_acc[p]),
    }
}

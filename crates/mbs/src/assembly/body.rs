//! Elements: everything that puts a force on nodes, as a function of the nodes' configuration,
//! velocity and acceleration ([`NodeMotion`]).
//!
//! Each element returns its residual $\mathbf r_e = \mathbf f_{inertia} + \mathbf f_{internal} -
//! \mathbf f_{external}$ on its *ports* (6 rows $[\mathbf f; \mathbf m]$ per node, inertial axes,
//! then the flexible body's modal coordinates) and the tangents $\mathbf M = \partial\mathbf r/\partial\mathbf A$,
//! $\mathbf C_t = \partial\mathbf r/\partial\mathbf V$, $\mathbf K_t = \partial\mathbf r/\partial\mathbf x$ with spatial
//! rotation variations, the superelement's conventions. Naming rule: `*_element` functions
//! return residual and tangents together.
//!
//! * Flexible: the AIC-FFR superelement ([`superelement::Superelement::evaluate`]); interface
//!   $k$'s orientation is its node's times a constant offset ($\mathbf R_k = \mathbf R_{node}\mathbf C_k$),
//!   which leaves spatial velocities and variations unchanged.
//! * Rigid body at its reference node, centre of mass $\mathbf b = \mathbf R\mathbf c$ from it,
//!   $\mathbf I_G = \mathbf R\mathbf J\mathbf R^T$ (`rigid_element`).
//! * Point mass, point-to-point spring-damper (`spring_element`), nodal loads (dead and
//!   follower, `load_element`).

#![allow(non_snake_case)]

use crate::error::SolveError;
use crate::model::user_force::{UserBuffer, UserForce};
use crate::node::NodeMotion;
use faer::Mat;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use superelement::so3::skew;
use superelement::{
    BodyState, Evaluation, Frame, PointLoad, PointLoadWorkspace, Superelement, SuperelementError,
    Workspace as SeWorkspace,
};

/// Residual and tangents of one element on its ports.
#[derive(Clone, Debug)]
pub(crate) struct ElementOutput {
    pub residual: Vec<f64>,
    /// The inertia, internal (elastic, damping) and external (load, gravity) parts of the
    /// residual, for the convergence scale.
    pub inertia: Vec<f64>,
    pub internal: Vec<f64>,
    pub external: Vec<f64>,
    pub M: Mat<f64>,
    pub C: Mat<f64>,
    pub K: Mat<f64>,
    /// New floating frame (flexible bodies).
    pub frame: Option<Frame>,
}

impl ElementOutput {
    pub(crate) fn zeros(n: usize, tangents: bool) -> Self {
        let k = if tangents { n } else { 0 };
        Self {
            residual: vec![0.0; n],
            inertia: vec![0.0; n],
            internal: vec![0.0; n],
            external: vec![0.0; n],
            M: Mat::zeros(k, k),
            C: Mat::zeros(k, k),
            K: Mat::zeros(k, k),
            frame: None,
        }
    }

    /// Zeroes the residual parts and, with `tangents`, the tangents (their size stays that of
    /// [`Self::zeros`]): the element functions below accumulate into a reused output.
    pub(crate) fn reset(&mut self, tangents: bool) {
        for v in [
            &mut self.residual,
            &mut self.inertia,
            &mut self.internal,
            &mut self.external,
        ] {
            v.fill(0.0);
        }
        if tangents {
            for A in [&mut self.M, &mut self.C, &mut self.K] {
                A.fill(0.0);
            }
        }
        self.frame = None;
    }

    fn finish(&mut self) {
        for i in 0..self.residual.len() {
            self.residual[i] = self.inertia[i] + self.internal[i] - self.external[i];
        }
    }
}

fn set3(M: &mut Mat<f64>, r: usize, c: usize, B: &Matrix3<f64>) {
    for i in 0..3 {
        for j in 0..3 {
            M[(r + i, c + j)] += B[(i, j)];
        }
    }
}

fn put(v: &mut [f64], at: usize, x: &Vector3<f64>) {
    v[at] += x.x;
    v[at + 1] += x.y;
    v[at + 2] += x.z;
}

/// The reused buffers of one flexible element (see [`FlexibleElement::buffer`]).
#[derive(Clone, Debug)]
pub(crate) struct FlexBuffer {
    pub ws: SeWorkspace,
    pub ev: Evaluation,
    pub state: BodyState,
    pub acc: Vec<f64>,
    /// The buffers of the body's load-point loads (`None` without any).
    pub loads: Option<PointLoadWorkspace>,
}

/// A flexible body placed on its nodes.
#[derive(Clone, Debug)]
pub(crate) struct FlexibleElement {
    pub body: usize,
    pub se: Superelement,
    pub nodes: Vec<usize>,
    /// $\mathbf C_k$: $\mathbf R_k = \mathbf R_{node}\mathbf C_k$.
    pub offsets: Vec<UnitQuaternion<f64>>,
    /// Scalar indices of $\boldsymbol\eta$.
    pub modal: Vec<usize>,
    /// $\|\mathbf K_{CB}\|_\infty$ and the body size, for the residual's round-off floor.
    pub k_norm: f64,
    pub size: f64,
    /// Loads at the body's load points: the load at unit factor (dead: inertial; follower:
    /// body axes) and its time function.
    pub loads: Vec<(PointLoad, crate::model::time_function::CompiledFunction)>,
}

impl FlexibleElement {
    /// The superelement's state from the node motions and the modal coordinates.
    pub(crate) fn body_state(&self, motions: &[NodeMotion], eta: &[f64], eta_dot: &[f64], frame: Frame) -> BodyState {
        BodyState {
            r: self.nodes.iter().map(|&n| motions[n].r).collect(),
            R: self
                .nodes
                .iter()
                .zip(&self.offsets)
                .map(|(&n, C)| motions[n].R * C)
                .collect(),
            v: self.nodes.iter().map(|&n| motions[n].v).collect(),
            omega: self.nodes.iter().map(|&n| motions[n].omega).collect(),
            eta: eta.to_vec(),
            eta_dot: eta_dot.to_vec(),
            frame,
        }
    }

    /// Buffers for [`Self::element_into`]: the superelement's workspace and
    /// output, the body state and the accelerations, sized once.
    pub(crate) fn buffer(&self) -> FlexBuffer {
        let n = self.se.n_coordinates();
        let N = self.nodes.len();
        let z = Vector3::zeros();
        let m = self.modal.len();
        FlexBuffer {
            ws: self.se.workspace(),
            ev: Evaluation::zeros(n),
            state: BodyState {
                r: vec![z; N],
                R: vec![UnitQuaternion::identity(); N],
                v: vec![z; N],
                omega: vec![z; N],
                eta: vec![0.0; m],
                eta_dot: vec![0.0; m],
                frame: Frame::identity(),
            },
            acc: vec![0.0; n],
            loads: (!self.loads.is_empty()).then(|| self.se.point_load_workspace()),
        }
    }

    /// The element's forces and tangents, without allocation: the body state is refilled from the node motions
    /// and `modal(i) = (η_i, η̇_i, η̈_i)`, the superelement evaluates into its workspace
    /// ([`Superelement::evaluate_into`]) and the result is copied into `out`, which must have
    /// been built for this element (`6N + m` rows). The body's load-point loads at time `t`,
    /// scaled by the load factor `lambda`, are added ([`Superelement::point_load_into`]).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn element_into(
        &self,
        motions: &[NodeMotion],
        modal: impl Fn(usize) -> (f64, f64, f64),
        frame: Frame,
        gravity: &Vector3<f64>,
        (t, lambda): (f64, f64),
        tangents: bool,
        buf: &mut FlexBuffer,
        out: &mut ElementOutput,
    ) -> Result<(), SuperelementError> {
        let N = self.nodes.len();
        let bs = &mut buf.state;
        for (k, (&n, C)) in self.nodes.iter().zip(&self.offsets).enumerate() {
            let m = &motions[n];
            bs.r[k] = m.r;
            bs.R[k] = m.R * C;
            bs.v[k] = m.v;
            bs.omega[k] = m.omega;
            buf.acc[6 * k..6 * k + 3].copy_from_slice(m.a.as_slice());
            buf.acc[6 * k + 3..6 * k + 6].copy_from_slice(m.alpha.as_slice());
        }
        for i in 0..self.modal.len() {
            let (x, xd, xdd) = modal(i);
            bs.eta[i] = x;
            bs.eta_dot[i] = xd;
            buf.acc[6 * N + i] = xdd;
        }
        bs.frame = frame;
        // Without tangents only the forces are read below: the residual alone forms no mass
        // matrix (the energy sensor takes T from the workspace, `kinetic_energy_in`).
        if tangents {
            self.se.evaluate_into(bs, &buf.acc, gravity, &mut buf.ws, &mut buf.ev)?;
        } else {
            self.se.residual_into(bs, &buf.acc, gravity, &mut buf.ws, &mut buf.ev)?;
        }
        let ev = &buf.ev;
        out.residual.copy_from_slice(&ev.residual);
        out.inertia.copy_from_slice(&ev.f_inertia);
        for ((o, e), d) in out.internal.iter_mut().zip(&ev.f_elastic).zip(&ev.f_damping) {
            *o = e + d;
        }
        out.external.copy_from_slice(&ev.f_gravity);
        if tangents {
            // Column slices: faer's generic `copy_from` costs several times more at these sizes.
            for (dst, src) in [
                (&mut out.M, &ev.mass),
                (&mut out.C, &ev.damping),
                (&mut out.K, &ev.stiffness),
            ] {
                for j in 0..src.ncols() {
                    dst.col_as_slice_mut(j).copy_from_slice(src.col_as_slice(j));
                }
            }
        }
        out.frame = Some(ev.frame);
        if let Some(pl) = buf.loads.as_mut() {
            for (load, time) in &self.loads {
                let x = time.eval(t).0 * lambda;
                if x == 0.0 {
                    continue;
                }
                let scaled = PointLoad {
                    force: load.force * x,
                    moment: load.moment * x,
                    ..*load
                };
                if tangents {
                    self.se.point_load_into(buf.ws.kinematics(), &scaled, pl)?;
                } else {
                    self.se.point_load_residual_into(buf.ws.kinematics(), &scaled, pl)?;
                }
                for (i, r) in pl.residual.iter().enumerate() {
                    out.residual[i] += r;
                    out.external[i] -= r;
                }
                if tangents {
                    out.K += &pl.stiffness;
                }
            }
        }
        Ok(())
    }
}

/// Rigid-body mass data in the reference node's axes.
#[derive(Clone, Debug)]
pub(crate) struct RigidElement {
    pub node: usize,
    pub mass: f64,
    /// Centre of mass from the node, node axes.
    pub c: Vector3<f64>,
    /// Inertia about the centre of mass, node axes.
    pub J: Matrix3<f64>,
}

/// Rigid body on its reference node: with $\mathbf b = \mathbf R\mathbf c$, $\mathbf I_G = \mathbf R\mathbf J\mathbf R^T$,
/// $\mathbf a_G = \mathbf a + \boldsymbol\alpha\times\mathbf b + \boldsymbol\omega\times(\boldsymbol\omega\times\mathbf b)$
/// and $\mathbf F = m(\mathbf a_G - \mathbf g)$:
/// $\mathbf r = [\mathbf F;\ \mathbf b\times\mathbf F + \mathbf I_G\boldsymbol\alpha + \boldsymbol\omega\times\mathbf I_G\boldsymbol\omega]$
/// (Newton-Euler about the node).
///
/// # Derivation
/// $\mathbf M = \partial\mathbf r/\partial[\mathbf a;\boldsymbol\alpha] = \begin{bmatrix}m\mathbf I & -m\tilde{\mathbf b}\\
/// m\tilde{\mathbf b} & \mathbf I_G - m\tilde{\mathbf b}\tilde{\mathbf b}\end{bmatrix}$. With
/// $\mathbf W = \partial\mathbf a_G/\partial\boldsymbol\omega = -\widetilde{\boldsymbol\omega\times\mathbf b} - \tilde{\boldsymbol\omega}\tilde{\mathbf b}$:
/// $\mathbf C_t = [\mathbf 0, m\mathbf W;\ \mathbf 0, m\tilde{\mathbf b}\mathbf W + \tilde{\boldsymbol\omega}\mathbf I_G - \widetilde{\mathbf I_G\boldsymbol\omega}]$.
/// A spatial rotation variation gives $\delta\mathbf b = -\tilde{\mathbf b}\delta\boldsymbol\pi$,
/// $\delta\mathbf I_G = \widetilde{\delta\boldsymbol\pi}\mathbf I_G - \mathbf I_G\widetilde{\delta\boldsymbol\pi}$, so with
/// $\mathbf A_b = -(\tilde{\boldsymbol\alpha} + \tilde{\boldsymbol\omega}\tilde{\boldsymbol\omega})\tilde{\mathbf b}$:
/// $\partial\mathbf F/\partial\boldsymbol\pi = m\mathbf A_b$ and $\partial\mathbf r_m/\partial\boldsymbol\pi =
/// \tilde{\mathbf F}\tilde{\mathbf b} + m\tilde{\mathbf b}\mathbf A_b - \widetilde{\mathbf I_G\boldsymbol\alpha} + \mathbf I_G\tilde{\boldsymbol\alpha} +
/// \tilde{\boldsymbol\omega}(\mathbf I_G\tilde{\boldsymbol\omega} - \widetilde{\mathbf I_G\boldsymbol\omega})$; nothing depends
/// on $\mathbf r$ or $\mathbf v$. Checked, assembled, by `tests/unit/tangent.rs` (rigid chain and mixed model).
///
/// Writes into `out` (6 rows, built by [`ElementOutput::zeros`]), like the other element
/// functions: an evaluation allocates nothing.
pub(crate) fn rigid_element(
    e: &RigidElement,
    m: &NodeMotion,
    gravity: &Vector3<f64>,
    tangents: bool,
    out: &mut ElementOutput,
) {
    out.reset(tangents);
    let R = m.R.to_rotation_matrix();
    let b = R * e.c;
    let IG = R.matrix() * e.J * R.matrix().transpose();
    let (w, al) = (m.omega, m.alpha);
    let aG = m.a + al.cross(&b) + w.cross(&w.cross(&b));
    let mass = e.mass;
    let Fi = aG * mass;
    let Fg = gravity * mass;
    put(&mut out.inertia, 0, &Fi);
    put(&mut out.inertia, 3, &(b.cross(&Fi) + IG * al + w.cross(&(IG * w))));
    put(&mut out.external, 0, &Fg);
    put(&mut out.external, 3, &b.cross(&Fg));
    out.finish();
    if tangents {
        let bt = skew(&b);
        let wt = skew(&w);
        let I3 = Matrix3::identity();
        set3(&mut out.M, 0, 0, &(I3 * mass));
        set3(&mut out.M, 0, 3, &(-bt * mass));
        set3(&mut out.M, 3, 0, &(bt * mass));
        set3(&mut out.M, 3, 3, &(IG - bt * bt * mass));
        let W = -skew(&w.cross(&b)) - wt * bt;
        set3(&mut out.C, 0, 3, &(W * mass));
        set3(&mut out.C, 3, 3, &(bt * W * mass + wt * IG - skew(&(IG * w))));
        let F = (aG - gravity) * mass;
        let Ab = -(skew(&al) + wt * wt) * bt;
        set3(&mut out.K, 0, 3, &(Ab * mass));
        let Km = skew(&F) * bt + bt * Ab * mass - skew(&(IG * al)) + IG * skew(&al) + wt * (IG * wt - skew(&(IG * w)));
        set3(&mut out.K, 3, 3, &Km);
    }
}

/// Point mass: $\mathbf r = [m(\mathbf a - \mathbf g);\ \mathbf 0]$.
pub(crate) fn point_mass_element(
    mass: f64,
    m: &NodeMotion,
    gravity: &Vector3<f64>,
    tangents: bool,
    out: &mut ElementOutput,
) {
    out.reset(tangents);
    put(&mut out.inertia, 0, &(m.a * mass));
    put(&mut out.external, 0, &(gravity * mass));
    out.finish();
    if tangents {
        set3(&mut out.M, 0, 0, &(Matrix3::identity() * mass));
    }
}

/// A spring-damper between two nodes (or a node and a fixed point).
#[derive(Clone, Debug)]
pub(crate) struct SpringElement {
    pub a: usize,
    pub b: Option<usize>,
    pub ground: Vector3<f64>,
    pub k: f64,
    pub c: f64,
    pub l0: f64,
}

/// Axial spring-damper: $\mathbf d = \mathbf x_b - \mathbf x_a$, $l = |\mathbf d|$, $\mathbf e = \mathbf d/l$,
/// $\dot l = \mathbf e\cdot(\mathbf v_b - \mathbf v_a)$, $f = k(l - l_0) + c\dot l$; residual $-f\mathbf e$ at
/// $a$, $+f\mathbf e$ at $b$.
///
/// # Derivation
/// With $\mathbf P = \mathbf I - \mathbf e\mathbf e^T$: $\partial\mathbf e/\partial\mathbf x_b = \mathbf P/l$,
/// $\partial\dot l/\partial\mathbf x_b = (\mathbf P\Delta\mathbf v)^T/l$, so
/// $\partial(f\mathbf e)/\partial\mathbf x_b = \mathbf e(k\mathbf e + c\mathbf P\Delta\mathbf v/l)^T + f\mathbf P/l$ and
/// $\partial(f\mathbf e)/\partial\mathbf v_b = c\,\mathbf e\mathbf e^T$; $a$ enters with the opposite sign.
/// Ports: $a$ (6 rows), then $b$ (6 rows) when $b$ is a node. Checked by
/// `tests/unit/tangent.rs::flexible_mixed_tangents_match_fd`.
/// Writes into `out` (6 or 12 rows) and returns the strain energy $\tfrac12k(l - l_0)^2$.
pub(crate) fn spring_element(
    s: &SpringElement,
    ma: &NodeMotion,
    mb: Option<&NodeMotion>,
    tangents: bool,
    out: &mut ElementOutput,
) -> f64 {
    let n = if mb.is_some() { 12 } else { 6 };
    out.reset(tangents);
    let (xb, vb) = mb.map_or((s.ground, Vector3::zeros()), |m| (m.r, m.v));
    let d = xb - ma.r;
    let l = d.norm();
    if l <= 0.0 {
        return 0.0;
    }
    let e = d / l;
    let dv = vb - ma.v;
    let ld = e.dot(&dv);
    let f = s.k * (l - s.l0) + s.c * ld;
    put(&mut out.internal, 0, &(-e * f));
    if n == 12 {
        put(&mut out.internal, 6, &(e * f));
    }
    out.finish();
    if tangents {
        let P = Matrix3::identity() - e * e.transpose();
        let Kb = e * (e * s.k + P * dv * (s.c / l)).transpose() + P * (f / l);
        let Cb = e * e.transpose() * s.c;
        set3(&mut out.K, 0, 0, &Kb);
        set3(&mut out.C, 0, 0, &Cb);
        if n == 12 {
            set3(&mut out.K, 6, 6, &Kb);
            set3(&mut out.K, 0, 6, &(-Kb));
            set3(&mut out.K, 6, 0, &(-Kb));
            set3(&mut out.C, 6, 6, &Cb);
            set3(&mut out.C, 0, 6, &(-Cb));
            set3(&mut out.C, 6, 0, &(-Cb));
        }
    }
    spring_energy(s, ma, mb)
}

/// Strain energy $\tfrac12k(l - l_0)^2$ of a spring (for the energy sensors).
pub(crate) fn spring_energy(s: &SpringElement, ma: &NodeMotion, mb: Option<&NodeMotion>) -> f64 {
    let xb = mb.map_or(s.ground, |m| m.r);
    let l = (xb - ma.r).norm();
    0.5 * s.k * (l - s.l0) * (l - s.l0)
}

/// A nodal load; `local` is its value in node axes for a follower.
#[derive(Clone, Debug)]
pub(crate) struct LoadElement {
    pub node: usize,
    pub moment: bool,
    pub follower: bool,
    /// Dead: the inertial value; follower: the value in node axes.
    pub value: Vector3<f64>,
    pub time: crate::model::time_function::CompiledFunction,
}

/// Load $\mathbf f = x(t)\,\mathbf f_0$ (dead) or $x(t)\,\mathbf R\mathbf f_0^{node}$ (follower); residual $-\lambda\mathbf f$.
/// A follower's tangent is $\partial(-\mathbf f)/\partial\boldsymbol\pi = \tilde{\mathbf f}$ (from
/// $\delta(\mathbf R\mathbf f_0) = \delta\boldsymbol\pi\times\mathbf f$); a dead load has none.
pub(crate) fn load_element(
    l: &LoadElement,
    m: &NodeMotion,
    t: f64,
    lambda: f64,
    tangents: bool,
    out: &mut ElementOutput,
) {
    out.reset(tangents);
    let x = l.time.eval(t).0 * lambda;
    let f = if l.follower { m.R * l.value * x } else { l.value * x };
    let at = if l.moment { 3 } else { 0 };
    put(&mut out.external, at, &f);
    out.finish();
    if tangents && l.follower {
        set3(&mut out.K, at, 3, &skew(&f));
    }
}

/// The user force's element output on its node ports: external part $\lambda\mathbf f_e$,
/// residual $-\lambda\mathbf f_e$, $\mathbf K = -\lambda\,\partial\mathbf f_e/\partial\mathbf x$,
/// $\mathbf C = -\lambda\,\partial\mathbf f_e/\partial\mathbf V$ (no mass). A non-finite force or
/// Jacobian is refused with [`SolveError::UserForce`].
#[allow(clippy::too_many_arguments)]
pub(crate) fn user_force_element(
    force: &dyn UserForce,
    index: usize,
    nodes: &[usize],
    all: &[NodeMotion],
    t: f64,
    lambda: f64,
    tangents: bool,
    buf: &mut UserBuffer,
    out: &mut ElementOutput,
) -> Result<(), SolveError> {
    out.reset(tangents);
    for (m, &n) in buf.motions.iter_mut().zip(nodes) {
        *m = all[n];
    }
    UserBuffer::eval(force, t, &buf.motions, &mut buf.wrench);
    let refuse = |what: &str| SolveError::UserForce {
        name: force.name().to_string(),
        index,
        at: crate::error::At::Time(t),
        what: what.to_string(),
    };
    if buf.wrench.iter().flatten().any(|x| !x.is_finite()) {
        return Err(refuse("the force is not finite"));
    }
    for (a, w) in buf.wrench.iter().enumerate() {
        for i in 0..6 {
            out.external[6 * a + i] = lambda * w[i];
            out.residual[6 * a + i] = -lambda * w[i];
        }
    }
    if !tangents {
        return Ok(());
    }
    buf.dx.fill(0.0);
    buf.dv.fill(0.0);
    if !force.jacobian(t, &buf.motions, buf.dx.as_mut(), buf.dv.as_mut()) {
        buf.fd_jacobian(force, t);
    }
    let n = 6 * nodes.len();
    for c in 0..n {
        for r in 0..n {
            let (k, d) = (buf.dx[(r, c)], buf.dv[(r, c)]);
            if !(k.is_finite() && d.is_finite()) {
                return Err(refuse("its Jacobian is not finite"));
            }
            out.K[(r, c)] = -lambda * k;
            out.C[(r, c)] = -lambda * d;
        }
    }
    Ok(())
}

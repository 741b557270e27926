//! The residual of one body and its tangent matrices for Newton \[S19\]:
//! $\mathbf r(\mathbf q, \dot{\mathbf q}, \ddot{\mathbf q}) = \mathbf M\ddot{\mathbf q} + \mathbf Q_v + \mathbf f_{el} +
//! \mathbf f_d - \mathbf f_g$, $\mathbf K_t = \partial\mathbf r/\partial\mathbf q$,
//! $\mathbf C_t = \partial\mathbf r/\partial\dot{\mathbf q}$, $\mathbf M = \partial\mathbf r/\partial\ddot{\mathbf q}$.
//!
//! Naming rule: `evaluate` returns forces and tangents together (they share every
//! intermediate), `forces` the forces and the mass matrix without the tangents (left NaN),
//! `residual` the residual and its force parts alone; `*_force`-style pieces live in [`crate::forces`].
//!
//! # Variations
//!
//! $\partial/\partial\mathbf q$ is taken with spatial variations: $\mathbf r_k \leftarrow \mathbf r_k +
//! \delta\mathbf r_k$, $\mathbf R_k \leftarrow \exp(\widetilde{\delta\boldsymbol\pi}_k)\mathbf R_k$,
//! $\boldsymbol\eta \leftarrow \boldsymbol\eta + \delta\boldsymbol\eta$, at fixed spatial velocities
//! $\mathbf v_k, \boldsymbol\omega_k$ and accelerations; the frame is re-solved (its variation is
//! $\mathbf Z_j\boldsymbol\Lambda\bar{\mathbf R}^T\delta\mathbf q$, (5.4)).

#![allow(non_snake_case)]

use crate::body::{BodyState, Superelement};
use crate::error::SuperelementError;
use crate::forces::{Level, Local, Motion, Scratch};
use crate::frame::{Frame, FrameScratch, FrameSolve};
use crate::local_coordinates::local_coordinates;
use crate::mass::MassVariant;
use crate::planar::wrap;
use crate::so3::skew;
use crate::transform::{add_mul_w, gemm, rotate_matrix, rotate_stiffness, sub_mul_psi, Kinematics};
use faer::{Accum, Mat};
use nalgebra::Vector3;

/// Forces and tangents of one body in absolute interface coordinates, order
/// $[\mathbf r_1, \boldsymbol\pi_1, \dots, \mathbf r_N, \boldsymbol\pi_N, \boldsymbol\eta]$.
#[derive(Clone, Debug)]
pub struct Evaluation {
    /// The frame solving (4.4) for this state: store it in the state as the next warm start.
    pub frame: Frame,
    /// Newton iterations of the frame solve.
    pub frame_iterations: usize,
    /// $\mathbf q^{jj}$.
    pub q_jj: Vec<f64>,
    /// $\mathbf r = \mathbf f_{in} + \mathbf f_{el} + \mathbf f_d - \mathbf f_g$ (equals the external
    /// interface forces at a solution).
    pub residual: Vec<f64>,
    /// Inertia force $\mathbf M\ddot{\mathbf q} + \mathbf Q_v$.
    pub f_inertia: Vec<f64>,
    /// Quadratic velocity force $\mathbf Q_v = \mathbf f_{in} - \mathbf M\ddot{\mathbf q}$ (not updated by
    /// [`Superelement::residual_into`]).
    pub q_v: Vec<f64>,
    /// Elastic force (6.5).
    pub f_elastic: Vec<f64>,
    /// Damping force.
    pub f_damping: Vec<f64>,
    /// Gravity (a load: it enters the residual with a minus sign).
    pub f_gravity: Vec<f64>,
    /// $\mathbf M$ (not updated by [`Superelement::residual_into`]).
    pub mass: Mat<f64>,
    /// $\mathbf K_t = \partial\mathbf r/\partial\mathbf q$ (NaN after [`Superelement::forces_into`], which
    /// does not form it; not updated by [`Superelement::residual_into`]).
    pub stiffness: Mat<f64>,
    /// $\mathbf C_t = \partial\mathbf r/\partial\dot{\mathbf q}$ (NaN after [`Superelement::forces_into`];
    /// not updated by [`Superelement::residual_into`]).
    pub damping: Mat<f64>,
}

impl Evaluation {
    /// Zeroed output for a body with `n` coordinates.
    pub fn zeros(n: usize) -> Self {
        let [q_jj, residual, f_inertia, q_v, f_elastic, f_damping, f_gravity] = std::array::from_fn(|_| vec![0.0; n]);
        let [mass, stiffness, damping] = std::array::from_fn(|_| Mat::zeros(n, n));
        Self {
            frame: Frame::identity(),
            frame_iterations: 0,
            q_jj,
            residual,
            f_inertia,
            q_v,
            f_elastic,
            f_damping,
            f_gravity,
            mass,
            stiffness,
            damping,
        }
    }
}

/// Every buffer one evaluation needs, sized for one superelement ([`Superelement::workspace`]):
/// with [`Superelement::evaluate_into`] a hot loop does not allocate.
#[derive(Clone, Debug)]
pub struct Workspace {
    pub(crate) kin: Kinematics,
    /// `kin` holds a configuration of this body (its $(\boldsymbol\Phi_j\boldsymbol\Psi)^{-1}$
    /// starts the next frame solve: `frame::solve_frame_in`).
    pub(crate) kin_valid: bool,
    pub(crate) qd: Vec<f64>,
    pub(crate) mo: Motion,
    pub(crate) loc: Local,
    pub(crate) scratch: Scratch,
    pub(crate) KL: Mat<f64>,
    pub(crate) n6: Mat<f64>,
    pub(crate) rho: Vec<f64>,
    /// The buffers of a planar body ([`crate::planar`]).
    pub(crate) planar: Option<Box<crate::planar::PlanarWorkspace>>,
}

impl Workspace {
    /// The configuration of the last evaluation (frame, $\mathbf q^{jj}$, $\mathbf Z_j$, $\mathbf T_j$, ...).
    /// For a planar body ([`crate::Superelement::into_planar`]) the evaluation sets the frame,
    /// $\mathbf R_j$, $\mathbf q^{jj}$ (the $6N + m$ layout), $\mathbf r_k^{jj}$ and
    /// $\boldsymbol\Lambda$ only: [`Kinematics::is_complete`] is false, and
    /// [`Self::complete_kinematics`] forms every matrix (those of the spatial body at that
    /// configuration); [`Kinematics::Z`] and [`Kinematics::Y`] are NaN before it.
    /// After a forces-only evaluation ([`crate::Superelement::residual_into`]) $\mathbf T_j$ and
    /// $\mathbf B$ are not formed ([`Kinematics::T`] is `None`); [`Self::complete_kinematics`]
    /// forms them.
    pub fn kinematics(&self) -> &Kinematics {
        &self.kin
    }

    /// [`Self::kinematics`] with $\mathbf T_j$, $\mathbf B$ and $\mathbf Y_r^T$ formed
    /// ([`Kinematics::complete`]).
    pub fn complete_kinematics(&mut self) -> &Kinematics {
        self.kin.complete();
        &self.kin
    }
}

/// The public entry points of `Superelement::evaluate_level` (one function a [`Level`], not a
/// level switch, in the API): `into` ones into reused buffers, `alloc` ones allocating them
/// ([`Superelement::workspace`], [`Evaluation::zeros`]) for an `into` one.
macro_rules! level_entry_points {
    () => {};
    ($(#[$doc:meta])* alloc $alloc:ident => $into:ident; $($rest:tt)*) => {
        $(#[$doc])*
        pub fn $alloc(
            &self,
            state: &BodyState,
            acc: &[f64],
            gravity: &Vector3<f64>,
        ) -> Result<Evaluation, SuperelementError> {
            let mut ws = self.workspace();
            let mut out = Evaluation::zeros(self.n);
            self.$into(state, acc, gravity, &mut ws, &mut out)?;
            Ok(out)
        }
        level_entry_points! { $($rest)* }
    };
    ($(#[$doc:meta])* into $into:ident => $level:expr; $($rest:tt)*) => {
        $(#[$doc])*
        pub fn $into(
            &self,
            state: &BodyState,
            acc: &[f64],
            gravity: &Vector3<f64>,
            ws: &mut Workspace,
            out: &mut Evaluation,
        ) -> Result<(), SuperelementError> {
            self.evaluate_level(state, acc, gravity, $level, ws, out)
        }
        level_entry_points! { $($rest)* }
    };
}

impl Superelement {
    /// The planar evaluation behind [`Superelement::evaluate_into`] and
    /// [`Superelement::residual_into`]; the body sees the in-plane gravity `g2` only.
    pub(crate) fn planar_evaluate(
        &self,
        state: &BodyState,
        acc: &[f64],
        g2: [f64; 2],
        level: Level,
        ws: &mut Workspace,
        out: &mut Evaluation,
    ) -> Result<(), SuperelementError> {
        let pb = self.planar_body();
        let pw = ws.planar.as_deref_mut().expect("a planar workspace");
        let N = pb.N;
        let r_max = self.read_planar(state, &mut pw.pos, &mut pw.phi)?;
        let warm_angle = pw.warm_angle(&state.frame.R);
        let (frame, iterations, sc) =
            self.planar_frame(&pw.pos, &pw.phi, &state.eta, r_max, &state.frame, warm_angle, &mut pw.f)?;
        let rs = &pw.pos;
        let z = state.r[0].z - self.x[0].z;
        let b = &mut pw.f;
        for k in 0..N {
            b.q[3 * k] = rs[k][0];
            b.q[3 * k + 1] = rs[k][1];
            b.q[3 * k + 2] = frame.1 + wrap(pw.phi[k] - frame.1);
            b.qd[3 * k] = state.v[k].x;
            b.qd[3 * k + 1] = state.v[k].y;
            b.qd[3 * k + 2] = state.omega[k].z;
        }
        if let FrameSolve::AtInterface(k) = self.frame_solve {
            // The explicit frame: the interface's angle itself.
            b.q[3 * k + 2] = frame.1;
        }
        b.q[3 * N..].copy_from_slice(&state.eta);
        b.qd[3 * N..].copy_from_slice(&state.eta_dot);
        for (i, &g) in pb.index.iter().enumerate() {
            b.qdd[i] = acc[g];
        }
        pb.forces(b, frame, sc, self.frame_solve, g2);
        let Gi0 = b.Gi;
        // Outputs in the 6N + m layout.
        let n3 = self.n;
        for v in [
            &mut out.residual,
            &mut out.f_inertia,
            &mut out.f_elastic,
            &mut out.f_damping,
            &mut out.f_gravity,
            &mut out.q_jj,
        ] {
            v.fill(0.0);
        }
        {
            // Slices, not the vectors through `out` and `b` at every entry.
            let [p0, p1, p2, p3] = &b.parts;
            let (fi, fe, fd, fg) = (
                &mut out.f_inertia[..],
                &mut out.f_elastic[..],
                &mut out.f_damping[..],
                &mut out.f_gravity[..],
            );
            let (res, qj) = (&mut out.residual[..], &mut out.q_jj[..]);
            let (bo, bq) = (&b.out[..], &b.qjj[..]);
            for (i, &g) in pb.index.iter().enumerate() {
                fi[g] = p0[i];
                fe[g] = p1[i];
                fd[g] = p2[i];
                fg[g] = p3[i];
                res[g] = bo[i];
                qj[g] = bq[i];
            }
        }
        let frame3 = self.frame_3d(frame, z);
        pw.returned(&frame3.R, frame.1);
        out.frame = frame3;
        out.frame_iterations = iterations;
        // M and C_t in closed form, K_t by dual numbers.
        if level.mass() {
            pb.mass_damping(pw, level.tangents());
        }
        if level.tangents() {
            pb.stiffness_pass(pw, frame, sc, self.frame_solve, &Gi0, g2);
        }
        let n = pb.n;
        let scatter = |src: &[f64], dst: &mut Mat<f64>| {
            dst.fill(0.0);
            for (j, &gj) in pb.index.iter().enumerate() {
                let col = dst.col_as_slice_mut(gj);
                for (i, &gi) in pb.index.iter().enumerate() {
                    col[gi] = src[i + n * j];
                }
            }
        };
        if level.mass() {
            scatter(&pw.mats[2], &mut out.mass);
            out.q_v.copy_from_slice(&out.f_inertia);
            for (j, &gj) in pb.index.iter().enumerate() {
                let a = acc[gj];
                for (i, &gi) in pb.index.iter().enumerate() {
                    out.q_v[gi] -= pw.mats[2][i + n * j] * a;
                }
            }
        }
        if level.tangents() {
            scatter(&pw.mats[0], &mut out.stiffness);
            scatter(&pw.mats[1], &mut out.damping);
        }
        debug_assert_eq!(out.q_jj.len(), n3);
        ws.kin.set_planar(frame3, iterations, &out.q_jj, &self.x);
        ws.kin_valid = false;
        Ok(())
    }

    /// Buffers for [`Self::evaluate_into`].
    pub fn workspace(&self) -> Workspace {
        let (N, n) = (self.n_interfaces, self.n);
        let mut kin = Kinematics::empty(N, n);
        let planar = self.planar.as_ref().map(|pb| {
            kin.set_source(&self.x, &self.Phi_j);
            Box::new(crate::planar::PlanarWorkspace::new(pb))
        });
        Workspace {
            kin,
            kin_valid: false,
            qd: vec![0.0; n],
            mo: Motion::new(N, n),
            loc: Local::new(n),
            scratch: Scratch::new(N, n, self.geometric.is_some()),
            KL: Mat::zeros(n, n),
            n6: Mat::zeros(n, 6),
            rho: vec![0.0; n],
            planar,
        }
    }

    level_entry_points! {
        /// Forces and tangents of the body at `state` with accelerations `acc` ($[\mathbf a_1,
        /// \boldsymbol\alpha_1, \dots, \ddot{\boldsymbol\eta}]$, spatial) under gravity `gravity`.
        /// The frame is solved from `state.frame`. Allocates; see [`Self::evaluate_into`].
        alloc evaluate => evaluate_into;
        /// [`Self::evaluate`] into reused buffers: `ws` from [`Self::workspace`], `out` from
        /// [`Evaluation::zeros`]: the forces, the mass matrix and the tangents.
        into evaluate_into => Level::Tangents;

        /// The forces and the mass matrix without the tangents (cheaper, for explicit integrators
        /// and energy checks): `stiffness` and `damping` are NaN. Allocates; see
        /// [`Self::forces_into`].
        alloc forces => forces_into;
        /// [`Self::forces`] into reused buffers: the forces and the mass matrix only, none of the
        /// tangent-only partials formed (the FFR $\partial\mathbf F/\partial\boldsymbol\nu$,
        /// $\partial\mathbf F/\partial\mathbf q$, the geometric Hessian $\mathbf H_G$, $\mathbf N_y$): about 30 % fewer
        /// instructions than [`Self::evaluate_into`] (`benches/evaluate.rs`; checked equal to the full
        /// evaluation by `tests/unit/evaluation.rs`). `out.stiffness` and `out.damping` are filled
        /// with NaN, so that tangents of an earlier call cannot be read as this state's.
        /// [`Self::residual_into`] skips the mass matrix too.
        into forces_into => Level::Mass;

        /// The residual alone, the hot-loop form of a Newton iteration that reuses its iteration
        /// matrix: into `out` go `residual`, `f_inertia`, `f_elastic`, `f_damping`, `f_gravity`,
        /// `frame`, `frame_iterations` and `q_jj`; `mass`, `q_v`, `stiffness` and `damping` keep their
        /// old values. Neither the FFR mass matrix nor the body-axis mass $\mathbf P^T\mathbf M_{ffr}\mathbf P$
        /// nor its rotation is formed, and the inertia contractions skip those only the partials
        /// need (`benches/evaluate.rs`, `--profile=residual`). The forces equal those of
        /// [`Self::evaluate_into`] to round-off (`tests/unit/evaluation.rs`); the workspace holds the
        /// same configuration afterwards ([`Self::strain_energy_in`], [`Self::kinetic_energy_in`]).
        into residual_into => Level::Forces;
    }

    fn evaluate_level(
        &self,
        state: &BodyState,
        acc: &[f64],
        gravity: &Vector3<f64>,
        level: Level,
        ws: &mut Workspace,
        out: &mut Evaluation,
    ) -> Result<(), SuperelementError> {
        if level == Level::Mass {
            // No tangents are formed: NaN, so that those of an earlier call cannot be read.
            out.stiffness.fill(f64::NAN);
            out.damping.fill(f64::NAN);
        }
        if acc.len() != self.n {
            return Err(SuperelementError::InvalidState {
                what: format!("{} accelerations for {} coordinates", acc.len(), self.n),
            });
        }
        if self.is_planar() {
            if ws.planar.is_none() {
                *ws = self.workspace();
            }
            return self.planar_evaluate(state, acc, [gravity.x, gravity.y], level, ws, out);
        }
        // The Newton iterates of (4.4) live in the configuration's own buffers, which are
        // rebuilt for the converged frame right after.
        let mut scratch = FrameScratch {
            q: &mut ws.kin.q_jj,
            r_loc: &mut ws.kin.r_loc,
            Lambda: &mut ws.kin.Lambda,
            last_G_inv: ws.kin_valid.then_some(ws.kin.G_inv),
        };
        // The configuration is rebuilt below; a failure on the way leaves it invalid.
        ws.kin_valid = false;
        let (frame, iterations) = self.solve_frame_in(state, &mut scratch)?;
        if self.frame_solve != FrameSolve::Newton {
            // The Newton solve returns right after computing q_jj at the converged frame
            // (`frame::newton_frame`); the explicit frames compute none.
            local_coordinates(&frame, &state.r, &state.R, &self.x, &state.eta, &mut ws.kin.q_jj);
        }
        ws.kin
            .update(frame, iterations, &self.x, self.Phi_j.as_ref(), level.tangents())?;
        ws.kin_valid = true;
        for k in 0..self.n_interfaces {
            ws.qd[6 * k..6 * k + 3].copy_from_slice(state.v[k].as_slice());
            ws.qd[6 * k + 3..6 * k + 6].copy_from_slice(state.omega[k].as_slice());
        }
        ws.qd[6 * self.n_interfaces..].copy_from_slice(&state.eta_dot);
        self.evaluate_local(acc, gravity, level, ws, out);
        Ok(())
    }

    /// [`Self::evaluate`] for a configuration already solved ([`Self::kinematics`]); allocates.
    pub fn evaluate_kinematics(&self, kin: &Kinematics, qd: &[f64], acc: &[f64], gravity: &Vector3<f64>) -> Evaluation {
        self.kinematics_level(kin, qd, acc, gravity, Level::Tangents)
    }

    /// [`Self::forces`] for a configuration already solved ([`Self::kinematics`]): the forces and
    /// the mass matrix, `stiffness` and `damping` NaN; allocates.
    pub fn forces_kinematics(&self, kin: &Kinematics, qd: &[f64], acc: &[f64], gravity: &Vector3<f64>) -> Evaluation {
        let mut out = self.kinematics_level(kin, qd, acc, gravity, Level::Mass);
        out.stiffness.fill(f64::NAN);
        out.damping.fill(f64::NAN);
        out
    }

    fn kinematics_level(
        &self,
        kin: &Kinematics,
        qd: &[f64],
        acc: &[f64],
        gravity: &Vector3<f64>,
        level: Level,
    ) -> Evaluation {
        if self.is_planar() {
            // The state of the configuration: interfaces placed by the frame and q_jj.
            let N = self.n_interfaces;
            let mut state = BodyState {
                r: Vec::with_capacity(N),
                R: Vec::with_capacity(N),
                v: Vec::with_capacity(N),
                omega: Vec::with_capacity(N),
                eta: kin.q_jj[6 * N..].to_vec(),
                eta_dot: qd[6 * N..].to_vec(),
                frame: kin.frame,
            };
            for k in 0..N {
                let u = Vector3::new(kin.q_jj[6 * k], kin.q_jj[6 * k + 1], kin.q_jj[6 * k + 2]);
                let th = Vector3::new(kin.q_jj[6 * k + 3], kin.q_jj[6 * k + 4], kin.q_jj[6 * k + 5]);
                state.r.push(kin.frame.r + kin.R_j * (self.x[k] + u));
                state.R.push(kin.frame.R * crate::so3::exp(&th));
                state.v.push(Vector3::new(qd[6 * k], qd[6 * k + 1], qd[6 * k + 2]));
                state
                    .omega
                    .push(Vector3::new(qd[6 * k + 3], qd[6 * k + 4], qd[6 * k + 5]));
            }
            let mut ws = self.workspace();
            let mut out = Evaluation::zeros(self.n);
            // A configuration of this body solves its frame at once from its own frame; a
            // failure (a kinematics of another body) gives NaN outputs, never other numbers.
            if self
                .planar_evaluate(&state, acc, [gravity.x, gravity.y], level, &mut ws, &mut out)
                .is_err()
            {
                for v in [&mut out.residual, &mut out.f_inertia, &mut out.q_v, &mut out.f_elastic] {
                    v.fill(f64::NAN);
                }
            }
            return out;
        }
        let mut ws = self.workspace();
        ws.kin = kin.clone();
        ws.qd.copy_from_slice(qd);
        let mut out = Evaluation::zeros(self.n);
        self.evaluate_local(acc, gravity, level, &mut ws, &mut out);
        out
    }

    /// The forces and tangents for the configuration and velocities in `ws`.
    ///
    /// # Derivation
    /// Every force is $\bar{\mathbf R}\boldsymbol\rho(\mathbf q^{jj}, \mathbf y, \mathbf a, \mathbf g^L)$
    /// ([`crate::forces`]). A variation $\delta\mathbf q$ moves $\mathbf q^{jj}$ by
    /// $\mathbf B\,\delta\mathbf q^L$ ($\delta\mathbf q^L = \bar{\mathbf R}^T\delta\mathbf q$) and turns the
    /// body axes by $\delta\boldsymbol\Pi = \mathbf Y_r\delta\mathbf q^L$, which changes the body-axis
    /// images of the fixed spatial vectors, $\delta\mathbf y = \mathbf W(\mathbf y)\delta\boldsymbol\Pi$
    /// (likewise $\mathbf a$, $\mathbf g^L$), and rotates the result, $\delta(\bar{\mathbf R}\boldsymbol\rho)
    /// = \bar{\mathbf R}(\delta\boldsymbol\rho - \mathbf W(\boldsymbol\rho)\delta\boldsymbol\Pi)$. Hence
    ///
    /// $$\mathbf K_t = \bar{\mathbf R}\Big[\frac{\partial\boldsymbol\rho}{\partial\mathbf q^{jj}}\mathbf B +
    /// \Big(\frac{\partial\boldsymbol\rho}{\partial\mathbf y}\mathbf W(\mathbf y) + \mathbf M^L\mathbf W(\mathbf a) +
    /// \frac{\partial\boldsymbol\rho}{\partial\mathbf g^L}\tilde{\mathbf g}^L - \mathbf W(\boldsymbol\rho)\Big)\mathbf Y_r\Big]\bar{\mathbf R}^T,$$
    ///
    /// $\mathbf C_t = \bar{\mathbf R}\,\partial\boldsymbol\rho/\partial\mathbf y\,\bar{\mathbf R}^T$,
    /// $\mathbf M = \bar{\mathbf R}\mathbf M^L\bar{\mathbf R}^T$. The term $\mathbf M^L\mathbf W(\mathbf a)\mathbf Y_r$
    /// (with the $\mathbf q^{jj}$-dependence of $\mathbf M^L$ inside $\partial\boldsymbol\rho/\partial\mathbf q^{jj}$)
    /// is $\partial(\mathbf M\ddot{\mathbf q})/\partial\mathbf q$. Checked entry by entry against
    /// central differences by `tests/unit/fd_tangent.rs::tangents_match_fd`.
    fn evaluate_local(
        &self,
        acc: &[f64],
        gravity: &Vector3<f64>,
        level: Level,
        ws: &mut Workspace,
        out: &mut Evaluation,
    ) {
        let tangents = level.tangents();
        let n = self.n;
        let N = self.n_interfaces;
        let kin = &ws.kin;
        let mo = &mut ws.mo;
        mo.update(kin, &ws.qd, acc, gravity, tangents);
        let loc = &mut ws.loc;
        let w = &mut ws.scratch;
        loc.clear(tangents);
        self.elastic(kin, loc, w, tangents);
        self.damping_force(kin, mo, loc, w, tangents);
        self.gravity(kin, mo, loc, w, tangents);
        if self.mass_variant == MassVariant::Exact {
            self.exact_inertia(kin, mo, loc, w, level);
        }
        if tangents {
            // The forces above left out the common left factors X^T (`Local::XE`) and
            // Lambda^T (`Local::Dq`).
            loc.apply_x_t(kin, &mut w.six_2n, &mut w.n_2n);
            loc.apply_lambda_t(&kin.Lambda);
        }
        if self.mass_variant == MassVariant::Lumped {
            self.lumped_inertia(kin, mo, loc, w, level);
        }
        let R = &kin.R_j;
        kin.to_inertial_into(&loc.rho_in, &mut out.f_inertia);
        kin.to_inertial_into(&loc.rho_el, &mut out.f_elastic);
        kin.to_inertial_into(&loc.rho_d, &mut out.f_damping);
        kin.to_inertial_into(&loc.rho_g, &mut out.f_gravity);
        // The residual from its rotated parts (one rotation fewer); the tangents need it in body
        // axes too.
        for i in 0..n {
            out.residual[i] = out.f_inertia[i] + out.f_elastic[i] + out.f_damping[i] - out.f_gravity[i];
        }
        if tangents {
            for i in 0..n {
                ws.rho[i] = loc.rho_in[i] + loc.rho_el[i] + loc.rho_d[i] - loc.rho_g[i];
            }
        }
        if level.mass() {
            rotate_matrix(R, N, &loc.M, &mut out.mass);
            out.q_v.copy_from_slice(&out.f_inertia);
            for j in 0..n {
                let a = acc[j];
                for (q, m) in out.q_v.iter_mut().zip(out.mass.col_as_slice(j)) {
                    *q -= m * a;
                }
            }
        }
        out.frame = kin.frame;
        out.frame_iterations = kin.frame_iterations;
        out.q_jj.copy_from_slice(&kin.q_jj);
        if !tangents {
            return;
        }
        kin.add_d_pt(&loc.F_sum, &mut ws.scratch.v1, &mut loc.Dq, 1.0);
        // K^L = Dq B + H Y_r, H = Dy W(y) + M W(a) + Dg g~ - W(rho). With B = T Lambda,
        // T = I - Psi Z and Y = Z Lambda: K^L = Dq Lambda + (-(Dq Psi) + [0, H]) Y, one product
        // with Y for both terms; H is formed in columns 3..6 of that n x 6 factor (`n6`).
        ws.n6.fill(0.0);
        sub_mul_psi(loc.Dq.as_ref(), &kin.r_loc, &kin.Lambda, &mut ws.n6);
        for b in 0..2 * N {
            let S = skew(&Vector3::new(ws.rho[3 * b], ws.rho[3 * b + 1], ws.rho[3 * b + 2]));
            for c in 0..3 {
                let h = &mut ws.n6.col_as_slice_mut(3 + c)[3 * b..3 * b + 3];
                for i in 0..3 {
                    h[i] -= S[(i, c)];
                }
            }
        }
        add_mul_w(loc.Dy.as_ref(), &mo.y, 2 * N, 1.0, &mut ws.n6, 3);
        add_mul_w(loc.M.as_ref(), &mo.a, 2 * N, 1.0, &mut ws.n6, 3);
        // Dg is left at zero without gravity (`forces.rs`, `gravity`), where g~ = 0 anyway.
        add_mul_w(loc.Dg.as_ref(), mo.g.as_slice(), 1, 1.0, &mut ws.n6, 3);
        // K^L = Dq Lambda + n6 Y: the product here, Dq Lambda inside the rotation.
        gemm(&mut ws.KL, ws.n6.as_ref(), kin.Y(), 1.0, Accum::Replace);
        rotate_stiffness(R, &kin.Lambda, &loc.Dq, &ws.KL, &mut out.stiffness);
        rotate_matrix(R, N, &loc.Dy, &mut out.damping);
    }

    /// Kinetic energy $\tfrac12\dot{\mathbf q}^T\mathbf M\dot{\mathbf q}$ of the chosen inertia variant.
    pub fn kinetic_energy(&self, state: &BodyState) -> Result<f64, SuperelementError> {
        if self.is_planar() {
            let (frame, _) = self.solve_frame(state)?;
            let kin = self.kinematics_at(state, frame, 0)?;
            let q = self.planar_q(&kin.q_jj);
            let y = self.planar_y(&frame, &state.velocity_vector());
            return self.planar_body().kinetic(&q, &y);
        }
        let kin = self.kinematics(state)?;
        let qd = state.velocity_vector();
        let ev = self.forces_kinematics(&kin, &qd, &vec![0.0; self.n], &Vector3::zeros());
        let mut T = 0.0;
        for j in 0..self.n {
            for i in 0..self.n {
                T += 0.5 * qd[i] * ev.mass[(i, j)] * qd[j];
            }
        }
        Ok(T)
    }

    /// Strain energy $U = \tfrac12\mathbf q^{jjT}\mathbf K_{CB}\mathbf q^{jj}$, plus $U_3 + U_4$ for a body
    /// with geometric stiffening ([`crate::body::GeometricStiffness`]). The elastic force is its
    /// gradient (`tests/unit/energy.rs`, `tests/unit/geometric.rs`).
    pub fn strain_energy(&self, kin: &Kinematics) -> f64 {
        if self.is_planar() {
            return self.planar_body().strain_energy(&self.planar_q(&kin.q_jj));
        }
        let mut f = vec![0.0; self.n];
        crate::mass::matvec(&self.K_CB, &kin.q_jj, &mut f);
        let U = 0.5 * f.iter().zip(&kin.q_jj).map(|(a, b)| a * b).sum::<f64>();
        match &self.geometric {
            Some(G) => U + G.energy(&kin.q_jj),
            None => U,
        }
    }

    /// [`Self::strain_energy`] at the configuration of the last [`Self::evaluate_into`] with
    /// `ws`, from what that evaluation formed: $\tfrac12\mathbf q^{jjT}\mathbf K_{CB}\mathbf q^{jj}$ plus,
    /// with geometric stiffening, $U_3 + U_4 = \mathbf q^{jjT}\mathbf b + \tfrac12\mathbf b^T\mathbf p$ with
    /// the evaluation's $\mathbf b$ and $\mathbf p$ ([`crate::body::GeometricStiffness`]), so no product
    /// with the $n^3$ entries of $\mathbf G$ and no allocation (an energy sensor at every step).
    /// Checked equal to [`Self::strain_energy`] by `tests/unit/geometric.rs`.
    pub fn strain_energy_in(&self, ws: &Workspace) -> f64 {
        if let (true, Some(pw)) = (self.is_planar(), &ws.planar) {
            let b = &pw.f;
            let q = &b.qjj;
            let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
            // fe = K q + b + sum_k (q_k + p_k) G_k q: U = q.(K q)/2 + q.b + b.p/2.
            let pb = self.planar_body();
            let mut U = 0.0;
            for (j, qj) in q.iter().enumerate() {
                let kq: f64 = pb.K[pb.n * j..pb.n * (j + 1)].iter().zip(q).map(|(k, x)| k * x).sum();
                U += 0.5 * qj * kq;
            }
            if pb.geometric.is_some() {
                U += dot(q, &b.b) + 0.5 * dot(&b.b, &b.p);
            }
            return U;
        }
        let q = &ws.kin.q_jj;
        let mut U = 0.0;
        for (j, qj) in q.iter().enumerate() {
            let kq: f64 = self.K_CB.col_as_slice(j).iter().zip(q).map(|(k, x)| k * x).sum();
            U += 0.5 * qj * kq;
        }
        if self.geometric.is_some() {
            let g = &ws.scratch.geometric;
            let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
            U += dot(q, &g.b) + 0.5 * dot(&g.b, &g.p);
        }
        U
    }

    /// [`Self::kinetic_energy`] at the configuration of the last evaluation with `ws`
    /// ([`Self::evaluate_into`] or [`Self::residual_into`], which forms no mass matrix) for the
    /// velocities `qd` (the order of [`BodyState::velocity_vector`]), without the $n\times n$ mass
    /// in absolute coordinates: with $\mathbf y = \bar{\mathbf R}^T\dot{\mathbf q}$ it is
    /// $\tfrac12\boldsymbol\nu^T\mathbf M_{ffr}\boldsymbol\nu$, $\boldsymbol\nu = \mathbf P\mathbf y$
    /// (`Exact`; $\mathbf M = \bar{\mathbf R}\mathbf P^T\mathbf M_{ffr}\mathbf P\bar{\mathbf R}^T$), or
    /// $\tfrac12\mathbf y^T\mathbf M_{CB}\mathbf y$ (`Lumped`). Allocates a few small buffers (an energy
    /// sensor). Checked equal to [`Self::kinetic_energy`] by `tests/unit/evaluation.rs`.
    pub fn kinetic_energy_in(&self, ws: &Workspace, qd: &[f64]) -> Result<f64, SuperelementError> {
        if qd.len() != self.n {
            return Err(SuperelementError::InvalidState {
                what: format!("{} velocities for {} coordinates", qd.len(), self.n),
            });
        }
        if self.is_planar() {
            // The evaluation's own velocities (an energy sensor after a step): from its buffers.
            if let Some(pw) = &ws.planar {
                let pb = self.planar_body();
                if pb.index.iter().zip(&pw.f.qd).all(|(&g, v)| qd[g] == *v) {
                    return Ok(pb.kinetic_in(&pw.f));
                }
            }
            let q = self.planar_q(&ws.kin.q_jj);
            let y = self.planar_y(&ws.kin.frame, qd);
            return self.planar_body().kinetic(&q, &y);
        }
        let kin = &ws.kin;
        // y, and nu = [xi; c] as the evaluation forms them (from the frame rows of P, the
        // deformed interface positions and Lambda).
        let mut mo = Motion::new(self.n_interfaces, self.n);
        mo.update(kin, qd, &vec![0.0; self.n], &Vector3::zeros(), false);
        let quadratic = |M: &Mat<f64>, v: &[f64]| {
            let mut T = 0.0;
            for (j, vj) in v.iter().enumerate() {
                let Mv: f64 = M.col_as_slice(j).iter().zip(v).map(|(m, x)| m * x).sum();
                T += 0.5 * vj * Mv;
            }
            T
        };
        Ok(match self.mass_variant {
            MassVariant::Lumped => quadratic(&self.M_CB, &mo.y),
            MassVariant::Exact => {
                let nu: Vec<f64> = mo.xi.iter().chain(&mo.c).copied().collect();
                self.inertia.kinetic_energy(&kin.q_jj, &nu)
            }
        })
    }

    /// Gravity potential $-\mathbf g\cdot(m\mathbf r_j + \mathbf R_j\mathbf s)$, $\mathbf s = m\mathbf d + \mathbf S_t\mathbf q^{jj}$.
    ///
    /// A planar body sees the x, y components of gravity only (a z component does no work in
    /// the plane).
    pub fn gravity_potential(&self, kin: &Kinematics, gravity: &Vector3<f64>) -> f64 {
        let in_plane;
        let gravity = if self.is_planar() {
            in_plane = Vector3::new(gravity.x, gravity.y, 0.0);
            &in_plane
        } else {
            gravity
        };
        let I = &self.inertia;
        let s: Vector3<f64> = I.d * I.mass + crate::mass::mul3(&I.S_t, &kin.q_jj);
        -gravity.dot(&(kin.frame.r * I.mass + kin.R_j * s))
    }
}

//! Test helpers shared with the multibody crate: the one central-difference
//! helper with its worst-entry report, state perturbations through the exponential map,
//! deterministic deformed moving states and a synthetic geometric stiffness; `fixtures` builds
//! reduced beam bodies through `fe-model` and `reduction`. Compiled into every build (a few
//! hundred lines, dropped by the linker where unused): a feature that added them for tests
//! gave the library two builds, one for the tests and one for the program.

#![allow(non_snake_case)]

use crate::body::{BodyState, Superelement};
use crate::frame::Frame;
use crate::so3;
use faer::{Mat, MatRef};
use nalgebra::{UnitQuaternion, Vector3};

/// Result of comparing an analytic Jacobian with central differences.
#[derive(Clone, Debug)]
pub struct FdReport {
    pub name: String,
    /// Worst $|a_{ij} - n_{ij}| / s_{ij}$ (see [`compare`]).
    pub worst: f64,
    pub row: usize,
    pub col: usize,
    pub analytic: f64,
    pub numeric: f64,
    pub scale: f64,
}

impl std::fmt::Display for FdReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}: worst relative error {:.3e} at ({}, {}): analytic {:.9e}, central difference {:.9e} (scale {:.3e})",
            self.name, self.worst, self.row, self.col, self.analytic, self.numeric, self.scale
        )
    }
}

/// Central differences of `f` ($\mathbb R^{n_{in}} \to \mathbb R^{n_{out}}$) at $\boldsymbol\delta = 0$:
/// column $j$ is $(\mathbf f(h_j\mathbf e_j) - \mathbf f(-h_j\mathbf e_j))/(2h_j)$. `f` receives the
/// perturbation vector and maps it to whatever it perturbs (use [`perturb_state`] for
/// states: rotations go through the exponential map).
pub fn fd_jacobian(steps: &[f64], mut f: impl FnMut(&[f64]) -> Vec<f64>) -> Mat<f64> {
    let n_in = steps.len();
    let mut cols: Vec<Vec<f64>> = Vec::with_capacity(n_in);
    let mut d = vec![0.0; n_in];
    for j in 0..n_in {
        d[j] = steps[j];
        let fp = f(&d);
        d[j] = -steps[j];
        let fm = f(&d);
        d[j] = 0.0;
        cols.push(fp.iter().zip(&fm).map(|(a, b)| (a - b) / (2.0 * steps[j])).collect());
    }
    let n_out = cols.first().map_or(0, |c| c.len());
    Mat::from_fn(n_out, n_in, |i, j| cols[j][i])
}

/// Worst entry of `analytic - numeric`, each entry measured against $s_{ij} = \max(\text{largest
/// entry of row } i, \text{largest entry of column } j, 10^{-7}\times\text{largest entry})$ of
/// either matrix.
///
/// Row and column scales keep a small block (an inertia term next to a stiffness term of
/// another row) from hiding behind the largest entry; the $10^{-7}$ floor keeps entries that
/// are zero analytically, where the difference quotient returns round-off, from dividing by zero.
pub fn compare(name: &str, analytic: MatRef<'_, f64>, numeric: MatRef<'_, f64>) -> FdReport {
    assert_eq!(
        (analytic.nrows(), analytic.ncols()),
        (numeric.nrows(), numeric.ncols()),
        "{name}: shapes differ"
    );
    let (m, n) = (analytic.nrows(), analytic.ncols());
    let a = |i, j| analytic[(i, j)];
    let b = |i, j| numeric[(i, j)];
    let mut row_max = vec![0.0f64; m];
    let mut col_max = vec![0.0f64; n];
    let mut global = 0.0f64;
    for j in 0..n {
        for i in 0..m {
            let v = a(i, j).abs().max(b(i, j).abs());
            row_max[i] = row_max[i].max(v);
            col_max[j] = col_max[j].max(v);
            global = global.max(v);
        }
    }
    let mut rep = FdReport {
        name: name.into(),
        worst: 0.0,
        row: 0,
        col: 0,
        analytic: 0.0,
        numeric: 0.0,
        scale: 0.0,
    };
    for j in 0..n {
        for i in 0..m {
            let s = row_max[i].max(col_max[j]).max(1e-7 * global).max(f64::MIN_POSITIVE);
            let e = (a(i, j) - b(i, j)).abs() / s;
            if e > rep.worst || !e.is_finite() {
                rep = FdReport {
                    name: name.into(),
                    worst: e,
                    row: i,
                    col: j,
                    analytic: a(i, j),
                    numeric: b(i, j),
                    scale: s,
                };
            }
        }
    }
    rep
}

/// [`fd_jacobian`] then [`compare`].
pub fn check_jacobian(
    name: &str,
    analytic: MatRef<'_, f64>,
    steps: &[f64],
    f: impl FnMut(&[f64]) -> Vec<f64>,
) -> FdReport {
    let numeric = fd_jacobian(steps, f);
    compare(name, analytic, numeric.as_ref())
}

/// The state moved by $\delta\mathbf q = [\delta\mathbf r_1, \delta\boldsymbol\pi_1, \dots, \delta\boldsymbol\eta]$:
/// $\mathbf r_k + \delta\mathbf r_k$, $\exp(\widetilde{\delta\boldsymbol\pi}_k)\mathbf R_k$ (spatial),
/// $\boldsymbol\eta + \delta\boldsymbol\eta$; velocities unchanged.
pub fn perturb_state(state: &BodyState, dq: &[f64]) -> BodyState {
    let N = state.r.len();
    let mut s = state.clone();
    for k in 0..N {
        s.r[k] += Vector3::new(dq[6 * k], dq[6 * k + 1], dq[6 * k + 2]);
        s.R[k] = so3::perturb(&s.R[k], &Vector3::new(dq[6 * k + 3], dq[6 * k + 4], dq[6 * k + 5]));
    }
    for (e, d) in s.eta.iter_mut().zip(&dq[6 * N..]) {
        *e += d;
    }
    s
}

/// The state with velocities $\dot{\mathbf q} + \delta\dot{\mathbf q}$.
pub fn perturb_velocity(state: &BodyState, dqd: &[f64]) -> BodyState {
    let N = state.r.len();
    let mut s = state.clone();
    for k in 0..N {
        s.v[k] += Vector3::new(dqd[6 * k], dqd[6 * k + 1], dqd[6 * k + 2]);
        s.omega[k] += Vector3::new(dqd[6 * k + 3], dqd[6 * k + 4], dqd[6 * k + 5]);
    }
    for (e, d) in s.eta_dot.iter_mut().zip(&dqd[6 * N..]) {
        *e += d;
    }
    s
}

/// Deterministic numbers in $[-1, 1)$ (splitmix64), so tests need no random crate and
/// always see the same states.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
    pub fn vector(&mut self) -> Vector3<f64> {
        Vector3::new(self.uniform(), self.uniform(), self.uniform())
    }
}

/// How far a test state is from the undeformed body at rest.
#[derive(Clone, Copy, Debug)]
pub struct StateSpec {
    /// Rotation of the body from the FE axes: angle \[deg\] about `axis`.
    pub angle_deg: f64,
    pub axis: Vector3<f64>,
    /// Elastic interface displacements (times the body size), elastic rotations \[rad\] and
    /// modal amplitudes (times the body size and the square root of the mass).
    pub deformation: f64,
    /// Rigid angular velocity \[rad/s\]; linear velocities scale with it and the body size,
    /// elastic rates with it and `deformation`, accelerations with its square.
    pub spin: f64,
    pub seed: u64,
}

impl StateSpec {
    /// A rotated (`angle_deg` about a skew axis), deformed (2%) and moving (3 rad/s) state.
    pub fn moving(angle_deg: f64, seed: u64) -> Self {
        Self {
            angle_deg,
            axis: Vector3::new(0.3, -0.5, 0.8),
            deformation: 0.02,
            spin: 3.0,
            seed,
        }
    }
}

/// The size $L$ of `se` that the test states and steps scale with: its farthest interface from
/// the frame origin, at least 0.1.
pub fn body_size(se: &Superelement) -> f64 {
    se.interface_positions()
        .iter()
        .map(|x| x.norm())
        .fold(0.0, f64::max)
        .max(0.1)
}

/// A deformed, rotated, moving state of `se` and accelerations for it (module docs). The warm
/// start is the rigid placement, a few percent of the body size away from the solution.
pub fn test_state(se: &Superelement, spec: &StateSpec) -> (BodyState, Vec<f64>) {
    let mut rng = Rng::new(spec.seed);
    let N = se.n_interfaces();
    let m = se.n_modes();
    let L = body_size(se);
    let R0 = UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(spec.axis), spec.angle_deg.to_radians());
    let r0 = Vector3::new(0.3, -0.7, 1.1) * L;
    let frame = Frame::new(r0, R0);
    let v0 = rng.vector() * (spec.spin * L);
    let w0 = rng.vector().normalize() * spec.spin;
    let mut s = se.rigid_state(frame, v0, w0);
    let e = spec.deformation;
    for k in 0..N {
        s.r[k] += R0 * (rng.vector() * (e * L));
        s.R[k] = so3::exp(&(R0 * (rng.vector() * e))) * s.R[k];
        s.v[k] += rng.vector() * (spec.spin * e * L);
        s.omega[k] += rng.vector() * (spec.spin * e);
    }
    let eta_scale = e * L * se.mass().sqrt();
    for i in 0..m {
        s.eta[i] = rng.uniform() * eta_scale;
        s.eta_dot[i] = rng.uniform() * eta_scale * spec.spin;
    }
    let mut acc = vec![0.0; 6 * N + m];
    for k in 0..N {
        let a = rng.vector() * (spec.spin * spec.spin * L);
        let al = rng.vector() * (spec.spin * spec.spin);
        acc[6 * k..6 * k + 3].copy_from_slice(a.as_slice());
        acc[6 * k + 3..6 * k + 6].copy_from_slice(al.as_slice());
    }
    for i in 0..m {
        acc[6 * N + i] = rng.uniform() * eta_scale * spec.spin * spec.spin;
    }
    (s, acc)
}

/// A state of a planar body ([`Superelement::into_planar`]) for tests and benches: the
/// undeformed body turned by `angle` (rad) about z with its frame origin at (0.3, -0.7, 0.25),
/// deformed in the plane (2 % of the body size, 0.02 rad, modal amplitudes alike), moving
/// (3 rad/s about z, in-plane velocities, modal rates), and in-plane accelerations in the
/// $6N + m$ layout (zero out of plane).
pub fn planar_test_state(se: &Superelement, angle: f64, seed: u64) -> (BodyState, Vec<f64>) {
    let mut rng = Rng::new(seed);
    let N = se.n_interfaces();
    let m = se.n_modes();
    let L = body_size(se);
    let R0 = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), angle);
    let frame = Frame::new(Vector3::new(0.3, -0.7, 0.25), R0);
    let (spin, e) = (3.0, 0.02);
    let planar = |s: f64, rng: &mut Rng| Vector3::new(rng.uniform() * s, rng.uniform() * s, 0.0);
    let v0 = planar(spin * L, &mut rng);
    let mut s = se.rigid_state(frame, v0, Vector3::new(0.0, 0.0, spin));
    for k in 0..N {
        s.r[k] += R0 * planar(e * L, &mut rng);
        s.R[k] = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), rng.uniform() * e) * s.R[k];
        s.v[k] += planar(spin * e * L, &mut rng);
        s.omega[k].z += rng.uniform() * spin * e;
    }
    let eta_scale = e * L * se.mass().sqrt();
    for i in 0..m {
        s.eta[i] = rng.uniform() * eta_scale;
        s.eta_dot[i] = rng.uniform() * eta_scale * spin;
    }
    let mut acc = vec![0.0; 6 * N + m];
    for k in 0..N {
        let a = planar(spin * spin * L, &mut rng);
        acc[6 * k] = a.x;
        acc[6 * k + 1] = a.y;
        acc[6 * k + 5] = rng.uniform() * spin * spin;
    }
    for i in 0..m {
        acc[6 * N + i] = rng.uniform() * eta_scale * spin * spin;
    }
    (s, acc)
}

/// How a superelement stores its reduced geometric stiffness ([`crate::compressed`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Compression {
    /// Compressed (`None`: the body has no geometric stiffness).
    pub geometric: Option<bool>,
    /// The $k$ of the nonzero $\mathbf G_k$.
    pub nonzero_G: Vec<usize>,
    /// Entries stored of all $\mathbf G_k$ together.
    pub stored: usize,
}

/// How `se` stores its reduced geometric stiffness.
pub fn compression(se: &Superelement) -> Compression {
    let G = se.geometric.as_ref();
    Compression {
        geometric: G.map(|G| G.compressed),
        nonzero_G: G.map_or(Vec::new(), |G| G.nonzero.iter().map(|(k, _)| *k).collect()),
        stored: G.map_or(0, |G| G.nonzero.iter().map(|(_, A)| A.stored()).sum()),
    }
}

/// A copy of `se` that uses the dense $\mathbf G_k$ (the general path that the compressed one
/// is checked against).
pub fn without_compression(se: &Superelement) -> Superelement {
    let mut dense = se.clone();
    if let Some(G) = dense.geometric.as_mut() {
        G.compressed = false;
    }
    dense
}

/// Typical magnitudes of the CB coordinates of [`test_state`] at relative deformation
/// `deformation`: $e L$ for interface displacements, $e$ for elastic rotations and
/// $e L\sqrt m$ for modal coordinates ($L$: farthest interface from the frame origin, at least
/// 0.1; $m$: the mass), as [`test_state`] draws them.
pub fn coordinate_scales(se: &Superelement, deformation: f64) -> Vec<f64> {
    let L = body_size(se);
    let mut s = Vec::with_capacity(se.n_coordinates());
    for _ in 0..se.n_interfaces() {
        s.extend([deformation * L; 3]);
        s.extend([deformation; 3]);
    }
    s.extend(vec![deformation * L * se.mass().sqrt(); se.n_modes()]);
    s
}

/// A synthetic geometric stiffness for `body` (for [`reduction::ReducedBody::geometric_stiffness`])
/// with the structure of a physical one: $\mathbf G_m = \sum_l (\mathbf K_{CB})_{ml}\mathbf S_l$ with random
/// symmetric $(\mathbf S_l)_{ij} = \gamma\,r_{lij}\,s_l/(s_i s_j\sqrt n)$, $r_{lij} = r_{lji}$ uniform in
/// $[-1, 1)$ ([`Rng`] from `seed`), $s_k$ = `scales[k]` (e.g. [`coordinate_scales`]).
///
/// Then $b_m = \tfrac12\mathbf q^T\mathbf G_m\mathbf q = (\mathbf K_{CB}\mathbf p)_m$ with $p_l = \tfrac12\mathbf q^T\mathbf S_l\mathbf q$:
/// like the work of a quadratic strain on the stresses of the CB coordinates, $\mathbf b$ lies in
/// the range of $\mathbf K_{CB}$ (rigid motions have no stress), and at coordinates of size $s_k$,
/// $\mathbf p \approx \gamma\mathbf q$: the geometric tangent is about $\gamma$ times $\mathbf K_{CB}$, the cubic energy
/// $\gamma$ and the quartic one $\gamma^2$ times the linear one. A test of the geometric terms is neither
/// dominated by them nor blind to them.
pub fn synthetic_geometric_stiffness(
    body: &reduction::ReducedBody,
    scales: &[f64],
    gamma: f64,
    seed: u64,
) -> Vec<reduction::DenseMatrix> {
    let n = body.n_coordinates();
    assert_eq!(scales.len(), n, "one scale per CB coordinate");
    let mut rng = Rng::new(seed);
    let S: Vec<Vec<f64>> = (0..n)
        .map(|l| {
            let mut S = vec![0.0; n * n];
            for j in 0..n {
                for i in 0..=j {
                    let v = gamma * rng.uniform() * scales[l] / (scales[i] * scales[j] * (n as f64).sqrt());
                    S[i + n * j] = v;
                    S[j + n * i] = v;
                }
            }
            S
        })
        .collect();
    let K = &body.K_CB.data;
    (0..n)
        .map(|m| {
            let mut G = reduction::DenseMatrix::zeros(n, n);
            for (l, Sl) in S.iter().enumerate() {
                let k = K[m + n * l];
                for (g, s) in G.data.iter_mut().zip(Sl) {
                    *g += k * s;
                }
            }
            G
        })
        .collect()
}

/// Reduced beam bodies for tests, built through `fe-model` and `reduction`.
pub mod fixtures {
    use fe_model::{BeamProperties, BeamSection, BeamTheory, FeModel, IsotropicMaterial, MassKind, NodeId};
    use nalgebra::{Point3, Vector3};
    use reduction::{reduce, CbSettings, ModeSelection, ReducedBody};

    /// Aluminium-like rectangle 50 x 30 mm: $I_y \ne I_z$, so no direction is special.
    pub fn properties(model: &mut FeModel, orientation: Vector3<f64>) -> BeamProperties {
        let material = model.add_material(IsotropicMaterial::new("aluminium", 70e9, 0.33, 2700.0).unwrap());
        let section = model.add_section(BeamSection::rectangle("rect", 0.05, 0.03, 0.33).unwrap());
        BeamProperties {
            section,
            material,
            orientation,
            theory: BeamTheory::EulerBernoulli,
            mass: MassKind::Consistent,
        }
    }

    /// A straight beam of `elements` elements from `a` to `b` with interfaces at both ends (and,
    /// with `auxiliary`, an auxiliary interface at the middle node: `elements` must be even).
    /// Returns the FE model, the interface nodes (in the body's interface order, the auxiliary
    /// one last) and the reduced body.
    pub fn straight_beam(
        a: Point3<f64>,
        b: Point3<f64>,
        elements: usize,
        modes: ModeSelection,
        auxiliary: bool,
    ) -> (FeModel, Vec<NodeId>, ReducedBody) {
        straight_beam_with(a, b, elements, CbSettings::new(modes), auxiliary)
    }

    /// [`straight_beam`] reduced with `settings` (e.g. with `geometric_stiffening`); its
    /// `auxiliary_node` is set from `auxiliary`.
    pub fn straight_beam_with(
        a: Point3<f64>,
        b: Point3<f64>,
        elements: usize,
        mut settings: CbSettings,
        auxiliary: bool,
    ) -> (FeModel, Vec<NodeId>, ReducedBody) {
        let mut model = FeModel::default();
        let axis = b - a;
        let orientation = axis.cross(&Vector3::new(0.3, 0.9, -0.2)).normalize();
        let props = properties(&mut model, orientation);
        let nodes = fe_model::generate::straight_beam(&mut model, a, b, elements, &props, Some("beam")).unwrap();
        let mut ends = vec![nodes[0], nodes[elements]];
        settings.auxiliary_node = None;
        if auxiliary {
            assert!(
                elements.is_multiple_of(2),
                "the auxiliary node is the middle node: use an even element count"
            );
            settings.auxiliary_node = Some(nodes[elements / 2]);
        }
        let interfaces: Vec<(String, NodeId)> = ends.iter().enumerate().map(|(i, n)| (format!("end{i}"), *n)).collect();
        let body = reduce(&model, "beam", &interfaces, &settings).unwrap();
        if auxiliary {
            // The reduction appends the auxiliary interface last.
            ends.push(nodes[elements / 2]);
        }
        (model, ends, body)
    }

    /// A straight beam of `elements` elements from `a` to `b` in a plane z = const (section
    /// axis along z) with interfaces at both ends: with `supported`, the out-of-plane dofs (uz,
    /// rx, ry) of its internal nodes are held, so that its fixed-interface modes are in-plane and
    /// it can be evaluated as a planar body ([`crate::Superelement::into_planar`]). Returns the FE
    /// model, the interface nodes and the reduced body (name "rod", interfaces "a" and "b").
    pub fn planar_beam(
        a: Point3<f64>,
        b: Point3<f64>,
        elements: usize,
        settings: CbSettings,
        supported: bool,
    ) -> (FeModel, Vec<NodeId>, ReducedBody) {
        assert_eq!(a.z, b.z, "a planar beam lies in a plane z = const");
        let mut model = FeModel::default();
        let props = properties(&mut model, Vector3::z());
        let nodes = fe_model::generate::straight_beam(&mut model, a, b, elements, &props, Some("beam")).unwrap();
        if supported {
            for n in &nodes[1..elements] {
                model.add_support(*n, fe_model::DofMask([false, false, true, true, true, false]));
            }
        }
        let ends = vec![nodes[0], nodes[elements]];
        let interfaces = vec![("a".to_string(), ends[0]), ("b".to_string(), ends[1])];
        let body = reduce(&model, "rod", &interfaces, &settings).unwrap();
        (model, ends, body)
    }

    /// An L-shaped frame in 3D (two members of 4 elements meeting at a corner, the second
    /// member out of the first one's plane of symmetry) with three interfaces: both free ends and
    /// the corner. Its centre of mass is at no node: the generic case of the centre-of-mass frame.
    pub fn l_frame(modes: ModeSelection) -> (FeModel, Vec<NodeId>, ReducedBody) {
        let mut model = FeModel::default();
        let props = properties(&mut model, Vector3::new(0.0, 0.0, 1.0));
        let a = model.add_node(Point3::new(0.0, 0.0, 0.0));
        let c = model.add_node(Point3::new(1.0, 0.0, 0.0));
        let b = model.add_node(Point3::new(1.2, 0.6, 0.3));
        fe_model::generate::beam_between(&mut model, a, c, 4, &props, Some("m1")).unwrap();
        let mut props2 = props.clone();
        props2.orientation = Vector3::new(0.0, 0.2, 1.0);
        fe_model::generate::beam_between(&mut model, c, b, 4, &props2, Some("m2")).unwrap();
        let interfaces = vec![("a".to_string(), a), ("corner".to_string(), c), ("b".to_string(), b)];
        let body = reduce(&model, "l-frame", &interfaces, &CbSettings::new(modes)).unwrap();
        (model, vec![a, c, b], body)
    }

    /// A hex8 block 1 x 0.2 x 0.3 m (5 x 1 x 2 bricks, aluminium) with an RBE2 interface on the
    /// face x = 0 and an RBE3 interface on the face x = 1, at the face centroids: a solid body
    /// with spider interfaces, whose second-order mass invariants are exact (module docs of
    /// `reduction::invariants`).
    pub fn solid_block(modes: ModeSelection) -> (FeModel, Vec<NodeId>, ReducedBody) {
        solid_block_with(CbSettings::new(modes))
    }

    /// [`solid_block`] reduced with `settings` (e.g. with `geometric_stiffening`).
    pub fn solid_block_with(settings: CbSettings) -> (FeModel, Vec<NodeId>, ReducedBody) {
        use fe_model::interface::{add_interface_on_set, SpiderKind};
        let mesh = fe_model::box_mesh::box_mesh(fe_model::CellKind::Hex8, [1.0, 0.2, 0.3], [5, 1, 2]).unwrap();
        let material = IsotropicMaterial::new("aluminium", 70e9, 0.33, 2700.0).unwrap();
        let mut model = fe_model::box_mesh::solid_model(mesh, material, MassKind::Consistent).unwrap();
        let a = add_interface_on_set(&mut model, "a", "x0", None, SpiderKind::Rbe2).unwrap();
        let b = add_interface_on_set(&mut model, "b", "x1", None, SpiderKind::Rbe3).unwrap();
        let interfaces = vec![("a".to_string(), a), ("b".to_string(), b)];
        let body = reduce(&model, "block", &interfaces, &settings).unwrap();
        (model, vec![a, b], body)
    }
}

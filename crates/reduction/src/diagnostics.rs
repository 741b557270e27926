//! A diagnostics table per reduced body: the fixed-interface frequencies, the modal effective
//! mass of every kept mode in the six rigid directions, and warnings when the kept modes do
//! not reach far enough above the frequencies a study will excite.
//!
//! # Modal effective mass of fixed-interface modes
//!
//! The standard definition for modes of a structure on a base (NASTRAN's `MEFFMASS` output;
//! the Craig-Bampton form as in Craig & Kurdila, *Fundamentals of Structural Dynamics*, 2nd
//! ed., Wiley 2006, in their treatment of component-mode synthesis): give the whole interface
//! set a unit rigid motion $\mathbf r_d$ in direction $d$ (translation along $x, y, z$ or
//! rotation about the axes through the centre of mass); the participation of mode $k$ is
//! $L_{kd} = \boldsymbol\phi_k^T\mathbf M\,\mathbf r_d$, and its effective mass
//! $m^{eff}_{kd} = L_{kd}^2 / m_k$ with the generalised mass
//! $m_k = \boldsymbol\phi_k^T\mathbf M\boldsymbol\phi_k$. The table gives $m^{eff}_{kd}$ as a
//! fraction of the body's mass ($d$ = translation) or of its moment of inertia about the axis
//! through the centre of mass ($d$ = rotation).
//!
//! # Derivation from the reduced body alone
//!
//! The reduced body holds no FE matrices, but $\mathbf M_{CB}$ is enough. Superscripts name its
//! blocks: $\mathbf M_{CB}^{\eta b}$ is the rows of the modal coordinates $\boldsymbol\eta$
//! and the columns of the interface coordinates $b$ (`M_CB[6N.., ..6N]`). Let
//! $\boldsymbol\Phi_{rig}$ ($6N \times 6$) be the rigid modes of the interface set (5.2) about
//! the centre of mass. In the CB basis $\mathbf V = [\mathbf V_b\ \mathbf V_\eta]$, the motion
//! $\mathbf V_b\boldsymbol\Phi_{rig}$ is the static response to a rigid motion of the
//! interfaces; for a body that is free in its FE model, $\mathbf K\mathbf R = \mathbf 0$
//! ($\mathbf R$: the rigid modes of the whole body) gives $\mathbf R_i = -\mathbf K_{ii}^{-1}
//! \mathbf K_{ib}\mathbf R_b = \boldsymbol\Psi\mathbf R_b$, so
//! $\mathbf V_b\boldsymbol\Phi_{rig} = \mathbf R$: the rigid motion of the whole body. Hence
//! $$\mathbf L = \mathbf V_\eta^T\mathbf M\mathbf R = \mathbf M_{CB}^{\eta b}\,
//! \boldsymbol\Phi_{rig},\qquad m_k = \mathbf M_{CB}^{\eta_k\eta_k},\qquad
//! \boldsymbol\Phi_{rig}^T\mathbf M_{CB}^{bb}\boldsymbol\Phi_{rig} = \mathbf R^T\mathbf M
//! \mathbf R,$$
//! the last being the body's rigid mass matrix ($m\mathbf 1$ and the inertia tensor about the
//! centre of mass on its diagonal blocks). No data beyond [`ReducedBody`] is needed.
//!
//! # What the sums mean
//!
//! The modes $\boldsymbol\phi_k$ are $\mathbf M_{ii}$-orthogonal and span the internal dofs, so
//! summed over *all* fixed-interface modes
//! $$\sum_k \frac{\mathbf L_k^T\mathbf L_k}{m_k} = (\mathbf M\mathbf R)_i^T\mathbf M_{ii}^{-1}
//! (\mathbf M\mathbf R)_i = \mathbf R^T\mathbf M\mathbf R - \mathbf R_b^T(\mathbf M_{bb} -
//! \mathbf M_{bi}\mathbf M_{ii}^{-1}\mathbf M_{ib})\mathbf R_b .$$
//! The last term is the mass the interfaces carry themselves: with a lumped mass matrix it is
//! the mass lumped at the interface nodes, with a consistent one its Schur complement. So
//! the effective masses of all modes add up to the total mass (inertia) minus what the
//! interfaces carry, and the sum over the *kept* modes falls short of that by the modes left
//! out. The table's `static` row is the rest,
//! $\mathrm{diag}\,\boldsymbol\Phi_{rig}^T(\mathbf M_{CB}^{bb} - \mathbf M_{CB}^{b\eta}
//! (\mathbf M_{CB}^{\eta\eta})^{-1}\mathbf M_{CB}^{\eta b})\boldsymbol\Phi_{rig}$ over the rigid
//! mass: the share the constraint modes carry (the interfaces' own, plus the modes not kept);
//! `kept + static = 1` for a free body. `tests/unit/diagnostics.rs` checks both identities
//! against an independent dense solution of the full FE model.
//!
//! For a body supported in its FE model, $\mathbf V_b\boldsymbol\Phi_{rig}$ is not a rigid
//! motion; the table is still computed, against the body's rigid mass, and a
//! [`DiagnosticWarning::NotFree`] says so.

#![allow(non_snake_case)]

use crate::reduced_body::ReducedBody;
use serde::{Deserialize, Serialize};
use std::fmt;

/// Names of the six rigid directions, in the order of every `[f64; 6]` here: translations
/// along $x, y, z$, rotations about the axes through the centre of mass.
pub const DIRECTIONS: [&str; 6] = ["Tx", "Ty", "Tz", "Rx", "Ry", "Rz"];

/// A mode counts as near or below the excitation when $f_k < \sqrt2 f_{exc}$: there the
/// undamped amplification $1/|1 - (f_{exc}/f_k)^2|$ of a harmonic load at $f_{exc}$ exceeds 2.
pub const NEAR_EXCITATION_RATIO: f64 = std::f64::consts::SQRT_2;

/// Relative difference between the CB static block's rigid mass and the body's rigid mass
/// above which the body is taken as supported in its FE model ([`DiagnosticWarning::NotFree`]).
/// For a free body both are the same quantity up to the round-off of the projections, about
/// $10^{-12}$ relative; a support changes it at order one.
pub const FREE_BODY_RTOL: f64 = 1e-6;

/// One fixed-interface mode of the table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModeDiagnostics {
    /// 1-based mode number, ascending frequency.
    pub mode: usize,
    /// Fixed-interface frequency (Hz).
    pub frequency_hz: f64,
    /// Generalised mass $m_k$ (1 for the mass-normalised modes of [`crate::reduce`]).
    pub generalized_mass: f64,
    /// Participation factors $\Gamma_{kd} = L_{kd}/m_k$.
    pub participation: [f64; 6],
    /// Effective mass $L_{kd}^2/m_k$ (kg for translations, kg m² for rotations).
    pub effective_mass: [f64; 6],
    /// `effective_mass` over the body's mass (translations) or inertia about the centre of
    /// mass (rotations).
    pub effective_fraction: [f64; 6],
}

/// Something the user should look at before using the body in a study.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum DiagnosticWarning {
    /// The excitation frequency or the factor is not usable; no frequency check was made.
    InvalidInput { what: String },
    /// No fixed-interface mode was kept but the study excites the body: the static modes are
    /// exact only well below the first fixed-interface frequency, which is unknown.
    StaticOnly { excitation_hz: f64 },
    /// The highest kept fixed-interface frequency is below `factor` times the excitation:
    /// modes are missing.
    ModesMissing {
        highest_hz: f64,
        excitation_hz: f64,
        factor: f64,
    },
    /// Kept modes near or below the excitation ([`NEAR_EXCITATION_RATIO`]): the study will
    /// excite them near resonance, so their damping matters.
    NearExcitation {
        modes: Vec<usize>,
        frequencies_hz: Vec<f64>,
        excitation_hz: f64,
    },
    /// The CB static modes do not carry the body's rigid mass in `direction`: the body is
    /// supported in its FE model, and the effective masses do not add up as the module docs
    /// say.
    NotFree {
        direction: String,
        static_block: f64,
        body: f64,
    },
}

impl fmt::Display for DiagnosticWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DiagnosticWarning::InvalidInput { what } => write!(f, "no frequency check: {what}"),
            DiagnosticWarning::StaticOnly { excitation_hz } => write!(
                f,
                "no fixed-interface modes kept, but the study excites up to {excitation_hz:.4e} Hz: the body's own dynamics are missing; keep the modes up to a few times that frequency (`cutoff_hz` in the part's [parts.reduction])"
            ),
            DiagnosticWarning::ModesMissing { highest_hz, excitation_hz, factor } => write!(
                f,
                "modes are missing: the highest kept fixed-interface mode is at {highest_hz:.4e} Hz, below {factor} x the excitation {excitation_hz:.4e} Hz = {:.4e} Hz; reduce again keeping the modes below it (`cutoff_hz = {:.4e}` in the part's [parts.reduction])",
                factor * excitation_hz,
                factor * excitation_hz
            ),
            DiagnosticWarning::NearExcitation { modes, frequencies_hz, excitation_hz } => {
                write!(f, "modes near or below the excitation {excitation_hz:.4e} Hz (f < sqrt(2) x excitation, resonance possible): ")?;
                for (k, (m, hz)) in modes.iter().zip(frequencies_hz).enumerate() {
                    write!(f, "{}mode {m} at {hz:.4e} Hz", if k > 0 { ", " } else { "" })?;
                }
                Ok(())
            }
            DiagnosticWarning::NotFree { direction, static_block, body } => write!(
                f,
                "the static modes carry {static_block:.6e} of the body's {body:.6e} in {direction}: the FE model was not free (supports?), so the effective masses are relative to a supported body"
            ),
        }
    }
}

/// The diagnostics of one body (module docs), plain data for reports; [`fmt::Display`]
/// prints the table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Diagnostics {
    pub body: String,
    pub n_interfaces: usize,
    /// The body's rigid mass in the six directions: $m, m, m, J_{xx}, J_{yy}, J_{zz}$ (inertia
    /// about the centre of mass).
    pub rigid_mass: [f64; 6],
    pub modes: Vec<ModeDiagnostics>,
    /// Sum of `effective_fraction` over the kept modes.
    pub kept_fraction: [f64; 6],
    /// The share the static (constraint) modes carry: the interfaces' own mass and the modes
    /// not kept (module docs). `kept + static = 1` for a free body.
    pub static_fraction: [f64; 6],
    /// The highest frequency the study excites (Hz), if given.
    pub excitation_hz: Option<f64>,
    /// The kept modes should reach `factor` times the excitation.
    pub factor: f64,
    pub warnings: Vec<DiagnosticWarning>,
}

/// The rigid modes of the interface set (5.2), undeformed, about `c`: $6N \times 6$,
/// row-major `[row][direction]`.
fn phi_rig(body: &ReducedBody, c: [f64; 3]) -> Vec<[f64; 6]> {
    let x: Vec<nalgebra::Vector3<f64>> = body.interfaces.iter().map(|p| p.position.into()).collect();
    let P = fe_model::rigid::rigid_modes(&x, &c.into(), 0);
    (0..P.nrows()).map(|r| [0, 1, 2, 3, 4, 5].map(|a| P[(r, a)])).collect()
}

/// The diagnostics table of `body`. `excitation_hz` is the highest frequency the study will
/// excite (a forcing frequency, the bandwidth of a driven motion); the kept fixed-interface
/// modes should reach `factor` times it (3 to 5 is common: the CB basis is accurate well
/// below the first mode left out).
pub fn diagnostics(body: &ReducedBody, excitation_hz: Option<f64>, factor: f64) -> Diagnostics {
    let nb = 6 * body.interfaces.len();
    let m = body.n_modes;
    let P = phi_rig(body, body.inertia.center_of_mass);
    let M = &body.M_CB;
    let J = body.inertia.inertia_com;
    let mass = body.inertia.mass;
    let rigid_mass = [mass, mass, mass, J[0][0], J[1][1], J[2][2]];
    let fraction = |value: f64, d: usize| {
        if rigid_mass[d] > 0.0 {
            value / rigid_mass[d]
        } else {
            0.0
        }
    };

    // Static block: diag(Phi_rig^T M_bb Phi_rig).
    let mut static_block = [0.0; 6];
    for d in 0..6 {
        let mut s = 0.0;
        for a in 0..nb {
            let Ma: f64 = (0..nb).map(|b| M.get(a, b) * P[b][d]).sum();
            s += P[a][d] * Ma;
        }
        static_block[d] = s;
    }
    let mut modes = Vec::with_capacity(m);
    let mut kept = [0.0; 6];
    for k in 0..m {
        let row = nb + k;
        let m_k = M.get(row, row);
        let mut participation = [0.0; 6];
        let mut effective_mass = [0.0; 6];
        let mut effective_fraction = [0.0; 6];
        for d in 0..6 {
            // L_kd = M_CB[eta_k, b] Phi_rig[:, d] (module docs).
            let L: f64 = (0..nb).map(|b| M.get(row, b) * P[b][d]).sum();
            participation[d] = L / m_k;
            effective_mass[d] = L * L / m_k;
            effective_fraction[d] = fraction(effective_mass[d], d);
            kept[d] += effective_mass[d];
        }
        modes.push(ModeDiagnostics {
            mode: k + 1,
            frequency_hz: body.fixed_interface_omega[k] / (2.0 * std::f64::consts::PI),
            generalized_mass: m_k,
            participation,
            effective_mass,
            effective_fraction,
        });
    }
    let kept_fraction = [0, 1, 2, 3, 4, 5].map(|d| fraction(kept[d], d));
    let static_fraction = [0, 1, 2, 3, 4, 5].map(|d| fraction(static_block[d] - kept[d], d));

    let mut warnings = Vec::new();
    for d in 0..6 {
        let (a, b) = (static_block[d], rigid_mass[d]);
        if (a - b).abs() > FREE_BODY_RTOL * b.abs().max(a.abs()) {
            warnings.push(DiagnosticWarning::NotFree {
                direction: DIRECTIONS[d].into(),
                static_block: a,
                body: b,
            });
        }
    }
    if let Some(f) = excitation_hz {
        if !(f > 0.0 && f.is_finite()) {
            warnings.push(DiagnosticWarning::InvalidInput {
                what: format!("the excitation frequency {f} Hz is not positive"),
            });
        } else if !(factor >= 1.0 && factor.is_finite()) {
            warnings.push(DiagnosticWarning::InvalidInput {
                what: format!("the factor {factor} must be at least 1 (3 to 5 is common)"),
            });
        } else if m == 0 {
            warnings.push(DiagnosticWarning::StaticOnly { excitation_hz: f });
        } else {
            let highest = modes.iter().map(|d| d.frequency_hz).fold(0.0, f64::max);
            if highest < factor * f {
                warnings.push(DiagnosticWarning::ModesMissing {
                    highest_hz: highest,
                    excitation_hz: f,
                    factor,
                });
            }
            let near: Vec<&ModeDiagnostics> = modes
                .iter()
                .filter(|d| d.frequency_hz < NEAR_EXCITATION_RATIO * f)
                .collect();
            if !near.is_empty() {
                warnings.push(DiagnosticWarning::NearExcitation {
                    modes: near.iter().map(|d| d.mode).collect(),
                    frequencies_hz: near.iter().map(|d| d.frequency_hz).collect(),
                    excitation_hz: f,
                });
            }
        }
    }
    Diagnostics {
        body: body.name.clone(),
        n_interfaces: body.interfaces.len(),
        rigid_mass,
        modes,
        kept_fraction,
        static_fraction,
        excitation_hz,
        factor,
        warnings,
    }
}

impl fmt::Display for Diagnostics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "body '{}': {} interfaces, {} fixed-interface modes, mass {:.6e} kg",
            self.body,
            self.n_interfaces,
            self.modes.len(),
            self.rigid_mass[0]
        )?;
        writeln!(
            f,
            "effective mass in % of the body's mass (T) and inertia about the centre of mass (R):"
        )?;
        write!(f, "{:>6} {:>12}", "mode", "f [Hz]")?;
        for d in DIRECTIONS {
            write!(f, " {d:>7}")?;
        }
        writeln!(f)?;
        let row = |f: &mut fmt::Formatter<'_>, label: &str, hz: Option<f64>, values: &[f64; 6]| -> fmt::Result {
            match hz {
                Some(hz) => write!(f, "{label:>6} {hz:>12.4e}")?,
                None => write!(f, "{label:<19}")?,
            }
            for v in values {
                write!(f, " {:>7.2}", 100.0 * v)?;
            }
            writeln!(f)
        };
        for m in &self.modes {
            row(f, &m.mode.to_string(), Some(m.frequency_hz), &m.effective_fraction)?;
        }
        row(f, "kept modes", None, &self.kept_fraction)?;
        row(f, "static modes", None, &self.static_fraction)?;
        writeln!(
            f,
            "(static: carried by the interfaces themselves and by the modes not kept)"
        )?;
        match self.excitation_hz {
            Some(hz) => writeln!(
                f,
                "excitation up to {hz:.4e} Hz; kept modes should reach {} x that",
                self.factor
            )?,
            None => writeln!(f, "no excitation frequency given: no frequency check")?,
        }
        if self.warnings.is_empty() {
            writeln!(f, "warnings: none")
        } else {
            writeln!(f, "warnings:")?;
            for w in &self.warnings {
                writeln!(f, "  - {w}")?;
            }
            Ok(())
        }
    }
}

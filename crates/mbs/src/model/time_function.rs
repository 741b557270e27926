//! Functions of time for drivers and loads: value, first and second derivative.
//!
//! A driver feeds a coordinate with $x(t)$, $\dot x(t)$, $\ddot x(t)$ (theory guide §8: "fed in with its
//! velocity and acceleration"), so every function here has exact derivatives; a load is scaled
//! by $x(t)$ only.

use crate::error::ModelError;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// How a table is interpolated between its points.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Interpolation {
    /// Piecewise linear: the rate jumps at the points and the acceleration is zero between
    /// them (the jumps are not fed in). For loads, or drivers of slow motions.
    Linear,
    /// Natural cubic spline: value, rate and acceleration are continuous (for drivers).
    CubicSpline,
}

/// A scalar function of time (serde data).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum TimeFunction {
    /// $x = c$.
    Constant { value: f64 },
    /// $x = x_0 + \dot x\,t$: a constant speed.
    Linear { initial: f64, rate: f64 },
    /// Linear from `from` at `t_start` to `to` at `t_end`, constant before and after (the
    /// rate jumps at both ends).
    Ramp {
        t_start: f64,
        t_end: f64,
        from: f64,
        to: f64,
    },
    /// From `from` to `to` with the quintic $10s^3 - 15s^4 + 6s^5$, $s = (t - t_s)/(t_e - t_s)$:
    /// rate and acceleration are zero at both ends.
    SmoothRamp {
        t_start: f64,
        t_end: f64,
        from: f64,
        to: f64,
    },
    /// The spin-up angle of validation problem C1 (Simo & Vu-Quoc 1986):
    /// $\theta = \frac{\omega_s}{T_s}\big(\frac{t^2}{2} + (\frac{T_s}{2\pi})^2(\cos\frac{2\pi t}{T_s} - 1)\big)$
    /// for $t \le T_s$, then $\omega_s(t - T_s/2)$.
    SpinUp { omega: f64, duration: f64 },
    /// $x = x_0 + A\sin(\omega t + \varphi)$.
    Sine {
        offset: f64,
        amplitude: f64,
        omega: f64,
        phase: f64,
    },
    /// Tabulated values (strictly increasing times), held constant outside the table.
    Table {
        times: Vec<f64>,
        values: Vec<f64>,
        interpolation: Interpolation,
    },
}

impl TimeFunction {
    /// $x = c$.
    pub fn constant(value: f64) -> Self {
        Self::Constant { value }
    }

    /// A table from CSV text: two columns `time, value` (comma, semicolon or whitespace
    /// separated); lines starting with `#` and a first line that is not numeric (a header)
    /// are skipped.
    pub fn table_from_csv(text: &str, interpolation: Interpolation) -> Result<Self, ModelError> {
        let mut times = Vec::new();
        let mut values = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let fields: Vec<&str> = line
                .split(|c: char| c == ',' || c == ';' || c.is_whitespace())
                .filter(|s| !s.is_empty())
                .collect();
            let parsed: Result<Vec<f64>, _> = fields.iter().map(|f| f.parse::<f64>()).collect();
            match parsed {
                Ok(v) if v.len() >= 2 => {
                    times.push(v[0]);
                    values.push(v[1]);
                }
                _ if times.is_empty() && i == 0 => continue,
                _ => {
                    return Err(ModelError::InvalidValue {
                        entity: "CSV table".into(),
                        what: format!("line {}: expected two numbers `time, value`, got '{line}'", i + 1),
                        id: None,
                    })
                }
            }
        }
        let f = Self::Table {
            times,
            values,
            interpolation,
        };
        f.compile("CSV table")?;
        Ok(f)
    }

    /// Checks the data and precomputes what evaluation needs (spline moments).
    pub(crate) fn compile(&self, entity: &str) -> Result<CompiledFunction, ModelError> {
        let bad = |what: String| {
            Err(ModelError::InvalidValue {
                entity: entity.into(),
                what,
                id: None,
            })
        };
        let finite = |xs: &[f64]| xs.iter().all(|x| x.is_finite());
        match self {
            Self::Constant { value } if !value.is_finite() => bad("constant is not finite".into()),
            Self::Linear { initial, rate } if !finite(&[*initial, *rate]) => bad("non-finite linear function".into()),
            Self::Ramp {
                t_start,
                t_end,
                from,
                to,
            }
            | Self::SmoothRamp {
                t_start,
                t_end,
                from,
                to,
            } => {
                if !finite(&[*t_start, *t_end, *from, *to]) || !(t_end > t_start) {
                    return bad(format!(
                        "ramp needs finite values and t_end > t_start (got {t_start} .. {t_end})"
                    ));
                }
                Ok(CompiledFunction {
                    f: self.clone(),
                    moments: Vec::new(),
                })
            }
            Self::SpinUp { omega, duration } if !(finite(&[*omega]) && *duration > 0.0 && duration.is_finite()) => bad(
                format!("spin-up needs a finite speed and a positive duration (got {omega}, {duration})"),
            ),
            Self::Sine {
                offset,
                amplitude,
                omega,
                phase,
            } if !finite(&[*offset, *amplitude, *omega, *phase]) => bad("non-finite sine".into()),
            Self::Table {
                times,
                values,
                interpolation,
            } => {
                if times.len() != values.len() || times.is_empty() {
                    return bad(format!("table has {} times and {} values", times.len(), values.len()));
                }
                if !finite(times) || !finite(values) {
                    return bad("table has a non-finite entry".into());
                }
                if let Some(i) = (1..times.len()).find(|&i| !(times[i] > times[i - 1])) {
                    return bad(format!(
                        "table times must increase strictly (row {i}: {} after {})",
                        times[i],
                        times[i - 1]
                    ));
                }
                let moments = match interpolation {
                    Interpolation::Linear => Vec::new(),
                    Interpolation::CubicSpline => natural_spline_moments(times, values),
                };
                Ok(CompiledFunction {
                    f: self.clone(),
                    moments,
                })
            }
            _ => Ok(CompiledFunction {
                f: self.clone(),
                moments: Vec::new(),
            }),
        }
    }
}

/// A checked [`TimeFunction`] with its precomputed data.
#[derive(Clone, Debug)]
pub(crate) struct CompiledFunction {
    f: TimeFunction,
    /// Second derivatives at the table points (natural cubic spline).
    moments: Vec<f64>,
}

impl CompiledFunction {
    /// $(x, \dot x, \ddot x)$ at `t`.
    pub(crate) fn eval(&self, t: f64) -> (f64, f64, f64) {
        match &self.f {
            TimeFunction::Constant { value } => (*value, 0.0, 0.0),
            TimeFunction::Linear { initial, rate } => (initial + rate * t, *rate, 0.0),
            TimeFunction::Ramp {
                t_start,
                t_end,
                from,
                to,
            } => {
                if t <= *t_start {
                    (*from, 0.0, 0.0)
                } else if t >= *t_end {
                    (*to, 0.0, 0.0)
                } else {
                    let r = (to - from) / (t_end - t_start);
                    (from + r * (t - t_start), r, 0.0)
                }
            }
            TimeFunction::SmoothRamp {
                t_start,
                t_end,
                from,
                to,
            } => {
                let d = t_end - t_start;
                let s = ((t - t_start) / d).clamp(0.0, 1.0);
                if t <= *t_start || t >= *t_end {
                    return (from + (to - from) * s, 0.0, 0.0);
                }
                let h = to - from;
                let x = from + h * s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
                let xd = h * 30.0 * s * s * (1.0 - s) * (1.0 - s) / d;
                let xdd = h * 60.0 * s * (1.0 - s) * (1.0 - 2.0 * s) / (d * d);
                (x, xd, xdd)
            }
            TimeFunction::SpinUp { omega, duration } => {
                let (w, T) = (*omega, *duration);
                if t <= T {
                    let c = T / (2.0 * PI);
                    let phi = 2.0 * PI * t / T;
                    (
                        w / T * (0.5 * t * t + c * c * (phi.cos() - 1.0)),
                        w / T * (t - c * phi.sin()),
                        w / T * (1.0 - phi.cos()),
                    )
                } else {
                    (w * (t - 0.5 * T), w, 0.0)
                }
            }
            TimeFunction::Sine {
                offset,
                amplitude,
                omega,
                phase,
            } => {
                let a = omega * t + phase;
                (
                    offset + amplitude * a.sin(),
                    amplitude * omega * a.cos(),
                    -amplitude * omega * omega * a.sin(),
                )
            }
            TimeFunction::Table {
                times,
                values,
                interpolation,
            } => {
                let n = times.len();
                if t <= times[0] {
                    return (values[0], 0.0, 0.0);
                }
                if t >= times[n - 1] {
                    return (values[n - 1], 0.0, 0.0);
                }
                // times[i] <= t < times[i + 1]
                let i = times.partition_point(|&x| x <= t) - 1;
                let h = times[i + 1] - times[i];
                let (y0, y1) = (values[i], values[i + 1]);
                match interpolation {
                    Interpolation::Linear => {
                        let s = (t - times[i]) / h;
                        (y0 + s * (y1 - y0), (y1 - y0) / h, 0.0)
                    }
                    Interpolation::CubicSpline => {
                        let (m0, m1) = (self.moments[i], self.moments[i + 1]);
                        let a = times[i + 1] - t;
                        let b = t - times[i];
                        let x = m0 * a * a * a / (6.0 * h)
                            + m1 * b * b * b / (6.0 * h)
                            + (y0 / h - m0 * h / 6.0) * a
                            + (y1 / h - m1 * h / 6.0) * b;
                        let xd = -m0 * a * a / (2.0 * h) + m1 * b * b / (2.0 * h) - (y0 / h - m0 * h / 6.0)
                            + (y1 / h - m1 * h / 6.0);
                        let xdd = (m0 * a + m1 * b) / h;
                        (x, xd, xdd)
                    }
                }
            }
        }
    }
}

/// Second derivatives $M_i$ of the natural cubic spline through $(t_i, y_i)$ ($M_0 = M_{n-1} = 0$),
/// from the tridiagonal system $h_{i-1}M_{i-1} + 2(h_{i-1} + h_i)M_i + h_iM_{i+1} =
/// 6\big(\frac{y_{i+1} - y_i}{h_i} - \frac{y_i - y_{i-1}}{h_{i-1}}\big)$ (Thomas algorithm).
fn natural_spline_moments(t: &[f64], y: &[f64]) -> Vec<f64> {
    let n = t.len();
    let mut m = vec![0.0; n];
    if n < 3 {
        return m;
    }
    let k = n - 2;
    let mut diag = vec![0.0; k];
    let mut rhs = vec![0.0; k];
    let mut upper = vec![0.0; k];
    for j in 0..k {
        let i = j + 1;
        let (h0, h1) = (t[i] - t[i - 1], t[i + 1] - t[i]);
        diag[j] = 2.0 * (h0 + h1);
        upper[j] = h1;
        rhs[j] = 6.0 * ((y[i + 1] - y[i]) / h1 - (y[i] - y[i - 1]) / h0);
    }
    for j in 1..k {
        let lower = t[j + 1] - t[j];
        let w = lower / diag[j - 1];
        diag[j] -= w * upper[j - 1];
        rhs[j] -= w * rhs[j - 1];
    }
    m[k] = rhs[k - 1] / diag[k - 1];
    for j in (0..k - 1).rev() {
        m[j + 1] = (rhs[j] - upper[j] * m[j + 2]) / diag[j];
    }
    m
}

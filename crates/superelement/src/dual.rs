//! Forward-mode dual numbers for the planar kernel ([`crate::planar`]): one generic residual,
//! evaluated with `f64` for the forces and with [`Dual`] for the tangents, whose derivative
//! parts are then the exact partial derivatives (to round-off) of the same arithmetic.

use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

/// The scalar of the generic planar residual: `f64` or a [`Dual`].
pub(crate) trait Scalar:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Neg<Output = Self>
    + Mul<f64, Output = Self>
    + AddAssign
    + SubAssign
{
    /// Whether the scalar carries derivatives (the frame's implicit derivative is added then).
    const DUAL: bool;
    /// A constant.
    fn cst(v: f64) -> Self;
    /// The derivative part alone (value zero).
    fn infinitesimal(self) -> Self;
    /// $(\sin x, \cos x)$.
    fn sin_cos(self) -> (Self, Self);
    /// $1/x$.
    fn recip(self) -> Self;
    /// `self + a * b`.
    #[inline(always)]
    fn mul_add_f(self, a: Self, b: f64) -> Self {
        self + a * b
    }
}

impl Scalar for f64 {
    const DUAL: bool = false;
    #[inline(always)]
    fn cst(v: f64) -> Self {
        v
    }
    #[inline(always)]
    fn infinitesimal(self) -> Self {
        0.0
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        f64::sin_cos(self)
    }
    #[inline(always)]
    fn recip(self) -> Self {
        1.0 / self
    }
}

/// $v + \sum_i d_i\varepsilon_i$ with $\varepsilon_i\varepsilon_j = 0$: `D` directional
/// derivatives carried through every operation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Dual<const D: usize> {
    pub v: f64,
    pub d: [f64; D],
}

impl<const D: usize> Add for Dual<D> {
    type Output = Self;
    #[inline(always)]
    fn add(mut self, o: Self) -> Self {
        self.v += o.v;
        for i in 0..D {
            self.d[i] += o.d[i];
        }
        self
    }
}

impl<const D: usize> Sub for Dual<D> {
    type Output = Self;
    #[inline(always)]
    fn sub(mut self, o: Self) -> Self {
        self.v -= o.v;
        for i in 0..D {
            self.d[i] -= o.d[i];
        }
        self
    }
}

impl<const D: usize> Mul for Dual<D> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        let mut d = [0.0; D];
        for i in 0..D {
            d[i] = self.v * o.d[i] + o.v * self.d[i];
        }
        Self { v: self.v * o.v, d }
    }
}

impl<const D: usize> Mul<f64> for Dual<D> {
    type Output = Self;
    #[inline(always)]
    fn mul(mut self, a: f64) -> Self {
        self.v *= a;
        for i in 0..D {
            self.d[i] *= a;
        }
        self
    }
}

impl<const D: usize> Neg for Dual<D> {
    type Output = Self;
    #[inline(always)]
    fn neg(mut self) -> Self {
        self.v = -self.v;
        for i in 0..D {
            self.d[i] = -self.d[i];
        }
        self
    }
}

impl<const D: usize> AddAssign for Dual<D> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        self.v += o.v;
        for i in 0..D {
            self.d[i] += o.d[i];
        }
    }
}

impl<const D: usize> SubAssign for Dual<D> {
    #[inline(always)]
    fn sub_assign(&mut self, o: Self) {
        self.v -= o.v;
        for i in 0..D {
            self.d[i] -= o.d[i];
        }
    }
}

impl<const D: usize> Scalar for Dual<D> {
    const DUAL: bool = true;
    #[inline(always)]
    fn cst(v: f64) -> Self {
        Self { v, d: [0.0; D] }
    }
    #[inline(always)]
    fn infinitesimal(mut self) -> Self {
        self.v = 0.0;
        self
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        let (s, c) = self.v.sin_cos();
        let mut ds = [0.0; D];
        let mut dc = [0.0; D];
        for i in 0..D {
            ds[i] = c * self.d[i];
            dc[i] = -s * self.d[i];
        }
        (Self { v: s, d: ds }, Self { v: c, d: dc })
    }
    #[inline(always)]
    fn recip(self) -> Self {
        let r = 1.0 / self.v;
        let f = -r * r;
        let mut d = [0.0; D];
        for i in 0..D {
            d[i] = f * self.d[i];
        }
        Self { v: r, d }
    }
    #[inline(always)]
    fn mul_add_f(mut self, a: Self, b: f64) -> Self {
        self.v += a.v * b;
        for i in 0..D {
            self.d[i] += a.d[i] * b;
        }
        self
    }
}

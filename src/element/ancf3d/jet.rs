//! Forward-mode automatic differentiation for the energy densities of the
//! full 3-D element: a [`Scalar`] is what a density is written over, `f64`
//! for the value, [`Dual`] for the value and gradient, [`Jet`] for the
//! value, gradient and Hessian.
//!
//! Every operation applies the chain rule exactly (product, quotient,
//! square root and `f(x)` with the caller's `f, f', f''`), so the
//! derivatives carry no truncation error: they are the analytic derivatives
//! of the density, evaluated in floating point. The element's tests check
//! them against finite differences all the same.

use std::ops::{Add, Mul, Neg, Sub};

/// A number a density can be written over.
pub(crate) trait Scalar:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self>
{
    /// A constant.
    fn cst(v: f64) -> Self;
    /// The value.
    fn value(&self) -> f64;
    /// `self · c` for a constant `c`.
    fn scale(self, c: f64) -> Self;
    /// `f(self)` given `f`, `f'` and `f''` at `self.value()`.
    fn map(self, f: f64, f1: f64, f2: f64) -> Self;
    /// `1 / self`.
    fn recip(self) -> Self {
        let v = self.value();
        let r = 1.0 / v;
        self.map(r, -r * r, 2.0 * r * r * r)
    }
    /// `√self`.
    fn sqrt(self) -> Self {
        let s = self.value().sqrt();
        self.map(s, 0.5 / s, -0.25 / (s * s * s))
    }
}

impl Scalar for f64 {
    #[inline]
    fn cst(v: f64) -> Self {
        v
    }
    #[inline]
    fn value(&self) -> f64 {
        *self
    }
    #[inline]
    fn scale(self, c: f64) -> Self {
        self * c
    }
    #[inline]
    fn map(self, f: f64, _: f64, _: f64) -> Self {
        f
    }
    #[inline]
    fn recip(self) -> Self {
        1.0 / self
    }
    #[inline]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
}

/// A value with its gradient over `N` variables.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Dual<const N: usize> {
    pub v: f64,
    pub g: [f64; N],
}

impl<const N: usize> Dual<N> {
    /// Variable `i` of `N` at value `v`.
    pub fn var(v: f64, i: usize) -> Self {
        let mut g = [0.0; N];
        if let Some(x) = g.get_mut(i) {
            *x = 1.0;
        }
        Dual { v, g }
    }
}

impl<const N: usize> Add for Dual<N> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: Self) -> Self {
        self.v += o.v;
        for (a, b) in self.g.iter_mut().zip(&o.g) {
            *a += b;
        }
        self
    }
}

impl<const N: usize> Sub for Dual<N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: Self) -> Self {
        self.v -= o.v;
        for (a, b) in self.g.iter_mut().zip(&o.g) {
            *a -= b;
        }
        self
    }
}

impl<const N: usize> Neg for Dual<N> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        self.scale(-1.0)
    }
}

impl<const N: usize> Mul for Dual<N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        let mut g = [0.0; N];
        for ((x, a), b) in g.iter_mut().zip(&self.g).zip(&o.g) {
            *x = a * o.v + b * self.v;
        }
        Dual { v: self.v * o.v, g }
    }
}

impl<const N: usize> Scalar for Dual<N> {
    #[inline]
    fn cst(v: f64) -> Self {
        Dual { v, g: [0.0; N] }
    }
    #[inline]
    fn value(&self) -> f64 {
        self.v
    }
    #[inline]
    fn scale(mut self, c: f64) -> Self {
        self.v *= c;
        self.g.iter_mut().for_each(|x| *x *= c);
        self
    }
    #[inline]
    fn map(mut self, f: f64, f1: f64, _: f64) -> Self {
        self.v = f;
        self.g.iter_mut().for_each(|x| *x *= f1);
        self
    }
}

/// A value with its gradient and Hessian (full, symmetric) over `N`
/// variables.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Jet<const N: usize> {
    pub v: f64,
    pub g: [f64; N],
    pub h: [[f64; N]; N],
}

impl<const N: usize> Jet<N> {
    /// Variable `i` of `N` at value `v`.
    pub fn var(v: f64, i: usize) -> Self {
        let mut j = Self::cst(v);
        if let Some(x) = j.g.get_mut(i) {
            *x = 1.0;
        }
        j
    }
}

impl<const N: usize> Add for Jet<N> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: Self) -> Self {
        self.v += o.v;
        for (a, b) in self.g.iter_mut().zip(&o.g) {
            *a += b;
        }
        for (ra, rb) in self.h.iter_mut().zip(&o.h) {
            for (a, b) in ra.iter_mut().zip(rb) {
                *a += b;
            }
        }
        self
    }
}

impl<const N: usize> Sub for Jet<N> {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        self + o.scale(-1.0)
    }
}

impl<const N: usize> Neg for Jet<N> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        self.scale(-1.0)
    }
}

impl<const N: usize> Mul for Jet<N> {
    type Output = Self;
    /// `(uv)'' = u'' v + u v'' + u' v'ᵀ + v' u'ᵀ`.
    #[inline]
    fn mul(self, o: Self) -> Self {
        let mut r = Self::cst(self.v * o.v);
        for i in 0..N {
            r.g[i] = self.g[i] * o.v + o.g[i] * self.v;
            let (ai, bi) = (self.g[i], o.g[i]);
            let (hi, oi) = (&self.h[i], &o.h[i]);
            let ri = &mut r.h[i];
            for j in 0..N {
                ri[j] = hi[j] * o.v + oi[j] * self.v + ai * o.g[j] + bi * self.g[j];
            }
        }
        r
    }
}

impl<const N: usize> Scalar for Jet<N> {
    #[inline]
    fn cst(v: f64) -> Self {
        Jet {
            v,
            g: [0.0; N],
            h: [[0.0; N]; N],
        }
    }
    #[inline]
    fn value(&self) -> f64 {
        self.v
    }
    #[inline]
    fn scale(mut self, c: f64) -> Self {
        self.v *= c;
        self.g.iter_mut().for_each(|x| *x *= c);
        for row in self.h.iter_mut() {
            row.iter_mut().for_each(|x| *x *= c);
        }
        self
    }
    /// `f(u)'' = f'(u) u'' + f''(u) u' u'ᵀ`.
    #[inline]
    fn map(mut self, f: f64, f1: f64, f2: f64) -> Self {
        self.v = f;
        let g = self.g;
        for (row, gi) in self.h.iter_mut().zip(&g) {
            for (x, gj) in row.iter_mut().zip(&g) {
                *x = f1 * *x + f2 * gi * gj;
            }
        }
        self.g.iter_mut().for_each(|x| *x *= f1);
        self
    }
}

/// A 3-vector of scalars.
pub(crate) type Vec3<T> = [T; 3];

#[inline]
pub(crate) fn dot<T: Scalar>(a: &Vec3<T>, b: &Vec3<T>) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub(crate) fn cross<T: Scalar>(a: &Vec3<T>, b: &Vec3<T>) -> Vec3<T> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
pub(crate) fn axpy<T: Scalar>(s: T, x: &Vec3<T>, y: &Vec3<T>) -> Vec3<T> {
    [s * x[0] + y[0], s * x[1] + y[1], s * x[2] + y[2]]
}

#[inline]
pub(crate) fn sub3<T: Scalar>(a: &Vec3<T>, b: &Vec3<T>) -> Vec3<T> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
pub(crate) fn mul3<T: Scalar>(s: T, a: &Vec3<T>) -> Vec3<T> {
    [s * a[0], s * a[1], s * a[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f<T: Scalar>(x: T, y: T) -> T {
        // x² y / √(x + y) + 1/y
        (x * x * y) * (x + y).sqrt().recip() + y.recip()
    }

    #[test]
    fn jet_derivatives_match_finite_differences() {
        let (x0, y0) = (0.7, 1.3);
        let j: Jet<2> = f(Jet::var(x0, 0), Jet::var(y0, 1));
        let d: Dual<2> = f(Dual::var(x0, 0), Dual::var(y0, 1));
        let h = 1e-5;
        let gx = (f(x0 + h, y0) - f(x0 - h, y0)) / (2.0 * h);
        let gy = (f(x0, y0 + h) - f(x0, y0 - h)) / (2.0 * h);
        assert!((j.v - f(x0, y0)).abs() < 1e-15 && (d.v - j.v).abs() < 1e-15);
        assert!((j.g[0] - gx).abs() < 1e-9 && (j.g[1] - gy).abs() < 1e-9);
        assert!((d.g[0] - j.g[0]).abs() < 1e-15 && (d.g[1] - j.g[1]).abs() < 1e-15);
        // Hessian by differences of the jet gradient
        let gp: Jet<2> = f(Jet::var(x0 + h, 0), Jet::var(y0, 1));
        let gm: Jet<2> = f(Jet::var(x0 - h, 0), Jet::var(y0, 1));
        for k in 0..2 {
            let fd = (gp.g[k] - gm.g[k]) / (2.0 * h);
            assert!((j.h[0][k] - fd).abs() < 1e-8, "{k}: {} vs {fd}", j.h[0][k]);
            assert!((j.h[0][k] - j.h[k][0]).abs() < 1e-14);
        }
    }
}

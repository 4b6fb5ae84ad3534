//! A minimal manifold interface so that numeric differentiation and the solver can perturb any
//! state the same way.
//!
//! `x.retract(δ) = x ⊕ δ` and `x.local(y) = y ⊖ x`, with `x.retract(x.local(y)) = y` and
//! `x.local(x.retract(δ)) = δ` near δ = 0. For Lie groups the perturbation is on the **right**:
//! `X ⊕ δ = X·Exp(δ)`, `Y ⊖ X = Log(X⁻¹Y)`. For vectors both are plain addition/subtraction.
//! Products (tuples, `Vec`) concatenate the components' tangents in order.

use crate::{SE3, SO3};
use nalgebra::{DVector, SVector, Vector3, Vector6};

/// A smooth manifold with a retraction and its local inverse (see the module docs).
pub trait Manifold: Clone {
    /// Dimension of the tangent space.
    fn dim(&self) -> usize;
    /// `self ⊕ delta`; `delta.len() == self.dim()`.
    fn retract(&self, delta: &[f64]) -> Self;
    /// `other ⊖ self`, written into `out` (`out.len() == self.dim()`).
    fn local(&self, other: &Self, out: &mut [f64]);
    /// `other ⊖ self` as a new vector.
    fn local_vec(&self, other: &Self) -> DVector<f64> {
        let mut v = DVector::zeros(self.dim());
        self.local(other, v.as_mut_slice());
        v
    }
}

impl Manifold for f64 {
    fn dim(&self) -> usize {
        1
    }
    fn retract(&self, d: &[f64]) -> Self {
        self + d[0]
    }
    fn local(&self, o: &Self, out: &mut [f64]) {
        out[0] = o - self;
    }
}

impl<const N: usize> Manifold for SVector<f64, N> {
    fn dim(&self) -> usize {
        N
    }
    fn retract(&self, d: &[f64]) -> Self {
        self + SVector::<f64, N>::from_column_slice(d)
    }
    fn local(&self, o: &Self, out: &mut [f64]) {
        out.copy_from_slice((o - self).as_slice());
    }
}

impl Manifold for DVector<f64> {
    fn dim(&self) -> usize {
        self.len()
    }
    fn retract(&self, d: &[f64]) -> Self {
        self + DVector::from_column_slice(d)
    }
    fn local(&self, o: &Self, out: &mut [f64]) {
        out.copy_from_slice((o - self).as_slice());
    }
}

impl Manifold for SO3 {
    fn dim(&self) -> usize {
        3
    }
    fn retract(&self, d: &[f64]) -> Self {
        self.plus(&Vector3::from_column_slice(d))
    }
    fn local(&self, o: &Self, out: &mut [f64]) {
        out.copy_from_slice(o.minus(self).as_slice());
    }
}

impl Manifold for SE3 {
    fn dim(&self) -> usize {
        6
    }
    fn retract(&self, d: &[f64]) -> Self {
        self.plus(&Vector6::from_column_slice(d))
    }
    fn local(&self, o: &Self, out: &mut [f64]) {
        out.copy_from_slice(o.minus(self).as_slice());
    }
}

impl<M: Manifold> Manifold for Vec<M> {
    fn dim(&self) -> usize {
        self.iter().map(Manifold::dim).sum()
    }
    fn retract(&self, d: &[f64]) -> Self {
        let mut k = 0;
        self.iter()
            .map(|m| {
                let n = m.dim();
                let r = m.retract(&d[k..k + n]);
                k += n;
                r
            })
            .collect()
    }
    fn local(&self, o: &Self, out: &mut [f64]) {
        let mut k = 0;
        for (a, b) in self.iter().zip(o) {
            let n = a.dim();
            a.local(b, &mut out[k..k + n]);
            k += n;
        }
    }
}

macro_rules! tuple_manifold {
    ($($name:ident $idx:tt),+) => {
        impl<$($name: Manifold),+> Manifold for ($($name,)+) {
            fn dim(&self) -> usize {
                0 $(+ self.$idx.dim())+
            }
            fn retract(&self, d: &[f64]) -> Self {
                let mut _k = 0;
                ($({
                    let n = self.$idx.dim();
                    let r = self.$idx.retract(&d[_k.._k + n]);
                    _k += n;
                    r
                },)+)
            }
            fn local(&self, o: &Self, out: &mut [f64]) {
                let mut _k = 0;
                $({
                    let n = self.$idx.dim();
                    self.$idx.local(&o.$idx, &mut out[_k.._k + n]);
                    _k += n;
                })+
            }
        }
    };
}
tuple_manifold!(A 0, B 1);
tuple_manifold!(A 0, B 1, C 2);
tuple_manifold!(A 0, B 1, C 2, D 3);
tuple_manifold!(A 0, B 1, C 2, D 3, E 4);

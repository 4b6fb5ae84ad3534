//! Shared test helpers (included by `mod common;`).
#![allow(dead_code)]

use nalgebra::DMatrix;
use preint_lie::Manifold;

/// Central-difference Jacobian on manifolds: column k = (f(x⊕h e_k) ⊖ f(x⊕−h e_k)) / 2h, both
/// local coordinates taken at f(x).
pub fn num_jac<X: Manifold, Y: Manifold>(f: impl Fn(&X) -> Y, x: &X, h: f64) -> DMatrix<f64> {
    let y0 = f(x);
    let (n, m) = (x.dim(), y0.dim());
    let mut j = DMatrix::zeros(m, n);
    let mut d = vec![0.0; n];
    for k in 0..n {
        d.iter_mut().for_each(|v| *v = 0.0);
        d[k] = h;
        let yp = y0.local_vec(&f(&x.retract(&d)));
        d[k] = -h;
        let ym = y0.local_vec(&f(&x.retract(&d)));
        j.set_column(k, &((yp - ym) / (2.0 * h)));
    }
    j
}

/// max |a − b| / max(1, max |b|).
pub fn rel_err(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    assert_eq!(a.shape(), b.shape());
    (a - b).amax() / b.amax().max(1.0)
}

pub fn dm<R: nalgebra::Dim, C: nalgebra::Dim, S: nalgebra::RawStorage<f64, R, C>>(
    m: &nalgebra::Matrix<f64, R, C, S>,
) -> DMatrix<f64> {
    DMatrix::from_iterator(m.nrows(), m.ncols(), m.iter().cloned())
}

/// A small deterministic generator (SplitMix64) so that the sampled tests print reproducible
/// worst cases; not used for anything statistical beyond "spread the inputs out".
pub struct SplitMix(u64);

impl SplitMix {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [a, b).
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.uniform()
    }

    /// Standard normal (Box–Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform(); // (0, 1]
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// Uniform direction on the unit sphere.
    pub fn unit_vector(&mut self) -> nalgebra::Vector3<f64> {
        nalgebra::Vector3::new(self.normal(), self.normal(), self.normal()).normalize()
    }

    /// Uniform (Haar) random rotation as a unit quaternion: four normals, normalised.
    pub fn unit_quaternion(&mut self) -> nalgebra::UnitQuaternion<f64> {
        nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            self.normal(),
            self.normal(),
            self.normal(),
            self.normal(),
        ))
    }
}

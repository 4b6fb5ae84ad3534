//! Shared test helpers (included by `mod common;`).
#![allow(dead_code)]

use lie::Manifold;
use nalgebra::DMatrix;

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

//! numpy ↔ nalgebra conversions and the checks that give a wrong shape a typed error naming
//! the argument.

use crate::errors::shape_err;
use nalgebra::{Matrix3, SMatrix, Vector3};
use numpy::ndarray::{Array1, Array2, ArrayView1, ArrayView2};
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2,
    PyUntypedArrayMethods,
};
use preint::{ImuSample, PreintError};
use pyo3::prelude::*;
use std::cell::RefCell;
use std::ops::Range;

/// A 3-vector from any sequence of three numbers (list, tuple, numpy array).
pub(crate) fn vec3(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vector3<f64>> {
    let v: Vec<f64> = obj
        .extract()
        .map_err(|_| shape_err(format!("{name}: expected three numbers")))?;
    if v.len() != 3 {
        return Err(shape_err(format!(
            "{name}: expected three numbers, got {}",
            v.len()
        )));
    }
    Ok(Vector3::new(v[0], v[1], v[2]))
}

/// An `R×C` matrix from nested sequences (a list of rows or a 2-D numpy array).
pub(crate) fn matrix<const R: usize, const C: usize>(
    name: &str,
    obj: &Bound<'_, PyAny>,
) -> PyResult<SMatrix<f64, R, C>> {
    let rows: Vec<Vec<f64>> = obj
        .extract()
        .map_err(|_| shape_err(format!("{name}: expected a {R}×{C} matrix of numbers")))?;
    if rows.len() != R || rows.iter().any(|r| r.len() != C) {
        return Err(shape_err(format!("{name}: expected a {R}×{C} matrix")));
    }
    Ok(SMatrix::<f64, R, C>::from_fn(|i, j| rows[i][j]))
}

/// A 3×3 covariance: a 3×3 matrix, or a number `s` meaning `s·I`.
pub(crate) fn cov3(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Matrix3<f64>> {
    if let Ok(s) = obj.extract::<f64>() {
        return Ok(Matrix3::identity() * s);
    }
    matrix::<3, 3>(name, obj)
}

/// A matrix as a new `R×C` numpy array (row-major).
pub(crate) fn mat_py<'py, const R: usize, const C: usize>(
    py: Python<'py>,
    m: &SMatrix<f64, R, C>,
) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((R, C), |(i, j)| m[(i, j)]).into_pyarray(py)
}

/// A 3-vector as a new numpy array.
pub(crate) fn vec_py<'py>(py: Python<'py>, v: &Vector3<f64>) -> Bound<'py, PyArray1<f64>> {
    Array1::from_iter(v.iter().copied()).into_pyarray(py)
}

/// An `N`-vector as a new numpy array.
pub(crate) fn svec_py<'py, const N: usize>(
    py: Python<'py>,
    v: &SMatrix<f64, N, 1>,
) -> Bound<'py, PyArray1<f64>> {
    Array1::from_iter(v.iter().copied()).into_pyarray(py)
}

/// The samples of the arrays `t_ns` (int64[N], nanoseconds), `gyro` (float64[N, 3], rad/s)
/// and `acc` (float64[N, 3], m/s²) as one vector. Shapes and dtypes are checked here, values
/// (finite, increasing timestamps) by the preintegrator, which names the sample. (For bindings
/// that need a whole stream at once; the window functions convert window by window.)
pub(crate) fn samples(
    t_ns: &Bound<'_, PyAny>,
    gyro: &Bound<'_, PyAny>,
    acc: &Bound<'_, PyAny>,
) -> PyResult<Vec<ImuSample>> {
    let arrays = SampleArrays::new(t_ns, gyro, acc)?;
    let v = arrays.views();
    let mut out = Vec::with_capacity(v.len());
    v.fill(0..v.len(), &mut out);
    Ok(out)
}

/// The three sample arrays, checked and borrowed read-only (numpy's borrow flags keep Rust
/// from writing them while they are read here).
pub(crate) struct SampleArrays<'py> {
    t: PyReadonlyArray1<'py, i64>,
    g: PyReadonlyArray2<'py, f64>,
    a: PyReadonlyArray2<'py, f64>,
}

impl<'py> SampleArrays<'py> {
    /// Checks dtypes, shapes and lengths (a typed `ShapeError` naming the argument).
    pub(crate) fn new(
        t_ns: &Bound<'py, PyAny>,
        gyro: &Bound<'py, PyAny>,
        acc: &Bound<'py, PyAny>,
    ) -> PyResult<Self> {
        let t = t_ns.cast::<PyArray1<i64>>().map_err(|_| {
            shape_err("t_ns: expected a 1-D numpy array of dtype int64 (nanoseconds)")
        })?;
        let g = rows3("gyro", gyro)?;
        let a = rows3("acc", acc)?;
        let (t, g, a) = (t.readonly(), g.readonly(), a.readonly());
        let n = t.len();
        if g.shape()[0] != n || a.shape()[0] != n {
            return Err(shape_err(format!(
                "t_ns, gyro and acc must have the same length: {n}, {}, {}",
                g.shape()[0],
                a.shape()[0]
            )));
        }
        Ok(Self { t, g, a })
    }

    /// Views of the arrays that can be read with the GIL released.
    pub(crate) fn views(&self) -> SampleViews<'_> {
        SampleViews {
            t: self.t.as_array(),
            g: self.g.as_array(),
            a: self.a.as_array(),
        }
    }
}

/// Read-only views of the sample arrays (`Send`: used inside `py.detach`).
pub(crate) struct SampleViews<'a> {
    t: ArrayView1<'a, i64>,
    g: ArrayView2<'a, f64>,
    a: ArrayView2<'a, f64>,
}

impl SampleViews<'_> {
    /// Number of samples.
    pub(crate) fn len(&self) -> usize {
        self.t.len()
    }

    /// Appends samples `range` to `out` (contiguous arrays are read as slices, others element
    /// by element).
    pub(crate) fn fill(&self, range: Range<usize>, out: &mut Vec<ImuSample>) {
        let (t, g, a) = (&self.t, &self.g, &self.a);
        if let (Some(ts), Some(gs), Some(as_)) = (t.as_slice(), g.as_slice(), a.as_slice()) {
            let (gs, as_) = (
                &gs[3 * range.start..3 * range.end],
                &as_[3 * range.start..3 * range.end],
            );
            out.extend(
                ts[range]
                    .iter()
                    .zip(gs.chunks_exact(3).zip(as_.chunks_exact(3)))
                    .map(|(&t, (g, a))| {
                        ImuSample::new(
                            t,
                            Vector3::new(g[0], g[1], g[2]),
                            Vector3::new(a[0], a[1], a[2]),
                        )
                    }),
            );
        } else {
            out.extend(range.map(|k| {
                ImuSample::new(
                    t[k],
                    Vector3::new(g[(k, 0)], g[(k, 1)], g[(k, 2)]),
                    Vector3::new(a[(k, 0)], a[(k, 1)], a[(k, 2)]),
                )
            }));
        }
    }

    /// The samples a keyframe window `[t_i_ns, t_j_ns]` reads, with `margin` samples beyond the
    /// last sample before `t_i` and the first after `t_j`. Binary search, as in
    /// `preint::preintegrate` (an unsorted stream is reported there).
    pub(crate) fn window_range(&self, t_i_ns: i64, t_j_ns: i64, margin: usize) -> Range<usize> {
        let n = self.len();
        let lo = self.partition_point(|t| t < t_i_ns);
        let hi = self.partition_point(|t| t <= t_j_ns);
        lo.saturating_sub(margin)..(hi.max(lo) + margin).min(n)
    }

    /// `f` on the samples of the keyframe window `[t_i_ns, t_j_ns]` and `margin` samples either
    /// side ([`SampleViews::window_range`]), converted into this thread's scratch buffer; a
    /// sample index in `f`'s error is counted from the start of the caller's arrays.
    pub(crate) fn in_window<T>(
        &self,
        (t_i_ns, t_j_ns): (i64, i64),
        margin: usize,
        f: impl FnOnce(&[ImuSample]) -> Result<T, PreintError>,
    ) -> Result<T, PreintError> {
        let range = self.window_range(t_i_ns, t_j_ns, margin);
        let offset = range.start;
        with_scratch(|buf| {
            self.fill(range, buf);
            f(buf).map_err(|e| shift(e, offset))
        })
    }

    fn partition_point(&self, pred: impl Fn(i64) -> bool) -> usize {
        let (mut lo, mut hi) = (0, self.len());
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            if pred(self.t[mid]) {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        lo
    }
}

/// Samples kept per thread between calls in [`with_scratch`]: a window of up to 2²⁰ samples
/// (56 MiB) reuses the buffer instead of allocating (and page-faulting) a new one per call.
const SCRATCH_KEEP: usize = 1 << 20;

thread_local! {
    static SCRATCH: RefCell<Vec<ImuSample>> = const { RefCell::new(Vec::new()) };
}

/// Samples either side of a keyframe window that its preintegration (and the deltas inside
/// it) may read: `preint::preintegrate` uses and checks at most 4 samples beyond the last sample
/// before `t_i` and the first after `t_j` (checks from 3 before to 3 after, a stencil reach of
/// 1), so the window of the range equals the window of the whole stream.
pub(crate) const WINDOW_MARGIN: usize = 8;

/// `e` with its sample index counted from the start of the caller's arrays, for an error of a
/// window integrated from the sub-range starting at sample `offset`.
fn shift(mut e: PreintError, offset: usize) -> PreintError {
    match &mut e {
        PreintError::NonFinite { index, .. }
        | PreintError::DuplicateTimestamp { index, .. }
        | PreintError::DecreasingTimestamp { index, .. }
        | PreintError::GapTooLarge { index, .. } => *index += offset,
        _ => {}
    }
    e
}

/// Runs `f` with an empty sample buffer: this thread's scratch buffer, kept for the next call
/// when its capacity is at most [`SCRATCH_KEEP`] samples.
pub(crate) fn with_scratch<R>(f: impl FnOnce(&mut Vec<ImuSample>) -> R) -> R {
    let mut buf = SCRATCH.with(|s| s.take());
    buf.clear();
    let r = f(&mut buf);
    if buf.capacity() <= SCRATCH_KEEP {
        SCRATCH.with(|s| *s.borrow_mut() = buf);
    }
    r
}

/// An `N×3` float64 array argument.
fn rows3<'a, 'py>(
    name: &str,
    obj: &'a Bound<'py, PyAny>,
) -> PyResult<&'a Bound<'py, PyArray2<f64>>> {
    let arr = obj.cast::<PyArray2<f64>>().map_err(|_| {
        shape_err(format!(
            "{name}: expected a numpy array of dtype float64 and shape (N, 3)"
        ))
    })?;
    if arr.shape()[1] != 3 {
        return Err(shape_err(format!(
            "{name}: expected shape (N, 3), got ({}, {})",
            arr.shape()[0],
            arr.shape()[1]
        )));
    }
    Ok(arr)
}

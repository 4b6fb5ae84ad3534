//! The samples' transforms in front of the loop, each raw sample mapped before the scheme's
//! loop sees it (the window's context samples too): the IMU intrinsics' correction
//! ([`crate::intrinsics`]; the noise densities are those of the corrected samples, so the loop
//! needs nothing more), then GTSAM's lever arm taken off each specific force
//! ([`CentripetalArm`], [`crate::LeverArm::Centripetal`]), of which the loop knows only the
//! rate coupling its gains carry (`engine.rs`).

use super::Engine;
use crate::extrinsics::CentripetalArm;
use crate::fast::correction::Kernel;
use crate::intrinsics::{Correction, IntrinsicJacobian};
use crate::measurement::PreintegratedImu;
use crate::sample::ImuSample;
use nalgebra::Vector3;

/// The transforms: the intrinsics' correction (with its kernel, chosen once for this
/// processor) and the lever arm with the gyro bias estimate it corrects the rates with.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Maps {
    intr: Option<(Correction, Kernel)>,
    arm: Option<(CentripetalArm, Vector3<f64>)>,
}

impl Maps {
    pub(crate) fn new(
        intr: Option<Correction>,
        arm: Option<(CentripetalArm, Vector3<f64>)>,
    ) -> Self {
        Self {
            intr: intr.map(|c| (c, Kernel::for_this_cpu())),
            arm,
        }
    }

    /// Nothing to transform.
    pub(super) fn is_identity(&self) -> bool {
        self.intr.is_none() && self.arm.is_none()
    }

    /// Sample `s` transformed.
    #[inline(always)]
    pub(crate) fn map(&self, s: &ImuSample) -> ImuSample {
        let mut x = *s;
        if let Some((c, k)) = &self.intr {
            x = k.apply(&c.columns, &x);
        }
        if let Some((arm, b_g)) = &self.arm {
            x = arm.map(&x, b_g);
        }
        x
    }

    /// Every sample of `src` transformed into `dst` (same length).
    fn map_all(&self, src: &[ImuSample], dst: &mut [ImuSample]) {
        match (&self.intr, &self.arm) {
            (Some((c, _)), None) => c.apply_all(src, dst),
            (None, Some((arm, b_g))) => {
                for (d, s) in dst.iter_mut().zip(src) {
                    *d = arm.map(s, b_g);
                }
            }
            (Some((c, _)), Some((arm, b_g))) => {
                c.apply_all(src, dst);
                for d in dst.iter_mut() {
                    *d = arm.map(d, b_g);
                }
            }
            (None, None) => dst.copy_from_slice(src),
        }
    }
}

/// A loop whose samples are transformed first.
#[derive(Clone, Debug)]
pub(super) struct Front<E> {
    inner: E,
    maps: Maps,
    /// The slice path's chunk of transformed samples (allocated at the slice path's first
    /// use: only `Level::Deltas` takes it).
    buf: Vec<ImuSample>,
}

impl<E> Front<E> {
    /// Samples transformed per chunk of the slice path: large, because the inner slice path
    /// pays a fixed cost per call (hermite4 clears a block buffer).
    const CHUNK: usize = 2048;

    pub(super) fn new(inner: E, maps: Maps) -> Self {
        Self {
            inner,
            maps,
            buf: Vec::new(),
        }
    }
}

impl<E: Engine + Clone + 'static> Engine for Front<E> {
    #[inline]
    fn push(&mut self, s: &ImuSample) {
        self.inner.push(&self.maps.map(s));
    }
    /// The slice fast path on the transformed samples, a chunk at a time (nothing is
    /// transformed when the loop cannot take a slice).
    fn run_slice(&mut self, samples: &[ImuSample], last_t_ns: i64, gap_limit: u64) -> usize {
        if !self.inner.slice_ready() {
            return 0;
        }
        let maps = self.maps;
        if self.buf.is_empty() {
            let zero = ImuSample::new(0, Vector3::zeros(), Vector3::zeros());
            self.buf = vec![zero; Self::CHUNK];
        }
        run_mapped(
            samples,
            last_t_ns,
            &mut self.buf,
            |src, dst| maps.map_all(src, dst),
            |buf, last| self.inner.run_slice(buf, last, gap_limit),
        )
    }
    fn slice_ready(&self) -> bool {
        self.inner.slice_ready()
    }
    fn len(&self) -> usize {
        self.inner.len()
    }
    fn measurement(&self) -> PreintegratedImu {
        self.inner.measurement()
    }
    fn measurement_and_intrinsics(&self) -> (PreintegratedImu, Option<IntrinsicJacobian>) {
        self.inner.measurement_and_intrinsics()
    }
    fn end_rates(&self) -> (Vector3<f64>, Vector3<f64>, f64) {
        self.inner.end_rates()
    }
    fn boxed_clone(&self) -> Box<dyn Engine> {
        Box::new(self.clone())
    }
}

/// `run` on `map` of every sample, `buf.len()` samples at a time through `buf` (the slice
/// path of the front): `map(src, dst)` writes the mapped chunk `src` into `dst`
/// (same length); stops at the first chunk `run` does not take whole and returns how many
/// samples were taken; `run` gets each chunk and the time of the sample before it.
fn run_mapped(
    samples: &[ImuSample],
    last_t_ns: i64,
    buf: &mut [ImuSample],
    map: impl Fn(&[ImuSample], &mut [ImuSample]),
    mut run: impl FnMut(&[ImuSample], i64) -> usize,
) -> usize {
    let (mut used, mut last) = (0, last_t_ns);
    for chunk in samples.chunks(buf.len()) {
        map(chunk, &mut buf[..chunk.len()]);
        let n = run(&buf[..chunk.len()], last);
        used += n;
        if n < chunk.len() {
            break;
        }
        last = chunk[n - 1].t_ns;
    }
    used
}

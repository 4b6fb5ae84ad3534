//! What `advise` assumes about the input between samples (`--input smooth|held`), the reference
//! and the lower rates that follow from it, and when each scheme is exact.
//!
//! - **smooth** (the default): the samples are point samples of a smooth signal, which is what
//!   a MEMS IMU delivers (its rate and specific force are continuous; its internal filter leaves
//!   a band-limited signal). No scheme is exact; the 4th-order `hermite4` scheme is the
//!   reference, and a lower rate is every d-th sample (what an IMU sampling the same signal at
//!   rate/d delivers, without its internal filtering).
//! - **held**: `(ω_k, a_k)` is constant over `[t_k, t_k+1]`, which is what an integrating IMU
//!   (delta-angle and delta-velocity outputs divided by the interval) or a sample-and-hold
//!   stream delivers. `galilean` is exact for it (the Gal(3) exponential of the held input;
//!   Delama et al., RA-L 2025) and is the reference; a lower rate is the mean of d consecutive
//!   samples held over their d intervals (what an integrating IMU at rate/d reports, without
//!   its coning and sculling terms).

use preint::{ImuSample, Scheme};

/// The input class `advise` is told the recording belongs to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum InputClass {
    /// Point samples of a smooth signal (a MEMS IMU): reference hermite4, Richardson-checked.
    #[default]
    Smooth,
    /// Rate and specific force constant over each sample interval (integrating IMUs,
    /// sample-and-hold streams): reference galilean, exact for this input.
    Held,
}

impl InputClass {
    /// The name printed (`smooth`, `held`).
    pub fn label(self) -> &'static str {
        match self {
            InputClass::Smooth => "smooth",
            InputClass::Held => "held",
        }
    }

    /// The reference scheme at the recording's rate: the scheme exact on this class if there
    /// is one, else the one of highest order on smooth input (the first of the registry among
    /// equals).
    pub fn reference(self) -> Scheme {
        self.exact_scheme().unwrap_or_else(|| {
            let order = |s: &Scheme| s.info().order;
            let best = Scheme::ALL.iter().map(order).max().unwrap_or(0);
            *Scheme::ALL
                .iter()
                .find(|s| order(s) == best)
                .expect("a registered scheme")
        })
    }

    /// The scheme whose deltas are exact (to round-off) on every input of this class, if any
    /// (the registry's [`preint::SchemeInfo::exact_when_held`]).
    pub fn exact_scheme(self) -> Option<Scheme> {
        match self {
            InputClass::Smooth => None,
            InputClass::Held => Scheme::ALL
                .iter()
                .copied()
                .find(|s| s.info().exact_when_held),
        }
    }

    /// The stream at 1/`d` of the recording's rate (module docs): every d-th sample (smooth),
    /// or the mean of each block of `d` samples at its first sample's time (held).
    pub fn decimate(self, samples: &[ImuSample], d: usize) -> Vec<ImuSample> {
        match self {
            InputClass::Smooth => samples.iter().step_by(d).copied().collect(),
            InputClass::Held => samples
                .chunks(d)
                .map(|b| {
                    let n = b.len() as f64;
                    let gyro = b.iter().map(|s| s.gyro).sum::<nalgebra::Vector3<f64>>() / n;
                    let acc = b.iter().map(|s| s.acc).sum::<nalgebra::Vector3<f64>>() / n;
                    ImuSample::new(b[0].t_ns, gyro, acc)
                })
                .collect(),
        }
    }
}

/// A scheme's accuracy: its global order on smooth input and the input on which each delta is
/// exact (its registry row, [`preint::SchemeInfo`]; `cli/tests/advise_exact.rs` checks each
/// claim against closed forms and measured slopes).
#[derive(Clone, Copy, Debug)]
pub struct Exactness {
    /// Global order of the deltas' error on smooth input (error ∝ hᵒʳᵈᵉʳ).
    pub order_smooth: u32,
    /// The input on which the scheme's deltas are exact.
    pub exact_on: &'static str,
}

/// [`Exactness`] of `s`.
pub fn exactness(s: Scheme) -> Exactness {
    let info = s.info();
    Exactness {
        order_smooth: info.order,
        exact_on: info.exact_on,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// Held decimation averages each block and keeps its first time; smooth keeps every d-th.
    #[test]
    fn decimation_per_input_class() {
        let s: Vec<ImuSample> = (0..5i64)
            .map(|k| {
                ImuSample::new(
                    k * 10,
                    Vector3::new(k as f64, 0.0, 0.0),
                    Vector3::new(0.0, 2.0 * k as f64, 0.0),
                )
            })
            .collect();
        let h = InputClass::Held.decimate(&s, 2);
        assert_eq!(h.iter().map(|s| s.t_ns).collect::<Vec<_>>(), [0, 20, 40]);
        assert_eq!(h[1].gyro.x, 2.5);
        assert_eq!(h[1].acc.y, 5.0);
        assert_eq!(h[2].gyro.x, 4.0);
        let m = InputClass::Smooth.decimate(&s, 2);
        assert_eq!(m[1].gyro.x, 2.0);
    }
}

//! Signal/noise separation for `advise`: a zero-phase 2nd-order Butterworth low-pass (biquad,
//! run forward and backward), with the cutoff chosen per sensor as the lowest one at which the
//! removed residual has the variance that white noise of the known density predicts.
//!
//! For white noise of per-sample variance σ²/Δt the residual `x − filtfilt(x)` keeps the
//! fraction `ρ(f_c) = (2/f_s)∫₀^{f_s/2} (1 − |H(f)|²)² df` of it (|H|² is the forward-backward
//! response). Below the motion's bandwidth the residual also carries signal and its variance
//! exceeds `ρ σ²/Δt`; the first cutoff (scanning upwards on a log grid) where the measured
//! residual variance is within 20 % of that prediction on all three axes is kept.

use preint::ImuSample;
use std::f64::consts::PI;

/// Normalised biquad coefficients `(b0, b1, b2, a1, a2)` of a Butterworth low-pass (RBJ cookbook).
fn butter(fc: f64, fs: f64) -> [f64; 5] {
    let w0 = 2.0 * PI * fc / fs;
    let (s, c) = w0.sin_cos();
    let alpha = s / (2.0 * std::f64::consts::FRAC_1_SQRT_2);
    let a0 = 1.0 + alpha;
    [
        (1.0 - c) / 2.0 / a0,
        (1.0 - c) / a0,
        (1.0 - c) / 2.0 / a0,
        -2.0 * c / a0,
        (1.0 - alpha) / a0,
    ]
}

fn pass(x: &mut [f64], k: &[f64; 5]) {
    // Steady-state start at the first value.
    let (mut x1, mut x2, mut y1, mut y2) = (x[0], x[0], x[0], x[0]);
    for v in x.iter_mut() {
        let x0 = *v;
        let y0 = k[0] * x0 + k[1] * x1 + k[2] * x2 - k[3] * y1 - k[4] * y2;
        (x2, x1, y2, y1) = (x1, x0, y1, y0);
        *v = y0;
    }
}

/// Zero-phase low-pass of one channel.
pub fn filtfilt(x: &[f64], fc: f64, fs: f64) -> Vec<f64> {
    let k = butter(fc, fs);
    let mut y = x.to_vec();
    pass(&mut y, &k);
    y.reverse();
    pass(&mut y, &k);
    y.reverse();
    y
}

/// Fraction of white-noise variance left in `x − filtfilt(x)`.
fn residual_fraction(fc: f64, fs: f64) -> f64 {
    let k = butter(fc, fs);
    let n = 2048;
    let mut acc = 0.0;
    for i in 0..n {
        let w = PI * (i as f64 + 0.5) / n as f64;
        let (z1, z2) = (
            nalgebra::Complex::new(w.cos(), -w.sin()),
            nalgebra::Complex::new((2.0 * w).cos(), -(2.0 * w).sin()),
        );
        let h = (z1 * k[1] + z2 * k[2] + k[0]) / (z1 * k[3] + z2 * k[4] + 1.0);
        let h2 = h.norm_sqr();
        acc += (1.0 - h2) * (1.0 - h2);
    }
    acc / n as f64
}

fn variance(x: &[f64]) -> f64 {
    let m = x.iter().sum::<f64>() / x.len() as f64;
    x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / x.len() as f64
}

/// The denoised stream and the cutoffs \[Hz\] chosen for (gyro, accelerometer); `None` when no
/// cutoff below 0.45·f_s explains the residual as noise (the stream is then left unfiltered).
pub fn denoise(
    samples: &[ImuSample],
    gyro_density: f64,
    acc_density: f64,
) -> (Vec<ImuSample>, [Option<f64>; 2]) {
    let n = samples.len();
    let dt = (samples[n - 1].t_ns - samples[0].t_ns) as f64 * 1e-9 / (n - 1) as f64;
    let fs = 1.0 / dt;
    let mut out = samples.to_vec();
    let mut cut = [None, None];
    for (sensor, density) in [(0usize, gyro_density), (1, acc_density)] {
        let chans: Vec<Vec<f64>> = (0..3)
            .map(|a| {
                samples
                    .iter()
                    .map(|s| if sensor == 0 { s.gyro[a] } else { s.acc[a] })
                    .collect()
            })
            .collect();
        let noise_var = density * density / dt;
        let mut fc = 0.1;
        while fc < 0.45 * fs {
            let rho = residual_fraction(fc, fs);
            let filtered: Vec<Vec<f64>> = chans.iter().map(|c| filtfilt(c, fc, fs)).collect();
            let ok = chans.iter().zip(&filtered).all(|(c, f)| {
                let r: Vec<f64> = c.iter().zip(f).map(|(a, b)| a - b).collect();
                variance(&r) <= 1.2 * rho * noise_var
            });
            if ok {
                for (k, s) in out.iter_mut().enumerate() {
                    for a in 0..3 {
                        if sensor == 0 {
                            s.gyro[a] = filtered[a][k]
                        } else {
                            s.acc[a] = filtered[a][k]
                        }
                    }
                }
                cut[sensor] = Some(fc);
                break;
            }
            fc *= 1.5;
        }
    }
    (out, cut)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn residual_fraction_limits() {
        // A cutoff near Nyquist removes almost nothing; a very low one removes almost everything.
        assert!(residual_fraction(0.44 * 200.0, 200.0) < 0.2);
        assert!(residual_fraction(0.5, 200.0) > 0.98);
    }

    #[test]
    fn passes_slow_signal_and_removes_fast() {
        let fs = 200.0;
        let slow: Vec<f64> = (0..4000)
            .map(|k| (2.0 * PI * 0.5 * k as f64 / fs).sin())
            .collect();
        let fast: Vec<f64> = (0..4000)
            .map(|k| (2.0 * PI * 60.0 * k as f64 / fs).sin())
            .collect();
        let fs_ = filtfilt(&slow, 5.0, fs);
        let ff = filtfilt(&fast, 5.0, fs);
        let mid = 1000..3000;
        assert!(
            slow[mid.clone()]
                .iter()
                .zip(&fs_[mid.clone()])
                .all(|(a, b)| (a - b).abs() < 1e-3)
        );
        assert!(ff[mid].iter().all(|v| v.abs() < 1e-2));
    }
}

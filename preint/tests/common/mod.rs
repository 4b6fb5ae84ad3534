//! Shared test helpers: an analytic trajectory with exact deltas, a seeded Gaussian generator,
//! and small utilities. Independent of the code under test (only `lie` Exp/Log).
#![allow(dead_code)]

use nalgebra::{Matrix3, Vector3};
use preint::{ImuSample, PreintegratedImu};
use preint_lie::SO3;

pub type V3 = Vector3<f64>;

/// Gravity used by every test scene [m/s²].
pub fn gravity() -> V3 {
    V3::new(0.0, 0.0, -9.81)
}

/// `R(t) = Exp(ω₁ t)·Exp(s(t) n)`, `s(t) = A sin(f t)`; `p(t)` sinusoidal. Body rate
/// `ω_b = Exp(s n)ᵀ ω₁ + ṡ n`, specific force `f_b = Rᵀ(p̈ − g)`: all closed form.
#[derive(Clone, Copy, Debug)]
pub struct Scene {
    pub w1: V3,
    pub n: V3,
    pub amp: f64,
    pub freq: f64,
}

impl Scene {
    /// Moderate motion: |ω| ≈ 1–2 rad/s, |a| ≈ 1–3 m/s².
    pub fn smooth() -> Self {
        Self {
            w1: V3::new(0.3, -0.5, 0.9),
            n: V3::new(1.0, 2.0, -0.5).normalize(),
            amp: 0.8,
            freq: 2.3,
        }
    }
    pub fn rot(&self, t: f64) -> SO3 {
        SO3::exp(&(self.w1 * t)) * SO3::exp(&(self.n * (self.amp * (self.freq * t).sin())))
    }
    pub fn omega(&self, t: f64) -> V3 {
        let s = self.amp * (self.freq * t).sin();
        let sd = self.amp * self.freq * (self.freq * t).cos();
        SO3::exp(&(self.n * s)).inverse().act(&self.w1) + self.n * sd
    }
    pub fn pos(&self, t: f64) -> V3 {
        V3::new(
            2.0 * (0.7 * t).sin(),
            1.5 * (0.5 * t).cos(),
            0.3 * (1.1 * t).sin(),
        )
    }
    pub fn vel(&self, t: f64) -> V3 {
        V3::new(
            1.4 * (0.7 * t).cos(),
            -0.75 * (0.5 * t).sin(),
            0.33 * (1.1 * t).cos(),
        )
    }
    pub fn acc_world(&self, t: f64) -> V3 {
        V3::new(
            -0.98 * (0.7 * t).sin(),
            -0.375 * (0.5 * t).cos(),
            -0.363 * (1.1 * t).sin(),
        )
    }
    pub fn sample(&self, t_ns: i64) -> ImuSample {
        let t = t_ns as f64 * 1e-9;
        let f = self.rot(t).inverse().act(&(self.acc_world(t) - gravity()));
        ImuSample::new(t_ns, self.omega(t), f)
    }
    /// Samples every `step_ns` over `[0, duration_ns]`.
    pub fn samples(&self, step_ns: i64, duration_ns: i64) -> Vec<ImuSample> {
        (0..=duration_ns / step_ns)
            .map(|k| self.sample(k * step_ns))
            .collect()
    }
    /// Exact (ΔR, Δv, Δp) between t0 and t1 [s] (Forster eq. 33 inverted).
    pub fn exact(&self, t0: f64, t1: f64) -> (SO3, V3, V3) {
        let (r0, r1) = (self.rot(t0), self.rot(t1));
        let dt = t1 - t0;
        let g = gravity();
        let ri = r0.inverse();
        (
            ri * r1,
            ri.act(&(self.vel(t1) - self.vel(t0) - g * dt)),
            ri.act(&(self.pos(t1) - self.pos(t0) - self.vel(t0) * dt - g * (0.5 * dt * dt))),
        )
    }
}

/// Errors [rad, m/s, m] of a measurement against reference deltas.
pub fn errors(m: &PreintegratedImu, r: &SO3, v: &V3, p: &V3) -> (f64, f64, f64) {
    (
        m.delta_r.minus(r).norm(),
        (m.delta_v - v).norm(),
        (m.delta_p - p).norm(),
    )
}

/// Least-squares slope of log(err) against log(h).
pub fn loglog_slope(h: &[f64], err: &[f64]) -> f64 {
    let x: Vec<f64> = h.iter().map(|v| v.ln()).collect();
    let y: Vec<f64> = err.iter().map(|v| v.ln()).collect();
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    sxy / sxx
}

/// Seeded standard normal generator (SplitMix64 + Box–Muller).
pub struct Gauss {
    state: u64,
    spare: Option<f64>,
}

impl Gauss {
    pub fn new(seed: u64) -> Self {
        Self {
            state: seed,
            spare: None,
        }
    }
    fn uniform(&mut self) -> f64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    pub fn next(&mut self) -> f64 {
        if let Some(s) = self.spare.take() {
            return s;
        }
        let (u1, u2) = (self.uniform(), self.uniform());
        let r = (-2.0 * u1.ln()).sqrt();
        let a = std::f64::consts::TAU * u2;
        self.spare = Some(r * a.sin());
        r * a.cos()
    }
    pub fn vec3(&mut self) -> V3 {
        V3::new(self.next(), self.next(), self.next())
    }
    /// `L z` with `L Lᵀ = cov`.
    pub fn correlated(&mut self, chol_l: &Matrix3<f64>) -> V3 {
        chol_l * self.vec3()
    }
}

/// Composition of consecutive deltas: `ΔR_ac = ΔR_ab ΔR_bc`, `Δv_ac = Δv_ab + ΔR_ab Δv_bc`,
/// `Δp_ac = Δp_ab + Δv_ab Δt_bc + ΔR_ab Δp_bc`.
pub fn compose(a: &PreintegratedImu, b: &PreintegratedImu) -> (SO3, V3, V3) {
    (
        a.delta_r * b.delta_r,
        a.delta_v + a.delta_r.act(&b.delta_v),
        a.delta_p + a.delta_v * b.delta_t + a.delta_r.act(&b.delta_p),
    )
}
pub mod factor_vars;
pub mod gtsam_fixture;
pub mod linearisation;
pub mod slices;

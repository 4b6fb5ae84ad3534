//! The suite's Monte Carlo NEES harness: `N` noisy realisations of a noise-free stream, each
//! drawn by the suite's own generator from a seed of its own, evaluated by the test, and the
//! statistics that say whether a covariance is right.
//!
//! A test states its scene (the noise-free samples), its noise ([`SampleNoise`]), what it
//! evaluates in each realisation (a closure returning the realisation's figures: χ², error
//! norms, …) and what it asserts on the figures' draws. Realisation `r` of a run seeded `seed`
//! reads `Gauss::new(seed | r)`, so a realisation's stream does not depend on which other
//! realisations, schemes or variants a test runs, nor on the order it runs them in.
//!
//! If the weight `Σ` of an error `e = d + n` (`d` a deterministic discretisation error, `n`
//! the noise's effect, `n ~ N(0, Σ)`) is right, `eᵀΣ⁻¹e` is non-central χ² with `k` degrees of
//! freedom and non-centrality `λ = dᵀΣ⁻¹d`: mean `k + λ`, variance `2k + 4λ`, so the mean of
//! `N` draws has standard deviation `√((2k + 4λ)/N)` ([`Chi2Draws`]).

use crate::{Gauss, mean, noisy_stream};
use nalgebra::{SMatrix, SVector};
use preint::{ImuBias, ImuNoise, ImuSample};

/// Per-sample standard deviations of the noise a realisation adds to every sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleNoise {
    /// White noise `(σ_g [rad/s], σ_a [m/s²])` of each sample.
    pub white: (f64, f64),
    /// Per-step standard deviations `(σ_bg [rad/s], σ_ba [m/s²])` of the bias random walk.
    pub walk: (f64, f64),
}

impl SampleNoise {
    /// The densities of `noise` at a sample period of `dt_s` \[s\]: white `σ/√Δt`, walk
    /// `σ_b √Δt` ([`ImuNoise::gyro_sample_std`], [`ImuNoise::gyro_bias_step_std`], …).
    pub fn at(noise: &ImuNoise, dt_s: f64) -> Self {
        Self {
            white: (noise.gyro_sample_std(dt_s), noise.acc_sample_std(dt_s)),
            walk: (
                noise.gyro_bias_step_std(dt_s),
                noise.acc_bias_step_std(dt_s),
            ),
        }
    }
}

/// The draws of each figure a Monte Carlo evaluates: `figures[k][r]` is figure `k` of
/// realisation `r`.
pub type Figures = Vec<Vec<f64>>;

/// The loop of every Monte Carlo of the suite: for `r` in `0..n`, the realisation `draw` makes
/// from `Gauss::new(seed | r)`, evaluated by `eval(r, &realisation)` into its figures (the
/// same number every time).
pub fn realise<S, V: IntoIterator<Item = f64>>(
    n: usize,
    seed: u64,
    mut draw: impl FnMut(&mut Gauss) -> S,
    mut eval: impl FnMut(usize, &S) -> V,
) -> Figures {
    let mut figures: Figures = Vec::new();
    for r in 0..n {
        let realisation = draw(&mut Gauss::new(seed | r as u64));
        let mut count = 0;
        for (k, x) in eval(r, &realisation).into_iter().enumerate() {
            if r == 0 {
                figures.push(Vec::with_capacity(n));
            }
            figures[k].push(x);
            count = k + 1;
        }
        assert_eq!(
            count,
            figures.len(),
            "realisation {r}: another number of figures"
        );
    }
    figures
}

/// `n` realisations of the noise-free samples `clean` with the noise `noise`
/// ([`noisy_stream`]).
#[derive(Clone, Copy, Debug)]
pub struct MonteCarlo<'a> {
    /// The noise-free samples (the scene's readings, with any constant bias).
    pub clean: &'a [ImuSample],
    /// What each realisation adds.
    pub noise: SampleNoise,
    /// Realisations.
    pub n: usize,
}

impl MonteCarlo<'_> {
    /// Fixed bias: each realisation is `clean` plus white noise; `eval(samples)` gives its
    /// figures.
    pub fn white<V: IntoIterator<Item = f64>>(
        &self,
        seed: u64,
        mut eval: impl FnMut(&[ImuSample]) -> V,
    ) -> Figures {
        let draw = |rng: &mut Gauss| noisy_stream(self.clean, rng, self.noise.white, None).0;
        realise(self.n, seed, draw, |_, s: &Vec<ImuSample>| eval(s))
    }

    /// Bias random walk: each realisation is `clean` plus white noise plus the walk from
    /// zero; `eval(samples, walk)` gives its figures, `walk` the walk's value at the last
    /// sample (`b_j − b_i`).
    pub fn walk<V: IntoIterator<Item = f64>>(
        &self,
        seed: u64,
        mut eval: impl FnMut(&[ImuSample], &ImuBias) -> V,
    ) -> Figures {
        let draw = |rng: &mut Gauss| {
            noisy_stream(self.clean, rng, self.noise.white, Some(self.noise.walk))
        };
        realise(
            self.n,
            seed,
            draw,
            |_, (s, w): &(Vec<ImuSample>, ImuBias)| eval(s, w),
        )
    }
}

/// NEES `eᵀΣ⁻¹e` (Cholesky solve).
pub fn nees<const N: usize>(e: &SVector<f64, N>, cov: &SMatrix<f64, N, N>) -> f64 {
    e.dot(
        &cov.cholesky()
            .expect("covariance positive definite")
            .solve(e),
    )
}

/// The 15-dim error `[e, b_j − b_i]` (order [δφ, δv, δp, δb_g, δb_a]) of the 9-dim delta
/// error `e` and the bias walk `b_j − b_i`.
pub fn combined_error(e: &SVector<f64, 9>, walk: &ImuBias) -> SVector<f64, 15> {
    let mut e15 = SVector::<f64, 15>::zeros();
    e15.fixed_rows_mut::<9>(0).copy_from(e);
    e15.fixed_rows_mut::<3>(9).copy_from(&walk.gyro);
    e15.fixed_rows_mut::<3>(12).copy_from(&walk.acc);
    e15
}

/// The χ² draws of one figure and the mean a correct weight predicts for them: `dof + λ`, the
/// mean of a non-central χ² (module docs), with standard deviation of the mean
/// `√((2 dof + 4λ)/N)`.
#[derive(Clone, Debug)]
pub struct Chi2Draws {
    /// Degrees of freedom `k`.
    pub dof: usize,
    /// Non-centrality `λ`: the noise-free (discretisation) χ².
    pub lambda: f64,
    /// The draws.
    pub draws: Vec<f64>,
}

impl Chi2Draws {
    /// Mean of the draws.
    pub fn mean(&self) -> f64 {
        mean(&self.draws)
    }

    /// `k + λ`.
    pub fn expected(&self) -> f64 {
        self.dof as f64 + self.lambda
    }

    /// `√((2k + 4λ)/N)`.
    pub fn std_of_mean(&self) -> f64 {
        ((2.0 * self.dof as f64 + 4.0 * self.lambda) / self.draws.len() as f64).sqrt()
    }

    /// `(mean − (k + λ)) / std_of_mean`.
    pub fn z(&self) -> f64 {
        (self.mean() - self.expected()) / self.std_of_mean()
    }

    /// `k + λ ∓ z · std_of_mean` (`z = 1.96`: the 95 % band of the mean).
    pub fn band(&self, z: f64) -> (f64, f64) {
        let (e, sd) = (self.expected(), self.std_of_mean());
        (e - z * sd, e + z * sd)
    }
}

/// `rows(i, setup)` of every setup on two threads (the CI machine's cores), thread `t` taking
/// the setups `i ≡ t (mod 2)` in order: thread 0's rows first, then thread 1's.
pub fn on_two_threads<S: Sync, R: Send>(
    setups: &[S],
    rows: impl Fn(usize, &S) -> Vec<R> + Sync,
) -> Vec<R> {
    let rows = &rows;
    std::thread::scope(|sc| {
        let handles: Vec<_> = (0..2)
            .map(|t| {
                sc.spawn(move || {
                    setups
                        .iter()
                        .enumerate()
                        .filter(|(i, _)| i % 2 == t)
                        .flat_map(|(i, s)| rows(i, s))
                        .collect::<Vec<R>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap())
            .collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn still(n: i64) -> Vec<ImuSample> {
        (0..n)
            .map(|k| {
                ImuSample::new(
                    k * 5_000_000,
                    Vector3::zeros(),
                    Vector3::new(0.0, 0.0, 9.81),
                )
            })
            .collect()
    }

    #[test]
    fn realisation_r_reads_its_own_seed() {
        let clean = still(3);
        let noise = SampleNoise {
            white: (0.5, 2.0),
            walk: (0.1, 0.3),
        };
        let mc = MonteCarlo {
            clean: &clean,
            noise,
            n: 4,
        };
        let f = mc.white(0xAB_0000, |s| [s[2].gyro.x, s[0].acc.z]);
        let g = mc.walk(0xCD_0000, |s, w| [s[1].acc.y, w.acc.x]);
        assert_eq!((f.len(), f[0].len(), g.len()), (2, 4, 2));
        for r in 0..4u64 {
            let (s, _) = noisy_stream(&clean, &mut Gauss::new(0xAB_0000 | r), (0.5, 2.0), None);
            assert_eq!(f[0][r as usize], s[2].gyro.x);
            assert_eq!(f[1][r as usize], s[0].acc.z);
            let (s, w) = noisy_stream(
                &clean,
                &mut Gauss::new(0xCD_0000 | r),
                (0.5, 2.0),
                Some((0.1, 0.3)),
            );
            assert_eq!((g[0][r as usize], g[1][r as usize]), (s[1].acc.y, w.acc.x));
        }
        assert_ne!(f[0][0], f[0][1]);
    }

    #[test]
    fn noise_at_a_period_is_the_densities_scaled() {
        let n = ImuNoise::euroc();
        let s = SampleNoise::at(&n, 0.01);
        assert!((s.white.0 - n.gyro_noise_density * 10.0).abs() < 1e-15);
        assert!((s.walk.1 - n.acc_random_walk * 0.1).abs() < 1e-15);
    }

    #[test]
    fn nees_of_a_known_error() {
        let e = SVector::<f64, 3>::new(2.0, 0.0, 3.0);
        let cov = SMatrix::<f64, 3, 3>::from_diagonal(&Vector3::new(4.0, 1.0, 9.0));
        assert!((nees(&e, &cov) - 2.0).abs() < 1e-15);
        let w = ImuBias::new(Vector3::new(1.0, 2.0, 3.0), Vector3::new(4.0, 5.0, 6.0));
        let e15 = combined_error(&SVector::<f64, 9>::repeat(-1.0), &w);
        assert_eq!((e15[8], e15[9], e15[14]), (-1.0, 1.0, 6.0));
    }

    #[test]
    fn mean_of_chi2_draws_against_its_expectation() {
        // 9 dof, λ = 2: expected 11, std of the mean √(26/4).
        let d = Chi2Draws {
            dof: 9,
            lambda: 2.0,
            draws: vec![10.0, 12.0, 14.0, 16.0],
        };
        assert_eq!((d.mean(), d.expected()), (13.0, 11.0));
        assert!((d.z() - 2.0 / 6.5f64.sqrt()).abs() < 1e-15);
        let (lo, hi) = d.band(1.0);
        assert!((hi - lo - 2.0 * 6.5f64.sqrt()).abs() < 1e-14);
    }

    #[test]
    fn two_threads_keep_each_threads_order() {
        let rows = on_two_threads(&[10, 11, 12, 13, 14], |i, s| vec![(i, *s)]);
        assert_eq!(rows, [(0, 10), (2, 12), (4, 14), (1, 11), (3, 13)]);
    }
}

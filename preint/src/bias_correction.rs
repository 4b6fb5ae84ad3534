//! The first-order bias correction of the preintegrated deltas (the mathematics:
//! [`BiasCorrection`](crate::BiasCorrection)).

use crate::choices::BiasCorrection;
use crate::error::PreintError;
use crate::measurement::{BiasJacobians, PreintegratedImu};
use crate::sample::ImuBias;
use nalgebra::{Matrix3, SVector, Vector3};
use preint_lie::se3::q_block;
use preint_lie::{SO3, hat, jl};

impl PreintegratedImu {
    /// Deltas corrected to first order for a new bias estimate `bias`, `δb = bias − bias_hat`,
    /// as [`bias_correction`](Self::bias_correction) says ([`BiasCorrection`]):
    /// [`BiasCorrection::Additive`] (Forster eq. 44) `ΔR·Exp(c_φ)`, `Δv + c_v`, `Δp + c_p` with
    /// `c_φ = ∂ΔR/∂b_g δb_g`, `c_v = ∂Δv/∂b_g δb_g + ∂Δv/∂b_a δb_a`, `c_p` likewise;
    /// [`BiasCorrection::Group`] `ΔR·Exp(c_φ)`, `Δv + ΔR Jl(c_φ) ΔRᵀ c_v`, `Δp + ΔR Jl(c_φ) ΔRᵀ c_p`
    /// (GTSAM 4.3's Galilean `biasCorrectedDelta`). Returns `(ΔR(b), Δv(b) [m/s], Δp(b) [m])`.
    ///
    /// # Panics
    ///
    /// If the bias cannot be applied ([`check_bias`](Self::check_bias): a [`Level::Deltas`](crate::Level::Deltas)
    /// measurement and `bias ≠ bias_hat`); [`try_corrected`](Self::try_corrected) returns the
    /// error instead.
    pub fn corrected(&self, bias: &ImuBias) -> (SO3, Vector3<f64>, Vector3<f64>) {
        self.assert_bias(bias);
        let c = correct(self, bias);
        (c.r, c.v, c.p)
    }

    /// [`corrected`](Self::corrected), or [`PreintError::NoBiasJacobians`] when the bias cannot
    /// be applied ([`check_bias`](Self::check_bias)).
    pub fn try_corrected(
        &self,
        bias: &ImuBias,
    ) -> Result<(SO3, Vector3<f64>, Vector3<f64>), PreintError> {
        self.check_bias(bias)?;
        let c = correct(self, bias);
        Ok((c.r, c.v, c.p))
    }
}

/// The bias-corrected deltas with what the factors need to differentiate them.
pub(crate) struct Corrected {
    /// `ΔR(b)`.
    pub r: SO3,
    /// `Jr(c_φ)`: `ΔR(b + ε) ≈ ΔR(b) Exp(Jr(c_φ) ∂ΔR/∂b_g ε_g)`.
    pub jr: Matrix3<f64>,
    /// `Δv(b)` [m/s], frame i.
    pub v: Vector3<f64>,
    /// `Δp(b)` \[m\], frame i.
    pub p: Vector3<f64>,
    /// `∂Δv(b)/∂δb`, `∂Δp(b)/∂δb` (the velocity and position blocks) and `∂ΔR/∂b_g` (the
    /// rotation block, unchanged: the rotation's derivative is `Jr(c_φ) ∂ΔR/∂b_g`).
    pub jac: BiasJacobians,
}

/// The corrected deltas of `pim` for the bias `bias` ([`BiasCorrection`]).
pub(crate) fn correct(pim: &PreintegratedImu, bias: &ImuBias) -> Corrected {
    correct_with_time_offset(pim, bias, 0.0).0
}

/// The deltas of `pim` corrected for `bias` and a time-offset change `dtd_s` \[s\] along the
/// tangent `J_b δb + J_td δt_d` ([`BiasCorrection`]; [`crate::time_offset`] for `J_td`), and `ζ`, the
/// derivative
/// of the corrected deltas with respect to `dtd_s`: rows 0..3 the rotation direction `u` with
/// `ΔR(b, t_d + ε) ≈ ΔR(b, t_d) Exp(ε Jr(c_φ) u)` (`Jr(c_φ)` is the returned `jr`), rows 3..9
/// `∂Δv/∂t_d`, `∂Δp/∂t_d`.
pub(crate) fn correct_with_time_offset(
    pim: &PreintegratedImu,
    bias: &ImuBias,
    dtd_s: f64,
) -> (Corrected, SVector<f64, 9>) {
    let dbg = bias.gyro - pim.bias_hat.gyro;
    let dba = bias.acc - pim.bias_hat.acc;
    let (j, td) = (&pim.jac, &pim.jac_td);
    let (t_r, t_v, t_p) = (
        td.fixed_rows::<3>(0).into_owned(),
        td.fixed_rows::<3>(3).into_owned(),
        td.fixed_rows::<3>(6).into_owned(),
    );
    let c_phi = j.d_r_d_bg * dbg + t_r * dtd_s;
    let (exp_c, jr) = SO3::exp_jr(&c_phi);
    let r = pim.delta_r.compose(&exp_c);
    let c_v = j.d_v_d_bg * dbg + j.d_v_d_ba * dba + t_v * dtd_s;
    let c_p = j.d_p_d_bg * dbg + j.d_p_d_ba * dba + t_p * dtd_s;
    match pim.bias_correction {
        BiasCorrection::Additive => (
            Corrected {
                r,
                jr,
                v: pim.delta_v + c_v,
                p: pim.delta_p + c_p,
                jac: *j,
            },
            *td,
        ),
        BiasCorrection::Group => {
            let dr = *pim.delta_r.matrix();
            let drt = dr.transpose();
            let jl_c = jl(&c_phi);
            let m = dr * jl_c * drt;
            // ∂(ΔR Jl(c_φ) ν)/∂c_φ, ν = ΔRᵀ c (crate::bias_correction).
            let through_phi = |c: &Vector3<f64>| -> Matrix3<f64> {
                let nu = drt * c;
                dr * (q_block(&nu, &c_phi) - hat(&(jl_c * nu)) * jl_c)
            };
            let (kv, kp) = (through_phi(&c_v), through_phi(&c_p));
            let mut z = SVector::<f64, 9>::zeros();
            z.fixed_rows_mut::<3>(0).copy_from(&t_r);
            z.fixed_rows_mut::<3>(3).copy_from(&(kv * t_r + m * t_v));
            z.fixed_rows_mut::<3>(6).copy_from(&(kp * t_r + m * t_p));
            let c = Corrected {
                r,
                jr,
                v: pim.delta_v + m * c_v,
                p: pim.delta_p + m * c_p,
                jac: BiasJacobians {
                    d_r_d_bg: j.d_r_d_bg,
                    d_v_d_bg: kv * j.d_r_d_bg + m * j.d_v_d_bg,
                    d_v_d_ba: m * j.d_v_d_ba,
                    d_p_d_bg: kp * j.d_r_d_bg + m * j.d_p_d_bg,
                    d_p_d_ba: m * j.d_p_d_ba,
                },
            };
            (c, z)
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::{BiasCorrection, Scheme};

    #[test]
    fn names_parse_and_scheme_defaults() {
        for c in BiasCorrection::ALL {
            assert_eq!(BiasCorrection::parse(c.name()), Some(c));
        }
        assert_eq!(BiasCorrection::parse("Group"), None);
        for s in Scheme::ALL {
            let want = if *s == Scheme::Galilean {
                BiasCorrection::Group
            } else {
                BiasCorrection::Additive
            };
            let p = crate::PreintParams::default().with_scheme(*s);
            assert_eq!(p.resolved_bias_correction(), want);
            let p = p.with_bias_correction(Some(BiasCorrection::Additive));
            assert_eq!(p.resolved_bias_correction(), BiasCorrection::Additive);
        }
    }
}

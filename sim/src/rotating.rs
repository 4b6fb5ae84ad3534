//! IMU readings in a rotating navigation frame (Earth rotation).
//!
//! The scene's trajectory (`p`, `v`, `a`, `R_nb`, `ω_b`) is expressed in the navigation frame
//! `n`, which rotates at the constant rate `ω_ie` [rad/s, navigation frame] with respect to
//! inertial space; gravity `g` is fixed in `n` (GTSAM's `omegaCoriolis` convention: `g` is
//! the local plumb-bob gravity and the centrifugal term is modelled separately). An ideal IMU
//! measures inertial quantities in the body frame:
//!
//! ```text
//! gyro  ω_m = ω_b + R_nbᵀ ω_ie
//! accel f   = R_nbᵀ (a + 2 ω_ie×v + ω_ie×(ω_ie×p) − g)
//! ```
//!
//! so the scene's states are the exact ground truth of a navigation solution in the rotating
//! frame (`preint::earth` for the prediction that inverts this).

use crate::scene::SceneState;
use nalgebra::Vector3;
use preint::ImuSample;

/// What an ideal IMU reads in state `st` at `t_ns` when the navigation frame rotates at
/// `earth_rate` [rad/s, navigation frame] (module docs); `None` is
/// [`SceneState::ideal_sample`] exactly.
pub fn ideal_sample_rotating(
    st: &SceneState,
    t_ns: i64,
    gravity: &Vector3<f64>,
    earth_rate: Option<&Vector3<f64>>,
) -> ImuSample {
    let Some(w) = earth_rate else {
        return st.ideal_sample(t_ns, gravity);
    };
    let r_t = st.r_wb.inverse();
    let inertial_acc = st.a + w.cross(&st.v) * 2.0 + w.cross(&w.cross(&st.p));
    ImuSample::new(
        t_ns,
        st.omega_b + r_t.act(w),
        r_t.act(&(inertial_acc - gravity)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::scene_by_name;

    #[test]
    fn without_a_rate_the_sample_is_the_plain_one() {
        let scene = scene_by_name("aggressive").unwrap();
        let st = scene.state(1.3);
        let g = Vector3::new(0.0, 0.0, -9.81);
        assert_eq!(
            ideal_sample_rotating(&st, 7, &g, None),
            st.ideal_sample(7, &g)
        );
    }

    #[test]
    fn at_rest_the_gyro_reads_the_earth_rate_in_the_body_frame() {
        let scene = scene_by_name("static").unwrap();
        let st = scene.state(0.5);
        let g = Vector3::new(0.0, 0.0, -9.81);
        let w = Vector3::new(0.0, 5e-5, 5e-5);
        let s = ideal_sample_rotating(&st, 0, &g, Some(&w));
        assert!((st.r_wb.act(&s.gyro) - w).amax() < 1e-20);
        // Centrifugal term at the scene's position, plus the plain specific force.
        let plain = st.ideal_sample(0, &g).acc;
        let c = w.cross(&w.cross(&st.p));
        assert!((s.acc - plain - st.r_wb.inverse().act(&c)).amax() < 1e-15);
    }
}

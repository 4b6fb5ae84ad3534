//! Exact preintegrated measurements from a scene (ground truth for preintegrators).

use crate::scene::{Scene, t_s};
use nalgebra::Vector3;
use preint_lie::SO3;

/// The exact preintegrated deltas between `t_i_ns` and `t_j_ns` (Forster 2017, eq. 33, with
/// the true, bias-free motion), `Δt = (t_j − t_i)·1e-9` s:
///
/// ```text
/// ΔR_ij = R_iᵀ R_j
/// Δv_ij = R_iᵀ (v_j − v_i − g Δt)
/// Δp_ij = R_iᵀ (p_j − p_i − v_i Δt − ½ g Δt²)
/// ```
///
/// `R` is body→world, `v`, `p` world frame [m/s, m], `gravity` the world gravity vector
/// [m/s²] (default convention `(0, 0, −9.81)`). Returns `(ΔR, Δv [m/s], Δp \[m\])` in the body
/// frame at `t_i`: what a preintegrator fed with noise-free, bias-free samples converges to.
pub fn exact_deltas(
    scene: &dyn Scene,
    t_i_ns: i64,
    t_j_ns: i64,
    gravity: Vector3<f64>,
) -> (SO3, Vector3<f64>, Vector3<f64>) {
    let si = scene.state(t_s(t_i_ns));
    let sj = scene.state(t_s(t_j_ns));
    let dt = (t_j_ns - t_i_ns) as f64 * 1e-9;
    let rit = si.r_wb.inverse();
    let delta_r = rit * sj.r_wb;
    let delta_v = rit * (sj.v - si.v - gravity * dt);
    let delta_p = rit * (sj.p - si.p - si.v * dt - gravity * (0.5 * dt * dt));
    (delta_r, delta_v, delta_p)
}

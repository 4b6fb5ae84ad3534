//! # preint-sim — an IMU simulator, exact ground truth and dead-reckoning integrators
//!
//! Conventions: world frame z up, gravity `g = (0, 0, −9.81)` m/s² by
//! default; `R_wb` rotates body→world; the accelerometer measures specific force
//! `a_m = S_a R_wbᵀ (a_w − g) + b_a + n_a` (reads +9.81 on the up axis at rest), the gyro
//! `ω_m = S_g ω_b + b_g + n_g` (the usual MEMS model, e.g. Furgale et al., IROS 2013); bias order [b_g, b_a]; integer-ns timestamps,
//! scene time `t_s = ns·1e-9` from a scene start at 0 ns.
//!
//! - [`scene`]: the [`Scene`] trait, [`SceneState`], [`scene_by_name`], [`SCENE_NAMES`] and
//!   the ZYX Euler-angle kinematics (`W`, `E = W⁻¹`).
//! - [`scenes`]: `seed-ellipse`, `static`, `multi-pose-static`, `gimbal-lock`, `spin`,
//!   `aggressive`, each documented with its formulas; derivatives are analytic.
//! - [`deltas`]: [`exact_deltas`], the exact preintegrated (ΔR, Δv, Δp) of a scene.
//! - [`imu`]: [`simulate`] (noise, bias random walk, scale/misalignment; ChaCha12 random
//!   numbers, see the module docs for the exact seeding and draw order) and [`write_dataset`]
//!   (EuRoC `imu.csv`, `groundtruth.csv`, Kalibr `imu.yaml`).
//! - [`rotating`]: the ideal readings in a navigation frame rotating at ω_ie (Earth rotation,
//!   [`SimConfig::earth_rate`]).
//! - [`bench`](mod@bench): [`synthetic_stream`], the stream every speed figure is measured on.
//! - [`deadreckon`]: [`dead_reckon`] with Euler / midpoint rules and quaternion / matrix-Exp /
//!   ZYX-Euler-angle attitude; [`euler_zyx_angles`], the raw Euler-angle states.

#![deny(missing_docs)]

pub mod bench;
pub mod deadreckon;
pub mod deltas;
pub mod imu;
pub mod rotating;
pub mod scene;
pub mod scenes;

pub use bench::synthetic_stream;
pub use deadreckon::{Attitude, Rule, dead_reckon, euler_zyx_angles, euler_zyx_of, rotation_error};
pub use deltas::exact_deltas;
pub use imu::{
    MAX_SIM_SAMPLES, SimConfig, SimError, SimOutput, period_ns, rng_from_seed, scale_misalignment,
    simulate, write_dataset,
};
pub use preint_io::GroundTruthState;
pub use scene::{SCENE_NAMES, Scene, SceneState, scene_by_name, t_s};
pub use scenes::{
    EulerScene, GimbalLockScene, MultiPoseStaticScene, SeedEllipseScene, SpinScene, StaticScene,
};

//! The built-in scenes. Each type documents its formulas; all derivatives are analytic.

mod euler;
mod gimbal_lock;
mod multi_pose;
mod seed_ellipse;
mod spin;
mod static_scene;

pub use euler::{EulerScene, Sines};
pub use gimbal_lock::GimbalLockScene;
pub use multi_pose::{MultiPoseStaticScene, quintic_blend};
pub use seed_ellipse::SeedEllipseScene;
pub use spin::SpinScene;
pub use static_scene::StaticScene;

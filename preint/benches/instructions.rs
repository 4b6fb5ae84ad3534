//! The loop whose instructions per sample `tools/instructions.sh` counts with valgrind's
//! callgrind: `integrate_slice` over the stream of `preint speed` and the criterion bench
//! (`preint_sim::synthetic_stream`, 200 Hz, EuRoC densities, `keep_samples` off).
//!
//! `cargo bench -p preint --bench instructions -- SCHEME LEVEL N [push]` runs it once (SCHEME:
//! euler | midpoint | hermite4 | galilean, LEVEL: deltas | covariance | combined; `push`: one sample at a
//! time through `integrate` instead of one slice); it prints nothing but a checksum, so that
//! the work is not optimised away. Without arguments (as `cargo bench` runs every bench) it
//! does nothing. With the environment variable `BODY=1` the IMU is mounted away from the body
//! origin (`body_p_sensor`: 0.3 m lever arm, rotated), as in `tests/tests/extrinsics.rs`; with
//! `BODY=centripetal` its lever arm is removed per sample (`LeverArm::Centripetal`). With
//! `INTR=1` IMU intrinsics are applied to every sample (`PreintParams::intrinsics`: 1 % scale,
//! 2 mrad misalignment, g-sensitivity 1e-3 (rad/s)/(m/s²)); with `INTR=jacobians` their
//! Jacobians are accumulated too.

use preint::{ImuBias, ImuNoise, Level, PreintParams, Preintegrator, Scheme};
use preint_sim::synthetic_stream;
use std::hint::black_box;

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    if args.len() < 3 {
        return;
    }
    let scheme =
        Scheme::from_name(&args[0]).unwrap_or_else(|| panic!("unknown scheme {}", args[0]));
    let level = match args[1].as_str() {
        "deltas" => Level::Deltas,
        "covariance" => Level::Covariance,
        "combined" => Level::Combined,
        s => panic!("unknown level {s}"),
    };
    let n: usize = args[2].parse().expect("sample count");
    let s = synthetic_stream(n);
    let mut prm = PreintParams::from_noise(&ImuNoise::euroc())
        .with_scheme(scheme)
        .with_level(level);
    prm.keep_samples = false;
    let body = std::env::var("BODY").unwrap_or_default();
    if body == "1" || body == "centripetal" {
        if body == "centripetal" {
            prm.lever_arm = preint::LeverArm::Centripetal;
        }
        prm.body_p_sensor = Some(preint::SensorPose::new(
            preint::lie::SO3::exp(&preint::nalgebra::Vector3::new(0.3, -0.5, 0.8)),
            preint::nalgebra::Vector3::new(0.1, -0.2, 0.2),
        ));
    }
    let intr = std::env::var("INTR").unwrap_or_default();
    if intr == "1" || intr == "jacobians" {
        let x = realistic_intrinsics();
        let applied = preint::intrinsics::AppliedIntrinsics::new(x);
        prm.intrinsics = Some(if intr == "jacobians" {
            applied.with_jacobians()
        } else {
            applied
        });
    }
    let mut pi = Preintegrator::new(prm, ImuBias::zero()).unwrap();
    if args.get(3).is_some_and(|a| a == "push") {
        push_all(&mut pi, &s);
    } else {
        pi.integrate_slice(black_box(&s)).unwrap();
    }
    let m = black_box(pi.finish().unwrap());
    println!("{}", m.delta_p.x + m.cov[(8, 8)]);
}

/// Every sample through `integrate`, one at a time (what `tools/instructions.sh` counts with
/// `PUSH=1`).
#[inline(never)]
fn push_all(pi: &mut Preintegrator, s: &[preint::ImuSample]) {
    for x in s {
        pi.integrate(black_box(x)).unwrap();
    }
}

/// The library's example intrinsics (`ImuIntrinsics::example`: 1 % scale, 2 mrad
/// misalignment and axis rotations, g-sensitivity 1e-3 (rad/s)/(m/s²)).
fn realistic_intrinsics() -> preint::intrinsics::ImuIntrinsics {
    preint::intrinsics::ImuIntrinsics::example(preint::intrinsics::IntrinsicsModel::Kalibr)
}

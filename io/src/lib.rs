//! IMU data in and out for the `preint` workspace.
//!
//! - [`ImuReader`]: one streaming sample source for every format — EuRoC / TUM-VI CSV, UZH-FPV
//!   `imu.txt`, GTSAM's KITTI text, any delimited text (columns from `--columns` or the header
//!   names, units from flags or the header names), and containers (ROS 1 bag, MCAP, `.db3`) —
//!   detected from the extension and the first lines when not given ([`ReadOptions`]). Samples
//!   come out in SI units with integer-nanosecond timestamps, converted from the decimal digits
//!   (no sample spacing is lost), validated (finite, strictly increasing), every error naming
//!   the file and the line or message ([`IoError`]). Line ends `\n`, `\r\n` and `\r` and a
//!   UTF-8 byte-order mark are accepted.
//! - EuRoC ground truth ([`groundtruth`]), Kalibr `imu.yaml` ([`kalibr`]), EuRoC IMU writers
//!   ([`euroc`]) — writers print shortest round-trip floats, so writing then reading is
//!   bit-exact.
//! - [`audit`]: what is wrong with a recording (timing, gaps, duplicates, clipping, units),
//!   in one streaming pass.
//! - [`plausibility`]: checks that the readings look like m/s², rad/s and the stated time unit.
//!
//! ```
//! use preint_io::{ImuReader, ReadOptions};
//! let text = "t_s,gyro_x_deg_s,gyro_y_deg_s,gyro_z_deg_s,acc_x_g,acc_y_g,acc_z_g\n\
//!             0.00,0.5,-0.4,0.2,-0.007,-0.001,-1.016\n\
//!             0.01,0.4,-0.4,0.1,-0.006,-0.001,-1.017\n";
//! let reader = ImuReader::from_text(text, "adis.csv", &ReadOptions::default()).unwrap();
//! assert_eq!(reader.info().describe(),
//!     "delimited (comma columns t,wx,wy,wz,ax,ay,az; time s, gyro deg/s, accel g)");
//! let samples = reader.read_all().unwrap();
//! assert_eq!(samples[1].t_ns, 10_000_000);
//! assert_eq!(samples[0].gyro.x, 0.5_f64.to_radians());
//! assert_eq!(samples[0].acc.z, -1.016 * 9.80665);
//! ```

#![deny(missing_docs)]

pub mod audit;
pub mod channel;
pub mod containers;
pub mod detect;
pub mod error;
pub mod euroc;
pub mod extrinsics;
pub mod groundtruth;
pub mod intrinsics;
pub mod kalibr;
pub mod layout;
pub mod lines;
pub mod number;
pub mod plausibility;
pub mod poses;
pub mod reader;
pub mod split;
mod text;
pub mod units;
mod yaml;

pub use audit::{Audit, AuditOptions, Auditor, Finding, Severity, audit_reader};
pub use channel::{ChannelSample, ChannelStream, Sensor};
pub use detect::Format;
pub use error::{IoError, Location};
pub use euroc::{euroc_imu_string, parse_euroc_imu, read_euroc_imu, write_euroc_imu};
pub use groundtruth::{
    GroundTruthState, euroc_groundtruth_string, parse_euroc_groundtruth, read_euroc_groundtruth,
    write_euroc_groundtruth,
};
pub use intrinsics::{
    ImuCalibration, kalibr_imu_string, openvins_imu_chain_string, parse_kalibr_imu,
    parse_openvins_imu_chain, read_kalibr_imu, read_openvins_imu_chain, write_kalibr_imu,
    write_openvins_imu_chain,
};
pub use kalibr::{
    kalibr_yaml_string, parse_kalibr_bias_model, parse_kalibr_noise_model, parse_kalibr_yaml,
    read_kalibr_bias_model, read_kalibr_noise_model, read_kalibr_yaml, write_kalibr_yaml,
};
pub use layout::{Column, Delimiter, TextLayout};
pub use plausibility::{UnitVerdict, check_si_units};
pub use poses::{PoseRow, parse_poses, read_poses};
pub use reader::{ImuReader, Located, Progress, ReadOptions, SourceInfo, Stamp};
pub use units::{AccelUnit, GyroUnit, TimeUnit, Units};

//! The Earth-rotation flags: the rate of a rotating navigation frame (`--earth-rate`,
//! `--latitude`, `--omega-coriolis`), the Coriolis mode (`--coriolis`) and the state a
//! prediction starts from (`--initial-state`).
//!
//! Frames and units: the world (navigation) frame is z up; with `--latitude` it is
//! east-north-up (x east, y north), so `ω_ie = Ω_E (0, cos φ, sin φ)` rad/s with
//! `Ω_E = 7.292115e-5` rad/s (WGS-84). Gravity stays fixed in the world frame.

use crate::CliError;
use nalgebra::Vector3;
use preint::earth::earth_rate_enu;
use preint::{CoriolisMode, NavState};

/// The rate of the simulated world frame (`simulate`).
#[derive(clap::Args, Clone, Debug, Default)]
pub struct EarthRateArgs {
    /// Simulate in a world frame rotating at ω_ie = x,y,z (rad/s, world frame), gravity fixed
    /// in it: the gyro reads ω_b + R_wbᵀω_ie, the accelerometer R_wbᵀ(a + 2ω_ie×v +
    /// ω_ie×(ω_ie×p) − g). At most 100 rad/s.
    #[arg(help_heading = "Scene", long, value_name = "X,Y,Z", allow_hyphen_values = true,
          value_parser = preint_analysis::parse::frame_rate, conflicts_with = "latitude")]
    pub earth_rate: Option<Vector3<f64>>,
    /// The Earth rate at this latitude (deg, −90..90) in an east-north-up world frame.
    #[arg(help_heading = "Scene", long, value_name = "DEG", allow_hyphen_values = true, value_parser = latitude)]
    pub latitude: Option<f64>,
}

impl EarthRateArgs {
    /// ω_ie [rad/s, world frame], if a flag gave one.
    pub fn rate(&self) -> Option<Vector3<f64>> {
        self.earth_rate.or(self.latitude.map(earth_rate_enu))
    }
}

pub use preint_analysis::parse::latitude;

/// Parses `first`, `second` or `exact`.
pub fn coriolis_mode(s: &str) -> Result<CoriolisMode, String> {
    match s.trim() {
        "first" => Ok(CoriolisMode::FirstOrder),
        "second" => Ok(CoriolisMode::SecondOrder),
        "exact" => Ok(CoriolisMode::Exact),
        _ => Err(format!(
            "`{s}` is not a Coriolis mode: use first, second or exact"
        )),
    }
}

/// The name of a mode as `--coriolis` takes it.
pub fn mode_label(m: CoriolisMode) -> &'static str {
    match m {
        CoriolisMode::FirstOrder => "first",
        CoriolisMode::SecondOrder => "second",
        CoriolisMode::Exact => "exact",
    }
}

/// Parses `px,py,pz,vx,vy,vz,qw,qx,qy,qz` (m, m/s, quaternion body→world) into a state:
/// |p| at most [`preint_analysis::parse::MAX_POSITION_M`], |v| below the speed of light.
pub fn initial_state(s: &str) -> Result<NavState, String> {
    use preint_analysis::parse::{MAX_POSITION_M, SPEED_OF_LIGHT_M_S};
    let x = preint_analysis::parse::numbers::<10>(
        s,
        "ten comma-separated numbers px,py,pz,vx,vy,vz,qw,qx,qy,qz",
    )?;
    let r = preint_analysis::parse::unit_quaternion([x[6], x[7], x[8], x[9]])?;
    let (p, v) = (
        Vector3::new(x[0], x[1], x[2]),
        Vector3::new(x[3], x[4], x[5]),
    );
    if p.norm() > MAX_POSITION_M {
        return Err(format!(
            "the position is {:.4e} m from the origin, beyond {MAX_POSITION_M:e} m (where a \
             double no longer resolves 0.1 mm)",
            p.norm()
        ));
    }
    if v.norm() >= SPEED_OF_LIGHT_M_S {
        return Err(format!(
            "the speed {:.4e} m/s is not below the speed of light",
            v.norm()
        ));
    }
    Ok(NavState::new(r, p, v))
}

/// Prediction flags of `integrate`.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct PredictArgs {
    /// Rotation rate of the world (navigation) frame ω_ie = x,y,z (rad/s, world frame), for the
    /// prediction (Earth rotation; gravity fixed in the frame). At most 100 rad/s.
    #[arg(help_heading = "Prediction", long, value_name = "X,Y,Z", allow_hyphen_values = true, value_parser = preint_analysis::parse::frame_rate)]
    pub omega_coriolis: Option<Vector3<f64>>,
    /// How ω_ie enters the prediction: first (first-order Coriolis), second (plus centrifugal
    /// terms) or exact (constant-rate rotating frame). Default exact; needs --omega-coriolis.
    #[arg(help_heading = "Prediction", long, value_name = "MODE", value_parser = coriolis_mode)]
    pub coriolis: Option<CoriolisMode>,
    /// State at the window's start, px,py,pz,vx,vy,vz,qw,qx,qy,qz (m, m/s, quaternion
    /// body→world): adds the predicted state at the window's end to the output.
    #[arg(help_heading = "Prediction", long, value_name = "P,V,Q", allow_hyphen_values = true, value_parser = initial_state)]
    pub initial_state: Option<NavState>,
}

impl PredictArgs {
    /// The rate and mode to set in the parameters; `--coriolis` without a rate is refused.
    pub fn earth(&self) -> Result<Option<(Vector3<f64>, CoriolisMode)>, CliError> {
        match (self.omega_coriolis, self.coriolis) {
            (None, Some(_)) => Err(CliError::Usage(
                "--coriolis needs a navigation-frame rate: give --omega-coriolis x,y,z (rad/s)"
                    .into(),
            )),
            (None, None) => Ok(None),
            (Some(w), m) => Ok(Some((w, m.unwrap_or_default()))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn states_and_modes() {
        let s = initial_state("1,2,3,4,5,6,1,0,0,0").unwrap();
        assert_eq!(s.p, Vector3::new(1.0, 2.0, 3.0));
        assert_eq!(s.v, Vector3::new(4.0, 5.0, 6.0));
        assert!(s.r.log().norm() < 1e-15);
        // Normalised when close to unit, refused when far.
        let h = std::f64::consts::FRAC_1_SQRT_2 * 1.0002;
        let s = initial_state(&format!("0,0,0,0,0,0,{h},0,0,{h}")).unwrap();
        assert!((s.r.log().z - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!(
            initial_state("0,0,0,0,0,0,2,0,0,0")
                .unwrap_err()
                .contains("norm")
        );
        assert!(
            initial_state("0,0,0,0,0,0,1,0,0")
                .unwrap_err()
                .contains("ten")
        );
        assert!(
            initial_state("0,0,nan,0,0,0,1,0,0,0")
                .unwrap_err()
                .contains("finite")
        );
        assert_eq!(coriolis_mode("second").unwrap(), CoriolisMode::SecondOrder);
        assert!(coriolis_mode("third").is_err());
        assert!(latitude("91").is_err() && latitude("-45").is_ok());
        assert!(
            initial_state("1e13,0,0,0,0,0,1,0,0,0")
                .unwrap_err()
                .contains("1e12")
        );
        assert!(
            initial_state("0,0,0,3e8,0,0,1,0,0,0")
                .unwrap_err()
                .contains("speed of light")
        );
        assert!(initial_state("4e11,0,0,2e8,0,0,1,0,0,0").is_ok());
    }
}

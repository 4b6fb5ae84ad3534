//! The units a source may use, and their conversion to the library's: timestamps in integer
//! nanoseconds, angular rate in rad/s, specific force in m/s².

use std::fmt;
use std::str::FromStr;

/// Standard gravity \[m/s²\] (CGPM 1901): the value of 1 g when converting accelerometer data.
pub const STANDARD_GRAVITY: f64 = 9.806_65;

/// Unit of the timestamps in a source. Converted to integer nanoseconds from the decimal
/// digits ([`crate::number::parse_scaled_integer`]), so no sample spacing is lost.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeUnit {
    /// Seconds.
    S,
    /// Milliseconds.
    Ms,
    /// Microseconds.
    Us,
    /// Nanoseconds.
    Ns,
}

impl TimeUnit {
    /// Power of ten from this unit to nanoseconds (s → 9).
    pub fn to_ns_exponent(self) -> i32 {
        match self {
            TimeUnit::S => 9,
            TimeUnit::Ms => 6,
            TimeUnit::Us => 3,
            TimeUnit::Ns => 0,
        }
    }
}

/// Unit of the gyroscope readings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GyroUnit {
    /// Radians per second.
    RadPerS,
    /// Degrees per second (multiplied by π/180).
    DegPerS,
}

impl GyroUnit {
    /// Factor from this unit to rad/s.
    pub fn to_rad_per_s(self) -> f64 {
        match self {
            GyroUnit::RadPerS => 1.0,
            GyroUnit::DegPerS => std::f64::consts::PI / 180.0,
        }
    }
}

/// Unit of the accelerometer readings (specific force).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccelUnit {
    /// Metres per second squared.
    MPerS2,
    /// Standard gravities (multiplied by [`STANDARD_GRAVITY`]).
    G,
}

impl AccelUnit {
    /// Factor from this unit to m/s².
    pub fn to_m_per_s2(self) -> f64 {
        match self {
            AccelUnit::MPerS2 => 1.0,
            AccelUnit::G => STANDARD_GRAVITY,
        }
    }
}

/// The three units of an IMU source.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Units {
    /// Timestamps.
    pub time: TimeUnit,
    /// Gyroscope.
    pub gyro: GyroUnit,
    /// Accelerometer.
    pub accel: AccelUnit,
}

impl Units {
    /// Nanoseconds, rad/s, m/s² (EuRoC, TUM-VI).
    pub const SI_NS: Units = Units {
        time: TimeUnit::Ns,
        gyro: GyroUnit::RadPerS,
        accel: AccelUnit::MPerS2,
    };
    /// Seconds, rad/s, m/s² (UZH-FPV, KITTI).
    pub const SI_S: Units = Units {
        time: TimeUnit::S,
        ..Units::SI_NS
    };
}

impl fmt::Display for Units {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "time {}, gyro {}, accel {}",
            self.time, self.gyro, self.accel
        )
    }
}

macro_rules! named_unit {
    ($ty:ty, $what:literal, $( $variant:path => $name:literal $(| $alias:literal)* ),+ $(,)?) => {
        impl fmt::Display for $ty {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(match self { $( $variant => $name, )+ })
            }
        }
        impl FromStr for $ty {
            type Err = String;
            fn from_str(s: &str) -> Result<Self, String> {
                match s.trim().to_ascii_lowercase().as_str() {
                    $( $name $(| $alias)* => Ok($variant), )+
                    other => Err(format!(
                        concat!("unknown ", $what, " `{}`; expected one of {}"),
                        other,
                        [$($name),+].join(", ")
                    )),
                }
            }
        }
    };
}

named_unit!(TimeUnit, "time unit",
    TimeUnit::S => "s" | "sec" | "seconds",
    TimeUnit::Ms => "ms",
    TimeUnit::Us => "us" | "µs",
    TimeUnit::Ns => "ns",
);
named_unit!(GyroUnit, "gyro unit",
    GyroUnit::RadPerS => "rad/s" | "rad_s" | "rads",
    GyroUnit::DegPerS => "deg/s" | "deg_s" | "dps",
);
named_unit!(AccelUnit, "accelerometer unit",
    AccelUnit::MPerS2 => "m/s2" | "m/s^2" | "m_s2" | "mps2",
    AccelUnit::G => "g",
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_names_list_the_choices() {
        for u in [TimeUnit::S, TimeUnit::Ms, TimeUnit::Us, TimeUnit::Ns] {
            assert_eq!(u.to_string().parse::<TimeUnit>(), Ok(u));
        }
        assert_eq!("DEG/S".parse::<GyroUnit>(), Ok(GyroUnit::DegPerS));
        assert_eq!("m/s^2".parse::<AccelUnit>(), Ok(AccelUnit::MPerS2));
        let e = "furlong".parse::<AccelUnit>().unwrap_err();
        assert!(e.contains("m/s2, g"), "{e}");
        assert_eq!(GyroUnit::DegPerS.to_rad_per_s(), 0.017453292519943295);
        assert_eq!(AccelUnit::G.to_m_per_s2(), 9.80665);
    }
}

//! The `--scheme` values and the labels printed for [`preint::Scheme`].

use clap::builder::{EnumValueParser, PossibleValue, TypedValueParser};
use clap::error::ErrorKind;

/// The integration scheme as given on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Scheme {
    /// First order (the sample at the start of each interval held over it).
    Euler,
    /// Second order (the mean of the samples at both ends of each interval).
    Midpoint,
    /// Fourth order, Hermite–Magnus (uses the neighbouring samples); also accepted as rk4 and
    /// high-order.
    #[value(name = "hermite4", alias = "rk4", alias = "high-order")]
    Hermite4,
    /// First order on smooth input, exact when the input is constant over each interval (the
    /// sample at the start held, composed with the exact Gal(3) exponential; GTSAM 4.3's
    /// PreintegratedImuMeasurementsG).
    Galilean,
}

impl From<Scheme> for preint::Scheme {
    fn from(s: Scheme) -> Self {
        match s {
            Scheme::Euler => preint::Scheme::Euler,
            Scheme::Midpoint => preint::Scheme::Midpoint,
            Scheme::Hermite4 => preint::Scheme::Hermite4,
            Scheme::Galilean => preint::Scheme::Galilean,
        }
    }
}

/// Every scheme, in the order of every table and chart: the three Forster-chart schemes by
/// order, then the Lie-group one.
pub const ALL: [preint::Scheme; 4] = [
    preint::Scheme::Euler,
    preint::Scheme::Midpoint,
    preint::Scheme::Hermite4,
    preint::Scheme::Galilean,
];

/// The scheme's name as printed in JSON and text: `euler`, `midpoint`, `hermite4` or
/// `galilean`.
pub fn label(s: preint::Scheme) -> &'static str {
    match s {
        preint::Scheme::Euler => "euler",
        preint::Scheme::Midpoint => "midpoint",
        preint::Scheme::Hermite4 => "hermite4",
        preint::Scheme::Galilean => "galilean",
    }
}

/// Parses `--scheme` as [`Scheme`] (so `--help` lists the values), and names an unknown value
/// as an unknown scheme with the accepted names.
#[derive(Clone, Copy, Debug, Default)]
pub struct SchemeParser;

impl TypedValueParser for SchemeParser {
    type Value = Scheme;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> Result<Scheme, clap::Error> {
        EnumValueParser::<Scheme>::new()
            .parse_ref(cmd, arg, value)
            .map_err(|_| {
                clap::Error::raw(
                    ErrorKind::InvalidValue,
                    format!(
                        "unknown scheme `{}`: expected euler, midpoint, hermite4 or galilean \
                         (also accepted: rk4, high-order)\n",
                        value.to_string_lossy()
                    ),
                )
                .with_cmd(cmd)
            })
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(
            <Scheme as clap::ValueEnum>::value_variants()
                .iter()
                .filter_map(clap::ValueEnum::to_possible_value),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum;

    #[test]
    fn names_aliases_and_labels() {
        for (input, want) in [
            ("euler", Scheme::Euler),
            ("midpoint", Scheme::Midpoint),
            ("hermite4", Scheme::Hermite4),
            ("rk4", Scheme::Hermite4),
            ("high-order", Scheme::Hermite4),
            ("galilean", Scheme::Galilean),
        ] {
            assert_eq!(Scheme::from_str(input, false).unwrap(), want, "{input}");
        }
        assert!(Scheme::from_str("rk5", false).is_err());
        for s in Scheme::value_variants() {
            let name = s.to_possible_value().unwrap().get_name().to_string();
            assert_eq!(label((*s).into()), name);
        }
        assert_eq!(
            ALL.map(label),
            ["euler", "midpoint", "hermite4", "galilean"]
        );
        for s in preint::Scheme::ALL {
            assert!(ALL.contains(s), "{s:?}");
            assert_eq!(label(*s), s.name());
        }
    }
}

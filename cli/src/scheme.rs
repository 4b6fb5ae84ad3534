//! The `--scheme` values and the labels printed for [`preint::Scheme`], all read from the
//! scheme registry ([`preint::SchemeInfo`]): a scheme added there appears here, in `--help`,
//! in every table, chart and report.

use clap::builder::{PossibleValue, TypedValueParser};
use clap::error::ErrorKind;

/// The integration scheme as given on the command line: `preint::Scheme` itself.
pub use preint::Scheme;

/// Every scheme, in the order of every table and chart (the registry's).
pub const ALL: [Scheme; Scheme::ALL.len()] = {
    let mut out = [Scheme::ALL[0]; Scheme::ALL.len()];
    let mut i = 0;
    while i < out.len() {
        out[i] = Scheme::ALL[i];
        i += 1;
    }
    out
};

/// The scheme's name as printed in JSON and text ([`preint::SchemeInfo::name`]).
pub fn label(s: Scheme) -> &'static str {
    s.info().name
}

/// The accepted names, for an error message: `euler, midpoint, hermite4 or galilean (also
/// accepted: rk4, high-order)`.
fn accepted() -> String {
    let names: Vec<&str> = ALL.iter().map(|s| s.info().name).collect();
    let list = match names.split_last() {
        Some((last, [])) => last.to_string(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    };
    let aliases: Vec<&str> = ALL.iter().flat_map(|s| s.info().aliases).copied().collect();
    if aliases.is_empty() {
        list
    } else {
        format!("{list} (also accepted: {})", aliases.join(", "))
    }
}

/// Every scheme with its one-line help and its aliases, for `preint --help`: `euler: first
/// order (…); …; hermite4: fourth order, Hermite–Magnus (…), printed as hermite4, also accepted
/// as rk4 or high-order; …`.
pub fn describe() -> String {
    let one = |s: &Scheme| {
        let info = s.info();
        let mut help = info.help.trim_end_matches('.').to_string();
        if let Some(first) = help.get(..1) {
            help = first.to_lowercase() + &help[1..];
        }
        let aliases = match info.aliases {
            [] => String::new(),
            a => format!(
                ", printed as {}, also accepted as {}",
                info.name,
                a.join(" or ")
            ),
        };
        format!("{}: {help}{aliases}", info.name)
    };
    ALL.iter().map(one).collect::<Vec<_>>().join("; ")
}

/// The help of `--scheme`: the aliases each scheme also accepts (the values and their help are
/// listed by clap from [`SchemeParser`]).
pub fn flag_help() -> String {
    let aliases: Vec<String> = ALL
        .iter()
        .filter(|s| !s.info().aliases.is_empty())
        .map(|s| format!("{} for {}", s.info().aliases.join(" and "), s.info().name))
        .collect();
    if aliases.is_empty() {
        "Integration scheme".to_string()
    } else {
        format!(
            "Integration scheme (also accepted: {}; printed as the scheme's name)",
            aliases.join(", ")
        )
    }
}

/// Parses `--scheme` by the registry's names and aliases (so `--help` lists the values with
/// their one-line help), and names an unknown value as an unknown scheme with the accepted
/// names.
#[derive(Clone, Copy, Debug, Default)]
pub struct SchemeParser;

impl TypedValueParser for SchemeParser {
    type Value = Scheme;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        _arg: Option<&clap::Arg>,
        value: &std::ffi::OsStr,
    ) -> Result<Scheme, clap::Error> {
        value.to_str().and_then(Scheme::from_name).ok_or_else(|| {
            clap::Error::raw(
                ErrorKind::InvalidValue,
                format!(
                    "unknown scheme `{}`: expected {}\n",
                    value.to_string_lossy(),
                    accepted()
                ),
            )
            .with_cmd(cmd)
        })
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(ALL.iter().map(|s| {
            let info = s.info();
            PossibleValue::new(info.name)
                .help(info.help)
                .aliases(info.aliases.iter().copied())
        })))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Scheme, clap::Error> {
        SchemeParser.parse_ref(&clap::Command::new("t"), None, std::ffi::OsStr::new(s))
    }

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
            assert_eq!(parse(input).unwrap(), want, "{input}");
        }
        let err = parse("rk5").unwrap_err().to_string();
        assert!(
            err.contains(
                "expected euler, midpoint, hermite4 or galilean (also accepted: rk4, high-order)"
            ),
            "{err}"
        );
        let values: Vec<String> = SchemeParser
            .possible_values()
            .unwrap()
            .map(|v| v.get_name().to_string())
            .collect();
        assert_eq!(values, ["euler", "midpoint", "hermite4", "galilean"]);
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

//! The command line's contract, checked on the whole clap command tree (every subcommand,
//! every argument, flattened and global ones included):
//!
//! - every argument, set to a valid value (its `possible_values` when clap knows them, else an
//!   example from [`EXAMPLES`]), parses into the typed [`Cli`] through both `try_parse_from`
//!   and `FromArgMatches`, without a panic (a derive whose field type disagrees with its value
//!   parser panics there), and changes the parsed command;
//! - a numeric argument takes a negative number after a space (`--flag -1`): clap hands it to
//!   the value parser instead of calling it an unexpected argument;
//! - every argument and subcommand has help text, and an argument whose default clap prints
//!   (`[default: …]`) does not state it in its own text as well (`default:`, `(default`);
//! - every argument sits under a help heading of [`HEADINGS`] (`--help` lists the flags in
//!   these groups): the reader flags under `Input` wherever they appear, `integrate`'s under
//!   input, preintegration, window, prediction and extras (and `--json` under output).
//!
//! A new argument without a value clap knows fails the test until it has a line in
//! [`EXAMPLES`].

use clap::{Arg, ArgAction, CommandFactory, FromArgMatches, Parser};
use preint_cli::{Cli, Command};
use std::panic::{AssertUnwindSafe, catch_unwind};

const EUROC: &str = "tests/data/euroc/V1_01_easy_imu0.csv";
const EUROC_GT: &str = "tests/data/euroc/V1_01_easy_groundtruth_vicon2gt.csv";
const EUROC_NOISE: &str = "tests/data/euroc/imu.yaml";

/// One valid value per argument: `(subcommand, argument id, argv after the flag)`, the
/// subcommand `"*"` for every subcommand that has the argument. A subcommand's own line wins
/// over a `"*"` line. The argv may go on with the flags the argument requires (`--gyro` needs
/// `--accel`). Flags (no value) and arguments with possible values need no line.
#[rustfmt::skip]
const EXAMPLES: &[(&str, &str, &[&str])] = &[
    // Reader flags (ImuArgs).
    ("*", "imu", &[EUROC]),
    ("*", "gyro", &["g.csv", "--accel", "a.csv"]),
    ("*", "accel", &["a.csv", "--gyro", "g.csv"]),
    ("*", "format", &["delimited"]),
    ("*", "columns", &["skip,t,ax,ay,az,wx,wy,wz"]),
    ("*", "delimiter", &["semicolon"]),
    ("*", "time_unit", &["us"]),
    ("*", "gyro_unit", &["deg/s"]),
    ("*", "accel_unit", &["g"]),
    ("*", "topic", &["/imu"]),
    ("*", "gyro_topic", &["/gyro", "--accel-topic", "/accel"]),
    ("*", "accel_topic", &["/accel", "--gyro-topic", "/gyro"]),
    ("*", "stamp", &["record"]),
    // Preintegration flags (PreintArgs).
    ("*", "noise", &[EUROC_NOISE]),
    ("*", "gravity", &["9.80665"]),
    ("*", "gravity_vector", &["-0.0414,0.0007,-9.8072"]),
    ("*", "body_p_sensor", &["0.1,0,0,1,0,0,0"]),
    ("*", "lever_arm", &["centripetal"]),
    ("*", "bias_correction", &["group"]),
    // Windows and ground truth.
    ("*", "from", &["1403715280000000000"]),
    ("*", "to", &["1403715281000000000"]),
    ("*", "poses", &[EUROC_GT]),
    ("*", "calibration", &["calib.yaml"]),
    ("*", "out", &["out/contract"]),
    ("convert", "out", &["out/contract/imu.csv"]),
    ("calibrate", "out", &["out/contract/calib.yaml"]),
    ("calibrate", "calibration", &["calib.yaml", "--poses", EUROC_GT]),
    ("calibrate", "scheme", &["euler", "--poses", EUROC_GT]),
    // integrate.
    ("integrate", "bias_gyro", &["0.001,-0.002,0"]),
    ("integrate", "bias_acc", &["0.01,0,-0.02"]),
    ("integrate", "omega_coriolis", &["0,4.6e-5,5.2e-5"]),
    ("integrate", "coriolis", &["second", "--omega-coriolis", "0,0,7.29e-5"]),
    ("integrate", "initial_state", &["0,0,0,1,0,0,1,0,0,0"]),
    ("integrate", "at", &["1403715280500000000,1403715280600000000"]),
    // factor.
    ("factor", "residual", &["component"]),
    ("*", "pose_rot_std", &["1.75e-3"]),
    ("*", "pose_pos_std", &["0.005"]),
    ("factor", "vel_std", &["0.01"]),
    ("factor", "bias_gyro_std", &["1e-4"]),
    ("factor", "bias_acc_std", &["0.01"]),
    ("factor", "window", &["0.5,1,2"]),
    // report --imu.
    ("report", "vel_std", &["0.01"]),
    ("report", "bias_gyro_std", &["1e-4"]),
    ("report", "bias_acc_std", &["0.01"]),
    // calibrate.
    ("calibrate", "estimate", &["time-offset,gyro-intrinsics", "--poses", EUROC_GT]),
    ("calibrate", "window", &["0.5,1,2,4", "--estimate", "noise", "--poses", EUROC_GT]),
    ("calibrate", "vel_std", &["0.01", "--estimate", "noise", "--poses", EUROC_GT]),
    ("calibrate", "bias_gyro_std", &["1e-4", "--estimate", "noise", "--poses", EUROC_GT]),
    ("calibrate", "bias_acc_std", &["0.01", "--estimate", "noise", "--poses", EUROC_GT]),
    ("calibrate", "pose_spacing", &["0.25", "--poses", EUROC_GT]),
    ("initialise", "pose_spacing", &["0.25"]),
    ("initialise", "bias_prior_std", &["0.01,0.1"]),
    ("*", "latitude", &["47.4"]),
    ("calibrate", "heading", &["30", "--latitude", "47.4"]),
    // advise, bench-steps.
    ("*", "window", &["0.5"]),
    ("advise", "fraction", &["0.05"]),
    ("bench-steps", "rates", &["100,200"]),
    // simulate.
    ("simulate", "rate", &["400"]),
    ("simulate", "duration", &["2.5"]),
    ("simulate", "noise", &["none"]),
    ("simulate", "seed", &["7"]),
    ("simulate", "earth_rate", &["0,0,7.292115e-5"]),
    // speed.
    ("speed", "samples", &["1000"]),
];

/// The argument ids each subcommand needs before any other argument can be tried (values
/// from [`EXAMPLES`]).
const REQUIRED: &[(&str, &[&str])] = &[
    ("simulate", &["out"]),
    ("integrate", &["imu"]),
    ("factor", &["imu", "poses", "from", "to"]),
    ("calibrate", &["imu"]),
    ("allan", &["imu"]),
    ("advise", &["imu", "noise"]),
    ("convert", &["imu", "out"]),
    ("audit", &["imu"]),
    ("initialise", &["imu", "poses"]),
];

/// Arguments clap adds itself.
const CLAP_OWN: &[&str] = &["help", "version"];

/// The example argv of `id` on `sub`, if the table has one.
fn example(sub: &str, id: &str) -> Option<Vec<String>> {
    let pick = |s: &str| {
        EXAMPLES
            .iter()
            .find(|(es, eid, _)| *es == s && *eid == id)
            .map(|(_, _, v)| v.iter().map(|x| x.to_string()).collect())
    };
    pick(sub).or_else(|| pick("*"))
}

/// Whether the argument takes a value (a flag takes none).
fn takes_value(arg: &Arg) -> bool {
    !matches!(
        arg.get_action(),
        ArgAction::SetTrue | ArgAction::SetFalse | ArgAction::Count
    )
}

/// The values to try for `arg` on `sub`, each an argv after the flag: every possible value
/// clap knows (followed by the arguments the table's example adds after its value, for a flag
/// that requires another), else the table's example; nothing for a flag. `Err` names the
/// missing line.
fn values(sub: &str, arg: &Arg) -> Result<Vec<Vec<String>>, String> {
    if !takes_value(arg) {
        return Ok(vec![Vec::new()]);
    }
    let id = arg.get_id().as_str();
    let possible = arg.get_possible_values();
    if !possible.is_empty() {
        let requires = example(sub, id).map_or(Vec::new(), |e| e[1..].to_vec());
        return Ok(possible
            .iter()
            .map(|p| {
                let mut v = vec![p.get_name().to_string()];
                v.extend(requires.iter().cloned());
                v
            })
            .collect());
    }
    example(sub, id).map(|v| vec![v]).ok_or_else(|| {
        format!(
            "`preint {sub} {}` has no example value: add a line (\"{sub}\", \"{id}\", &[…]) or \
             (\"*\", \"{id}\", &[…]) to EXAMPLES in cli/tests/contract.rs",
            flag(arg)
        )
    })
}

fn flag(arg: &Arg) -> String {
    format!(
        "--{}",
        arg.get_long().expect("every argument is a long flag")
    )
}

/// The argv of `preint sub` with its required arguments, less those that conflict with
/// `tried` (`--gyro` replaces `--imu`), then `--tried VALUE…`.
fn argv(sub: &clap::Command, tried: Option<(&Arg, &[String])>) -> Vec<String> {
    let name = sub.get_name();
    let mut v = vec!["preint".to_string(), name.to_string()];
    let required = REQUIRED
        .iter()
        .find(|(s, _)| *s == name)
        .map_or(&[][..], |(_, ids)| *ids);
    for id in required {
        let arg = sub
            .get_arguments()
            .find(|a| a.get_id() == *id)
            .unwrap_or_else(|| panic!("REQUIRED names `{id}`, not an argument of {name}"));
        if let Some((t, _)) = tried {
            let clash = |a: &Arg, b: &Arg| sub.get_arg_conflicts_with(a).contains(&b);
            if t.get_id() == arg.get_id() || clash(t, arg) || clash(arg, t) {
                continue;
            }
        }
        v.push(flag(arg));
        v.extend(example(name, id).unwrap_or_else(|| panic!("no example for `{id}`")));
    }
    if let Some((t, values)) = tried {
        v.push(flag(t));
        v.extend(values.iter().cloned());
    }
    v
}

/// Parses `argv` both ways, under `catch_unwind`, and reads the typed values; the `Debug` of
/// the parsed command, or what went wrong.
fn parse(argv: &[String]) -> Result<String, String> {
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        let direct = Cli::try_parse_from(argv).map_err(|e| e.render().to_string())?;
        let matches = Cli::command()
            .try_get_matches_from(argv)
            .map_err(|e| e.render().to_string())?;
        let converted = Cli::from_arg_matches(&matches).map_err(|e| e.render().to_string())?;
        let (a, b) = (format!("{direct:?}"), format!("{converted:?}"));
        if a != b {
            return Err(format!(
                "try_parse_from and FromArgMatches disagree:\n{a}\n{b}"
            ));
        }
        exercise(&converted);
        Ok(a)
    }));
    outcome.unwrap_or_else(|p| {
        let msg = p
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        Err(format!("panicked: {msg}"))
    })
}

/// Reads the typed values the way the commands do: the reader options of every subcommand
/// that reads a recording.
fn exercise(cli: &Cli) {
    let input = match &cli.command {
        Command::Integrate(a) => Some(&a.input),
        Command::Factor(a) => Some(&a.input),
        Command::Calibrate(a) => Some(&a.input),
        Command::Initialise(a) => {
            let _ = format!("{:?}", a.options());
            Some(&a.input)
        }
        Command::Allan(a) => Some(&a.input),
        Command::Advise(a) => Some(&a.input),
        Command::Convert(a) => Some(&a.input),
        Command::Audit(a) => Some(&a.input),
        Command::Report(a) => a.input.as_ref(),
        Command::Simulate(_) | Command::BenchSteps(_) | Command::Speed(_) => None,
    };
    if let Some(i) = input {
        let i = i.to_input();
        let _ = format!("{:?} {} {}", i.options(), i.label(), i.is_split());
    }
}

/// The subcommands (clap's own `help` left out), with global arguments propagated.
fn subcommands() -> Vec<clap::Command> {
    let mut cmd = Cli::command();
    cmd.build();
    cmd.get_subcommands()
        .filter(|s| s.get_name() != "help")
        .cloned()
        .collect()
}

fn own_arguments(sub: &clap::Command) -> impl Iterator<Item = &Arg> {
    sub.get_arguments()
        .filter(|a| !CLAP_OWN.contains(&a.get_id().as_str()))
}

#[test]
fn clap_finds_the_command_consistent() {
    Cli::command().debug_assert();
}

#[test]
fn every_argument_parses_into_the_typed_command() {
    let mut failures = Vec::new();
    let mut tried = 0;
    for sub in subcommands() {
        let base = argv(&sub, None);
        let base_debug = match parse(&base) {
            Ok(d) => d,
            Err(e) => {
                failures.push(format!(
                    "{base:?} (the required arguments; see REQUIRED) fails: {e}"
                ));
                continue;
            }
        };
        for arg in own_arguments(&sub) {
            let values = match values(sub.get_name(), arg) {
                Ok(v) => v,
                Err(e) => {
                    failures.push(e);
                    continue;
                }
            };
            let mut changed = false;
            for value in &values {
                let v = argv(&sub, Some((arg, value)));
                tried += 1;
                match parse(&v) {
                    Ok(d) => changed |= d != base_debug,
                    Err(e) => failures.push(format!("{} in {v:?}: {e}", flag(arg))),
                }
            }
            let required = REQUIRED
                .iter()
                .any(|(s, ids)| *s == sub.get_name() && ids.contains(&arg.get_id().as_str()));
            if !changed && !required {
                failures.push(format!(
                    "`preint {} {}` with {values:?} parses to the same command as without it",
                    sub.get_name(),
                    flag(arg)
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(tried > 150, "only {tried} argument values tried");
}

/// Whether every comma-separated part of the argument's first example value is a number.
fn is_numeric(values: &[String]) -> bool {
    values.first().is_some_and(|v| {
        v.split(',')
            .all(|x| x.parse::<f64>().is_ok_and(f64::is_finite))
    })
}

#[test]
fn numeric_arguments_take_negative_numbers_after_a_space() {
    let mut failures = Vec::new();
    let mut numeric = 0;
    for sub in subcommands() {
        for arg in own_arguments(&sub) {
            let Ok(values) = values(sub.get_name(), arg) else {
                continue; // reported by every_argument_parses_into_the_typed_command
            };
            let Some(value) = values.into_iter().find(|v| is_numeric(v)) else {
                continue;
            };
            numeric += 1;
            for negative in ["-1", "-1e-3", "-0.5,1,2"] {
                let mut value = value.clone();
                value[0] = negative.to_string();
                let v = argv(&sub, Some((arg, &value)));
                let outcome = catch_unwind(|| Cli::try_parse_from(&v));
                match outcome {
                    Err(_) => failures.push(format!("{v:?} panicked")),
                    Ok(Err(e)) => {
                        let text = e.render().to_string();
                        let named = text.contains(&format!("'{}", flag(arg)));
                        if e.kind() == clap::error::ErrorKind::UnknownArgument || !named {
                            failures.push(format!("{v:?}: {text}"));
                        }
                    }
                    Ok(Ok(_)) => {}
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(numeric >= 20, "only {numeric} numeric arguments found");
}

#[test]
fn every_argument_has_help_and_states_its_default_once() {
    let mut failures = Vec::new();
    for sub in subcommands() {
        let name = sub.get_name().to_string();
        if sub
            .get_about()
            .is_none_or(|a| a.to_string().trim().is_empty())
        {
            failures.push(format!("`preint {name}` has no about text"));
        }
        for arg in own_arguments(&sub) {
            let help = arg
                .get_long_help()
                .or(arg.get_help())
                .map(|h| h.to_string())
                .unwrap_or_default();
            if help.trim().is_empty() {
                failures.push(format!("`preint {name} {}` has no help text", flag(arg)));
            }
            let shown = !arg.get_default_values().is_empty() && !arg.is_hide_default_value_set();
            let lower = help.to_lowercase();
            if shown && (lower.contains("default:") || lower.contains("(default")) {
                failures.push(format!(
                    "`preint {name} {}` states a default in its help and clap prints \
                     [default: {:?}] after it: {help}",
                    flag(arg),
                    arg.get_default_values()
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The help headings, in the order `--help` of a subcommand tends to show them.
const HEADINGS: &[&str] = &[
    "Input",
    "Window",
    "Preintegration",
    "Prediction",
    "Extras",
    "Ground truth",
    "Factor",
    "Known poses",
    "Sensor model",
    "Earth rotation",
    "Analysis",
    "Scene",
    "Sensor",
    "Benchmark",
    "Output",
];

/// The reader flags (`ImuArgs`), under `Input` in every subcommand that reads a recording.
const READER: &[&str] = &[
    "imu",
    "gyro",
    "accel",
    "format",
    "columns",
    "delimiter",
    "time_unit",
    "gyro_unit",
    "accel_unit",
    "topic",
    "gyro_topic",
    "accel_topic",
    "stamp",
    "no_unit_check",
];

#[test]
fn every_argument_has_a_help_heading() {
    let mut failures = Vec::new();
    for sub in subcommands() {
        let name = sub.get_name();
        let mut used = std::collections::BTreeSet::new();
        for arg in own_arguments(&sub) {
            let id = arg.get_id().as_str();
            match arg.get_help_heading() {
                None => failures.push(format!("`preint {name} {}` has no help heading", flag(arg))),
                Some(h) if !HEADINGS.contains(&h) => failures.push(format!(
                    "`preint {name} {}` is under {h:?}, not one of {HEADINGS:?}",
                    flag(arg)
                )),
                Some(h) => {
                    used.insert(h);
                    if READER.contains(&id) && h != "Input" {
                        failures.push(format!("`preint {name} {}` is under {h:?}", flag(arg)));
                    }
                }
            }
        }
        if name == "integrate" {
            let want = [
                "Extras",
                "Input",
                "Output",
                "Prediction",
                "Preintegration",
                "Window",
            ];
            if !used.iter().eq(want.iter()) {
                failures.push(format!(
                    "`preint integrate`'s headings are {used:?}, not {want:?}"
                ));
            }
        }
        let help = sub.clone().render_long_help().to_string();
        for h in &used {
            if !help.contains(&format!("{h}:")) {
                failures.push(format!(
                    "`preint {name} --help` does not show the heading {h}"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

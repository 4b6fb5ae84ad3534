//! Every `preint …` command line of the documentation runs, as written, through the built
//! binary.
//!
//! - Command lines: the lines starting with `preint ` (or `$ preint `) in the fenced code
//!   blocks of `README.md`, `cli/README.md` and `docs/*.md`, joined over `\` continuations, and
//!   the lines starting with `preint ` in the `--help` of the command and of every subcommand
//!   (examples, after-help). A trailing `# …` comment is not part of the command; one that
//!   says `exit N` gives the exit status expected (default 0).
//! - Each runs with the repository root as its working directory. `--out X` is moved into a
//!   temporary directory, and a later argument equal to `X` or under `X/` of the same source
//!   follows it (a help example that simulates into `sim` and then reads `sim/imu.csv`); a
//!   subcommand whose `--out` has a default gets a temporary `--out`.
//! - The code spans of the prose (`` `preint factor --residual component|logmap` ``, or a span
//!   that starts with a subcommand and a flag, as in the README's table) are synopses, not
//!   runnable lines: their subcommand and every `--flag` in them must exist.
//!
//! [`SLOW`] names the command lines too slow to run here, with the reason; they are parsed
//! only, and each must still be in the docs.

mod common;

use clap::CommandFactory;
use preint_cli::Cli;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Command lines that are only parsed, not run: `(command line as extracted, reason)`. Empty:
/// the slowest documented line, `preint report`, takes a few seconds at the test profile's
/// opt-level 2 and runs.
const SLOW: &[(&str, &str)] = &[];

/// A command line found in the documentation.
struct Documented {
    /// Where: `FILE:LINE` or `preint SUB --help`.
    source: String,
    /// The command line as written (comment removed).
    line: String,
    /// Its expected exit status.
    exit: i32,
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn markdown_files() -> Vec<PathBuf> {
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    let mut files = vec![root().join("README.md"), root().join("cli/README.md")];
    files.extend(docs);
    files
}

/// Splits `line` into the command and its trailing `# …` comment (a `#` after a space,
/// outside quotes).
fn split_comment(line: &str) -> (&str, &str) {
    let mut quote = None;
    let mut prev = ' ';
    for (i, c) in line.char_indices() {
        match (quote, c) {
            (None, '\'' | '"') => quote = Some(c),
            (Some(q), c) if c == q => quote = None,
            (None, '#') if prev.is_whitespace() => return (line[..i].trim(), &line[i + 1..]),
            _ => {}
        }
        prev = c;
    }
    (line.trim(), "")
}

/// The exit status a comment documents (`exit N`), else 0.
fn documented_exit(comment: &str) -> i32 {
    let words: Vec<&str> = comment.split_whitespace().collect();
    words
        .windows(2)
        .find(|w| w[0] == "exit")
        .and_then(|w| {
            w[1].trim_matches(|c: char| !c.is_ascii_digit())
                .parse()
                .ok()
        })
        .unwrap_or(0)
}

/// The `preint` command lines of `lines` (`fenced`: only inside fenced code blocks), with
/// `\` continuations joined; `(line number, command, expected exit)`.
fn command_lines(text: &str, fenced: bool) -> Vec<(usize, String, i32)> {
    let mut found = Vec::new();
    let mut in_fence = !fenced;
    let mut lines = text.lines().enumerate();
    while let Some((k, line)) = lines.next() {
        let t = line.trim_start();
        if fenced && t.starts_with("```") {
            in_fence = !in_fence;
            continue;
        }
        let t = t.strip_prefix("$ ").unwrap_or(t);
        if !in_fence || !t.starts_with("preint ") {
            continue;
        }
        let mut joined = t.to_string();
        while let Some(head) = joined.strip_suffix('\\') {
            joined = head.trim_end().to_string();
            let (_, next) = lines.next().expect("a continuation line");
            joined.push(' ');
            joined.push_str(next.trim());
        }
        let (command, comment) = split_comment(&joined);
        found.push((k + 1, command.to_string(), documented_exit(comment)));
    }
    found
}

/// Shell words of a plain command line (single and double quotes; no operators).
fn words(line: &str) -> Result<Vec<String>, String> {
    let mut out = Vec::new();
    let mut cur: Option<String> = None;
    let mut quote = None;
    for c in line.chars() {
        match (quote, c) {
            (None, '\'' | '"') => {
                quote = Some(c);
                cur.get_or_insert_with(String::new);
            }
            (Some(q), c) if c == q => quote = None,
            (None, c) if c.is_whitespace() => out.extend(cur.take()),
            (None, '|' | '>' | '<' | ';' | '&') => {
                return Err(format!(
                    "`{c}`: write the documented command as one plain command"
                ));
            }
            (_, c) => cur.get_or_insert_with(String::new).push(c),
        }
    }
    out.extend(cur);
    Ok(out)
}

fn documented() -> Vec<Documented> {
    let mut all = Vec::new();
    for file in markdown_files() {
        let text = std::fs::read_to_string(&file).unwrap();
        let name = file.strip_prefix(root()).unwrap().display().to_string();
        for (line, command, exit) in command_lines(&text, true) {
            all.push(Documented {
                source: format!("{name}:{line}"),
                line: command,
                exit,
            });
        }
    }
    all.extend(help_commands());
    all
}

fn subcommand_names() -> Vec<String> {
    Cli::command()
        .get_subcommands()
        .map(|s| s.get_name().to_string())
        .collect()
}

/// The command lines of `preint --help` and `preint SUB --help` for every subcommand.
fn help_commands() -> Vec<Documented> {
    let mut all = Vec::new();
    let mut pages = vec![Vec::new()];
    pages.extend(subcommand_names().into_iter().map(|s| vec![s]));
    for page in pages {
        let mut args = page.clone();
        args.push("--help".into());
        let o = common::bin().args(&args).output().unwrap();
        assert!(o.status.success(), "preint {args:?}");
        let text = String::from_utf8(o.stdout).unwrap();
        for (_, command, exit) in command_lines(&text, false) {
            all.push(Documented {
                source: format!("preint {}", args.join(" ")),
                line: command,
                exit,
            });
        }
    }
    all
}

/// `argv` with `--out X` moved under `tmp` (recorded in `moved`, per source) and the
/// arguments under a moved `X` following it; a temporary `--out` where the subcommand has a
/// default one.
fn rewrite(argv: &[String], tmp: &Path, moved: &mut BTreeMap<String, PathBuf>) -> Vec<String> {
    let mut out = Vec::with_capacity(argv.len() + 2);
    let mut k = 0;
    while k < argv.len() {
        let a = &argv[k];
        if a == "--out" && k + 1 < argv.len() {
            let old = argv[k + 1].trim_end_matches('/').to_string();
            let new = tmp.join(format!("{}-{}", moved.len(), old.replace('/', "_")));
            out.push(a.clone());
            out.push(new.display().to_string());
            moved.insert(old, new);
            k += 2;
            continue;
        }
        let followed = moved.iter().find_map(|(old, new)| {
            let rest = a.strip_prefix(old.as_str())?;
            (rest.is_empty() || rest.starts_with('/')).then(|| format!("{}{rest}", new.display()))
        });
        out.push(followed.unwrap_or_else(|| a.clone()));
        k += 1;
    }
    let cmd = Cli::command();
    let sub = argv.get(1).and_then(|s| cmd.find_subcommand(s));
    let default_out = sub.and_then(|s| s.get_arguments().find(|a| a.get_id() == "out"));
    if default_out.is_some_and(|a| !a.get_default_values().is_empty())
        && !argv.iter().any(|a| a == "--out")
    {
        out.push("--out".into());
        out.push(
            tmp.join(format!("{}-default", moved.len()))
                .display()
                .to_string(),
        );
    }
    out
}

#[test]
fn every_documented_command_line_runs() {
    let docs = documented();
    let tmp = common::tmp("documented");
    let mut failures = Vec::new();
    for (slow, _) in SLOW {
        if !docs.iter().any(|d| d.line == *slow) {
            failures.push(format!(
                "SLOW names `{slow}`, which no doc or help text has"
            ));
        }
    }
    let mut moved: BTreeMap<String, BTreeMap<String, PathBuf>> = BTreeMap::new();
    let (mut from_docs, mut from_help) = (0, 0);
    for d in &docs {
        let file = d.source.split(':').next().unwrap().to_string();
        if d.source.starts_with("preint ") {
            from_help += 1;
        } else {
            from_docs += 1;
        }
        let argv = match words(&d.line) {
            Ok(w) => w,
            Err(e) => {
                failures.push(format!("{}: `{}`: {e}", d.source, d.line));
                continue;
            }
        };
        let argv = rewrite(&argv, &tmp, moved.entry(file).or_default());
        if SLOW.iter().any(|(s, _)| *s == d.line) {
            use clap::Parser;
            if let Err(e) = Cli::try_parse_from(&argv) {
                failures.push(format!("{}: `{}` does not parse: {e}", d.source, d.line));
            }
            continue;
        }
        println!("{}: {}", d.source, argv.join(" "));
        let o = common::bin()
            .args(&argv[1..])
            .current_dir(root())
            .output()
            .unwrap();
        if o.status.code() != Some(d.exit) {
            failures.push(format!(
                "{}: `{}` exited with {:?}, the doc says {}:\n{}",
                d.source,
                d.line,
                o.status.code(),
                d.exit,
                String::from_utf8_lossy(&o.stderr)
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(
        from_docs >= 8,
        "only {from_docs} command lines found in the docs"
    );
    assert!(
        from_help >= 3,
        "only {from_help} command lines found in --help"
    );
}

/// The code spans of `text` outside fenced blocks, `(line number, span)`; a span may wrap
/// over lines of one paragraph.
fn code_spans(text: &str) -> Vec<(usize, String)> {
    let mut prose = String::new();
    let mut in_fence = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_fence = !in_fence;
            prose.push('\n');
            continue;
        }
        if !in_fence {
            prose.push_str(line);
        }
        prose.push('\n');
    }
    let mut spans = Vec::new();
    let mut rest = prose.as_str();
    let mut offset = 0;
    while let Some(open) = rest.find('`') {
        let after = &rest[open + 1..];
        let Some(close) = after.find('`') else { break };
        let span = &after[..close];
        if span.contains("\n\n") {
            // An unmatched backtick: go on from the next one.
            offset += open + 1;
            rest = after;
            continue;
        }
        let line = prose[..offset + open].matches('\n').count() + 1;
        spans.push((line, span.replace('\n', " ")));
        offset += open + close + 2;
        rest = &after[close + 1..];
    }
    spans
}

/// What is wrong with the synopses of `text` (file `name`): a subcommand or a flag that does
/// not exist; and the number of synopses checked.
fn synopsis_failures(name: &str, text: &str, cmd: &clap::Command) -> (usize, Vec<String>) {
    let mut failures = Vec::new();
    let mut checked = 0;
    for (line, span) in code_spans(text) {
        let tokens: Vec<&str> = span.split_whitespace().collect();
        let (sub, flags) = match tokens.iter().position(|t| *t == "preint") {
            Some(k) => match tokens.get(k + 1) {
                Some(s) if !s.starts_with('<') && !s.starts_with("--") => (*s, &tokens[k + 2..]),
                _ => continue,
            },
            None if tokens.len() > 1
                && cmd.find_subcommand(tokens[0]).is_some()
                && tokens[1].starts_with("--") =>
            {
                (tokens[0], &tokens[1..])
            }
            None => continue,
        };
        let Some(s) = cmd.find_subcommand(sub) else {
            failures.push(format!("{name}:{line}: `{span}`: no subcommand `{sub}`"));
            continue;
        };
        checked += 1;
        for t in flags {
            let t = t
                .trim_start_matches('[')
                .trim_end_matches([']', ',', '.', ')']);
            let Some(long) = t.strip_prefix("--") else {
                continue;
            };
            let long = long.split(['=', '|']).next().unwrap();
            if !s.get_arguments().any(|a| a.get_long() == Some(long)) {
                failures.push(format!("{name}:{line}: `{span}`: `{sub}` has no --{long}"));
            }
        }
    }
    (checked, failures)
}

/// The command with global arguments propagated to the subcommands.
fn built() -> clap::Command {
    let mut c = Cli::command();
    c.build();
    c
}

#[test]
fn every_documented_synopsis_names_existing_flags() {
    let cmd = built();
    let mut failures = Vec::new();
    let mut checked = 0;
    for file in markdown_files() {
        let text = std::fs::read_to_string(&file).unwrap();
        let name = file.strip_prefix(root()).unwrap().display().to_string();
        let (n, f) = synopsis_failures(&name, &text, &cmd);
        checked += n;
        failures.extend(f);
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(checked >= 20, "only {checked} synopses found");
}

#[test]
fn extraction_follows_continuations_comments_and_fences() {
    let text = "preint speed\n```sh\npreint integrate --imu a.csv \\\n    --to 5   # exit 2: why\n\
                $ preint audit --imu 'b c.csv'\nnot preint\n```\npreint report\n";
    let found = command_lines(text, true);
    assert_eq!(
        found,
        vec![
            (3, "preint integrate --imu a.csv --to 5".to_string(), 2),
            (5, "preint audit --imu 'b c.csv'".to_string(), 0),
        ]
    );
    assert_eq!(
        words("preint audit --imu 'b c.csv'").unwrap(),
        ["preint", "audit", "--imu", "b c.csv"]
    );
    assert!(words("preint integrate --imu a.csv | head").is_err());
    let spans = code_spans("a `preint x\ny` b\n\n```\n`z`\n```\n`w`");
    assert_eq!(
        spans,
        vec![(1, "preint x y".to_string()), (7, "w".to_string())]
    );
    let doc = "`integrate --imu FILE [--no-such] --json` and `preint frobnicate --x` and \
               `preint <subcommand> --help`, `factor --residual logmap\\|component`";
    let (checked, failures) = synopsis_failures("doc.md", doc, &built());
    assert_eq!(checked, 2, "{failures:?}");
    assert_eq!(failures.len(), 2, "{failures:?}");
    assert!(
        failures[0].contains("`integrate` has no --no-such"),
        "{failures:?}"
    );
    assert!(
        failures[1].contains("no subcommand `frobnicate`"),
        "{failures:?}"
    );
}

/// The lines of `text` that run `cargo SUB` for one of `subs` (shell comments left out).
fn cargo_lines<'a>(text: &'a str, subs: &[&str]) -> Vec<&'a str> {
    text.lines()
        .map(|l| split_comment(l).0)
        .filter(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            w.windows(2)
                .any(|p| p[0] == "cargo" && subs.contains(&p[1]))
        })
        .collect()
}

/// Installs and CI builds use the committed `Cargo.lock` (`--locked`): every `cargo install`
/// of the docs, every `cargo test` and `cargo clippy` of `.ci/run` and `tools/test`, and the
/// maturin build of the Python package (`locked = true` in `python/pyproject.toml`).
#[test]
fn installs_and_ci_builds_are_locked() {
    let mut lines = Vec::new();
    for file in markdown_files() {
        let text = std::fs::read_to_string(&file).unwrap();
        let name = file.strip_prefix(root()).unwrap().display().to_string();
        lines.extend(
            cargo_lines(&text, &["install"])
                .into_iter()
                .map(|l| (name.clone(), l.trim_matches('`').to_string())),
        );
    }
    for script in [".ci/run", "tools/test"] {
        let text = std::fs::read_to_string(root().join(script)).unwrap();
        lines.extend(
            cargo_lines(&text, &["test", "clippy", "build"])
                .into_iter()
                .map(|l| (script.to_string(), l.to_string())),
        );
    }
    let unlocked: Vec<_> = lines
        .iter()
        .filter(|(_, l)| !l.contains("--locked"))
        .collect();
    assert!(unlocked.is_empty(), "without --locked: {unlocked:?}");
    assert!(lines.len() >= 4, "{lines:?}");
    let pyproject = std::fs::read_to_string(root().join("python/pyproject.toml")).unwrap();
    assert!(
        pyproject.lines().any(|l| l.trim() == "locked = true"),
        "python/pyproject.toml: [tool.maturin] needs locked = true"
    );
}

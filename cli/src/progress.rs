//! Progress bars on stderr, shown only to a person at a terminal.

/// A progress bar on stderr with `len` steps, or `None` when stderr is not a terminal (CI,
/// pipes, `--json` consumers see nothing extra).
pub fn bar(len: u64, what: &str) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let pb = indicatif::ProgressBar::new(len);
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{prefix} [{bar:30}] {pos}/{len} {msg} ({elapsed})")
    {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_prefix(what.to_string());
    Some(pb)
}

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

/// A byte-count bar for reading a recording, drawn by a background thread from the reader's
/// [`preint_io::Progress`]; it appears only at a terminal and only once reading has taken a
/// second, and clears itself when dropped.
pub struct ReadingBar {
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl ReadingBar {
    /// Starts the bar for `progress`, labelled `what`.
    pub fn start(progress: &preint_io::Progress, what: &str) -> Self {
        use std::io::IsTerminal;
        use std::sync::atomic::{AtomicBool, Ordering};
        let stop = std::sync::Arc::new(AtomicBool::new(false));
        if !std::io::stderr().is_terminal() || progress.total() == 0 {
            return Self { stop, thread: None };
        }
        let (flag, progress, what) = (stop.clone(), progress.clone(), what.to_string());
        let thread = std::thread::spawn(move || {
            let started = std::time::Instant::now();
            let mut pb: Option<indicatif::ProgressBar> = None;
            while !flag.load(Ordering::Relaxed) {
                std::thread::sleep(std::time::Duration::from_millis(100));
                if pb.is_none() && started.elapsed().as_secs_f64() >= 1.0 {
                    // Start the rate estimate from what was read before the bar appeared.
                    let bar = bytes_bar(progress.total(), &what);
                    bar.set_position(progress.done());
                    bar.reset_eta();
                    pb = Some(bar);
                }
                if let Some(pb) = &pb {
                    pb.set_position(progress.done());
                }
            }
            if let Some(pb) = pb {
                pb.finish_and_clear();
            }
        });
        Self {
            stop,
            thread: Some(thread),
        }
    }
}

impl Drop for ReadingBar {
    fn drop(&mut self) {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn bytes_bar(total: u64, what: &str) -> indicatif::ProgressBar {
    let pb = indicatif::ProgressBar::new(total);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{prefix} [{bar:30}] {bytes}/{total_bytes} ({bytes_per_sec}, {eta} left)",
    ) {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_prefix(what.to_string());
    pb
}

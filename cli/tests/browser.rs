//! `preint report`'s pages (built-in scenes, and `--imu` on a slice of EuRoC V1_01) in a real
//! browser: headless Chromium lays them out at 800 and 1 400 px wide, and nothing may stick out of the window, every chart must have rendered within it, and
//! the conclusions box must be there and non-empty.
//!
//! Method: the page is copied beside itself with a probe script appended. Chromium loads the
//! copy and prints the DOM (`--dump-dom`); the probe runs on the load event, measures the
//! layout and writes the measurements into the DOM as percent-encoded JSON, which the test
//! reads back from the printed DOM. The copy is the only change: the page itself has no script.
//!
//! Chromium is `$PREINT_CHROMIUM` when that is set, else the first of `/usr/bin/chromium`,
//! `/usr/bin/chromium-browser`, `/usr/bin/google-chrome` that exists. Without it the test prints
//! that it skipped, unless `PREINT_BROWSER_TEST=required` (set by CI), in which case it fails.

mod common;

use common::{json, tmp};
use serde_json::Value;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// How long one Chromium run may take before it is killed and the test fails.
const BROWSER_TIMEOUT: Duration = Duration::from_secs(90);

/// The probe: after the load event, the layout measurements as percent-encoded JSON in
/// `<pre id="probe-result">` (percent-encoding keeps the DOM serialisation from escaping it).
const PROBE: &str = r#"<script>
window.addEventListener('load', function () {
  var vw = document.documentElement.clientWidth, over = [], charts = [];
  var all = document.querySelectorAll('body *');
  for (var i = 0; i < all.length; i++) {
    var el = all[i];
    if (el.closest('defs, clipPath, title, script, style')) continue;
    var r = el.getBoundingClientRect();
    if (r.width === 0 && r.height === 0) continue;
    if (r.right > vw + 0.5 || r.left < -0.5) {
      over.push(el.tagName + (el.id ? '#' + el.id : '') + ' [' + r.left.toFixed(1) + ', ' +
        r.right.toFixed(1) + '] ' + (el.textContent || '').trim().slice(0, 60));
    }
  }
  document.querySelectorAll('svg, img').forEach(function (c) {
    var r = c.getBoundingClientRect(), f = c.closest('figure');
    charts.push({
      tag: c.tagName.toLowerCase(),
      file: f ? f.getAttribute('data-file') : null,
      width: r.width,
      height: r.height,
      loaded: c.tagName.toLowerCase() === 'img' ? (c.complete && c.naturalWidth > 0) : true
    });
  });
  var box = document.getElementById('conclusions');
  var out = {
    innerWidth: window.innerWidth,
    clientWidth: vw,
    scrollWidth: document.documentElement.scrollWidth,
    overflowing: over,
    charts: charts,
    figures: document.querySelectorAll('figure').length,
    conclusionsText: box ? box.textContent.trim().length : -1,
    conclusionsItems: box ? box.querySelectorAll('li').length : -1
  };
  var pre = document.createElement('pre');
  pre.id = 'probe-result';
  pre.textContent = encodeURIComponent(JSON.stringify(out));
  document.body.appendChild(pre);
});
</script>"#;

/// The Chromium binary, if any: `$PREINT_CHROMIUM` when set (and only there), else the first
/// of the usual paths that exists.
fn chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("PREINT_CHROMIUM") {
        return Some(PathBuf::from(p)).filter(|p| p.is_file());
    }
    [
        "/usr/bin/chromium",
        "/usr/bin/chromium-browser",
        "/usr/bin/google-chrome",
    ]
    .into_iter()
    .map(PathBuf::from)
    .find(|p| p.is_file())
}

/// Decodes `encodeURIComponent`'s output.
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            let hex = std::str::from_utf8(&b[i + 1..i + 3]).expect("ASCII");
            out.push(u8::from_str_radix(hex, 16).expect("percent escape"));
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).expect("UTF-8 JSON")
}

/// Loads `page` in headless Chromium with a window `width` px wide and returns the probe's
/// measurements.
fn measure(browser: &Path, page: &Path, width: u32, work: &Path) -> Value {
    let profile = work.join(format!("profile-{width}"));
    let dom_path = work.join(format!("dom-{width}.html"));
    let log_path = work.join(format!("chromium-{width}.log"));
    let dom_file = std::fs::File::create(&dom_path).unwrap();
    let log_file = std::fs::File::create(&log_path).unwrap();
    let mut child = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-dev-shm-usage",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--no-default-browser-check",
            "--hide-scrollbars",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("--window-size={width},2000"))
        .arg("--dump-dom")
        .arg(format!("file://{}", page.display()))
        .stdin(Stdio::null())
        .stdout(dom_file)
        .stderr(log_file)
        .spawn()
        .unwrap_or_else(|e| panic!("{}: {e}", browser.display()));
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if t0.elapsed() > BROWSER_TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("Chromium did not finish within {BROWSER_TIMEOUT:?} at {width} px");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let log = || std::fs::read_to_string(&log_path).unwrap_or_default();
    assert!(
        status.success(),
        "Chromium failed at {width} px: {status}\n{}",
        log()
    );
    let dom = std::fs::read_to_string(&dom_path).unwrap();
    let start = dom.find("<pre id=\"probe-result\">").unwrap_or_else(|| {
        panic!(
            "no probe result in the DOM at {width} px ({dom_path:?})\n{}",
            log()
        )
    }) + "<pre id=\"probe-result\">".len();
    let end = start + dom[start..].find("</pre>").expect("closed <pre>");
    serde_json::from_str(&percent_decode(&dom[start..end])).expect("probe JSON")
}

/// Checks the measurements at one window width (at least `min_charts` charts).
fn check(m: &Value, width: u32, min_charts: usize) {
    let num = |k: &str| m[k].as_f64().unwrap_or_else(|| panic!("{k} in {m}"));
    assert_eq!(
        num("innerWidth"),
        f64::from(width),
        "window width at {width} px: {m}"
    );
    let vw = num("clientWidth");
    assert!(
        num("scrollWidth") <= num("innerWidth") && num("scrollWidth") <= vw,
        "horizontal overflow at {width} px: scrollWidth {} > {vw}",
        num("scrollWidth")
    );
    let over = m["overflowing"].as_array().unwrap();
    assert!(
        over.is_empty(),
        "{} elements end beyond the {vw} px viewport at {width} px: {over:#?}",
        over.len()
    );
    let charts = m["charts"].as_array().unwrap();
    assert!(
        charts.len() >= min_charts,
        "{} charts at {width} px",
        charts.len()
    );
    assert_eq!(charts.len() as f64, num("figures"), "one chart per figure");
    for c in charts {
        let (w, h) = (c["width"].as_f64().unwrap(), c["height"].as_f64().unwrap());
        assert!(
            c["loaded"].as_bool().unwrap(),
            "not loaded at {width} px: {c}"
        );
        assert!(w > 0.0 && h > 0.0, "not rendered at {width} px: {c}");
        assert!(w <= vw, "wider than the viewport at {width} px: {c}");
    }
    assert!(
        num("conclusionsText") > 0.0 && num("conclusionsItems") >= 3.0,
        "conclusions box missing or empty at {width} px: {m}"
    );
}

#[test]
fn report_page_fits_the_window_in_chromium() {
    let d = tmp("browser");
    let out = json(&["report", "--out", d.to_str().unwrap()]);
    let html = std::fs::read_to_string(d.join("index.html")).unwrap();
    // Self-contained: no script, stylesheet, font or image from anywhere.
    for needle in [
        "<script", "<link", "<img", "<iframe", "url(http", "@import", "src=",
    ] {
        assert!(!html.contains(needle), "the page contains {needle}");
    }
    // The conclusions state what the figures say, e.g. advise's recommendation per scene.
    let conclusions: Vec<&str> = out["conclusions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_str().unwrap())
        .collect();
    assert!(conclusions.len() >= 3, "{out}");
    for (scene, adv) in out["summary"]["advise"].as_object().unwrap() {
        let (s, rate) = (&adv["recommended_scheme"], &adv["recommended_rate"]);
        let said = match (s.as_str(), rate.as_f64()) {
            (Some(s), Some(r)) => format!("{s} at {} Hz on `{scene}`", (r * 1e3).round() / 1e3),
            _ => format!("nothing on `{scene}`"),
        };
        assert!(
            conclusions.iter().any(|c| c.contains(&said)),
            "{said} not in {conclusions:#?}"
        );
    }
    lay_out(&html, &d, 8);
}

/// The page on a recording (`report --imu`, the first 25 s of EuRoC V1_01 with its ground
/// truth) passes the same checks.
#[test]
fn report_imu_page_fits_the_window_in_chromium() {
    let d = tmp("browser-imu");
    let imu = common::head_rows(
        "tests/data/euroc/V1_01_easy_imu0.csv",
        &d,
        "imu25.csv",
        5000,
    );
    let gt = common::repo("tests/data/euroc/V1_01_easy_groundtruth_vicon2gt.csv");
    let out = d.join("out");
    let j = json(&[
        "report",
        "--imu",
        imu.to_str().unwrap(),
        "--poses",
        &gt,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(j["conclusions"].as_array().unwrap().len() >= 3, "{j}");
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    for needle in [
        "<script", "<link", "<img", "<iframe", "url(http", "@import", "src=",
    ] {
        assert!(!html.contains(needle), "the page contains {needle}");
    }
    lay_out(&html, &out, 1);
}

/// Lays out `html` (written in `dir`) in Chromium at 800 and 1 400 px and checks it, or says
/// that it skipped without Chromium (fails instead with `PREINT_BROWSER_TEST=required`).
fn lay_out(html: &str, dir: &Path, min_charts: usize) {
    let Some(browser) = chromium() else {
        let required = std::env::var("PREINT_BROWSER_TEST").is_ok_and(|v| v == "required");
        assert!(
            !required,
            "PREINT_BROWSER_TEST=required, but no Chromium (install chromium, or set PREINT_CHROMIUM)"
        );
        // Straight to stderr, past the test harness' capture, so that the skip is seen.
        let _ = writeln!(
            std::io::stderr(),
            "browser test skipped: no Chromium found (install chromium, or set PREINT_CHROMIUM)"
        );
        return;
    };
    let probe = dir.join("index-probe.html");
    std::fs::write(
        &probe,
        html.replacen("</body>", &format!("{PROBE}</body>"), 1),
    )
    .unwrap();
    for width in [800, 1400] {
        let m = measure(&browser, &probe, width, dir);
        check(&m, width, min_charts);
    }
}

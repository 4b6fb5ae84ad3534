//! The SVG text of a [`Figure`]: layout, axes with ticks, clipped series, legend.
//!
//! Layout (in SVG units; the picture scales with its container): 960 wide; the title; the
//! panels side by side, each a plot area with its tick labels and axis labels around it; below
//! them the legend, whose entries flow left to right in rows.

use super::scale::Scale;
use super::{Color, Figure, Marker, Panel, Series, Stroke};
use std::fmt::Write as _;

/// Width of the picture.
const W: f64 = 960.0;
/// Height of the title band.
const TITLE_H: f64 = 44.0;
/// Left margin of a plot area inside its panel (tick labels and the y label).
const ML: f64 = 84.0;
/// Right margin of a plot area inside its panel.
const MR: f64 = 30.0;
/// Bottom margin of a plot area (tick labels and the x label).
const MB: f64 = 58.0;
/// Height of a plot area.
const PH: f64 = 380.0;
/// Height of a legend row.
const ROW: f64 = 24.0;
/// Approximate advance of one character of the 15-unit legend font.
const CHAR_W: f64 = 8.4;

/// Escapes text for SVG.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The legend entries: every named series once, in the order of first appearance.
fn legend_entries(fig: &Figure) -> Vec<&Series> {
    let mut out: Vec<&Series> = Vec::new();
    for s in fig.panels.iter().flat_map(|p| &p.series) {
        if !s.name.is_empty() && !out.iter().any(|o| o.name == s.name) {
            out.push(s);
        }
    }
    out
}

/// Positions (x, row) of the legend entries, flowing in rows within the picture.
fn legend_layout(entries: &[&Series]) -> Vec<(f64, usize)> {
    let (x0, x_max) = (ML, W - 12.0);
    let (mut x, mut row) = (x0, 0);
    entries
        .iter()
        .map(|s| {
            let w = 40.0 + s.name.chars().count() as f64 * CHAR_W + 24.0;
            if x > x0 && x + w > x_max {
                (x, row) = (x0, row + 1);
            }
            let at = (x, row);
            x += w;
            at
        })
        .collect()
}

fn dash(stroke: Stroke) -> &'static str {
    match stroke {
        Stroke::Dashed => " stroke-dasharray=\"7 4\"",
        Stroke::Dotted => " stroke-dasharray=\"1 4\" stroke-linecap=\"round\"",
        Stroke::Solid | Stroke::None => "",
    }
}

/// A marker at `(x, y)`, with an optional hover text.
fn marker(out: &mut String, m: Marker, c: Color, x: f64, y: f64, tip: Option<&str>) {
    let c = c.hex();
    let (tag, attrs) = match m {
        Marker::None => return,
        Marker::Circle => (
            "circle",
            format!("cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"3.5\" fill=\"{c}\""),
        ),
        Marker::Square => (
            "rect",
            format!(
                "x=\"{:.1}\" y=\"{:.1}\" width=\"8\" height=\"8\" fill=\"{c}\" stroke=\"#000\" stroke-width=\"0.8\"",
                x - 4.0,
                y - 4.0
            ),
        ),
        Marker::Diamond => (
            "path",
            format!(
                "d=\"M{x:.1} {:.1}l5.5 5.5-5.5 5.5-5.5-5.5z\" fill=\"{c}\" stroke=\"#000\" stroke-width=\"0.8\"",
                y - 5.5
            ),
        ),
        Marker::Ring => (
            "circle",
            format!(
                "cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"7\" fill=\"none\" stroke=\"{c}\" stroke-width=\"1.4\""
            ),
        ),
    };
    let _ = match tip {
        Some(t) => writeln!(out, "<{tag} {attrs}><title>{}</title></{tag}>", esc(t)),
        None => writeln!(out, "<{tag} {attrs}/>"),
    };
}

/// A series' line through `pts` (already in picture coordinates; `None` breaks the line).
fn polyline(out: &mut String, s: &Series, pts: &[Option<(f64, f64)>]) {
    if s.stroke == Stroke::None {
        return;
    }
    for run in pts.split(Option::is_none) {
        if run.len() < 2 {
            continue;
        }
        let coords: Vec<String> = run
            .iter()
            .flatten()
            .map(|(x, y)| format!("{x:.1},{y:.1}"))
            .collect();
        let _ = writeln!(
            out,
            "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{}\" stroke-linejoin=\"round\"{}/>",
            coords.join(" "),
            s.color.hex(),
            s.width,
            dash(s.stroke)
        );
    }
}

/// The axes, grid, ticks and labels of a plot area at `(x0, y0)` of size `pw × PH`.
fn axes(out: &mut String, p: &Panel, sx: &Scale, sy: &Scale, x0: f64, y0: f64, pw: f64) {
    let grid = "stroke=\"#000\" stroke-width=\"1\"";
    for (t, label) in &sx.ticks {
        let x = x0 + (t - sx.lo) / (sx.hi - sx.lo) * pw;
        let op = if label.is_some() || !sx.log {
            0.16
        } else {
            0.06
        };
        let _ = writeln!(
            out,
            "<line x1=\"{x:.1}\" y1=\"{y0:.1}\" x2=\"{x:.1}\" y2=\"{:.1}\" {grid} opacity=\"{op}\"/>",
            y0 + PH
        );
        if let Some(l) = label {
            let _ = writeln!(
                out,
                "<text x=\"{x:.1}\" y=\"{:.1}\" font-size=\"14\" text-anchor=\"middle\">{}</text>",
                y0 + PH + 18.0,
                esc(l)
            );
        }
    }
    for (t, label) in &sy.ticks {
        let y = y0 + PH - (t - sy.lo) / (sy.hi - sy.lo) * PH;
        let op = if label.is_some() || !sy.log {
            0.16
        } else {
            0.06
        };
        let _ = writeln!(
            out,
            "<line x1=\"{x0:.1}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\" {grid} opacity=\"{op}\"/>",
            x0 + pw
        );
        if let Some(l) = label {
            let _ = writeln!(
                out,
                "<text x=\"{:.1}\" y=\"{:.1}\" font-size=\"14\" text-anchor=\"end\">{}</text>",
                x0 - 6.0,
                y + 4.5,
                esc(l)
            );
        }
    }
    let _ = writeln!(
        out,
        "<rect x=\"{x0:.1}\" y=\"{y0:.1}\" width=\"{pw:.1}\" height=\"{PH}\" fill=\"none\" stroke=\"#444\"/>\n\
         <text x=\"{:.1}\" y=\"{:.1}\" font-size=\"15\" text-anchor=\"middle\">{}</text>\n\
         <text x=\"{:.1}\" y=\"{:.1}\" font-size=\"15\" text-anchor=\"middle\" transform=\"rotate(-90 {:.1} {:.1})\">{}</text>",
        x0 + pw / 2.0,
        y0 + PH + 44.0,
        esc(&p.x.label),
        x0 - ML + 18.0,
        y0 + PH / 2.0,
        x0 - ML + 18.0,
        y0 + PH / 2.0,
        esc(&p.y.label)
    );
}

/// One panel: axes, then the series clipped to the plot area (those marked `behind` first).
fn panel(out: &mut String, p: &Panel, id: &str, x0: f64, y0: f64, pw: f64) {
    let all: Vec<(f64, f64)> = p
        .series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .collect();
    let sx = Scale::new(&all.iter().map(|q| q.0).collect::<Vec<_>>(), p.x.log);
    let sy = Scale::new(&all.iter().map(|q| q.1).collect::<Vec<_>>(), p.y.log);
    if !p.title.is_empty() {
        let _ = writeln!(
            out,
            "<text x=\"{:.1}\" y=\"{:.1}\" font-size=\"15\" text-anchor=\"middle\">{}</text>",
            x0 + pw / 2.0,
            y0 - 9.0,
            esc(&p.title)
        );
    }
    axes(out, p, &sx, &sy, x0, y0, pw);
    let _ = writeln!(
        out,
        "<clipPath id=\"{id}\"><rect x=\"{x0:.1}\" y=\"{y0:.1}\" width=\"{pw:.1}\" height=\"{PH}\"/></clipPath>\n<g clip-path=\"url(#{id})\">"
    );
    let order = p
        .series
        .iter()
        .filter(|s| s.behind)
        .chain(p.series.iter().filter(|s| !s.behind));
    for s in order {
        let pts: Vec<Option<(f64, f64)>> = s
            .points
            .iter()
            .map(|&(x, y)| {
                let (fx, fy) = (sx.frac(x)?, sy.frac(y)?);
                Some((x0 + fx * pw, y0 + PH - fy * PH))
            })
            .collect();
        polyline(out, s, &pts);
        for (i, q) in pts.iter().enumerate() {
            if let Some((x, y)) = q {
                marker(
                    out,
                    s.marker,
                    s.color,
                    *x,
                    *y,
                    s.tips.get(i).map(String::as_str),
                );
            }
        }
    }
    out.push_str("</g>\n");
}

/// The legend entry of `s` at `(x, y)` (the swatch's centre line).
fn legend_entry(out: &mut String, s: &Series, x: f64, y: f64) {
    if s.stroke != Stroke::None {
        let _ = writeln!(
            out,
            "<line x1=\"{x:.1}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\" stroke=\"{}\" stroke-width=\"{}\"{}/>",
            x + 30.0,
            s.color.hex(),
            s.width.max(1.6),
            dash(s.stroke)
        );
    }
    marker(out, s.marker, s.color, x + 15.0, y, None);
    let _ = writeln!(
        out,
        "<text x=\"{:.1}\" y=\"{:.1}\" font-size=\"15\">{}</text>",
        x + 38.0,
        y + 5.0,
        esc(&s.name)
    );
}

/// The SVG text of `fig`, its clip-path ids prefixed with `id`.
pub fn render(fig: &Figure, id: &str) -> String {
    let n = fig.panels.len().max(1) as f64;
    let pw_panel = W / n;
    let mt = if fig.panels.iter().any(|p| !p.title.is_empty()) {
        26.0
    } else {
        8.0
    };
    let y0 = TITLE_H + mt;
    let legend_top = y0 + PH + MB + 10.0;
    let entries = legend_entries(fig);
    let at = legend_layout(&entries);
    let rows = at.iter().map(|a| a.1 + 1).max().unwrap_or(0);
    let h = (legend_top + rows as f64 * ROW + 6.0).ceil();
    let mut out = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 {W} {h}\" width=\"100%\" \
         style=\"max-width:{W}px;height:auto\" font-family=\"sans-serif\" role=\"img\" aria-label=\"{t}\">\n\
         <rect width=\"{W}\" height=\"{h}\" fill=\"#fff\"/>\n\
         <text x=\"{:.1}\" y=\"28\" font-size=\"20\" text-anchor=\"middle\">{t}</text>\n",
        W / 2.0,
        t = esc(&fig.title)
    );
    for (k, p) in fig.panels.iter().enumerate() {
        let x0 = k as f64 * pw_panel + ML;
        panel(
            &mut out,
            p,
            &format!("{id}-p{k}"),
            x0,
            y0,
            pw_panel - ML - MR,
        );
    }
    for (s, (x, row)) in entries.iter().zip(at) {
        legend_entry(&mut out, s, x, legend_top + row as f64 * ROW + ROW / 2.0);
    }
    out.push_str("</svg>\n");
    out
}

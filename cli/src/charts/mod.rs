//! SVG charts: one or more panels side by side, each with labelled axes (linear or
//! logarithmic), and one legend below the panels, outside the plotted data ([`render`],
//! [`draw`]); the figures the commands draw ([`figures`]).
//!
//! The SVG has a `viewBox` and `width="100%"` with a `max-width` of its natural width, so it
//! scales down with the window instead of overflowing it. Each scheme has one colour
//! ([`scheme_color`]) in every chart, and the HTML report styles scheme names with the same
//! colours.

pub mod figures;
mod scale;
mod svg;

use preint::Scheme;
use std::path::Path;

/// An RGB colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Color(pub u8, pub u8, pub u8);

impl Color {
    /// `#rrggbb`.
    pub fn hex(self) -> String {
        format!("#{:02x}{:02x}{:02x}", self.0, self.1, self.2)
    }

    /// The colour written `#rrggbb`, if it is.
    pub fn parse_hex(s: &str) -> Option<Self> {
        let h = s.strip_prefix('#').filter(|h| h.len() == 6)?;
        let byte = |i: usize| u8::from_str_radix(h.get(i..i + 2)?, 16).ok();
        Some(Color(byte(0)?, byte(2)?, byte(4)?))
    }
}

/// Colours of curves that are not schemes (sensor axes, attitude representations): orange, sky
/// blue, yellow, near-black; none of them is a scheme's colour.
pub const OTHER_COLORS: [Color; 4] = [
    Color(230, 159, 0),
    Color(86, 180, 233),
    Color(240, 228, 66),
    Color(40, 40, 40),
];

/// The neutral colour of reference lines (Pareto front, thresholds, style keys).
pub const NEUTRAL: Color = Color(110, 110, 110);

/// The colour of a scheme in every chart and table: its registry row's
/// ([`preint::SchemeInfo::colour`]; euler, midpoint, hermite4, galilean: vermilion, blue,
/// bluish green, reddish purple, Okabe–Ito, distinguishable with the common colour vision
/// deficiencies).
pub fn scheme_color(s: Scheme) -> Color {
    Color::parse_hex(s.info().colour).unwrap_or(NEUTRAL)
}

/// How a series' line is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stroke {
    /// A continuous line.
    Solid,
    /// Dashes (reference and fitted lines).
    Dashed,
    /// Dots.
    Dotted,
    /// No line (markers only).
    None,
}

/// The marker drawn at each point of a series.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// No marker.
    None,
    /// A filled circle.
    Circle,
    /// A filled square.
    Square,
    /// A filled diamond.
    Diamond,
    /// A hollow ring around the point (highlights points of other series).
    Ring,
}

/// One named series of (x, y) points.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend label; an empty name keeps the series out of the legend.
    pub name: String,
    /// Points; a non-finite or (on a log axis) non-positive point breaks the line.
    pub points: Vec<(f64, f64)>,
    /// Colour of the line and the markers.
    pub color: Color,
    /// Line style.
    pub stroke: Stroke,
    /// Line width \[px\].
    pub width: f64,
    /// Marker at each point.
    pub marker: Marker,
    /// Drawn before every series that is not (under them).
    pub behind: bool,
    /// Hover text per point (empty, or one per point).
    pub tips: Vec<String>,
}

impl Series {
    /// A solid line with a circle at each point.
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>, color: Color) -> Self {
        Self {
            name: name.into(),
            points,
            color,
            stroke: Stroke::Solid,
            width: 2.0,
            marker: Marker::Circle,
            behind: false,
            tips: Vec::new(),
        }
    }

    /// A thin solid line without markers (dense curves).
    pub fn curve(name: impl Into<String>, points: Vec<(f64, f64)>, color: Color) -> Self {
        Self {
            width: 1.6,
            marker: Marker::None,
            ..Self::line(name, points, color)
        }
    }

    /// A thin dashed line without markers (fitted and reference lines).
    pub fn reference(name: impl Into<String>, points: Vec<(f64, f64)>, color: Color) -> Self {
        Self {
            stroke: Stroke::Dashed,
            width: 1.3,
            marker: Marker::None,
            ..Self::line(name, points, color)
        }
    }

    /// Markers only, no line.
    pub fn markers(
        name: impl Into<String>,
        points: Vec<(f64, f64)>,
        color: Color,
        marker: Marker,
    ) -> Self {
        Self {
            stroke: Stroke::None,
            marker,
            ..Self::line(name, points, color)
        }
    }

    /// A legend entry only (no points): explains a line style or a marker used by other series.
    pub fn key(name: impl Into<String>, color: Color, stroke: Stroke, marker: Marker) -> Self {
        Self {
            stroke,
            marker,
            width: 1.6,
            ..Self::line(name, Vec::new(), color)
        }
    }

    /// The same series with another line style.
    pub fn with_stroke(mut self, stroke: Stroke) -> Self {
        self.stroke = stroke;
        self
    }

    /// The same series with another marker.
    pub fn with_marker(mut self, marker: Marker) -> Self {
        self.marker = marker;
        self
    }

    /// The same series with another line width.
    pub fn with_width(mut self, width: f64) -> Self {
        self.width = width;
        self
    }

    /// The same series drawn under the others.
    pub fn drawn_behind(mut self) -> Self {
        self.behind = true;
        self
    }

    /// The same series with a hover text per point.
    pub fn with_tips(mut self, tips: Vec<String>) -> Self {
        self.tips = tips;
        self
    }
}

/// One axis.
#[derive(Clone, Debug)]
pub struct Axis {
    /// Label with unit.
    pub label: String,
    /// Logarithmic.
    pub log: bool,
}

impl Axis {
    /// A logarithmic axis.
    pub fn log(label: impl Into<String>) -> Self {
        Self {
            label: label.into(),
            log: true,
        }
    }

    /// A linear axis.
    pub fn linear(label: impl Into<String>) -> Self {
        Self {
            label: label.into(),
            log: false,
        }
    }
}

/// One plot area with its axes and series.
#[derive(Clone, Debug)]
pub struct Panel {
    /// Title above the plot area (empty: none).
    pub title: String,
    /// Horizontal axis.
    pub x: Axis,
    /// Vertical axis.
    pub y: Axis,
    /// Series, drawn in order (those marked `behind` first).
    pub series: Vec<Series>,
}

/// A chart: a title, panels side by side, and one legend below them listing every named
/// series once (series of the same name in several panels share an entry).
#[derive(Clone, Debug)]
pub struct Figure {
    /// Title.
    pub title: String,
    /// Panels, left to right.
    pub panels: Vec<Panel>,
}

/// The SVG text of `fig`; `id` (unique within an HTML page) prefixes the SVG's internal ids.
pub fn render(fig: &Figure, id: &str) -> String {
    svg::render(fig, id)
}

/// Writes `fig` as an SVG file (its internal ids prefixed with the file's stem, so that several
/// charts can be embedded in one page).
pub fn draw(path: &Path, fig: &Figure) -> Result<(), String> {
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("chart");
    let id: String = stem
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect();
    let svg = render(fig, &id);
    if let Some((line, text)) = preint_io::error::non_finite_line(&svg) {
        return Err(format!(
            "{}: not written: line {line} of the chart would hold a non-finite number ({text})",
            path.display()
        ));
    }
    std::fs::write(path, svg).map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_a_scalable_svg_with_a_legend_below_the_plot() {
        let dir = std::env::temp_dir().join(format!("preint-chart-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("c.svg");
        let fig = Figure {
            title: "t & u".into(),
            panels: vec![Panel {
                title: String::new(),
                x: Axis::log("x [s]"),
                y: Axis::log("y [m]"),
                series: vec![
                    Series::line(
                        "a",
                        vec![(1.0, 1.0), (10.0, 0.1)],
                        scheme_color(Scheme::Euler),
                    ),
                    Series::reference("b", vec![(2.0, 0.5), (3.0, 0.4)], NEUTRAL).drawn_behind(),
                ],
            }],
        };
        draw(&p, &fig).unwrap();
        let svg = std::fs::read_to_string(&p).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("viewBox=\"0 0 960 ") && svg.contains("width=\"100%\""));
        assert!(svg.contains("x [s]") && svg.contains("y [m]") && svg.contains("t &amp; u"));
        assert!(svg.contains("stroke-dasharray") && svg.contains("clip-path=\"url(#c-p0)\""));
        // The reference line is drawn first, and both series are in the legend.
        let (a, b) = (svg.find("#d55e00").unwrap(), svg.find("#6e6e6e").unwrap());
        assert!(b < a);
        assert!(svg.contains(">a</text>") && svg.contains(">b</text>"));
    }

    /// Every registered scheme's colour is a `#rrggbb` colour of its own, none of them a
    /// colour of the curves that are not schemes.
    #[test]
    fn every_scheme_has_a_colour_of_its_own() {
        let mut seen: Vec<Color> = OTHER_COLORS.to_vec();
        seen.push(NEUTRAL);
        for s in Scheme::ALL {
            let c = Color::parse_hex(s.info().colour).expect("a #rrggbb colour");
            assert_eq!(c.hex(), s.info().colour, "{s:?}");
            assert!(!seen.contains(&c), "{s:?}: {} is taken", c.hex());
            seen.push(c);
        }
        assert_eq!(Color::parse_hex("#d55e0"), None);
        assert_eq!(Color::parse_hex("d55e00"), None);
    }
}

//! SVG charts with plotters: labelled axes with units, legends, optional log scales
//! ([`draw`]), and the figures the commands draw ([`figures`]).

pub mod figures;

use plotters::coord::combinators::IntoLogRange;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::prelude::*;
use std::path::Path;

/// One named series of (x, y) points.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend label.
    pub name: String,
    /// Points; non-finite or (on log axes) non-positive points are skipped.
    pub points: Vec<(f64, f64)>,
    /// Draw a line through the points (else markers only).
    pub line: bool,
    /// Dashed thin line (for fitted/reference lines).
    pub dashed: bool,
}

impl Series {
    /// A line series with markers.
    pub fn line(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            line: true,
            dashed: false,
        }
    }
    /// A thin reference line without markers.
    pub fn reference(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            dashed: true,
            ..Self::line(name, points)
        }
    }
}

/// Chart layout.
pub struct Chart<'a> {
    /// Title.
    pub title: &'a str,
    /// X-axis label with unit.
    pub x_label: &'a str,
    /// Y-axis label with unit.
    pub y_label: &'a str,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

fn usable(c: &Chart, p: &(f64, f64)) -> bool {
    p.0.is_finite() && p.1.is_finite() && (!c.log_x || p.0 > 0.0) && (!c.log_y || p.1 > 0.0)
}

fn range(vals: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (1.0, 10.0);
    }
    if log {
        let (l, h) = (
            lo.log10().floor(),
            hi.log10().ceil().max(lo.log10().floor() + 1.0),
        );
        (10f64.powf(l), 10f64.powf(h))
    } else {
        let pad = ((hi - lo) * 0.05).max(1e-12);
        (lo - pad, hi + pad)
    }
}

/// Draws the mesh, the series and the legend on a chart whose axes are `X` and `Y` (linear or
/// logarithmic).
fn plot<'a, X, Y>(
    mut ctx: ChartContext<'a, SVGBackend<'a>, Cartesian2d<X, Y>>,
    chart: &Chart,
    series: &[Series],
) -> Result<(), String>
where
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    ctx.configure_mesh()
        .x_desc(chart.x_label)
        .y_desc(chart.y_label)
        .x_label_formatter(&|v| fmt_tick(*v))
        .y_label_formatter(&|v| fmt_tick(*v))
        .draw()
        .map_err(|e| e.to_string())?;
    for (i, s) in series.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|p| usable(chart, p))
            .collect();
        let style = if s.dashed {
            color.stroke_width(1)
        } else {
            color.stroke_width(2)
        };
        if s.line {
            let anno = ctx
                .draw_series(LineSeries::new(pts.clone(), style))
                .map_err(|e| e.to_string())?;
            anno.label(s.name.clone()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
        }
        if !s.dashed {
            let anno = ctx
                .draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))
                .map_err(|e| e.to_string())?;
            if !s.line {
                anno.label(s.name.clone())
                    .legend(move |(x, y)| Circle::new((x + 9, y), 4, color.filled()));
            }
        }
    }
    ctx.configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| e.to_string())
}

/// Writes an SVG chart of `series` to `path` (900×560 px).
pub fn draw(path: &Path, chart: &Chart, series: &[Series]) -> Result<(), String> {
    let all: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .filter(|p| usable(chart, p))
        .collect();
    let (x0, x1) = range(all.iter().map(|p| p.0), chart.log_x);
    let (y0, y1) = range(all.iter().map(|p| p.1), chart.log_y);
    let root = SVGBackend::new(path, (900, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut b = ChartBuilder::on(&root);
    b.caption(chart.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(78);
    let e = |e: plotters::drawing::DrawingAreaErrorKind<_>| e.to_string();
    match (chart.log_x, chart.log_y) {
        (true, true) => plot(
            b.build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
                .map_err(e)?,
            chart,
            series,
        ),
        (true, false) => plot(
            b.build_cartesian_2d((x0..x1).log_scale(), y0..y1)
                .map_err(e)?,
            chart,
            series,
        ),
        (false, true) => plot(
            b.build_cartesian_2d(x0..x1, (y0..y1).log_scale())
                .map_err(e)?,
            chart,
            series,
        ),
        (false, false) => plot(
            b.build_cartesian_2d(x0..x1, y0..y1).map_err(e)?,
            chart,
            series,
        ),
    }?;
    root.present()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(())
}

fn fmt_tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e4).contains(&a) {
        format!("{v:.0e}")
    } else {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// Indices of the Pareto-optimal points when minimising both coordinates (cost, error).
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].0.is_finite() && points[i].1.is_finite())
        .collect();
    idx.sort_by(|&a, &b| {
        points[a]
            .0
            .total_cmp(&points[b].0)
            .then(points[a].1.total_cmp(&points[b].1))
    });
    let mut best = f64::INFINITY;
    let mut front = Vec::new();
    for i in idx {
        if points[i].1 < best {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_keeps_only_undominated_points() {
        let pts = [
            (1.0, 10.0),
            (2.0, 5.0),
            (3.0, 7.0),
            (4.0, 1.0),
            (5.0, 1.0),
            (0.5, f64::NAN),
        ];
        assert_eq!(pareto_front(&pts), vec![0, 1, 3]);
    }

    #[test]
    fn draws_a_valid_svg() {
        let dir = std::env::temp_dir().join(format!("preint-chart-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("c.svg");
        let c = Chart {
            title: "t",
            x_label: "x [s]",
            y_label: "y [m]",
            log_x: true,
            log_y: true,
        };
        draw(
            &p,
            &c,
            &[
                Series::line("a", vec![(1.0, 1.0), (10.0, 0.1)]),
                Series::reference("b", vec![(2.0, 0.5), (3.0, 0.4)]),
            ],
        )
        .unwrap();
        let svg = std::fs::read_to_string(&p).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("x [s]") && svg.contains("y [m]"));
    }
}

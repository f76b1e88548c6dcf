//! SVG line charts (plotters' SVG backend: no fonts needed at build time; the viewer renders text).

use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

/// One line of a chart.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

const COLORS: [RGBColor; 8] = [
    RGBColor(0, 0, 0),
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
];

fn range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    if log {
        (lo / 1.3, hi * 1.3)
    } else {
        let pad = (hi - lo).max(hi.abs() * 0.05).max(1e-9) * 0.05;
        ((lo - pad).min(0.0_f64.max(lo - pad)), hi + pad)
    }
}

/// A line chart with labelled axes and a legend, as an SVG document.
pub fn line_chart(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    log_x: bool,
    log_y: bool,
) -> anyhow::Result<String> {
    line_chart_with_references(title, x_label, y_label, series, &[], log_x, log_y)
}

/// [`line_chart`] plus dashed reference lines: `references[i]` is drawn dashed in the colour of
/// `series[i]` (a competitor's rate beside the series measured against it).
pub fn line_chart_with_references(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    references: &[Series],
    log_x: bool,
    log_y: bool,
) -> anyhow::Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 600)).into_drawing_area();
        root.fill(&WHITE)?;
        let all = || series.iter().chain(references).flat_map(|s| s.points.iter());
        let (x0, x1) = range(all().map(|p| p.0), log_x);
        let (y0, y1) = range(all().map(|p| p.1), log_y);
        let mut builder = ChartBuilder::on(&root);
        builder.caption(title, ("sans-serif", 20)).margin(20).x_label_area_size(50).y_label_area_size(70);
        macro_rules! draw {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(x_label)
                    .y_desc(y_label)
                    .axis_desc_style(("sans-serif", 16))
                    .label_style(("sans-serif", 13))
                    .draw()?;
                for (i, s) in series.iter().enumerate() {
                    let color = COLORS[i % COLORS.len()];
                    chart
                        .draw_series(LineSeries::new(s.points.iter().copied(), color.stroke_width(2)))?
                        .label(s.label.clone())
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
                    chart.draw_series(s.points.iter().map(|&p| Circle::new(p, 3, color.filled())))?;
                }
                for (i, s) in references.iter().enumerate() {
                    let color = COLORS[i % COLORS.len()];
                    chart
                        .draw_series(DashedLineSeries::new(
                            s.points.iter().copied(),
                            8,
                            5,
                            color.stroke_width(2).into(),
                        ))?
                        .label(s.label.clone())
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(1)));
                }
                chart
                    .configure_series_labels()
                    .position(SeriesLabelPosition::UpperLeft)
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .label_font(("sans-serif", 13))
                    .draw()?;
            }};
        }
        match (log_x, log_y) {
            (true, true) => draw!(builder.build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?),
            (true, false) => draw!(builder.build_cartesian_2d((x0..x1).log_scale(), y0..y1)?),
            (false, true) => draw!(builder.build_cartesian_2d(x0..x1, (y0..y1).log_scale())?),
            (false, false) => {
                draw!(builder.build_cartesian_2d::<RangedCoordf64, RangedCoordf64>((x0..x1).into(), (y0..y1).into())?)
            }
        }
        root.present()?;
    }
    Ok(svg)
}

/// A grouped bar chart: one group of bars per category, one bar per series (`None`: no bar), a
/// logarithmic or linear y axis, and labelled horizontal lines (targets). Plain SVG.
pub fn bar_chart(
    title: &str,
    y_label: &str,
    categories: &[String],
    series: &[(String, Vec<Option<f64>>)],
    lines: &[(f64, String)],
    log_y: bool,
) -> String {
    use std::fmt::Write as _;
    let (w, h) = (1000.0, 600.0);
    let (left, right, top, bottom) = (80.0, 20.0, 50.0, 130.0);
    let values = series.iter().flat_map(|s| s.1.iter().flatten().copied()).chain(lines.iter().map(|l| l.0));
    let (lo, hi) = values
        .filter(|v| v.is_finite() && (!log_y || *v > 0.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    let (lo, hi) = if lo > hi {
        (0.1, 1.0)
    } else if log_y {
        (lo / 1.5, hi * 1.5)
    } else {
        (0.0, hi * 1.1)
    };
    let f = |v: f64| if log_y { v.max(lo).ln() } else { v };
    let y = |v: f64| top + (h - top - bottom) * (1.0 - (f(v) - f(lo)) / (f(hi) - f(lo)));
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif"><rect width="{w}" height="{h}" fill="white"/><text x="{}" y="28" font-size="20" text-anchor="middle">{}</text>"#,
        w / 2.0,
        escape(title)
    );
    // Axis ticks: powers of ten and their 2× and 5× on a log axis, ten steps on a linear one.
    let mut ticks = Vec::new();
    if log_y {
        let mut p = 10f64.powf(lo.log10().floor());
        while p <= hi {
            for m in [1.0, 2.0, 5.0] {
                if (lo..=hi).contains(&(p * m)) {
                    ticks.push(p * m);
                }
            }
            p *= 10.0;
        }
    } else {
        let step = 10f64.powf((hi / 5.0).log10().floor());
        ticks.extend((0..).map(|i| i as f64 * step).take_while(|v| *v <= hi));
    }
    for t in ticks {
        let _ = write!(
            s,
            r##"<line x1="{left}" x2="{}" y1="{y:.1}" y2="{y:.1}" stroke="#ddd"/><text x="{}" y="{:.1}" font-size="12" text-anchor="end">{t}</text>"##,
            w - right,
            left - 6.0,
            y(t) + 4.0,
            y = y(t)
        );
    }
    let _ = write!(
        s,
        r#"<text x="20" y="{:.1}" font-size="14" text-anchor="middle" transform="rotate(-90 20 {:.1})">{}</text>"#,
        (top + h - bottom) / 2.0,
        (top + h - bottom) / 2.0,
        escape(y_label)
    );
    let group = (w - left - right) / categories.len().max(1) as f64;
    let bar = group * 0.8 / series.len().max(1) as f64;
    for (c, name) in categories.iter().enumerate() {
        let x0 = left + group * c as f64 + group * 0.1;
        for (i, (_, vals)) in series.iter().enumerate() {
            if let Some(v) = vals.get(c).copied().flatten().filter(|v| v.is_finite() && (!log_y || *v > 0.0)) {
                let RGBColor(r, g, b) = COLORS[(i + 1) % COLORS.len()];
                let (yt, yb) = (y(v), y(lo));
                let _ = write!(
                    s,
                    r#"<rect x="{:.1}" y="{yt:.1}" width="{:.1}" height="{:.1}" fill="rgb({r},{g},{b})"><title>{}: {v:.3}</title></rect>"#,
                    x0 + bar * i as f64,
                    bar * 0.9,
                    (yb - yt).max(0.0),
                    escape(&series[i].0)
                );
            }
        }
        let cx = x0 + group * 0.4;
        let _ = write!(
            s,
            r#"<text x="{cx:.1}" y="{:.1}" font-size="12" text-anchor="end" transform="rotate(-35 {cx:.1} {:.1})">{}</text>"#,
            h - bottom + 16.0,
            h - bottom + 16.0,
            escape(name)
        );
    }
    for (v, label) in lines {
        let yv = y(*v);
        let _ = write!(
            s,
            r##"<line x1="{left}" x2="{}" y1="{yv:.1}" y2="{yv:.1}" stroke="#000" stroke-dasharray="6 4"/><text x="{}" y="{:.1}" font-size="12" text-anchor="end">{}</text>"##,
            w - right,
            w - right - 4.0,
            yv - 4.0,
            escape(label)
        );
    }
    let _ = write!(s, r##"<line x1="{left}" x2="{left}" y1="{top}" y2="{}" stroke="#000"/>"##, h - bottom);
    for (i, (label, _)) in series.iter().enumerate() {
        let RGBColor(r, g, b) = COLORS[(i + 1) % COLORS.len()];
        let (lx, ly) = (left + 10.0 + 150.0 * (i % 6) as f64, 40.0 + 0.0 * i as f64);
        let _ = write!(
            s,
            r#"<rect x="{lx}" y="{ly}" width="12" height="12" fill="rgb({r},{g},{b})"/><text x="{}" y="{}" font-size="12">{}</text>"#,
            lx + 16.0,
            ly + 11.0,
            escape(label)
        );
    }
    s.push_str("</svg>\n");
    s
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

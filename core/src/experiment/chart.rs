//! Small SVG charts for the experiment: line charts with error bars (one series per
//! algorithm, budgets on the x axis) and a scatter plot.
//!
//! Plain string building, like [`crate::render`]: four chart kinds with axes, ticks and a
//! legend need no dependency, and the output stays byte-identical for identical input.
//! Every element carries a `class` (`series`, `point`, `errorbar`, `axis`, `tick`,
//! `legend`, `refline`) for styling and tests.

use std::fmt::Write as _;

use crate::render::esc;

/// Width of the whole chart, SVG px.
const WIDTH: f64 = 720.0;
/// Height of the whole chart, SVG px.
const HEIGHT: f64 = 440.0;
/// Margin left of the plot area, px: the y axis's ticks and label.
const LEFT: f64 = 70.0;
/// Margin right of the plot area, px: the legend.
const RIGHT: f64 = 170.0;
/// Margin above the plot area, px: the title and subtitle.
const TOP: f64 = 50.0;
/// Margin below the plot area, px: the x axis's ticks and label.
const BOTTOM: f64 = 55.0;

/// The colour of series `i` (matplotlib's tab10).
pub fn colour(i: usize) -> &'static str {
    const TAB10: [&str; 10] = [
        "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
        "#bcbd22", "#17becf",
    ];
    TAB10[i % TAB10.len()]
}

/// Draws the marker of series `i` (circle, square, triangle, diamond, inverted triangle,
/// cross, then again) centred on `(x, y)`: the shape tells overlapping series apart.
fn marker(s: &mut String, i: usize, x: f64, y: f64, class: &str, fill: &str) {
    let r = 4.0;
    let stroke = r##"stroke="#ffffff" stroke-width="0.8""##;
    let _ = match i % 6 {
        0 => writeln!(
            s,
            r#"<circle class="{class}" cx="{x:.1}" cy="{y:.1}" r="{r}" fill="{fill}" {stroke}/>"#
        ),
        1 => writeln!(
            s,
            r#"<rect class="{class}" x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{fill}" {stroke}/>"#,
            x - r * 0.9,
            y - r * 0.9,
            r * 1.8,
            r * 1.8
        ),
        2 => writeln!(
            s,
            r#"<path class="{class}" d="M{x:.1},{:.1} L{:.1},{:.1} L{:.1},{:.1} Z" fill="{fill}" {stroke}/>"#,
            y - r * 1.2,
            x + r * 1.1,
            y + r * 0.8,
            x - r * 1.1,
            y + r * 0.8
        ),
        3 => writeln!(
            s,
            r#"<path class="{class}" d="M{x:.1},{:.1} L{:.1},{y:.1} L{x:.1},{:.1} L{:.1},{y:.1} Z" fill="{fill}" {stroke}/>"#,
            y - r * 1.2,
            x + r * 1.2,
            y + r * 1.2,
            x - r * 1.2
        ),
        4 => writeln!(
            s,
            r#"<path class="{class}" d="M{x:.1},{:.1} L{:.1},{:.1} L{:.1},{:.1} Z" fill="{fill}" {stroke}/>"#,
            y + r * 1.2,
            x + r * 1.1,
            y - r * 0.8,
            x - r * 1.1,
            y - r * 0.8
        ),
        _ => writeln!(
            s,
            r#"<path class="{class}" d="M{:.1},{:.1} L{:.1},{:.1} M{:.1},{:.1} L{:.1},{:.1}" stroke="{fill}" stroke-width="2.2"/>"#,
            x - r,
            y - r,
            x + r,
            y + r,
            x - r,
            y + r,
            x + r,
            y - r
        ),
    };
}

/// One point of a line series: `x`, `y` and an optional error bar `(low, high)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinePoint {
    pub x: f64,
    pub y: f64,
    pub bar: Option<(f64, f64)>,
}

/// A named series.
#[derive(Debug, Clone, PartialEq)]
pub struct Series<P> {
    pub name: String,
    /// Index into the colour palette ([`colour`]).
    pub colour: usize,
    pub points: Vec<P>,
}

/// A dashed horizontal reference line with a label.
#[derive(Debug, Clone, PartialEq)]
pub struct RefLine {
    pub y: f64,
    pub label: String,
}

/// A line chart; with `log_y` the y axis is logarithmic (values `<= 0` are left out).
#[derive(Debug, Clone, PartialEq)]
pub struct LineChart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series<LinePoint>>,
    pub ref_lines: Vec<RefLine>,
    pub log_y: bool,
    /// Ticks on the x axis at exactly these values (the budgets); empty: automatic.
    pub x_ticks: Vec<f64>,
}

/// A scatter plot; `subtitle` is a second title line.
#[derive(Debug, Clone, PartialEq)]
pub struct ScatterChart {
    pub title: String,
    pub subtitle: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series<(f64, f64)>>,
}

/// "Nice" tick values covering `[lo, hi]` (about `n` of them): steps of 1, 2 or 5 times a
/// power of ten. Returns the ticks and the axis range they span.
fn nice_ticks(lo: f64, hi: f64, n: usize) -> (Vec<f64>, f64, f64) {
    let (lo, hi) = if hi - lo < 1e-12 * lo.abs().max(1.0) {
        let pad = lo.abs().max(1.0) * 0.1;
        (lo - pad, hi + pad)
    } else {
        (lo, hi)
    };
    let raw = (hi - lo) / n.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).floor() * step;
    let last = (hi / step).ceil() * step;
    let count = ((last - first) / step).round() as usize;
    let ticks = (0..=count).map(|i| first + i as f64 * step).collect();
    (ticks, first, last)
}

/// Powers of ten covering `[lo, hi]` (both `> 0`).
fn log_ticks(lo: f64, hi: f64) -> (Vec<f64>, f64, f64) {
    let a = lo.log10().floor() as i32;
    let b = (hi.log10().ceil() as i32).max(a + 1);
    let ticks = (a..=b).map(|e| 10f64.powi(e)).collect();
    (ticks, 10f64.powi(a), 10f64.powi(b))
}

/// A tick label without needless digits.
fn tick_label(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if (1e-3..1e6).contains(&a) {
        let s = format!("{v:.3}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{v:e}")
    }
}

/// Maps data to pixels.
struct Frame {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    log_y: bool,
}

impl Frame {
    fn px(&self, x: f64) -> f64 {
        LEFT + (x - self.x0) / (self.x1 - self.x0) * (WIDTH - LEFT - RIGHT)
    }

    fn py(&self, y: f64) -> f64 {
        let t = if self.log_y {
            (y.log10() - self.y0.log10()) / (self.y1.log10() - self.y0.log10())
        } else {
            (y - self.y0) / (self.y1 - self.y0)
        };
        HEIGHT - BOTTOM - t * (HEIGHT - TOP - BOTTOM)
    }
}

/// The texts around a chart.
struct Labels<'a> {
    title: &'a str,
    subtitle: &'a str,
    x: &'a str,
    y: &'a str,
}

/// The document head, title, axes, ticks, labels (everything but the data).
fn frame_svg(s: &mut String, f: &Frame, labels: &Labels, xt: &[f64], yt: &[f64]) {
    let Labels {
        title,
        subtitle,
        x: x_label,
        y: y_label,
    } = *labels;
    // `write!` into a String cannot fail; the results are ignored on purpose.
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH:.0}" height="{HEIGHT:.0}" viewBox="0 0 {WIDTH:.0} {HEIGHT:.0}" font-family="sans-serif">"#
    );
    let _ = writeln!(s, "<title>{}</title>", esc(title));
    let _ = writeln!(
        s,
        r##"<rect x="0" y="0" width="{WIDTH:.0}" height="{HEIGHT:.0}" fill="#ffffff"/>"##
    );
    let _ = writeln!(
        s,
        r##"<text class="title" x="{:.1}" y="22" font-size="15" font-weight="bold" text-anchor="middle" fill="#111">{}</text>"##,
        (LEFT + WIDTH - RIGHT) / 2.0,
        esc(title)
    );
    if !subtitle.is_empty() {
        let _ = writeln!(
            s,
            r##"<text class="subtitle" x="{:.1}" y="39" font-size="11" text-anchor="middle" fill="#333">{}</text>"##,
            (LEFT + WIDTH - RIGHT) / 2.0,
            esc(subtitle)
        );
    }
    let (l, r, t, b) = (LEFT, WIDTH - RIGHT, TOP, HEIGHT - BOTTOM);
    for &y in yt {
        let py = f.py(y);
        let _ = writeln!(
            s,
            r##"<line class="grid" x1="{l:.1}" y1="{py:.1}" x2="{r:.1}" y2="{py:.1}" stroke="#e5e5e5"/>"##
        );
        let _ = writeln!(
            s,
            r##"<text class="tick" x="{:.1}" y="{:.1}" font-size="11" text-anchor="end" fill="#333">{}</text>"##,
            l - 6.0,
            py + 4.0,
            tick_label(y)
        );
    }
    for &x in xt {
        let px = f.px(x);
        let _ = writeln!(
            s,
            r##"<line class="tick" x1="{px:.1}" y1="{b:.1}" x2="{px:.1}" y2="{:.1}" stroke="#333"/>"##,
            b + 5.0
        );
        let _ = writeln!(
            s,
            r##"<text class="tick" x="{px:.1}" y="{:.1}" font-size="11" text-anchor="middle" fill="#333">{}</text>"##,
            b + 18.0,
            tick_label(x)
        );
    }
    let _ = writeln!(
        s,
        r##"<path class="axis" d="M{l:.1},{t:.1} L{l:.1},{b:.1} L{r:.1},{b:.1}" fill="none" stroke="#333"/>"##
    );
    let _ = writeln!(
        s,
        r##"<text class="label" x="{:.1}" y="{:.1}" font-size="12" text-anchor="middle" fill="#111">{}</text>"##,
        (l + r) / 2.0,
        HEIGHT - 12.0,
        esc(x_label)
    );
    let _ = writeln!(
        s,
        r##"<text class="label" x="16" y="{:.1}" font-size="12" text-anchor="middle" fill="#111" transform="rotate(-90 16 {:.1})">{}</text>"##,
        (t + b) / 2.0,
        (t + b) / 2.0,
        esc(y_label)
    );
}

/// The legend entries of a chart's series: name and colour index, in order.
fn legend_entries<P>(series: &[Series<P>]) -> Vec<(String, usize)> {
    series.iter().map(|s| (s.name.clone(), s.colour)).collect()
}

/// The legend on the right: one entry per series name.
fn legend_svg(s: &mut String, entries: &[(String, usize)], marker_line: bool) {
    let x = WIDTH - RIGHT + 18.0;
    for (i, (name, c)) in entries.iter().enumerate() {
        let y = TOP + 10.0 + i as f64 * 20.0;
        let col = colour(*c);
        if marker_line {
            let _ = writeln!(
                s,
                r##"<line class="legend" x1="{x:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="{col}" stroke-width="2.5"/>"##,
                x + 22.0
            );
        }
        marker(s, *c, x + 11.0, y, "legend", col);
        let _ = writeln!(
            s,
            r##"<text class="legend" x="{:.1}" y="{:.1}" font-size="12" fill="#111">{}</text>"##,
            x + 30.0,
            y + 4.0,
            esc(name)
        );
    }
}

impl LineChart {
    /// The chart as one SVG document.
    pub fn to_svg(&self) -> String {
        let ok = |v: f64| v.is_finite() && (!self.log_y || v > 0.0);
        let mut xs: Vec<f64> = self.x_ticks.clone();
        let mut ys: Vec<f64> = Vec::new();
        for p in self.series.iter().flat_map(|s| &s.points) {
            if ok(p.y) {
                xs.push(p.x);
                ys.push(p.y);
                if let Some((lo, hi)) = p.bar {
                    ys.extend([lo, hi].into_iter().filter(|v| ok(*v)));
                }
            }
        }
        ys.extend(self.ref_lines.iter().map(|r| r.y).filter(|v| ok(*v)));
        let (xlo, xhi) = min_max(&xs).unwrap_or((0.0, 1.0));
        let (ylo, yhi) = min_max(&ys).unwrap_or(if self.log_y { (1.0, 10.0) } else { (0.0, 1.0) });
        // The data range (not from zero): differences between planners are what matter.
        let (yt, y0, y1) = if self.log_y {
            log_ticks(ylo, yhi)
        } else {
            let pad = (yhi - ylo) * 0.05;
            nice_ticks(ylo - pad, yhi + pad, 6)
        };
        let (xt, x0, x1) = if self.x_ticks.is_empty() {
            nice_ticks(xlo, xhi, 6)
        } else {
            // A little room either side of the first and last budget.
            let pad = ((xhi - xlo) * 0.06).max(1.0);
            (self.x_ticks.clone(), xlo - pad, xhi + pad)
        };
        let f = Frame {
            x0,
            x1,
            y0,
            y1,
            log_y: self.log_y,
        };
        let mut s = String::new();
        let labels = Labels {
            title: &self.title,
            subtitle: "",
            x: &self.x_label,
            y: &self.y_label,
        };
        frame_svg(&mut s, &f, &labels, &xt, &yt);
        for r in self.ref_lines.iter().filter(|r| ok(r.y)) {
            let py = f.py(r.y);
            let _ = writeln!(
                s,
                r##"<line class="refline" x1="{LEFT:.1}" y1="{py:.1}" x2="{:.1}" y2="{py:.1}" stroke="#555" stroke-dasharray="6 4"/>"##,
                WIDTH - RIGHT
            );
            let _ = writeln!(
                s,
                r##"<text class="refline" x="{:.1}" y="{:.1}" font-size="10" text-anchor="end" fill="#555">{}</text>"##,
                WIDTH - RIGHT - 4.0,
                py - 4.0,
                esc(&r.label)
            );
        }
        // Series side by side around each x so that error bars do not hide each other.
        let n = self.series.len().max(1) as f64;
        for (si, series) in self.series.iter().enumerate() {
            let dx = (si as f64 - (n - 1.0) / 2.0) * 5.0;
            let col = colour(series.colour);
            let pts: Vec<(f64, f64)> = series
                .points
                .iter()
                .filter(|p| ok(p.y))
                .map(|p| (f.px(p.x) + dx, f.py(p.y)))
                .collect();
            let _ = writeln!(s, r#"<g class="series" data-name="{}">"#, esc(&series.name));
            if pts.len() > 1 {
                let d: Vec<String> = pts.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
                let _ = writeln!(
                    s,
                    r#"<polyline class="series" points="{}" fill="none" stroke="{col}" stroke-width="2"/>"#,
                    d.join(" ")
                );
            }
            for p in series.points.iter().filter(|p| ok(p.y)) {
                let (px, py) = (f.px(p.x) + dx, f.py(p.y));
                if let Some((lo, hi)) = p.bar.filter(|(lo, hi)| ok(*lo) && ok(*hi)) {
                    let (a, b) = (f.py(lo), f.py(hi));
                    let _ = writeln!(
                        s,
                        r#"<path class="errorbar" d="M{px:.1},{a:.1} L{px:.1},{b:.1} M{:.1},{a:.1} L{:.1},{a:.1} M{:.1},{b:.1} L{:.1},{b:.1}" stroke="{col}" stroke-width="1.2" fill="none"/>"#,
                        px - 3.0,
                        px + 3.0,
                        px - 3.0,
                        px + 3.0
                    );
                }
                marker(&mut s, series.colour, px, py, "point", col);
            }
            let _ = writeln!(s, "</g>");
        }
        legend_svg(&mut s, &legend_entries(&self.series), true);
        s.push_str("</svg>\n");
        s
    }
}

impl ScatterChart {
    /// The chart as one SVG document.
    pub fn to_svg(&self) -> String {
        let pts: Vec<(f64, f64)> = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().copied())
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .collect();
        let xs: Vec<f64> = pts.iter().map(|p| p.0).collect();
        let ys: Vec<f64> = pts.iter().map(|p| p.1).collect();
        // 3 % of the spread either side keeps points off the axes.
        let padded = |v: &[f64]| {
            min_max(v).map_or((0.0, 1.0), |(a, b)| {
                let pad = (b - a) * 0.03;
                (a - pad, b + pad)
            })
        };
        let (xlo, xhi) = padded(&xs);
        let (ylo, yhi) = padded(&ys);
        let (xt, x0, x1) = nice_ticks(xlo, xhi, 6);
        let (yt, y0, y1) = nice_ticks(ylo, yhi, 6);
        let f = Frame {
            x0,
            x1,
            y0,
            y1,
            log_y: false,
        };
        let mut s = String::new();
        let labels = Labels {
            title: &self.title,
            subtitle: &self.subtitle,
            x: &self.x_label,
            y: &self.y_label,
        };
        frame_svg(&mut s, &f, &labels, &xt, &yt);
        for series in &self.series {
            let col = colour(series.colour);
            let _ = writeln!(s, r#"<g class="series" data-name="{}">"#, esc(&series.name));
            for &(x, y) in series
                .points
                .iter()
                .filter(|(x, y)| x.is_finite() && y.is_finite())
            {
                marker(&mut s, series.colour, f.px(x), f.py(y), "point", col);
            }
            let _ = writeln!(s, "</g>");
        }
        legend_svg(&mut s, &legend_entries(&self.series), false);
        s.push_str("</svg>\n");
        s
    }
}

fn min_max(v: &[f64]) -> Option<(f64, f64)> {
    let mut it = v.iter().copied().filter(|x| x.is_finite());
    let first = it.next()?;
    Some(it.fold((first, first), |(a, b), x| (a.min(x), b.max(x))))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_ticks_cover_the_range() {
        let (t, lo, hi) = nice_ticks(0.0, 17.3, 6);
        assert_eq!(lo, 0.0);
        assert!(hi >= 17.3);
        assert!(t.len() >= 4 && t.len() <= 12, "{t:?}");
        let (t, lo, hi) = nice_ticks(5.0, 5.0, 6);
        assert!(lo < 5.0 && hi > 5.0 && !t.is_empty());
        let (t, lo, hi) = log_ticks(0.004, 61.0);
        assert_eq!((lo, hi), (1e-3, 100.0));
        assert_eq!(t.len(), 6);
    }

    #[test]
    fn line_chart_has_one_polyline_per_series_and_escapes_names() {
        let c = LineChart {
            title: "Utility <nats>".into(),
            x_label: "budget (m)".into(),
            y_label: "utility".into(),
            series: vec![
                Series {
                    name: "a&b".into(),
                    colour: 0,
                    points: vec![
                        LinePoint {
                            x: 30.0,
                            y: 1.0,
                            bar: Some((0.5, 1.5)),
                        },
                        LinePoint {
                            x: 40.0,
                            y: 2.0,
                            bar: None,
                        },
                    ],
                },
                Series {
                    name: "c".into(),
                    colour: 1,
                    points: vec![LinePoint {
                        x: 30.0,
                        y: 3.0,
                        bar: None,
                    }],
                },
            ],
            ref_lines: vec![RefLine {
                y: 0.7,
                label: "dense".into(),
            }],
            log_y: false,
            x_ticks: vec![30.0, 40.0],
        };
        let svg = c.to_svg();
        assert!(svg.starts_with("<svg"));
        assert!(svg.trim_end().ends_with("</svg>"));
        assert_eq!(svg.matches("<polyline").count(), 1);
        assert_eq!(svg.matches(r#"class="errorbar""#).count(), 1);
        assert_eq!(svg.matches(r#"class="point""#).count(), 3);
        assert!(svg.contains("a&amp;b") && svg.contains("Utility &lt;nats&gt;"));
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
    }

    #[test]
    fn log_chart_skips_non_positive_values() {
        let c = LineChart {
            title: "t".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            series: vec![Series {
                name: "s".into(),
                colour: 2,
                points: vec![
                    LinePoint {
                        x: 1.0,
                        y: 0.0,
                        bar: None,
                    },
                    LinePoint {
                        x: 2.0,
                        y: 50.0,
                        bar: None,
                    },
                ],
            }],
            ref_lines: vec![],
            log_y: true,
            x_ticks: vec![],
        };
        let svg = c.to_svg();
        assert_eq!(svg.matches(r#"class="point""#).count(), 1);
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
    }
}

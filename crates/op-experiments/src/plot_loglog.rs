//! Log-log work-precision plots for the reports (docs/model.md §6): one series per method, points
//! joined in order, an optional horizontal spread bar per point (e.g. min-max of repeated timings),
//! highlighted points (e.g. the Pareto front) drawn with a ring, and
//! horizontal reference lines (e.g. a target error). Hand-written SVG like
//! [`super::plot`].

use std::fmt::Write;

use op_dynamics::Real;

use super::plot::{esc, frame, header};

/// One point of a [`LogLogSeries`].
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct LogLogPoint {
    /// x (> 0 to be drawn).
    pub x: Real,
    /// y (> 0 to be drawn).
    pub y: Real,
    /// Horizontal spread `(low, high)` around `x`, drawn as a bar.
    pub x_spread: Option<(Real, Real)>,
    /// Drawn with a ring (e.g. on the Pareto front).
    pub highlight: bool,
}

/// One series: a marker per point, joined by a line.
#[derive(Clone, Debug, PartialEq)]
pub struct LogLogSeries {
    /// Legend text.
    pub label: String,
    /// SVG colour.
    pub color: String,
    /// The points, in the order they are joined.
    pub points: Vec<LogLogPoint>,
}

/// A plot with logarithmic x and y axes.
#[derive(Clone, Debug, PartialEq)]
pub struct LogLogPlot {
    /// Title above the plot.
    pub title: String,
    /// x-axis label.
    pub x_label: String,
    /// y-axis label.
    pub y_label: String,
    /// The series.
    pub series: Vec<LogLogSeries>,
    /// Horizontal reference lines with a label.
    pub hlines: Vec<(Real, String)>,
    /// Legend text for highlighted points (`None`: no legend entry).
    pub highlight_label: Option<String>,
    /// Picture width in pixels.
    pub width: Real,
    /// Picture height in pixels.
    pub height: Real,
}

impl LogLogPlot {
    /// An empty plot of 720 x 460 pixels.
    pub fn new(title: &str, x_label: &str, y_label: &str) -> LogLogPlot {
        LogLogPlot {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
            hlines: Vec::new(),
            highlight_label: None,
            width: 720.0,
            height: 460.0,
        }
    }

    /// The decade range `[floor(log10 min), ceil(log10 max)]` of the
    /// drawable values, at least one decade wide; `(0, 1)` when there is
    /// none.
    fn decades(values: impl Iterator<Item = Real>) -> (Real, Real) {
        let (mut lo, mut hi) = (Real::INFINITY, Real::NEG_INFINITY);
        for v in values.filter(|v| v.is_finite() && *v > 0.0) {
            lo = lo.min(v.log10());
            hi = hi.max(v.log10());
        }
        if !lo.is_finite() {
            return (0.0, 1.0);
        }
        let (a, b) = (lo.floor(), hi.ceil());
        (a, if b > a { b } else { a + 1.0 })
    }

    /// The SVG document: title, decade grid, frame and axis labels,
    /// reference lines, series, legend.
    pub fn svg(&self) -> String {
        let (w, h) = (self.width, self.height);
        let area = self.area();
        let (left, top, pw, ph) = (area.left, area.top, area.pw, area.ph);
        let mut s = header(w, h);
        let _ = writeln!(
            s,
            r#"<text x="{}" y="22" text-anchor="middle" font-size="15">{}</text>"#,
            left + pw / 2.0,
            esc(&self.title)
        );
        area.write_grid(&mut s);
        frame(&mut s, [left, top, pw, ph], h, &self.x_label, &self.y_label);
        self.write_hlines(&mut s, &area);
        for ser in &self.series {
            write_series(&mut s, &area, ser);
        }
        self.write_legend(&mut s, &area);
        s.push_str("</svg>\n");
        s
    }

    /// The plot area: the decades covering the drawable points (with their
    /// spreads) in x, and those points and the reference lines in y.
    fn area(&self) -> Area {
        let (w, h) = (self.width, self.height);
        let (left, right, top, bottom) = (70.0, 200.0, 36.0, 50.0);
        let pts = || {
            self.series
                .iter()
                .flat_map(|s| s.points.iter())
                .filter(|p| ok(p.x) && ok(p.y))
        };
        let x = Self::decades(pts().flat_map(|p| {
            let (a, b) = p.x_spread.unwrap_or((p.x, p.x));
            [p.x, a, b]
        }));
        let y = Self::decades(
            pts()
                .map(|p| p.y)
                .chain(self.hlines.iter().map(|(y, _)| *y)),
        );
        Area {
            left,
            top,
            pw: w - left - right,
            ph: h - top - bottom,
            x,
            y,
        }
    }

    /// The dotted horizontal reference lines (those > 0) with their labels.
    fn write_hlines(&self, s: &mut String, area: &Area) {
        let (left, pw) = (area.left, area.pw);
        for (y, label) in &self.hlines {
            if ok(*y) {
                let _ = writeln!(
                    s,
                    r##"<line x1="{left}" y1="{0:.1}" x2="{1}" y2="{0:.1}" stroke="#888" stroke-dasharray="2,3"/><text x="{2}" y="{3:.1}" font-size="11" fill="#555">{4}</text>"##,
                    area.sy(*y),
                    left + pw,
                    left + 4.0,
                    area.sy(*y) - 4.0,
                    esc(label)
                );
            }
        }
    }

    /// The legend right of the plot area: one entry per series, then the
    /// highlighted points' entry if labelled.
    fn write_legend(&self, s: &mut String, area: &Area) {
        let lx = area.left + area.pw + 14.0;
        let top = area.top;
        for (k, ser) in self.series.iter().enumerate() {
            let y = top + 14.0 + 18.0 * k as Real;
            let _ = writeln!(
                s,
                r#"<line x1="{lx}" y1="{y}" x2="{}" y2="{y}" stroke="{}" stroke-width="2"/><circle cx="{}" cy="{y}" r="3" fill="{}"/><text x="{}" y="{}" font-size="12">{}</text>"#,
                lx + 24.0,
                ser.color,
                lx + 12.0,
                ser.color,
                lx + 30.0,
                y + 4.0,
                esc(&ser.label)
            );
        }
        if let Some(label) = &self.highlight_label {
            let y = top + 14.0 + 18.0 * self.series.len() as Real;
            let _ = writeln!(
                s,
                r#"<circle cx="{}" cy="{y}" r="7" fill="none" stroke="black" stroke-width="1.3"/><text x="{}" y="{}" font-size="12">{}</text>"#,
                lx + 12.0,
                lx + 30.0,
                y + 4.0,
                esc(label)
            );
        }
    }
}

/// Whether `v` can be drawn on a log axis: finite and positive.
fn ok(v: Real) -> bool {
    v.is_finite() && v > 0.0
}

/// One series: the line through its drawable points, then per point its
/// spread bar, its marker and, if highlighted, its ring.
fn write_series(s: &mut String, area: &Area, ser: &LogLogSeries) {
    let mut d = String::new();
    for p in ser.points.iter().filter(|p| ok(p.x) && ok(p.y)) {
        let _ = write!(
            d,
            "{}{:.1},{:.1} ",
            if d.is_empty() { "M" } else { "L" },
            area.sx(p.x),
            area.sy(p.y)
        );
    }
    if !d.is_empty() {
        let _ = writeln!(
            s,
            r#"<path d="{d}" fill="none" stroke="{}" stroke-width="1.4"/>"#,
            ser.color
        );
    }
    for p in ser.points.iter().filter(|p| ok(p.x) && ok(p.y)) {
        let (cx, cy) = (area.sx(p.x), area.sy(p.y));
        if let Some((a, b)) = p.x_spread.filter(|(a, b)| ok(*a) && ok(*b)) {
            let _ = writeln!(
                s,
                r#"<line x1="{:.1}" y1="{cy:.1}" x2="{:.1}" y2="{cy:.1}" stroke="{}" stroke-width="1"/>"#,
                area.sx(a),
                area.sx(b),
                ser.color
            );
        }
        let _ = writeln!(
            s,
            r#"<circle cx="{cx:.1}" cy="{cy:.1}" r="3" fill="{}"/>"#,
            ser.color
        );
        if p.highlight {
            let _ = writeln!(
                s,
                r#"<circle cx="{cx:.1}" cy="{cy:.1}" r="7" fill="none" stroke="black" stroke-width="1.3"/>"#
            );
        }
    }
}

/// The plot area of a [`LogLogPlot`] (`left`, `top`, width `pw`, height
/// `ph`, pixels) and its decade ranges `x` and `y` (log10 values).
struct Area {
    left: Real,
    top: Real,
    pw: Real,
    ph: Real,
    x: (Real, Real),
    y: (Real, Real),
}

impl Area {
    /// Pixel column of `x` (> 0).
    fn sx(&self, x: Real) -> Real {
        let (x0, x1) = self.x;
        self.left + (x.log10() - x0) / (x1 - x0) * self.pw
    }

    /// Pixel row of `y` (> 0).
    fn sy(&self, y: Real) -> Real {
        let (y0, y1) = self.y;
        self.top + (1.0 - (y.log10() - y0) / (y1 - y0)) * self.ph
    }

    /// Decade grid lines with their labels: at most about 8 in x and 10 in
    /// y (every n-th decade).
    fn write_grid(&self, s: &mut String) {
        let (left, top, pw, ph) = (self.left, self.top, self.pw, self.ph);
        let ((x0, x1), (y0, y1)) = (self.x, self.y);
        let x_step = ((x1 - x0) / 8.0).ceil().max(1.0) as i64;
        for k in (x0 as i64..=x1 as i64).step_by(x_step as usize) {
            let x = left + (k as Real - x0) / (x1 - x0) * pw;
            let _ = writeln!(
                s,
                r##"<line x1="{x:.1}" y1="{top}" x2="{x:.1}" y2="{}" stroke="#ddd"/><text x="{x:.1}" y="{}" text-anchor="middle" font-size="11">1e{k}</text>"##,
                top + ph,
                top + ph + 16.0
            );
        }
        let y_step = ((y1 - y0) / 10.0).ceil().max(1.0) as i64;
        for k in (y0 as i64..=y1 as i64).step_by(y_step as usize) {
            let y = top + (1.0 - (k as Real - y0) / (y1 - y0)) * ph;
            let _ = writeln!(
                s,
                r##"<line x1="{left}" y1="{y:.1}" x2="{}" y2="{y:.1}" stroke="#ddd"/><text x="{}" y="{:.1}" text-anchor="end" font-size="11">1e{k}</text>"##,
                left + pw,
                left - 6.0,
                y + 4.0
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_points_rings_and_skips_non_positive_values() {
        let mut plot = LogLogPlot::new("t", "x", "y");
        plot.series.push(LogLogSeries {
            label: "a".into(),
            color: "red".into(),
            points: vec![
                LogLogPoint {
                    x: 1e-3,
                    y: 1e-6,
                    x_spread: Some((9e-4, 2e-3)),
                    highlight: true,
                },
                LogLogPoint {
                    x: 1e-1,
                    y: 0.0,
                    x_spread: None,
                    highlight: false,
                },
            ],
        });
        let svg = plot.svg();
        assert_eq!(svg.matches("r=\"3\"").count(), 2, "one marker + legend");
        assert_eq!(svg.matches("r=\"7\"").count(), 1, "one ring");
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
        assert!(svg.contains(">1e-3<") && svg.contains(">1e-6<"));
    }
}

//! Hand-written SVG figures for the reports: line plots with axes, ticks,
//! a legend, optional log scale and shaded time intervals, and panels of
//! particle shapes. No plotting crate: a few hundred bytes of SVG per
//! element, readable in any browser and in the markdown report.

use std::fmt::Write;

use op_dynamics::{Point3, Real, Vec3};

/// One curve of a [`LinePlot`].
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// SVG colour.
    pub color: String,
    /// Dashed line.
    pub dashed: bool,
    /// `(x, y)` points, in order.
    pub points: Vec<(Real, Real)>,
}

/// A line plot.
#[derive(Clone, Debug, PartialEq)]
pub struct LinePlot {
    /// Title above the plot.
    pub title: String,
    /// x-axis label.
    pub x_label: String,
    /// y-axis label.
    pub y_label: String,
    /// Logarithmic y axis (non-positive values are dropped).
    pub log_y: bool,
    /// Logarithmic x axis (non-positive values are dropped).
    pub log_x: bool,
    /// The curves.
    pub series: Vec<Series>,
    /// Shaded x intervals with a label (e.g. load phases).
    pub bands: Vec<(Real, Real, String)>,
    /// Horizontal reference lines with a label (e.g. a tolerance).
    pub hlines: Vec<(Real, String)>,
    /// Fixed y range (points outside are clipped), or `None` to fit the
    /// data.
    pub y_range: Option<(Real, Real)>,
    /// Picture width in pixels.
    pub width: Real,
    /// Picture height in pixels.
    pub height: Real,
}

impl LinePlot {
    /// An empty plot of 640 x 400 pixels.
    pub fn new(title: &str, x_label: &str, y_label: &str) -> LinePlot {
        LinePlot {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            log_y: false,
            log_x: false,
            series: Vec::new(),
            bands: Vec::new(),
            hlines: Vec::new(),
            y_range: None,
            width: 640.0,
            height: 400.0,
        }
    }

    /// Adds a curve.
    pub fn line(mut self, label: &str, color: &str, points: Vec<(Real, Real)>) -> LinePlot {
        self.series.push(Series {
            label: label.into(),
            color: color.into(),
            dashed: false,
            points,
        });
        self
    }

    /// The SVG document: title, shaded bands, grid and tick labels, frame
    /// and axis labels, reference lines, curves, legend.
    pub fn svg(&self) -> String {
        let (w, h) = (self.width, self.height);
        let axes = self.axes();
        let mut s = header(w, h);
        let _ = writeln!(
            s,
            r#"<text x="{}" y="22" text-anchor="middle" font-size="15">{}</text>"#,
            w / 2.0,
            esc(&self.title)
        );
        let (top, ph) = (axes.top, axes.ph);
        let bands = self.visible_bands(&axes);
        for (a, b, _) in &bands {
            let _ = writeln!(
                s,
                r##"<rect x="{:.1}" y="{top}" width="{:.1}" height="{ph}" fill="#f2e6c9"/>"##,
                axes.sx(*a),
                axes.sx(*b) - axes.sx(*a)
            );
        }
        self.write_ticks(&mut s, &axes);
        for (a, b, label) in &bands {
            let _ = writeln!(
                s,
                r##"<text x="{:.1}" y="{:.1}" text-anchor="middle" font-size="11" fill="#8a6d3b">{}</text>"##,
                0.5 * (axes.sx(*a) + axes.sx(*b)),
                top + ph - 6.0,
                esc(label)
            );
        }
        frame(
            &mut s,
            [axes.left, top, axes.pw, ph],
            h,
            &self.x_label,
            &self.y_label,
        );
        self.write_hlines(&mut s, &axes);
        self.write_curves(&mut s, &axes);
        self.write_legend(&mut s, &axes);
        s.push_str("</svg>\n");
        s
    }

    /// `x` on the x axis's scale (log10 on a log axis).
    fn tx(&self, x: Real) -> Real {
        if self.log_x {
            x.log10()
        } else {
            x
        }
    }

    /// `y` on the y axis's scale (log10 on a log axis).
    fn ty(&self, y: Real) -> Real {
        if self.log_y {
            y.log10()
        } else {
            y
        }
    }

    /// Whether a point can be drawn: finite, positive on a log axis,
    /// within the fixed y range if any.
    fn usable(&self, &(x, y): &(Real, Real)) -> bool {
        let in_range = |y: Real| self.y_range.is_none_or(|(a, b)| y >= a && y <= b);
        x.is_finite()
            && y.is_finite()
            && (!self.log_y || y > 0.0)
            && (!self.log_x || x > 0.0)
            && in_range(y)
    }

    /// The range `(x0, x1, y0, y1)`, on the axes' scales, of the usable
    /// points and the reference lines (the fixed y range if any; the unit
    /// square when there is nothing to draw; at least 1 wide in x).
    fn data_range(&self) -> (Real, Real, Real, Real) {
        let (tx, ty) = (|x: Real| self.tx(x), |y: Real| self.ty(y));
        let pts = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().filter(|p| self.usable(p)));
        let (mut x0, mut x1, mut y0, mut y1) = (
            Real::INFINITY,
            Real::NEG_INFINITY,
            Real::INFINITY,
            Real::NEG_INFINITY,
        );
        for &(x, y) in pts {
            x0 = x0.min(tx(x));
            x1 = x1.max(tx(x));
            y0 = y0.min(ty(y));
            y1 = y1.max(ty(y));
        }
        for (y, _) in &self.hlines {
            if !self.log_y || *y > 0.0 {
                y0 = y0.min(ty(*y));
                y1 = y1.max(ty(*y));
            }
        }
        if !x0.is_finite() {
            (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
        }
        if let Some((a, b)) = self.y_range {
            (y0, y1) = (ty(a), ty(b));
        }
        if x1 <= x0 {
            x1 = x0 + 1.0;
        }
        (x0, x1, y0, y1)
    }

    /// The plot area and the axes: the data range widened to the ticks
    /// (whole decades on a log axis, "nice" steps otherwise; a fixed
    /// linear y range is kept and only its ticks inside are drawn).
    fn axes(&self) -> Axes {
        let (w, h) = (self.width, self.height);
        let (left, right, top, bottom) = (70.0, 20.0, 36.0, 50.0);
        let (x0, x1, y0, mut y1) = self.data_range();
        let (xt, x0, x1) = if self.log_x {
            decades(x0, x1)
        } else {
            ticks(x0, x1)
        };
        let (yt, y0, y1) = if let (Some(_), false) = (self.y_range, self.log_y) {
            let (t, _, _) = ticks(y0, y1);
            (
                t.into_iter()
                    .filter(|v| *v >= y0 - 1e-12 && *v <= y1 + 1e-12)
                    .collect(),
                y0,
                y1,
            )
        } else if self.log_y {
            decades(y0, y1)
        } else {
            if y1 <= y0 {
                y1 = y0 + 1.0;
            }
            ticks(y0, y1)
        };
        Axes {
            log_x: self.log_x,
            log_y: self.log_y,
            left,
            top,
            pw: w - left - right,
            ph: h - top - bottom,
            x: (x0, x1),
            y: (y0, y1),
            xt,
            yt,
        }
    }

    /// The shaded bands clipped to the x range (none on a log x axis).
    fn visible_bands(&self, axes: &Axes) -> Vec<(Real, Real, &String)> {
        let (x0, x1) = axes.x;
        self.bands
            .iter()
            .filter(|_| !self.log_x)
            .map(|(a, b, l)| (a.max(x0), b.min(x1), l))
            .filter(|(a, b, _)| b > a)
            .collect()
    }

    /// The vertical then the horizontal grid lines, each with its label.
    fn write_ticks(&self, s: &mut String, axes: &Axes) {
        let (left, top, pw, ph) = (axes.left, axes.top, axes.pw, axes.ph);
        for &t in &axes.xt {
            let label = if self.log_x {
                format!("1e{}", t as i64)
            } else {
                fmt_tick(t)
            };
            let _ = writeln!(
                s,
                r##"<line x1="{0:.1}" y1="{top}" x2="{0:.1}" y2="{1}" stroke="#ddd"/><text x="{0:.1}" y="{2}" text-anchor="middle" font-size="11">{3}</text>"##,
                axes.sxt(t),
                top + ph,
                top + ph + 16.0,
                label
            );
        }
        for &t in &axes.yt {
            let label = if self.log_y {
                format!("1e{}", t as i64)
            } else {
                fmt_tick(t)
            };
            let _ = writeln!(
                s,
                r##"<line x1="{left}" y1="{0:.1}" x2="{1}" y2="{0:.1}" stroke="#ddd"/><text x="{2}" y="{3:.1}" text-anchor="end" font-size="11">{4}</text>"##,
                axes.syt(t),
                left + pw,
                left - 6.0,
                axes.syt(t) + 4.0,
                label
            );
        }
    }

    /// The dotted horizontal reference lines with their labels (those
    /// drawable on the y axis).
    fn write_hlines(&self, s: &mut String, axes: &Axes) {
        let (left, pw) = (axes.left, axes.pw);
        for (y, label) in &self.hlines {
            if !self.log_y || *y > 0.0 {
                let _ = writeln!(
                    s,
                    r##"<line x1="{left}" y1="{0:.1}" x2="{1}" y2="{0:.1}" stroke="#888" stroke-dasharray="2,3"/><text x="{1}" y="{2:.1}" text-anchor="end" font-size="11" fill="#555">{3}</text>"##,
                    axes.sy(*y),
                    left + pw - 4.0,
                    axes.sy(*y) - 4.0,
                    esc(label)
                );
            }
        }
    }

    /// One path per curve; the pen lifts over points that cannot be drawn.
    fn write_curves(&self, s: &mut String, axes: &Axes) {
        for ser in &self.series {
            let mut d = String::new();
            let mut pen_up = true;
            for p in &ser.points {
                if !self.usable(p) {
                    pen_up = true;
                    continue;
                }
                let _ = write!(
                    d,
                    "{}{:.1},{:.1} ",
                    if pen_up { "M" } else { "L" },
                    axes.sx(p.0),
                    axes.sy(p.1)
                );
                pen_up = false;
            }
            let dash = if ser.dashed {
                r#" stroke-dasharray="6,4""#
            } else {
                ""
            };
            let _ = writeln!(
                s,
                r#"<path d="{d}" fill="none" stroke="{}" stroke-width="1.6"{dash}/>"#,
                ser.color
            );
        }
    }

    /// The legend box in the top right corner, one entry per curve.
    fn write_legend(&self, s: &mut String, axes: &Axes) {
        let (left, top, pw) = (axes.left, axes.top, axes.pw);
        if !self.series.is_empty() {
            let _ = writeln!(
                s,
                r##"<rect x="{}" y="{}" width="176" height="{}" fill="white" fill-opacity="0.85" stroke="#ccc"/>"##,
                left + pw - 178.0,
                top + 4.0,
                16.0 * self.series.len() as Real + 6.0
            );
        }
        for (k, ser) in self.series.iter().enumerate() {
            let y = top + 14.0 + 16.0 * k as Real;
            let x = left + pw - 170.0;
            let _ = writeln!(
                s,
                r#"<line x1="{x}" y1="{y}" x2="{}" y2="{y}" stroke="{}" stroke-width="2"/><text x="{}" y="{}" font-size="12">{}</text>"#,
                x + 24.0,
                ser.color,
                x + 30.0,
                y + 4.0,
                esc(&ser.label)
            );
        }
    }
}

/// The plot area of a [`LinePlot`] (`left`, `top`, width `pw`, height
/// `ph`, pixels) and its axes: ranges `x`, `y` and tick positions on the
/// axes' scales (log10 on a log axis).
struct Axes {
    log_x: bool,
    log_y: bool,
    left: Real,
    top: Real,
    pw: Real,
    ph: Real,
    x: (Real, Real),
    y: (Real, Real),
    xt: Vec<Real>,
    yt: Vec<Real>,
}

impl Axes {
    /// Pixel column of `t`, on the x axis's scale.
    fn sxt(&self, t: Real) -> Real {
        let (x0, x1) = self.x;
        self.left + (t - x0) / (x1 - x0) * self.pw
    }

    /// Pixel column of the data value `x`.
    fn sx(&self, x: Real) -> Real {
        self.sxt(if self.log_x { x.log10() } else { x })
    }

    /// Pixel row of `t`, on the y axis's scale.
    fn syt(&self, t: Real) -> Real {
        let (y0, y1) = self.y;
        self.top + (1.0 - (t - y0) / (y1 - y0)) * self.ph
    }

    /// Pixel row of the data value `y`.
    fn sy(&self, y: Real) -> Real {
        self.syt(if self.log_y { y.log10() } else { y })
    }
}

/// Whole decades covering `[a, b]` (log10 values), at least one: the
/// ticks and the widened range.
fn decades(a: Real, b: Real) -> (Vec<Real>, Real, Real) {
    let (a, b) = (a.floor(), b.ceil().max(a.floor() + 1.0));
    (((a as i64)..=(b as i64)).map(|k| k as Real).collect(), a, b)
}

/// The plot area's border (`[left, top, width, height]`) and the axis
/// labels, centred below it and along its left side, in a picture of
/// height `h`.
pub(crate) fn frame(s: &mut String, area: [Real; 4], h: Real, x_label: &str, y_label: &str) {
    let [left, top, pw, ph] = area;
    let _ = writeln!(
        s,
        r##"<rect x="{left}" y="{top}" width="{pw}" height="{ph}" fill="none" stroke="#333"/>"##
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle" font-size="13">{}</text>"#,
        left + pw / 2.0,
        h - 12.0,
        esc(x_label)
    );
    let _ = writeln!(
        s,
        r#"<text transform="translate(18,{}) rotate(-90)" text-anchor="middle" font-size="13">{}</text>"#,
        top + ph / 2.0,
        esc(y_label)
    );
}

/// The SVG opening tag and white background of a `w` x `h` picture.
pub(crate) fn header(w: Real, h: Real) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"sans-serif\">\n<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>\n"
    )
}

/// `t` escaped for SVG text.
pub(crate) fn esc(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn fmt_tick(t: Real) -> String {
    if t == 0.0 {
        "0".into()
    } else if t.abs() >= 1e4 || t.abs() < 1e-3 {
        format!("{t:.0e}")
    } else {
        let s = format!("{t:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// "Nice" ticks (1, 2, 5 times a power of ten) covering `[a, b]`, and the
/// widened range.
fn ticks(a: Real, b: Real) -> (Vec<Real>, Real, Real) {
    let raw = (b - a) / 6.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let lo = (a / step).floor() * step;
    let hi = (b / step).ceil() * step;
    let n = ((hi - lo) / step).round() as i64;
    ((0..=n).map(|k| lo + k as Real * step).collect(), lo, hi)
}

/// At most about `max` points of `points` (sorted by x): the largest `y`
/// of each bucket of consecutive points, so peaks survive.
pub fn downsample(points: &[(Real, Real)], max: usize) -> Vec<(Real, Real)> {
    if points.len() <= max || max == 0 {
        return points.to_vec();
    }
    let per = points.len().div_ceil(max);
    points
        .chunks(per)
        .filter_map(|c| {
            c.iter()
                .copied()
                .filter(|p| p.1.is_finite())
                .max_by(|a, b| a.1.total_cmp(&b.1))
        })
        .collect()
}

/// One panel of [`shapes_svg`]: a caption, the particles' positions and
/// normals (drawn in the x-y plane).
#[derive(Clone, Debug, PartialEq)]
pub struct ShapePanel {
    /// Caption under the panel.
    pub caption: String,
    /// Positions, in chain order.
    pub positions: Vec<Point3>,
    /// Normals (drawn as short ticks).
    pub normals: Vec<Vec3>,
}

/// Panels of planar particle chains side by side, at one common scale, in
/// rows of `per_row`; `reference` (the rest shape, if any) is drawn in
/// grey under each panel, centred on the panel's shape.
pub fn shapes_svg(
    title: &str,
    panels: &[ShapePanel],
    reference: Option<&[Point3]>,
    per_row: usize,
) -> String {
    let per_row = per_row.max(1);
    let (cell, pad) = (230.0, 14.0);
    let rows = panels.len().div_ceil(per_row);
    let (w, h) = (
        cell * per_row.min(panels.len()).max(1) as Real,
        40.0 + cell * rows as Real,
    );
    let scale = (cell / 2.0 - pad - 12.0) / shapes_extent(panels, reference);
    let mut s = header(w, h);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="22" text-anchor="middle" font-size="15">{}</text>"#,
        w / 2.0,
        esc(title)
    );
    for (k, p) in panels.iter().enumerate() {
        let origin = (
            cell * (k % per_row) as Real + cell / 2.0,
            40.0 + cell * (k / per_row) as Real + cell / 2.0 - 10.0,
        );
        shape_panel(&mut s, p, reference, origin, cell, scale);
    }
    s.push_str("</svg>\n");
    s
}

/// The x-y coordinates of `pts` about their mean.
fn centred(pts: &[Point3]) -> Vec<(Real, Real)> {
    let n = pts.len().max(1) as Real;
    let (cx, cy) = pts
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p.x / n, a.1 + p.y / n));
    pts.iter().map(|p| (p.x - cx, p.y - cy)).collect()
}

/// The largest centred x or y coordinate of the panels' shapes and the
/// reference (at least `1e-9`): the common scale's half width.
fn shapes_extent(panels: &[ShapePanel], reference: Option<&[Point3]>) -> Real {
    let mut extent: Real = 1e-9;
    for p in panels {
        for (x, y) in centred(&p.positions) {
            extent = extent.max(x.abs()).max(y.abs());
        }
    }
    if let Some(r) = reference {
        for (x, y) in centred(r) {
            extent = extent.max(x.abs()).max(y.abs());
        }
    }
    extent
}

/// One panel of [`shapes_svg`] centred on `(ox, oy)`, `cell` wide, at
/// `scale` pixels per unit: its border, the reference, the chain, its
/// normals and particles (the first in green), the caption.
fn shape_panel(
    s: &mut String,
    p: &ShapePanel,
    reference: Option<&[Point3]>,
    (ox, oy): (Real, Real),
    cell: Real,
    scale: Real,
) {
    let tx = |(x, y): (Real, Real)| (ox + x * scale, oy - y * scale);
    let _ = writeln!(
        s,
        r##"<rect x="{}" y="{}" width="{}" height="{}" fill="none" stroke="#ccc"/>"##,
        ox - cell / 2.0 + 4.0,
        oy - cell / 2.0 + 14.0,
        cell - 8.0,
        cell - 8.0
    );
    if let Some(r) = reference {
        let d: Vec<String> = centred(r)
            .into_iter()
            .map(tx)
            .map(|(x, y)| format!("{x:.1},{y:.1}"))
            .collect();
        let _ = writeln!(
            s,
            r##"<polyline points="{}" fill="none" stroke="#bbb" stroke-width="1.2"/>"##,
            d.join(" ")
        );
    }
    let c = centred(&p.positions);
    let d: Vec<String> = c
        .iter()
        .copied()
        .map(tx)
        .map(|(x, y)| format!("{x:.1},{y:.1}"))
        .collect();
    let _ = writeln!(
        s,
        r##"<polyline points="{}" fill="none" stroke="#1f5fa8" stroke-width="1.6"/>"##,
        d.join(" ")
    );
    for (i, &q) in c.iter().enumerate() {
        let (x, y) = tx(q);
        if let Some(n) = p.normals.get(i) {
            let (nx, ny) = (x + n.x * 12.0, y - n.y * 12.0);
            let _ = writeln!(
                s,
                r##"<line x1="{x:.1}" y1="{y:.1}" x2="{nx:.1}" y2="{ny:.1}" stroke="#c0392b" stroke-width="1.2"/>"##
            );
        }
        let fill = if i == 0 { "#2c7a2c" } else { "#1f5fa8" };
        let _ = writeln!(
            s,
            r#"<circle cx="{x:.1}" cy="{y:.1}" r="3.2" fill="{fill}"/>"#
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{ox}" y="{}" text-anchor="middle" font-size="12">{}</text>"#,
        oy + cell / 2.0 - 2.0,
        esc(&p.caption)
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_cover_the_range_with_round_steps() {
        let (t, lo, hi) = ticks(0.3, 9.7);
        assert!(
            lo <= 0.3 && hi >= 9.7 && t.len() >= 4 && t.len() <= 12,
            "{t:?}"
        );
        assert_eq!(t[1] - t[0], 2.0);
    }

    #[test]
    fn plots_are_well_formed_svg() {
        let p = LinePlot {
            log_y: true,
            ..LinePlot::new("O(t)", "t", "O")
        }
        .line("a", "red", vec![(0.0, 1e-3), (1.0, 1e-5), (2.0, 0.0)]);
        let s = p.svg();
        assert!(s.starts_with("<svg") && s.trim_end().ends_with("</svg>"));
        assert!(s.contains("<path") && s.contains("1e-5") && !s.contains("NaN"));
        let p = LinePlot {
            log_x: true,
            log_y: true,
            ..LinePlot::new("dt(k)", "k", "dt")
        }
        .line("a", "red", vec![(-1.0, 1.0), (10.0, 0.3), (1e4, 1e-2)]);
        let s = p.svg();
        assert!(s.contains("1e4") && s.contains("1e1") && s.contains("1e-2") && !s.contains("NaN"));
        let d = downsample(
            &(0..1000)
                .map(|k| (k as Real, (k % 7) as Real))
                .collect::<Vec<_>>(),
            100,
        );
        assert!(d.len() <= 100 && d.iter().all(|p| p.1 == 6.0));
    }
}

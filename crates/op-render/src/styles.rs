//! The four pictures of oriented particles (seed 000 §5, figure 4):
//! (a) each particle as its local axes, (b) as a small flat disc, (c) the
//! triangulation as a wireframe, (d) the triangulation flat shaded.
//!
//! Which vertices are particles: those of the objects without faces (our frames
//! export particles that way, position plus normal); when every object has
//! faces, the mesh vertices themselves (a triangulation over the particles).

use std::fmt;
use std::str::FromStr;

use nalgebra::Vector3;

use super::camera::Camera;
use super::error::RenderError;
use super::obj::{ObjData, ObjObject};
use super::raster::Canvas;

type V3 = Vector3<f64>;

/// How particles and meshes are drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Style {
    /// Each particle as its local frame: two tangent axes (red, green) and the
    /// normal (blue), 0.4 of the particle spacing long (figure 4a).
    Axes,
    /// Each particle as a flat disc perpendicular to its normal, half the
    /// spacing in radius, lit by a fixed light, with a thin dark rim (figure 4b).
    Discs,
    /// Triangle edges and `l` lines, hidden lines removed (figure 4c).
    Wireframe,
    /// Flat-shaded triangles, one palette colour per object (figure 4d). Default.
    #[default]
    Shaded,
}

impl Style {
    /// All styles, in figure order.
    pub const ALL: [Style; 4] = [Style::Axes, Style::Discs, Style::Wireframe, Style::Shaded];

    /// The name accepted by [`FromStr`] (`axes`, `discs`, `wireframe`, `shaded`).
    pub fn name(self) -> &'static str {
        match self {
            Style::Axes => "axes",
            Style::Discs => "discs",
            Style::Wireframe => "wireframe",
            Style::Shaded => "shaded",
        }
    }
}

impl fmt::Display for Style {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Style {
    type Err = RenderError;

    /// Parses a style name, ignoring case and surrounding blanks.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let wanted = s.trim().to_ascii_lowercase();
        Style::ALL
            .into_iter()
            .find(|st| st.name() == wanted)
            .ok_or_else(|| {
                let names: Vec<&str> = Style::ALL.iter().map(|st| st.name()).collect();
                RenderError::option(
                    "style",
                    format!("unknown style '{s}', expected one of: {}", names.join(", ")),
                )
            })
    }
}

/// Object colours, picked by object index.
const PALETTE: [[f64; 3]; 6] = [
    [0.30, 0.52, 0.80],
    [0.88, 0.48, 0.22],
    [0.38, 0.68, 0.36],
    [0.78, 0.34, 0.52],
    [0.82, 0.70, 0.26],
    [0.50, 0.44, 0.78],
];
const AXIS_T1: [u8; 3] = [215, 40, 40];
const AXIS_T2: [u8; 3] = [35, 150, 55];
const AXIS_N: [u8; 3] = [40, 80, 215];
const DOT: [u8; 3] = [60, 60, 60];
const AMBIENT: f64 = 0.35;
/// Relative depth bias that lets lines win over the surface they lie on.
const LINE_BIAS: f64 = 2e-3;

fn palette(index: usize) -> [f64; 3] {
    PALETTE[index % PALETTE.len()]
}

fn to_rgb(c: [f64; 3], k: f64) -> [u8; 3] {
    c.map(|x| (x * k * 255.0).round().clamp(0.0, 255.0) as u8)
}

/// Draws world-space shapes onto a canvas through a camera.
pub(crate) struct Painter<'a> {
    cam: &'a Camera,
    canvas: Canvas,
    /// Raster pixels per nominal line-width unit.
    unit: f64,
    /// Unit vector towards the light, view space.
    light: V3,
    background: [u8; 3],
    scratch: Vec<V3>,
}

impl<'a> Painter<'a> {
    /// A painter on `canvas`; `unit` is the raster size of one nominal pixel of line width.
    pub(crate) fn new(cam: &'a Camera, canvas: Canvas, unit: f64, background: [u8; 3]) -> Self {
        Painter {
            cam,
            canvas,
            unit,
            light: V3::new(-0.4, 0.55, -0.73).normalize(),
            background,
            scratch: Vec::new(),
        }
    }

    /// The finished canvas.
    pub(crate) fn into_canvas(self) -> Canvas {
        self.canvas
    }

    fn triangle(&mut self, p: [V3; 3], color: [u8; 3], bias: f64) {
        let view = p.map(|q| self.cam.to_view(q));
        let mut poly = std::mem::take(&mut self.scratch);
        self.cam.clip_polygon(&view, &mut poly);
        // One clipping plane: a triangle stays a polygon of at most 4 vertices.
        if (3..=4).contains(&poly.len()) {
            let mut screen = [[0.0; 3]; 4];
            for (k, &v) in poly.iter().enumerate() {
                screen[k] = self.cam.project(v);
            }
            for k in 1..poly.len() - 1 {
                self.canvas
                    .triangle(screen[0], screen[k], screen[k + 1], color, bias);
            }
        }
        self.scratch = poly;
    }

    fn segment(&mut self, a: V3, b: V3, width: f64, color: [u8; 3], bias: f64) {
        let (va, vb) = (self.cam.to_view(a), self.cam.to_view(b));
        if let Some((va, vb)) = self.cam.clip_segment(va, vb) {
            let (sa, sb) = (self.cam.project(va), self.cam.project(vb));
            self.canvas.line(sa, sb, width * self.unit, color, bias);
        }
    }

    fn dot(&mut self, p: V3, radius: f64, color: [u8; 3]) {
        let v = self.cam.to_view(p);
        if v.z >= self.cam.near() {
            self.canvas
                .disc(self.cam.project(v), radius * self.unit, color, LINE_BIAS);
        }
    }

    /// Two-sided Lambert shading of `base` for a surface of world normal `n`.
    fn shade(&self, n: V3, base: [f64; 3]) -> [u8; 3] {
        let lambert = self.cam.dir_to_view(n).dot(&self.light).abs();
        to_rgb(base, AMBIENT + (1.0 - AMBIENT) * lambert)
    }
}

/// A particle to draw: position, unit normal if any, object index.
struct Particle {
    p: V3,
    n: Option<V3>,
    object: usize,
}

/// Draws `data` in `style`; returns notes about fallbacks (never printed here).
pub(crate) fn draw(data: &ObjData, style: Style, painter: &mut Painter<'_>) -> Vec<String> {
    let mut notes = Vec::new();
    let objects = data.objects();
    let faceless = objects.iter().filter(|o| !o.has_faces()).count();
    match style {
        Style::Axes => axes(&particles(data, &mut notes), painter),
        Style::Discs => discs(&particles(data, &mut notes), painter),
        Style::Wireframe => {
            if objects
                .iter()
                .any(|o| o.has_faces() || !o.lines().is_empty())
            {
                wireframe(objects, painter);
                let skipped = objects
                    .iter()
                    .filter(|o| !o.has_faces() && o.lines().is_empty())
                    .count();
                note_skipped(&mut notes, style, skipped);
            } else {
                notes.push(
                    "wireframe: no faces or lines in the data, drawing particles as discs".into(),
                );
                discs(&particles(data, &mut notes), painter);
            }
        }
        Style::Shaded => {
            if faceless < objects.len() {
                shaded(objects, painter);
                note_skipped(&mut notes, style, faceless);
            } else {
                notes.push("shaded: no faces in the data, drawing particles as discs".into());
                discs(&particles(data, &mut notes), painter);
            }
        }
    }
    notes
}

fn note_skipped(notes: &mut Vec<String>, style: Style, count: usize) {
    if count > 0 {
        notes.push(format!(
            "{style}: {count} object(s) without faces not drawn (use the axes or discs style to see particles)"
        ));
    }
}

/// The particles of `data`: vertices of faceless objects, or all vertices if none.
fn particles(data: &ObjData, notes: &mut Vec<String>) -> Vec<Particle> {
    let objects = data.objects();
    let any_faceless = objects.iter().any(|o| !o.has_faces());
    if !any_faceless {
        notes.push("no objects without faces: drawing mesh vertices as particles".into());
    }
    let mut out = Vec::new();
    for (index, o) in objects.iter().enumerate() {
        if any_faceless && o.has_faces() {
            continue;
        }
        for (p, n) in o.vertices().iter().zip(o.normals()) {
            out.push(Particle {
                p: V3::from(*p),
                n: n.map(V3::from),
                object: index,
            });
        }
    }
    out
}

/// Median nearest-neighbour distance of `points` (on an evenly strided sample
/// of at most 256 of them), or a bounding-box estimate when that is undefined.
pub(crate) fn spacing(points: &[V3]) -> f64 {
    let n = points.len();
    let (mut lo, mut hi) = (V3::repeat(f64::INFINITY), V3::repeat(f64::NEG_INFINITY));
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let diag = if n > 0 { (hi - lo).norm() } else { 0.0 };
    let tiny = diag * 1e-9;
    let stride = n.div_ceil(256).max(1);
    let mut nearest: Vec<f64> = (0..n)
        .step_by(stride)
        .filter_map(|i| {
            points
                .iter()
                .map(|q| (q - points[i]).norm())
                .filter(|&d| d > tiny)
                .min_by(f64::total_cmp)
        })
        .collect();
    if !nearest.is_empty() {
        nearest.sort_by(f64::total_cmp);
        return nearest[nearest.len() / 2];
    }
    if diag > 0.0 {
        diag / (n as f64).sqrt().max(2.0)
    } else {
        0.5
    }
}

/// Deterministic unit tangents `(t1, t2)` with `t1 x t2 = n` for a unit `n`.
fn tangents(n: V3) -> (V3, V3) {
    let helper = if n.x.abs() < 0.9 { V3::x() } else { V3::y() };
    let t1 = helper.cross(&n).normalize();
    let t2 = n.cross(&t1);
    (t1, t2)
}

fn axes(particles: &[Particle], painter: &mut Painter<'_>) {
    let points: Vec<V3> = particles.iter().map(|q| q.p).collect();
    let len = 0.4 * spacing(&points);
    for q in particles {
        match q.n {
            Some(n) => {
                let (t1, t2) = tangents(n);
                painter.segment(q.p, q.p + t1 * len, 1.6, AXIS_T1, 0.0);
                painter.segment(q.p, q.p + t2 * len, 1.6, AXIS_T2, 0.0);
                painter.segment(q.p, q.p + n * len, 1.6, AXIS_N, 0.0);
                painter.dot(q.p, 1.3, DOT);
            }
            None => painter.dot(q.p, 2.5, DOT),
        }
    }
}

/// Perimeter points of a disc, as many as the sides of its polygon.
const DISC_SIDES: usize = 24;

fn discs(particles: &[Particle], painter: &mut Painter<'_>) {
    let points: Vec<V3> = particles.iter().map(|q| q.p).collect();
    let radius = 0.5 * spacing(&points);
    let ring: Vec<(f64, f64)> = (0..DISC_SIDES)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / DISC_SIDES as f64;
            (a.cos(), a.sin())
        })
        .collect();
    let eye = painter.cam.eye();
    for q in particles {
        // Without a normal the disc faces the eye.
        let n = q.n.unwrap_or_else(|| {
            let d = eye - q.p;
            if d.norm() > 0.0 {
                d.normalize()
            } else {
                V3::z()
            }
        });
        let (t1, t2) = tangents(n);
        let rim: Vec<V3> = ring
            .iter()
            .map(|&(c, s)| q.p + (t1 * c + t2 * s) * radius)
            .collect();
        let base = palette(q.object);
        let fill = painter.shade(n, base);
        for k in 0..DISC_SIDES {
            painter.triangle([q.p, rim[k], rim[(k + 1) % DISC_SIDES]], fill, 0.0);
        }
        let edge = to_rgb(base, 0.3);
        for k in 0..DISC_SIDES {
            painter.segment(rim[k], rim[(k + 1) % DISC_SIDES], 0.9, edge, LINE_BIAS);
        }
    }
}

/// Sorted unique edges of an object's triangles and lines.
fn edges(o: &ObjObject) -> Vec<[usize; 2]> {
    let mut e: Vec<[usize; 2]> = o
        .triangles()
        .iter()
        .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
        .chain(o.lines().iter().copied())
        .filter(|[a, b]| a != b)
        .map(|[a, b]| [a.min(b), a.max(b)])
        .collect();
    e.sort_unstable();
    e.dedup();
    e
}

fn world_triangle(o: &ObjObject, t: &[usize; 3]) -> [V3; 3] {
    t.map(|i| V3::from(o.vertices()[i]))
}

fn wireframe(objects: &[ObjObject], painter: &mut Painter<'_>) {
    // Hidden-line removal: faces go into the depth buffer in the background colour.
    let bg = painter.background;
    for o in objects {
        for t in o.triangles() {
            painter.triangle(world_triangle(o, t), bg, 0.0);
        }
    }
    for (index, o) in objects.iter().enumerate() {
        let color = to_rgb(palette(index), 0.55);
        for [a, b] in edges(o) {
            let (pa, pb) = (V3::from(o.vertices()[a]), V3::from(o.vertices()[b]));
            painter.segment(pa, pb, 1.2, color, LINE_BIAS);
        }
        for &i in o.points() {
            painter.dot(V3::from(o.vertices()[i]), 2.0, color);
        }
    }
}

fn shaded(objects: &[ObjObject], painter: &mut Painter<'_>) {
    for (index, o) in objects.iter().enumerate() {
        let base = palette(index);
        for t in o.triangles() {
            let p = world_triangle(o, t);
            let n = (p[1] - p[0]).cross(&(p[2] - p[0]));
            if let Some(n) = n.try_normalize(0.0) {
                let color = painter.shade(n, base);
                painter.triangle(p, color, 0.0);
            }
        }
        if o.has_faces() {
            let color = to_rgb(base, 0.35);
            for &[a, b] in o.lines() {
                let (pa, pb) = (V3::from(o.vertices()[a]), V3::from(o.vertices()[b]));
                painter.segment(pa, pb, 1.2, color, LINE_BIAS);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn style_names_round_trip() {
        for st in Style::ALL {
            assert_eq!(st.name().parse::<Style>().unwrap(), st);
            assert_eq!(st.to_string(), st.name());
        }
        assert_eq!(" Discs ".parse::<Style>().unwrap(), Style::Discs);
        let err = "phong".parse::<Style>().unwrap_err().to_string();
        assert!(err.contains("'phong'"), "{err}");
        assert!(err.contains("axes, discs, wireframe, shaded"), "{err}");
    }

    #[test]
    fn tangents_are_orthonormal_and_right_handed() {
        for n in [
            V3::x(),
            V3::y(),
            -V3::z(),
            V3::new(1.0, 2.0, -3.0).normalize(),
        ] {
            let (t1, t2) = tangents(n);
            assert!((t1.norm() - 1.0).abs() < 1e-12 && (t2.norm() - 1.0).abs() < 1e-12);
            assert!(t1.dot(&n).abs() < 1e-12 && t2.dot(&n).abs() < 1e-12);
            assert!((t1.cross(&t2) - n).norm() < 1e-12);
        }
    }

    #[test]
    fn spacing_of_a_grid_and_fallbacks() {
        let grid: Vec<V3> = (0..400)
            .map(|i| V3::new((i % 20) as f64 * 0.25, (i / 20) as f64 * 0.25, 0.0))
            .collect();
        assert!((spacing(&grid) - 0.25).abs() < 1e-12);
        // Duplicates are ignored.
        let dup = vec![V3::zeros(), V3::zeros(), V3::x()];
        assert!((spacing(&dup) - 1.0).abs() < 1e-12);
        assert_eq!(spacing(&[V3::zeros()]), 0.5);
        assert_eq!(spacing(&[]), 0.5);
    }
}

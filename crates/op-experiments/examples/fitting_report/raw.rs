//! The report's raw-scan classes: samples of the analytic shapes spoiled
//! the way scans are (Gaussian noise, uniform outliers, a density step,
//! scan lines, an open sheet with noise), generated here from
//! `Shape::sample` with fixed seeds.

use op_dynamics::{Point3, Real, Vec3};
use op_scene::fit::shapes::Shape;
use op_scene::pointsets::PointSet;

use super::targets::Truth;

/// A small deterministic generator (xorshift64).
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }

    /// Uniform in `[0, 1)`.
    fn next(&mut self) -> Real {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as Real / (1u64 << 53) as Real
    }

    /// A standard normal variable (Box-Muller).
    fn gaussian(&mut self) -> Real {
        let u = self.next().max(Real::MIN_POSITIVE);
        let v = self.next();
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// The bounding box of `points`: its corners.
fn bounds(points: &[Point3]) -> (Vec3, Vec3) {
    points.iter().fold(
        (
            Vec3::repeat(Real::INFINITY),
            Vec3::repeat(Real::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.inf(&p.coords), hi.sup(&p.coords)),
    )
}

/// `n` samples of `shape` with Gaussian noise of standard deviation
/// `share` of the bounding box's diagonal on each coordinate.
fn noisy(shape: Shape, n: usize, share: Real) -> PointSet {
    let clean = shape.sample(n, 17).positions;
    let (lo, hi) = bounds(&clean);
    let sigma = share * (hi - lo).norm();
    let mut rng = Rng::new(11);
    let positions = clean
        .iter()
        .map(|p| p + Vec3::new(rng.gaussian(), rng.gaussian(), rng.gaussian()) * sigma)
        .collect();
    PointSet {
        positions,
        normals: None,
    }
}

/// `n` samples of `shape` and `share` of `n` more uniform in its bounding
/// box.
fn with_outliers(shape: Shape, n: usize, share: Real) -> PointSet {
    let mut positions = shape.sample(n, 17).positions;
    let (lo, hi) = bounds(&positions);
    let mut rng = Rng::new(7);
    let extra = (share * n as Real).round() as usize;
    for _ in 0..extra {
        let t = Vec3::new(rng.next(), rng.next(), rng.next());
        positions.push(Point3::from(lo + (hi - lo).component_mul(&t)));
    }
    PointSet {
        positions,
        normals: None,
    }
}

/// About `n` samples of `shape`, `ratio` times sparser where `x > 0`.
fn density_step(shape: Shape, n: usize, ratio: Real) -> PointSet {
    let dense = shape.sample(2 * n, 17).positions;
    let mut rng = Rng::new(3);
    let positions: Vec<Point3> = dense
        .into_iter()
        .filter(|p| p.x <= 0.0 || rng.next() * ratio < 1.0)
        .collect();
    PointSet {
        positions,
        normals: None,
    }
}

/// About `n` samples of `shape` along scan lines: the curves where it
/// meets the planes `y = k d`, sampled `ratio` times more densely along
/// each line than the lines are apart (a laser line scanner's pattern).
fn scan_lines(shape: Shape, n: usize, ratio: Real) -> PointSet {
    // Samples within a band of half-width `w` about each plane: `2 w / d`
    // of a dense set; along a line they are `A / (N 2 w)` apart for an
    // area `A` sampled by `N`. With the lines `d` apart, `ratio` times
    // the distance along them: `d = ratio A / (2 w N)`, and `n` kept:
    // `N 2 w / d = n`.
    let dense_n = 40 * n;
    let dense = shape.sample(dense_n, 17).positions;
    let area = shape_area(shape);
    // From the two conditions: d² = ratio A / n.
    let d = (ratio * area / n as Real).sqrt();
    let w = n as Real * d / (2.0 * dense_n as Real);
    let positions: Vec<Point3> = dense
        .into_iter()
        .filter(|p| (p.y - (p.y / d).round() * d).abs() < w)
        .collect();
    PointSet {
        positions,
        normals: None,
    }
}

/// The surface area of the analytic shapes (the ellipsoid by Knud
/// Thomsen's formula, within about 1%).
fn shape_area(shape: Shape) -> Real {
    use std::f64::consts::PI;
    match shape {
        Shape::Torus => 4.0 * PI * PI * 1.0 * 0.4,
        Shape::Ellipsoid => {
            let (a, b, c) = (1.0f64, 0.7f64, 0.5f64);
            let p = 1.6075;
            4.0 * PI * ((a * b).powf(p) + (a * c).powf(p) + (b * c).powf(p)) / 3.0
        }
        .powf(1.0 / 1.6075),
        _ => 4.0,
    }
}

/// The classes of the report, named, with their shape (the truth for the
/// vertex-to-surface distance): `n` samples each (the arrows fewer, the
/// last `10 n`).
pub(crate) fn classes(n: usize) -> Vec<(String, PointSet, Shape, Truth)> {
    let mut out = Vec::new();
    for (shape, share) in [
        (Shape::Torus, 0.0025),
        (Shape::Torus, 0.005),
        (Shape::Torus, 0.01),
        (Shape::Ellipsoid, 0.005),
        (Shape::Ellipsoid, 0.01),
        (Shape::HoledSaddle, 0.005),
    ] {
        out.push((
            format!(
                "{} {n}, Gaussian noise {}% of the diagonal",
                shape.name(),
                100.0 * share
            ),
            noisy(shape, n, share),
            shape,
            // The targets hold up to 0.5% of noise.
            if share <= 0.005 {
                Truth::of(shape)
            } else {
                Truth::of(shape).beyond()
            },
        ));
    }
    for share in [0.01, 0.05] {
        out.push((
            format!("torus {n} + {}% uniform outliers", 100.0 * share),
            with_outliers(Shape::Torus, n, share),
            Shape::Torus,
            Truth::of(Shape::Torus).with_outliers(),
        ));
    }
    let step = density_step(Shape::Torus, n, 10.0);
    out.push((
        format!(
            "torus, density step 10:1 at x = 0 ({} samples)",
            step.positions.len()
        ),
        step,
        Shape::Torus,
        Truth::of(Shape::Torus),
    ));
    for ratio in [5.0, 10.0] {
        let lines = scan_lines(Shape::Torus, n, ratio);
        out.push((
            format!(
                "torus, scan lines {ratio}:1 ({} samples)",
                lines.positions.len()
            ),
            lines,
            Shape::Torus,
            Truth::of(Shape::Torus),
        ));
    }
    // A thin part: the arrow's shaft is 0.08 thick, about 1.8, 2.3 and
    // 3.6 default spacings at these counts.
    for count in [500, 800, 2000] {
        out.push((
            format!("arrow {count} (a thin shaft, a sharp head)"),
            Shape::Arrow.sample(count, 17),
            Shape::Arrow,
            Truth::of(Shape::Arrow),
        ));
    }
    out.push((
        format!("torus {}, Gaussian noise 0.5% of the diagonal", 10 * n),
        noisy(Shape::Torus, 10 * n, 0.005),
        Shape::Torus,
        Truth::of(Shape::Torus),
    ));
    out
}

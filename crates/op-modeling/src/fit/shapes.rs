//! Analytic test shapes for point-set fitting, sampled uniformly at random
//! with a fixed seed, with their distance to the true surface and the
//! topology a fit must reproduce (genus 0, 1, 2 and an open
//! patch with a hole). Shared by `tests/fit.rs` and
//! `crates/op-experiments/examples/fitting_report/`.

use op_dynamics::{Point3, Real, Vec3};

use super::PointSet;

/// An analytic surface to sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Ellipsoid with semi-axes 1, 0.7, 0.5 (genus 0, χ = 2).
    Ellipsoid,
    /// Torus of major radius 1, minor 0.4 about z (genus 1, χ = 0).
    Torus,
    /// Two tori (major radius 1, minor 0.4) centred at x = ±1.1, joined
    /// by a smooth union of their distance functions (genus 2, χ = -2).
    DoubleTorus,
    /// The saddle `z = 0.2 (x² - y²)` over `[-1, 1]²` without the disc of
    /// radius 0.35 about the z axis: open, χ = 0, 2 boundary loops.
    HoledSaddle,
    /// An arrow along x (genus 0, χ = 2): a shaft, the capsule of radius
    /// [`ARROW_SHAFT`] about the segment from x = -1 to x = 0.5, joined to
    /// a head, the solid cone of base radius 0.2 at x = 0.5 and apex at
    /// x = 1. A thin part (the shaft is 0.08 thick, a tenth of its length
    /// and of the ellipsoid's thinnest axis) and sharp features (the apex,
    /// the rim of the head's base). Not in [`Shape::ALL`]: the fitting
    /// report's thin-part class.
    Arrow,
}

/// Radius of [`Shape::Arrow`]'s shaft.
pub const ARROW_SHAFT: Real = 0.04;

impl Shape {
    /// All shapes.
    pub const ALL: [Shape; 4] = [
        Shape::Ellipsoid,
        Shape::Torus,
        Shape::DoubleTorus,
        Shape::HoledSaddle,
    ];

    /// Short name.
    pub fn name(self) -> &'static str {
        match self {
            Shape::Ellipsoid => "ellipsoid",
            Shape::Torus => "torus",
            Shape::DoubleTorus => "double torus",
            Shape::HoledSaddle => "saddle with hole",
            Shape::Arrow => "arrow",
        }
    }

    /// True for an open surface (fit with `open`).
    pub fn is_open(self) -> bool {
        self == Shape::HoledSaddle
    }

    /// The Euler characteristic and boundary loops of the surface.
    pub fn topology(self) -> (i64, usize) {
        match self {
            Shape::Ellipsoid => (2, 0),
            Shape::Torus => (0, 0),
            Shape::DoubleTorus => (-2, 0),
            Shape::HoledSaddle => (0, 2),
            Shape::Arrow => (2, 0),
        }
    }

    /// `n` samples uniform in area (the double torus: uniform on each
    /// torus outside the other, projected on the joined surface), from
    /// `seed`.
    pub fn sample(self, n: usize, seed: u64) -> PointSet {
        let mut rng = Rng(seed ^ 0x9e37_79b9_7f4a_7c15);
        let mut positions = Vec::with_capacity(n);
        while positions.len() < n {
            let p = match self {
                Shape::Ellipsoid => {
                    let axes = Vec3::new(1.0, 0.7, 0.5);
                    let u = rng.unit();
                    // Area element of the map u -> axes ∘ u, relative to
                    // its largest (at u = ±z).
                    let w = u.component_div(&axes).norm() * axes.min();
                    if rng.next() > w {
                        continue;
                    }
                    Point3::from(u.component_mul(&axes))
                }
                Shape::Torus => match torus_point(&mut rng, 0.0) {
                    Some(p) => p,
                    None => continue,
                },
                Shape::DoubleTorus => {
                    let c = if rng.next() < 0.5 { -1.1 } else { 1.1 };
                    let Some(p) = torus_point(&mut rng, c) else {
                        continue;
                    };
                    if torus_sdf(&p, -c) < 0.0 {
                        continue;
                    }
                    project(&p, double_torus_sdf)
                }
                Shape::HoledSaddle => {
                    let (x, y) = (2.0 * rng.next() - 1.0, 2.0 * rng.next() - 1.0);
                    if x * x + y * y < 0.35 * 0.35 {
                        continue;
                    }
                    // Area element sqrt(1 + |∇z|²), at most sqrt(1 + 0.32).
                    let w = (1.0 + 0.16 * (x * x + y * y)).sqrt() / 1.32f64.sqrt();
                    if rng.next() > w {
                        continue;
                    }
                    Point3::new(x, y, 0.2 * (x * x - y * y))
                }
                Shape::Arrow => match arrow_point(&mut rng) {
                    Some(p) => p,
                    None => continue,
                },
            };
            positions.push(p);
        }
        PointSet {
            positions,
            normals: None,
        }
    }

    /// Distance from `p` to the surface (first order in the distance for
    /// the ellipsoid, the saddle and the junction of the double torus).
    pub fn distance(self, p: &Point3) -> Real {
        match self {
            Shape::Ellipsoid => {
                let axes = Vec3::new(1.0, 0.7, 0.5);
                let q = p.coords.component_div(&axes);
                let f = q.norm_squared() - 1.0;
                let grad = 2.0 * q.component_div(&axes);
                f.abs() / grad.norm().max(1e-12)
            }
            Shape::Torus => torus_sdf(p, 0.0).abs(),
            Shape::DoubleTorus => {
                let f = double_torus_sdf(p);
                f.abs() / gradient(p, double_torus_sdf).norm().max(1e-12)
            }
            Shape::HoledSaddle => {
                let f = p.z - 0.2 * (p.x * p.x - p.y * p.y);
                f.abs() / (1.0 + 0.16 * (p.x * p.x + p.y * p.y)).sqrt()
            }
            Shape::Arrow => arrow_sdf(p).abs(),
        }
    }
}

/// splitmix64.
struct Rng(u64);

impl Rng {
    /// Uniform in `[0, 1)`.
    fn next(&mut self) -> Real {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as Real / (1u64 << 53) as Real
    }

    /// Uniform on the unit sphere.
    fn unit(&mut self) -> Vec3 {
        let z = 2.0 * self.next() - 1.0;
        let phi = std::f64::consts::TAU * self.next();
        let s = (1.0 - z * z).sqrt();
        Vec3::new(s * phi.cos(), s * phi.sin(), z)
    }
}

/// A point uniform in area on the torus (major 1, minor 0.4) centred at
/// `(cx, 0, 0)`, or `None` when rejected.
fn torus_point(rng: &mut Rng, cx: Real) -> Option<Point3> {
    let (u, v) = (
        std::f64::consts::TAU * rng.next(),
        std::f64::consts::TAU * rng.next(),
    );
    // Area element (R + a cos v), relative to its largest R + a.
    if rng.next() > (1.0 + 0.4 * v.cos()) / 1.4 {
        return None;
    }
    let r = 1.0 + 0.4 * v.cos();
    Some(Point3::new(cx + r * u.cos(), r * u.sin(), 0.4 * v.sin()))
}

/// Signed distance to the torus (major 1, minor 0.4) centred at `(cx, 0, 0)`.
fn torus_sdf(p: &Point3, cx: Real) -> Real {
    let q = ((p.x - cx).hypot(p.y) - 1.0).hypot(p.z);
    q - 0.4
}

/// Smooth union (polynomial smooth minimum, width 0.2) of the tori at
/// x = ±1.1.
fn double_torus_sdf(p: &Point3) -> Real {
    let (a, b) = (torus_sdf(p, -1.1), torus_sdf(p, 1.1));
    let k = 0.2;
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k / 4.0
}

/// The arrow's head: base radius, the base's and the apex's x.
const HEAD: (Real, Real, Real) = (0.2, 0.5, 1.0);

/// The arrow's shaft: from x = -1 to the head's base.
const SHAFT_FROM: Real = -1.0;

/// A point uniform in area on the arrow's surface, or `None` when rejected
/// (inside the other part): a part picked in proportion to its area (the
/// shaft's capsule, the head's lateral surface, the head's base), a point
/// uniform on it.
fn arrow_point(rng: &mut Rng) -> Option<Point3> {
    use std::f64::consts::{PI, TAU};
    let (r, length) = (ARROW_SHAFT, HEAD.1 - SHAFT_FROM);
    let (big, base, apex) = HEAD;
    let slant = (apex - base).hypot(big);
    let areas = [
        TAU * r * length + 4.0 * PI * r * r,
        PI * big * slant,
        PI * big * big,
    ];
    let mut pick = rng.next() * areas.iter().sum::<Real>();
    let phi = TAU * rng.next();
    let p = if pick < areas[0] {
        // The capsule: its cylinder, or a point of its two caps.
        pick = rng.next() * areas[0];
        if pick < TAU * r * length {
            let x = SHAFT_FROM + length * rng.next();
            Point3::new(x, r * phi.cos(), r * phi.sin())
        } else {
            let u = rng.unit() * r;
            let end = if u.x < 0.0 { SHAFT_FROM } else { base };
            Point3::new(end, 0.0, 0.0) + u
        }
    } else if pick < areas[0] + areas[1] {
        // The cone: area grows linearly from the apex.
        let t = rng.next().sqrt();
        let rho = big * t;
        Point3::new(apex - (apex - base) * t, rho * phi.cos(), rho * phi.sin())
    } else {
        let rho = big * rng.next().sqrt();
        Point3::new(base, rho * phi.cos(), rho * phi.sin())
    };
    // Keep the union's surface only: not strictly inside the other part.
    let inside_other = if pick < areas[0] {
        head_sdf(&p) < -1e-12
    } else {
        shaft_sdf(&p) < -1e-12
    };
    (!inside_other).then_some(p)
}

/// Signed distance to the arrow's shaft (the capsule).
fn shaft_sdf(p: &Point3) -> Real {
    let x = p.x.clamp(SHAFT_FROM, HEAD.1);
    (p - Point3::new(x, 0.0, 0.0)).norm() - ARROW_SHAFT
}

/// Signed distance to the arrow's head (the solid cone), from the triangle
/// it sweeps in the (x, distance from the axis) half-plane.
fn head_sdf(p: &Point3) -> Real {
    let (big, base, apex) = HEAD;
    let q = (p.x, p.y.hypot(p.z));
    let to_segment = |a: (Real, Real), b: (Real, Real)| {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let t = (((q.0 - a.0) * dx + (q.1 - a.1) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
        (q.0 - a.0 - t * dx).hypot(q.1 - a.1 - t * dy)
    };
    let d = to_segment((base, 0.0), (base, big)).min(to_segment((base, big), (apex, 0.0)));
    let inside = q.0 > base && q.1 < big * (apex - q.0) / (apex - base);
    if inside {
        -d
    } else {
        d
    }
}

/// Signed distance to the arrow: the union of its shaft and head (exact
/// outside and on the surface).
fn arrow_sdf(p: &Point3) -> Real {
    shaft_sdf(p).min(head_sdf(p))
}

/// Central-difference gradient of `f`.
fn gradient(p: &Point3, f: fn(&Point3) -> Real) -> Vec3 {
    let e = 1e-6;
    Vec3::from_fn(|i, _| {
        let mut a = *p;
        let mut b = *p;
        a[i] += e;
        b[i] -= e;
        (f(&a) - f(&b)) / (2.0 * e)
    })
}

/// `p` moved onto the zero set of `f` by Newton steps along the gradient.
fn project(p: &Point3, f: fn(&Point3) -> Real) -> Point3 {
    let mut q = *p;
    for _ in 0..20 {
        let v = f(&q);
        let g = gradient(&q, f);
        let g2 = g.norm_squared().max(1e-12);
        q -= g * (v / g2);
        if v.abs() < 1e-12 {
            break;
        }
    }
    q
}

/// `n` pseudo-random points (a fixed linear congruential sequence, the same
/// every call) in the box `[0, size]³`: unit tests' scattered data.
pub fn scattered(n: usize, size: Real) -> Vec<Point3> {
    let mut state = 12345u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as Real / (1u64 << 53) as Real * size
    };
    (0..n)
        .map(|_| Point3::new(next(), next(), next()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_lie_on_their_surfaces() {
        for shape in Shape::ALL.into_iter().chain([Shape::Arrow]) {
            let s = shape.sample(300, 1);
            assert_eq!(s.positions.len(), 300);
            let worst = s
                .positions
                .iter()
                .map(|p| shape.distance(p))
                .fold(0.0, Real::max);
            assert!(worst < 1e-9, "{shape:?}: {worst}");
            assert_eq!(s, shape.sample(300, 1));
        }
    }
}

//! The health report of a run: what a user must know before trusting
//! exit 0.
//!
//! The runner ([`crate::run()`]) watches every frame and writes what it saw
//! into `summary.json`:
//!
//! - **pieces**: the connected components of each object's particles, two
//!   particles joined when they are closer than the object material's
//!   interaction range ([`op_dynamics::interactions::PreparedMaterial::cutoff`]), at
//!   the start (before the settle phase) and at the last frame. An object
//!   that ends in more pieces than it started with broke: the run ends as
//!   diverged (exit 3) unless the scene expects it (tearing and cutting
//!   scenes say so in their header, [`crate::Scene::expected_warnings`])
//!   or the run accepts it (`opsim run --allow-breakup`); then it is a
//!   warning, with the count.
//! - **bond stretch**: the largest ratio of current to rest distance over
//!   the object's rest neighbour pairs (pairs of original particles at most
//!   [`NEIGHBOUR_PAIR_FACTOR`] rest spacings apart in the rest shape) over
//!   all frames.
//! - **escape**: how far a particle got from the scene's bounds (the box of
//!   the particles at frame 0 and of the tools' positions over the run),
//!   in units of the scene's size, after allowing for the motion that
//!   gravity, the initial velocities and the force windows can cause.
//!   [`ESCAPE_WARNING`] sizes is a warning; `world.divergence.extent_growth`
//!   sizes (default [`DEFAULT_EXTENT_GROWTH`]) is an explosion, which ends
//!   the run like a divergence (exit 3).
//!
//! The energy checks (runaway kinetic energy, energy gained by a passive
//! scene) are the runner's; their scale comes from [`energy_floor`], which
//! is never zero, so a scene that starts at rest is measured against the
//! energy its own inputs can give it rather than against nothing.

use op_dynamics::{Divergence, Point3, Real, Vec3};
use op_modeling::cell_map::CellMap;
use rayon::prelude::*;

use crate::built_scene::{BuiltObject, BuiltScene};

/// Rest neighbour pairs are the original particles at most this many rest
/// spacings apart in the rest shape.
pub const NEIGHBOUR_PAIR_FACTOR: Real = 1.5;
/// A particle this many scene sizes beyond the scene's bounds (after the
/// allowed motion) is reported in `warnings`.
pub const ESCAPE_WARNING: Real = 100.0;
/// Default of `world.divergence.extent_growth`: a particle this many scene
/// sizes beyond the scene's bounds is an explosion (exit 3).
pub const DEFAULT_EXTENT_GROWTH: Real = 1e4;
/// A passive scene whose total energy rises above the lowest earlier frame
/// by more than this fraction of its energy scale gets a warning (the
/// divergence check `world.divergence.energy_gain` is off by default).
pub const ENERGY_GAIN_WARNING: Real = 1e-2;

/// Axis-aligned box.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
struct Bounds {
    min: Vec3,
    max: Vec3,
}

impl Bounds {
    fn empty() -> Self {
        Bounds {
            min: Vec3::repeat(Real::INFINITY),
            max: Vec3::repeat(Real::NEG_INFINITY),
        }
    }

    fn add(&mut self, p: &Vec3) {
        if p.iter().all(|c| c.is_finite()) {
            self.min = self.min.inf(p);
            self.max = self.max.sup(p);
        }
    }

    fn diagonal(&self) -> Real {
        if self.min.x > self.max.x {
            0.0
        } else {
            (self.max - self.min).norm()
        }
    }

    /// Distance from `p` to the box (0 inside).
    fn distance(&self, p: &Vec3) -> Real {
        let below = (self.min - p).sup(&Vec3::zeros());
        let above = (p - self.max).sup(&Vec3::zeros());
        (below + above).norm()
    }
}

/// Per-object figures of the health report.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
struct ObjectHealth {
    /// Interaction range of the object's material (0: no interaction, no
    /// pieces reported).
    range: Real,
    /// Rest neighbour pairs: ids and rest distance.
    pairs: Vec<(u32, u32, Real)>,
    /// Pieces when the watch started (before the settle phase).
    pieces_start: Option<usize>,
    /// Largest bond stretch seen.
    stretch_max: Real,
}

/// What the health report found for one object at the end of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectFindings {
    /// Connected components at the last frame (`None` when the object's
    /// material has no interaction range).
    pub pieces: Option<usize>,
    /// Largest bond stretch seen (1 = rest length; 0 when the object has
    /// no rest neighbour pair).
    pub bond_stretch_max: Real,
}

/// Watches a run frame by frame; see the module docs.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Health {
    bounds: Bounds,
    size: Real,
    /// Speed allowance: initial speeds, plus the speed the scene's
    /// features can give (a wind's air speed).
    speed: Real,
    /// Acceleration allowance: gravity plus the largest force window per
    /// unit mass.
    accel: Real,
    /// World time the watch started at.
    t0: Real,
    explode_at: Real,
    objects: Vec<ObjectHealth>,
    escape_max: Real,
    escaped_object: Option<usize>,
}

impl Health {
    /// Starts watching `scene` in its current state, for a run lasting
    /// `duration` from now; `extent_growth` is the explosion threshold in
    /// scene sizes. The runner starts before the settle phase, so the
    /// scene's bounds and pieces are those of its inputs and an explosion
    /// while settling is measured against them.
    pub fn new(scene: &BuiltScene, duration: Real, extent_growth: Real) -> Health {
        let w = &scene.world;
        let p = w.particles();
        let mut bounds = Bounds::empty();
        for x in p.positions() {
            bounds.add(&x.coords);
        }
        let t0 = w.time();
        for tool in &scene.tools {
            for k in 0..=64 {
                let t = t0 + duration * k as Real / 64.0;
                bounds.add(&tool.pose(t).position);
            }
        }
        // At least one interaction range: a scene that starts as a point
        // (particles on top of each other) still has the size its material
        // gives it.
        let spacing = scene
            .objects
            .iter()
            .flat_map(|o| [o.rest_spacing, object_range(scene, o)])
            .filter(|r| r.is_finite())
            .fold(0.0, Real::max);
        let size = bounds.diagonal().max(spacing).max(Real::MIN_POSITIVE);
        let speed = p
            .velocities()
            .iter()
            .map(|v| v.norm())
            .filter(|v| v.is_finite())
            .fold(0.0, Real::max)
            + scene.speed_allowance();
        let ext = &w.params().external;
        let min_mass = p
            .masses()
            .iter()
            .copied()
            .filter(|m| *m > 0.0)
            .fold(Real::INFINITY, Real::min);
        let window = ext
            .forces
            .iter()
            .map(|f| Vec3::from(f.force).norm() / min_mass)
            .filter(|a| a.is_finite())
            .fold(0.0, Real::max);
        let accel = Vec3::from(ext.gravity).norm() + window;
        let ranges: Vec<Real> = scene
            .objects
            .iter()
            .map(|o| object_range(scene, o))
            .collect();
        let counts = piece_counts(scene, &ranges);
        let objects = scene
            .objects
            .iter()
            .zip(ranges)
            .zip(counts)
            .map(|((o, range), pieces_start)| ObjectHealth {
                range,
                pairs: rest_pairs(o),
                pieces_start,
                stretch_max: 0.0,
            })
            .collect();
        Health {
            bounds,
            size,
            speed,
            accel,
            t0,
            explode_at: extent_growth,
            objects,
            escape_max: 0.0,
            escaped_object: None,
        }
    }

    /// The scene's size: the diagonal of its bounds, at least its largest
    /// rest spacing and interaction range.
    pub fn size(&self) -> Real {
        self.size
    }

    /// Observes the current frame; returns the explosion message when a
    /// particle is `extent_growth` scene sizes beyond the scene's bounds.
    pub fn observe(&mut self, scene: &BuiltScene) -> Option<Divergence> {
        let w = &scene.world;
        let p = w.particles();
        let t = (w.time() - self.t0).max(0.0);
        let allowed = self.speed * t + 0.5 * self.accel * t * t;
        let mut worst: Option<(Real, u32, usize)> = None;
        for (o, (obj, h)) in scene.objects.iter().zip(&mut self.objects).enumerate() {
            for &(a, b, rest) in &h.pairs {
                if let (Some(sa), Some(sb)) = (p.slot_of(a), p.slot_of(b)) {
                    let d = (p.positions()[sa] - p.positions()[sb]).norm();
                    h.stretch_max = h.stretch_max.max(d / rest);
                }
            }
            for id in obj.all_ids() {
                let Some(s) = p.slot_of(id) else { continue };
                let x = p.positions()[s].coords;
                let d = (self.bounds.distance(&x) - allowed).max(0.0) / self.size;
                let d = if d.is_nan() { Real::INFINITY } else { d };
                if worst.is_none_or(|(m, _, _)| d > m) {
                    worst = Some((d, id, o));
                }
            }
        }
        let (d, id, o) = worst?;
        if d > self.escape_max {
            self.escape_max = d;
            self.escaped_object = Some(o);
        }
        (d > self.explode_at).then(|| Divergence {
            step: w.steps(),
            time: w.time(),
            particle: Some(id),
            reason: format!(
                "exploded: it is in object {:?}, {} scene sizes ({}) beyond the scene's \
                 bounds, more than world.divergence.extent_growth = {}",
                scene.objects[o].name,
                crate::error::short(d),
                crate::error::short(self.size),
                crate::error::short(self.explode_at)
            ),
        })
    }

    /// The findings per object, the warnings and the breakups (an object
    /// in more pieces than when the watch started: `object "NAME" broke
    /// into N pieces (M at the start) ...`), at the end of the run.
    pub fn finish(&self, scene: &BuiltScene) -> (Vec<ObjectFindings>, Vec<String>, Vec<String>) {
        let mut warnings = Vec::new();
        let mut breakups = Vec::new();
        let ranges: Vec<Real> = self.objects.iter().map(|h| h.range).collect();
        let counts = piece_counts(scene, &ranges);
        let findings = scene
            .objects
            .iter()
            .zip(&self.objects)
            .zip(counts)
            .map(|((o, h), now)| {
                if let (Some(start), Some(end)) = (h.pieces_start, now) {
                    if end > start {
                        breakups.push(format!(
                            "object {:?} broke into {end} pieces ({start} at the start): parts of \
                             it are farther apart than its material's interaction range ({})",
                            o.name,
                            crate::error::short(h.range)
                        ));
                    }
                }
                ObjectFindings {
                    pieces: now,
                    bond_stretch_max: h.stretch_max,
                }
            })
            .collect();
        if self.escape_max > ESCAPE_WARNING {
            let name = self
                .escaped_object
                .map_or("?", |o| scene.objects[o].name.as_str());
            warnings.push(format!(
                "object {name:?} left the scene's bounds: a particle got {} scene sizes ({}) \
                 beyond them, more than gravity, the initial velocities and the force windows \
                 can explain",
                crate::error::short(self.escape_max),
                crate::error::short(self.size)
            ));
        }
        (findings, warnings, breakups)
    }
}

/// Largest coordinate a frame file can hold: PLY stores single-precision
/// floats.
pub const MAX_WRITTEN_COORDINATE: Real = f32::MAX as Real;

/// The divergence a frame would write: a particle with a non-finite
/// temperature, or a coordinate beyond [`MAX_WRITTEN_COORDINATE`] (which a
/// PLY frame would write as infinity), named with its object; `None` when
/// every value of the state can be written. (The world's own check after
/// each step already refuses non-finite positions, velocities and
/// orientations.) The runner checks it before every frame, so no frame file
/// ever holds a non-finite value.
pub fn unwritable(scene: &BuiltScene) -> Option<Divergence> {
    let w = &scene.world;
    let p = w.particles();
    let bad = (0..p.len()).find_map(|s| {
        let x = p.positions()[s];
        if x.iter()
            .any(|c| c.is_nan() || c.abs() > MAX_WRITTEN_COORDINATE)
        {
            Some((
                s,
                format!(
                    "position {:?} beyond what a frame file holds",
                    x.coords.as_slice()
                ),
            ))
        } else if !p.temperatures()[s].is_finite() {
            Some((s, format!("temperature {}", p.temperatures()[s])))
        } else {
            None
        }
    })?;
    let (slot, what) = bad;
    let object = scene
        .objects
        .get(p.objects()[slot] as usize)
        .map_or("?", |o| o.name.as_str());
    Some(Divergence {
        step: w.steps(),
        time: w.time(),
        particle: Some(p.ids()[slot]),
        reason: format!(
            "{what} in object {object:?}: the frame is not written (exit 3, the frames before \
             it are valid)"
        ),
    })
}

/// Interaction range of an object: the largest cut-off of its particles'
/// materials.
fn object_range(scene: &BuiltScene, o: &BuiltObject) -> Real {
    let p = scene.world.particles();
    let materials = scene.world.materials();
    o.all_ids()
        .filter_map(|id| p.slot_of(id))
        .filter_map(|s| materials.get(p.materials()[s] as usize))
        .map(|m| m.cutoff())
        .fold(0.0, Real::max)
}

/// The rest neighbour pairs of an object (see the module docs).
fn rest_pairs(o: &BuiltObject) -> Vec<(u32, u32, Real)> {
    let reach = NEIGHBOUR_PAIR_FACTOR * o.rest_spacing;
    if !(reach > 0.0 && reach.is_finite()) {
        return Vec::new();
    }
    // Rest positions pair with ids in order (as far as both go).
    let n = o.ids.len().min(o.rest.len());
    close_pairs(&o.rest[..n], reach)
        .into_iter()
        .filter(|&(_, _, d)| d > 0.0)
        .map(|(a, b, d)| (o.ids[a], o.ids[b], d))
        .collect()
}

/// Per object of `scene`, its [`pieces`] at its interaction range
/// (`ranges`, in object order; `None` where it is 0), the objects side by
/// side: each count is its own grid over its own particles (two skinned
/// balls of 144,605 particles: 0.19 s each).
fn piece_counts(scene: &BuiltScene, ranges: &[Real]) -> Vec<Option<usize>> {
    let p = scene.world.particles();
    let objects: Vec<(Vec<u32>, Real)> = scene
        .objects
        .iter()
        .zip(ranges)
        .map(|(o, &range)| (o.all_ids().collect(), range))
        .collect();
    objects
        .par_iter()
        .map(|(ids, range)| (*range > 0.0).then(|| pieces_of(p, ids, *range)))
        .collect()
}

/// Connected components of the object's current particles, joined when
/// closer than `range`.
pub fn pieces(scene: &BuiltScene, o: &BuiltObject, range: Real) -> usize {
    let ids: Vec<u32> = o.all_ids().collect();
    pieces_of(scene.world.particles(), &ids, range)
}

/// [`pieces`] of the particles `ids` of `p`.
fn pieces_of(p: &op_dynamics::Particles, ids: &[u32], range: Real) -> usize {
    let points: Vec<Point3> = ids
        .iter()
        .filter_map(|&id| p.slot_of(id).map(|s| p.positions()[s]))
        .collect();
    point_pieces(&points, range)
}

/// Connected components of `points`, two joined when closer than `range`
/// (single linkage); a point with non-finite coordinates is a piece of
/// its own.
pub fn point_pieces(points: &[Point3], range: Real) -> usize {
    let mut sets = op_modeling::disjoint_sets::DisjointSets::new(points.len());
    for (a, b, _) in close_pairs(points, range) {
        sets.union(a, b);
    }
    sets.count()
}

/// Every pair of `points` (indices, `a < b`) closer than `reach`, with its
/// distance, by a hash grid of cell size `reach`: in increasing `a`, each
/// point's pairs in the order of the cells around it and of the points in
/// a cell, whatever the thread count. Points with non-finite coordinates
/// have no pairs (their own pieces).
///
/// The grid is built on one thread, the pairs searched in parallel: the
/// search, 27 lookups a point, is most of a piece count (`perf` on the
/// scene report's 316 x 316 skinned cloth, one frame: 5.8% of the run),
/// and the piece counts most of the runner's `measure` stage.
fn close_pairs(points: &[Point3], reach: Real) -> Vec<(usize, usize, Real)> {
    let cell = |x: &Point3| -> Option<[i64; 3]> {
        let c = [x.x / reach, x.y / reach, x.z / reach];
        // Beyond ±2^52 cells the grid cannot tell neighbours apart; such
        // particles are reported separately (the escape check sees them).
        c.iter()
            .all(|v| v.is_finite() && v.abs() < 4.5e15)
            .then(|| c.map(|v| v.floor() as i64))
    };
    // A multiply-xor hash of the cells (op_modeling::cell_map): each point
    // looks up 27 of them (two objects of 144,605 particles: the four
    // piece counts of a run took 0.85 s with SipHash, 0.75 s with it).
    let mut grid: CellMap<Vec<usize>> = CellMap::default();
    for (k, x) in points.iter().enumerate() {
        if let Some(c) = cell(x) {
            grid.entry(c).or_default().push(k);
        }
    }
    let pairs_of = |a: usize, out: &mut Vec<(usize, usize, Real)>| {
        let x = &points[a];
        let Some(c) = cell(x) else { return };
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                        continue;
                    };
                    for &b in list {
                        if b <= a {
                            continue;
                        }
                        let d = (points[b] - x).norm();
                        if d < reach {
                            out.push((a, b, d));
                        }
                    }
                }
            }
        }
    };
    // Chunks of points in order, each with its pairs in order.
    const CHUNK: usize = 2048;
    let chunks: Vec<Vec<(usize, usize, Real)>> = (0..points.len().div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut out = Vec::new();
            for a in c * CHUNK..((c + 1) * CHUNK).min(points.len()) {
                pairs_of(a, &mut out);
            }
            out
        })
        .collect();
    chunks.concat()
}

/// The energy scale no run falls below: the kinetic energy every particle
/// would have moving at the larger of one scene size per frame interval
/// and the speed gravity gives over the run (or a feature such as wind
/// can give, [`BuiltScene::speed_allowance`]). Never zero for a scene with
/// mass, so a scene that starts at rest is not measured against nothing.
pub fn energy_floor(scene: &BuiltScene, size: Real, duration: Real) -> Real {
    let w = &scene.world;
    let g = Vec3::from(w.params().external.gravity).norm();
    let v = (size * scene.frame_rate)
        .max(g * (duration + scene.settle))
        .max(scene.speed_allowance());
    let mass: Real = w.particles().masses().iter().sum();
    0.5 * mass * v * v
}

/// Warnings for particles that start inside an obstacle that acts on them
/// (seed 000 §6): its penalty pushes each out with up to `stiffness` times
/// its depth at once, which can throw it far (a stiff mode `opsim check`
/// then blames on the step). One warning per obstacle, with the count and
/// the deepest particle; at the world's current time (the runner asks
/// before the settle phase).
pub fn started_inside(scene: &BuiltScene) -> Vec<String> {
    use op_modeling::tools::{parry_pose, signed_distance, Role};
    let Some(tools) = op_modeling::Tools::of(&scene.world) else {
        return Vec::new();
    };
    let p = scene.world.particles();
    let t = scene.world.time();
    let mut warnings = Vec::new();
    for tool in tools.tools() {
        let Role::Obstacle { stiffness, .. } = tool.params().role else {
            continue;
        };
        let inside = tool.inside(t, p);
        let Some(&first) = inside.first() else {
            continue;
        };
        let pose = tool.pose(t);
        let frame = parry_pose(&pose.position, &pose.rotation);
        // The depth, where the projection defines one (not at a ball's
        // centre, say, where every direction is closest).
        let depth = |slot: usize| {
            signed_distance(tool.shape(), &frame, &p.positions()[slot].coords)
                .map_or(0.0, |(d, _)| (-d).max(0.0))
        };
        let (mut deepest, mut slot) = (depth(first), first);
        for &s in &inside[1..] {
            let d = depth(s);
            if d > deepest {
                (deepest, slot) = (d, s);
            }
        }
        let count = inside.len();
        let name = scene
            .objects
            .get(p.objects()[slot] as usize)
            .map_or("?", |o| o.name.as_str());
        warnings.push(format!(
            "{count} particle(s) start inside obstacle {:?} (the deepest, of object {name:?}, \
             {} inside): its penalty pushes them out with up to stiffness x depth ({}) at \
             once and can throw them; place the objects outside the tool, or start its path \
             clear of them",
            tool.params().name,
            crate::error::short(deepest),
            crate::error::short(stiffness * deepest),
        ));
    }
    warnings
}

/// `x` to three decimals, for messages (`2` for 2.0, `0.89` for 0.8904).
fn round3(x: Real) -> Real {
    (x * 1000.0).round() / 1000.0
}

/// Warnings for objects of a bonded material (`bonds`, op_dynamics::bonds)
/// whose particles formed no bond: bonds join the pairs within the bond
/// radius when the world is built, and a particle without one is held by
/// nothing but the material's spacing law (none at all for a lattice held
/// by its bonds' memory, such as `plastic_clay`), so it drifts off. One
/// warning per object, with the count, the bond radius and the object's
/// rest spacing.
pub fn unbonded(scene: &BuiltScene) -> Vec<String> {
    let w = &scene.world;
    let Some(bonds) = w.bonds() else {
        return Vec::new();
    };
    let p = w.particles();
    let mut bonded = vec![false; p.id_bound()];
    for &(a, b) in bonds.pairs() {
        bonded[a as usize] = true;
        bonded[b as usize] = true;
    }
    let mut warnings = Vec::new();
    for object in &scene.objects {
        let radius = object
            .ids
            .iter()
            .filter_map(|&id| p.slot_of(id))
            .filter_map(|s| w.materials()[p.materials()[s] as usize].bonds())
            .map(|b| b.radius)
            .fold(0.0, Real::max);
        if radius == 0.0 {
            continue;
        }
        let loose = object
            .ids
            .iter()
            .filter(|&&id| p.slot_of(id).is_some() && !bonded[id as usize])
            .count();
        if loose > 0 {
            warnings.push(format!(
                "{loose} of {} particle(s) of object {:?} have no bond: bonds join particles \
                 within the bond radius {} when the world is built, and the object's rest \
                 spacing is {}; such particles are held by nothing but the spacing law \
                 (raise bonds.radius above the spacing, or sample the object more finely)",
                object.ids.len(),
                object.name,
                round3(radius),
                round3(object.rest_spacing),
            ));
        }
    }
    warnings
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn close_pairs_are_every_close_pair_in_order_of_the_first() {
        // More points than one parallel chunk, a few thousand close pairs.
        let mut rng = op_test_support::Rng::new(7);
        let pts: Vec<Point3> = (0..5000)
            .map(|_| {
                Point3::new(
                    rng.uniform(0.0, 20.0),
                    rng.uniform(0.0, 20.0),
                    rng.uniform(0.0, 2.0),
                )
            })
            .collect();
        let reach = 0.5;
        let found = close_pairs(&pts, reach);
        assert!(found.windows(2).all(|w| w[0].0 <= w[1].0));
        let mut got: Vec<(usize, usize)> = found.iter().map(|&(a, b, _)| (a, b)).collect();
        got.sort_unstable();
        let mut brute = Vec::new();
        for a in 0..pts.len() {
            for b in a + 1..pts.len() {
                if (pts[b] - pts[a]).norm() < reach {
                    brute.push((a, b));
                }
            }
        }
        assert!(brute.len() > 1000, "{} pairs", brute.len());
        assert_eq!(got, brute);
    }

    #[test]
    fn close_pairs_and_bounds() {
        let pts: Vec<Point3> = [0.0, 0.5, 1.0, 3.0, 3.4]
            .iter()
            .map(|&x| Point3::new(x, 0.0, 0.0))
            .collect();
        let found: Vec<(usize, usize)> = close_pairs(&pts, 0.6)
            .into_iter()
            .map(|(a, b, _)| (a, b))
            .collect();
        assert_eq!(found, vec![(0, 1), (1, 2), (3, 4)]);
        let mut b = Bounds::empty();
        b.add(&Vec3::zeros());
        b.add(&Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(b.distance(&Vec3::new(0.5, 0.5, 0.0)), 0.0);
        assert!((b.distance(&Vec3::new(4.0, 1.0, 0.0)) - 3.0).abs() < 1e-12);
    }
}

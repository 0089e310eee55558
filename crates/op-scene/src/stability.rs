//! The largest stable step of a scene, estimated before it runs.
//!
//! A fixed-step scheme is stable on a mode of angular frequency `ω` only
//! while `dt ω` stays below a bound of the scheme: 2 for velocity Verlet and
//! symplectic Euler, about 2.785 for RK4 (the classic stability-region
//! limit on the imaginary axis); explicit Euler needs the damping rate `c`
//! (linear damping over mass) to outweigh the growth it adds, `dt < c / ω²`.
//! `reports/stability.md` measures these laws on probe systems
//! (`dt sqrt(λ) ≈ 2` for velocity Verlet).
//!
//! `ω² = λ`, the largest eigenvalue of the mass-weighted Hessian
//! `M^-1/2 H M^-1/2` of the potential energy over positions and rotation
//! vectors, is found by power iteration on a sample of the scene: every
//! object's generator shrunk to a patch of the same spacing and curvature
//! ([`SAMPLE_PARTICLES`] particles at most), built with the scene's
//! materials and tools, its Hessian-vector products by central differences
//! of the forces and torques. The sample's memory and work are bounded
//! whatever the scene's size, so `opsim check` can afford it: at most
//! [`SAMPLE_TOTAL`] particles (a scene of more objects than that allows at
//! [`SAMPLE_PARTICLES_MIN`] each is sampled in its first objects) and
//! [`SAMPLE_PAIRS`] pairs (fewer particles per object, then fewer objects,
//! for dense clouds and objects on top of each other).
//!
//! **Skin contact** acts outside the world (a stage of the scene), so the
//! sample has no skins; its stiffness is added as a bound instead
//! ([`contact_stiffness`]). By Weyl's inequality the largest eigenvalue of
//! the sum of two symmetric operators is at most the sum of theirs, so
//! `λ ≤ λ_world + λ_contact`, with `λ_contact` the largest contact spring
//! of a particle over its mass:
//!
//! - an obstacle tool of stiffness `k` meeting a skin presses it with
//!   the pressure `k_E g d` of its contact energy (op-implicit
//!   `ObstacleContact`), whose stiffness `k_E = k / (g r0²)` makes a
//!   particle's footprint `r0²` a spring `k`, as a bare particle's;
//! - two skins press with `s · e · area` (op-implicit `implicit_contact`),
//!   `s` the mean of their stiffnesses and `e` the other skin's field
//!   excess, which grows with depth at the other skin's field slope `g`
//!   at its surface (`g = ISO |f'(t)| / f(t)` for a skin `t` from its
//!   skeleton, `19 / (12 R)` at the default `t = R / 2`): over a
//!   particle's footprint `r0²` the spring is `s g r0²`;
//! - the springs of every obstacle and skin an object meets add.
//!
//! **The edge and the recommended step.** The bound is the edge of linear
//! stability: at it a run can still blow up (the spiral breaks at exactly
//! 1.0). `opsim run` at multiples of the bound (exit 3 on a blow-up or an
//! unexpected breakup) measured where six shipped scenes fail:
//!
//! | scene | bound | runs clean at | fails at |
//! |---|---|---|---|
//! | `spiral` | 0.1422 | 0.9 | 1.0 |
//! | `fig_12_plastic` | 0.01929 | 1.2 | 2.0 |
//! | `sphere_shell` | 0.09618 | 1.0 | (above 1.0 the frame interval refuses it) |
//! | `ball_vs_spiral` (two skins) | 0.04286 | 1.0 | 1.99 (0.6 of the world-only bound, 0.1422) |
//! | `sheet_on_box` (obstacle on a skin) | 0.03297 | 0.9 | 1.0 |
//! | `sheet_on_sphere` (obstacle on a skin) | 0.02008 | 0.7 | 0.8 |
//!
//! So the recommended step is [`RECOMMENDED_FRACTION`] of the bound: every
//! one of them runs clean there.

use std::path::Path;

use op_dynamics::{Flags, Point3, Quat, Real, Scheme, Vec3, World};

use crate::error::{short, SceneError};
use crate::generators::Generator;
use crate::schema::Scene;

/// Largest number of particles per object in the sample.
pub const SAMPLE_PARTICLES: usize = 400;
/// Largest number of particles in the whole sample: a scene of many
/// objects samples fewer particles of each (at least
/// [`SAMPLE_PARTICLES_MIN`]), so the sample stays bounded in total.
pub const SAMPLE_TOTAL: usize = 2000;
/// Fewest particles per object in the sample.
pub const SAMPLE_PARTICLES_MIN: usize = 8;

/// Largest number of neighbour pairs in the sample (module docs).
pub const SAMPLE_PAIRS: usize = 20_000;

/// Removes from each of the first `keep` objects of `built` all but the
/// `n` particles nearest its first one (by rest position; ties by id), and
/// every particle of the objects after them.
fn trim(
    built: &mut crate::BuiltScene,
    n: usize,
    keep: usize,
) -> Result<(), op_dynamics::WorldError> {
    let p = built.world.particles();
    let mut extra = Vec::new();
    for (k, o) in built.objects.iter().enumerate() {
        let n = if k < keep { n } else { 0 };
        let live: Vec<(u32, Point3)> = o
            .ids
            .iter()
            .zip(&o.rest)
            .filter(|(&id, _)| p.slot_of(id).is_some())
            .map(|(&id, x)| (id, *x))
            .collect();
        if live.len() > n {
            let first = live[0].1;
            let mut by_distance: Vec<(Real, u32)> = live
                .iter()
                .map(|(id, x)| ((x - first).norm(), *id))
                .collect();
            by_distance.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            extra.extend(by_distance[n..].iter().map(|e| e.1));
        }
    }
    if !extra.is_empty() {
        built.world.remove_particles(&extra)?;
    }
    Ok(())
}

/// The sample's particles per object for a scene of `objects` objects.
fn per_object(objects: usize) -> usize {
    (SAMPLE_TOTAL / objects.max(1)).clamp(SAMPLE_PARTICLES_MIN, SAMPLE_PARTICLES)
}
/// Power iterations.
const ITERATIONS: usize = 60;
/// The recommended step as a fraction of the estimated edge of stability
/// (module docs: the largest fraction at which every measured scene runs
/// clean).
pub const RECOMMENDED_FRACTION: Real = 0.7;

/// What [`estimate`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct StepEstimate {
    /// Largest eigenvalue of the mass-weighted Hessian, 1/time².
    pub lambda: Real,
    /// Object whose particle moves most in that mode.
    pub object: String,
    /// The skin contact's part of `lambda`, when the scene has skin
    /// contact ([`contact_stiffness`]): its bound and the object with the
    /// stiffest contact spring per mass.
    pub contact: Option<(Real, String)>,
    /// Largest stable step of the scene's scheme (`None` for the adaptive
    /// scheme, whose controller shrinks the step as needed, or when the
    /// scene has no stiffness).
    pub dt_max: Option<Real>,
}

impl StepEstimate {
    /// The recommended step: [`RECOMMENDED_FRACTION`] of
    /// [`StepEstimate::dt_max`].
    pub fn recommended(&self) -> Option<Real> {
        self.dt_max.map(|m| m * RECOMMENDED_FRACTION)
    }

    /// Whether no step is stable: explicit Euler without damping, whose
    /// edge `c / ω²` is 0 when the damping rate `c` is.
    pub fn no_stable_step(&self) -> bool {
        self.dt_max == Some(0.0)
    }

    /// Why no step is stable, in words ([`StepEstimate::no_stable_step`]).
    pub const NO_STABLE_STEP: &'static str = "explicit Euler grows every undamped oscillation \
        at any step (its edge of stability is c / ω², c the linear damping rate, here 0): give \
        world.linear_damping > 0 or use another scheme";

    /// Whether `dt` is beyond the estimated edge of stability
    /// ([`StepEstimate::dt_max`]): `opsim run` refuses it unless asked.
    pub fn beyond_edge(&self, dt: Real) -> bool {
        self.dt_max.is_some_and(|max| dt > max)
    }

    /// The refusal of a step `dt` beyond the edge
    /// ([`StepEstimate::beyond_edge`]), or `None` for a step within it:
    /// the edge, the recommended step and what runs it anyway
    /// (`override_hint`: `opsim run`'s flag, the Python package's keyword),
    /// after `origin` (the scene file). `opsim run` and the Python package
    /// refuse such a step with this message.
    pub fn refusal(&self, dt: Real, origin: &str, override_hint: &str) -> Option<String> {
        self.beyond_edge(dt).then(|| {
            if self.no_stable_step() {
                return format!(
                    "{origin}: world.dt = {dt} is not stable: {}; or run it anyway with \
                     {override_hint}",
                    Self::NO_STABLE_STEP
                );
            }
            format!(
                "{origin}: world.dt = {dt} is beyond the estimated edge of stability {:.3e} \
                 ({} recommended; see `opsim check`): reduce dt, use the Adaptive scheme, or \
                 run it anyway with {override_hint}",
                self.dt_max.unwrap_or(Real::NAN),
                self.recommended()
                    .map_or("no step".to_string(), |r| format!("{r:.3e}"))
            )
        })
    }

    /// The warning for a step `dt` above [`StepEstimate::recommended`].
    pub fn warning(&self, dt: Real, scheme: &Scheme) -> Option<String> {
        let (max, recommended) = (self.dt_max?, self.recommended()?);
        if self.no_stable_step() {
            return Some(format!(
                "world.dt = {}: no step is stable for {scheme:?} here: {}",
                short(dt),
                Self::NO_STABLE_STEP
            ));
        }
        (dt > recommended).then(|| {
            format!(
                "world.dt = {} exceeds the recommended step {} ({RECOMMENDED_FRACTION} of the \
                 estimated edge of stability of {scheme:?}, {}; stiffest mode ω² = {} 1/time², in \
                 object {:?}{}): the run may oscillate or blow up; reduce dt or use the \
                 Adaptive scheme",
                short(dt),
                short(recommended),
                short(max),
                short(self.lambda),
                self.object,
                self.contact
                    .as_ref()
                    .map_or(String::new(), |(l, o)| format!(
                        ", skin contact at most {} of it, in object {o:?}",
                        short(*l)
                    ))
            )
        })
    }
}

/// The stability bound `dt sqrt(λ)` of a scheme; explicit Euler's depends
/// on the damping rate `c` as `dt < c / λ`.
pub fn largest_stable_step(scheme: &Scheme, lambda: Real, damping_rate: Real) -> Option<Real> {
    if !(lambda > 0.0 && lambda.is_finite()) {
        return None;
    }
    match scheme {
        Scheme::VelocityVerlet | Scheme::SymplecticEuler => Some(2.0 / lambda.sqrt()),
        Scheme::Rk4 => Some(2.785 / lambda.sqrt()),
        Scheme::ExplicitEuler => Some(damping_rate / lambda),
        _ => None,
    }
}

/// A generator of the same spacing and curvature as `g`, with at most
/// about `n` particles (a list keeps the `n` particles nearest its first
/// one, as the trim after the build does; points files are kept whole here
/// and trimmed after the build).
fn sample_generator(g: &Generator, n: usize) -> Generator {
    let mut g = g.clone();
    match &mut g {
        Generator::Spiral { count, .. } | Generator::Chain { count, .. } => {
            *count = (*count).min(n);
        }
        Generator::HexSheet { nx, ny, .. } => {
            let side = (n as Real).sqrt() as usize;
            *nx = (*nx).min(side);
            *ny = (*ny).min(side);
        }
        Generator::SphereShell {
            radius, spacing, ..
        } => {
            // Count ∝ (radius / spacing)²: shrink the radius, not below
            // two spacings.
            let count = 4.0 * std::f64::consts::PI * (*radius / *spacing).powi(2);
            if count > n as Real {
                *radius = (*radius * (n as Real / count).sqrt()).max(2.0 * *spacing);
            }
        }
        Generator::SolidBall {
            radius, spacing, ..
        } => {
            // Count ∝ (radius / spacing)³: shrink the radius, not below
            // two spacings.
            let count = crate::generators::solid_ball_estimate(*radius, *spacing);
            if count > n as Real {
                *radius = (*radius * (n as Real / count).cbrt()).max(2.0 * *spacing);
            }
        }
        Generator::TorusShell {
            major,
            minor,
            spacing,
            ..
        } => {
            let count = 4.0 * std::f64::consts::PI.powi(2) * *major * *minor / (*spacing).powi(2);
            if count > n as Real {
                let f = (n as Real / count).sqrt();
                *minor = (*minor * f).max(*spacing);
                *major = (*major * f).max(2.0 * *minor);
            }
        }
        Generator::List { particles } => {
            if particles.len() > n {
                let first = Point3::from(particles[0].position);
                let mut by_distance: Vec<(Real, usize)> = particles
                    .iter()
                    .enumerate()
                    .map(|(k, q)| ((Point3::from(q.position) - first).norm(), k))
                    .collect();
                by_distance.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                let mut keep: Vec<usize> = by_distance[..n].iter().map(|e| e.1).collect();
                keep.sort_unstable();
                *particles = keep.into_iter().map(|k| particles[k].clone()).collect();
            }
        }
        Generator::Points { .. } => {}
    }
    g
}

/// The sample scene of the module docs: shrunk generators, no overrides
/// (their selections count the full objects' particles), no force window,
/// no creation, no skin, no settle phase.
fn sample_scene(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    let n = per_object(s.objects.len());
    for o in &mut s.objects {
        o.generator = sample_generator(&o.generator, n);
        o.overrides.clear();
        o.skin = None;
    }
    s.forces.clear();
    s.creation = None;
    s.world.settle = 0.0;
    s
}

/// The bounded sample of a scene (see the module docs: built and trimmed) and
/// its stable-step estimate: what `opsim check` reports without building
/// the whole scene.
pub struct Sample {
    /// The sample, built (each object at most [`SAMPLE_PARTICLES`]
    /// particles, fewer in a scene of more than five objects:
    /// [`SAMPLE_TOTAL`]; its world holds the scene's materials, kernel and
    /// tools).
    pub built: crate::BuiltScene,
    /// The stable-step estimate.
    pub estimate: StepEstimate,
    /// What the full scene computes ([`crate::BuiltScene::stages`]): the
    /// sample's world stages with the scene's tools, skins, contact,
    /// creation and triangulation, which the sample leaves out.
    pub stages: Vec<String>,
}

/// Estimates the largest stable step of `scene` (see the module docs).
///
/// # Errors
///
/// The scene's own validation and build errors.
pub fn estimate(scene: &Scene, base_dir: Option<&Path>) -> Result<StepEstimate, SceneError> {
    Ok(sample(scene, base_dir)?.estimate)
}

/// Builds the sample of `scene` and estimates its stable step.
///
/// # Errors
///
/// The scene's own validation and build errors.
pub fn sample(scene: &Scene, base_dir: Option<&Path>) -> Result<Sample, SceneError> {
    let sample = sample_scene(scene);
    let mut built = sample.build_world(base_dir, None)?;
    let failed = |e: op_dynamics::WorldError| SceneError::Build {
        file: scene.origin().to_string(),
        message: format!("sampling the scene for its stable step: {e}"),
    };
    // Trim points files and lists to the particles nearest each object's
    // first one.
    // More objects than the total allows at their fewest particles: the
    // first ones only.
    let objects = built.objects.len();
    let mut n = per_object(objects);
    let mut keep = (SAMPLE_TOTAL / n).clamp(1, objects.max(1));
    trim(&mut built, n, keep).map_err(failed)?;
    // A dense cloud (many particles within one cut-off) or objects on top
    // of each other have pairs growing as the square of their particles:
    // fewer particles per object, then fewer objects, until the sample's
    // pairs are bounded too.
    for _ in 0..16 {
        built.world.evaluate_forces();
        let pairs = built.world.neighbour_pairs().map_or(0, |l| l.num_pairs());
        if pairs <= SAMPLE_PAIRS || (n <= SAMPLE_PARTICLES_MIN && keep <= 1) {
            break;
        }
        let shrink = (SAMPLE_PAIRS as Real / pairs as Real).sqrt();
        if n > SAMPLE_PARTICLES_MIN {
            n = ((n as Real * shrink) as usize).max(SAMPLE_PARTICLES_MIN);
        } else {
            keep = ((keep as Real * shrink) as usize).max(1);
        }
        trim(&mut built, n, keep).map_err(failed)?;
    }
    let world = &mut built.world;
    let (lambda, slot) = largest_eigenvalue(world);
    let p = world.particles();
    let object = slot
        .and_then(|s| built.objects.get(p.objects()[s] as usize))
        .map_or_else(String::new, |o| o.name.clone());
    let mass = p
        .masses()
        .iter()
        .copied()
        .filter(|m| *m > 0.0)
        .fold(0.0, Real::max);
    let damping_rate = world.params().external.linear_damping / mass.max(Real::MIN_POSITIVE);
    let contact = contact_stiffness(scene, &built);
    let lambda = lambda + contact.as_ref().map_or(0.0, |c| c.0);
    let estimate = StepEstimate {
        lambda,
        object,
        contact,
        dt_max: largest_stable_step(&scene.world.integrator, lambda, damping_rate),
    };
    let skins = scene.objects.iter().filter(|o| o.skin.is_some()).count();
    let stages = crate::built_scene::stage_names(
        built.enabled(),
        scene.tools.iter().map(|t| t.role.name()),
        skins > 0,
        crate::built_scene::contact(skins, !scene.tool_params().1.is_empty()),
        scene.creation.as_ref().map(|c| c.fit.is_some()),
        scene.outputs.triangulation,
    );
    Ok(Sample {
        built,
        estimate,
        stages,
    })
}

/// The bound of skin contact's part of the largest eigenvalue (module
/// docs): the stiffest contact spring of a particle over its mass, and its
/// object; `None` when the scene has no skin contact. `sample` is the
/// scene's sample as built (its objects in scene order, without skins).
pub fn contact_stiffness(scene: &Scene, sample: &crate::BuiltScene) -> Option<(Real, String)> {
    let skinned: Vec<usize> = (0..scene.objects.len())
        .filter(|&o| scene.objects[o].skin.is_some())
        .collect();
    let (_, skin_tools, _) = scene.tool_params();
    let mut stiffest: Option<(Real, String)> = None;
    for &o in &skinned {
        let (Some(skin), Some(built)) = (&scene.objects[o].skin, sample.objects().get(o)) else {
            continue;
        };
        let footprint = built.rest_spacing * built.rest_spacing;
        // Every obstacle and skin it meets may press at once: their springs
        // add.
        let tools: Real = skin_tools
            .iter()
            .filter(|t| t.2.contains(&o))
            .map(|t| t.3 .0)
            .sum();
        let skins = skinned
            .iter()
            .filter(|&&q| q != o)
            .filter_map(|&q| scene.objects[q].skin.as_ref())
            .map(|other| {
                0.5 * (skin.stiffness + other.stiffness)
                    * crate::skins::surface_slope(other)
                    * footprint
            })
            .sum::<Real>();
        let p = sample.world().particles();
        let mass = built
            .ids
            .iter()
            .filter_map(|&id| p.slot_of(id))
            .map(|s| p.masses()[s])
            .filter(|m| *m > 0.0)
            .fold(Real::INFINITY, Real::min);
        let lambda = (tools + skins) / mass;
        if lambda.is_finite() && lambda > 0.0 && stiffest.as_ref().is_none_or(|s| lambda > s.0) {
            stiffest = Some((lambda, scene.objects[o].name.clone()));
        }
    }
    stiffest
}

/// The largest eigenvalue (in magnitude) of the mass-weighted Hessian at
/// the world's current state, and the slot moving most in its mode. Fixed
/// positions and orientations are left out. Velocity-dependent forces
/// (damping, friction) do not change between the two sides of a central
/// difference and cancel. The state is restored afterwards.
pub fn largest_eigenvalue(world: &mut World) -> (Real, Option<usize>) {
    let n = world.particles().len();
    let base_p: Vec<Point3> = world.particles().positions().to_vec();
    let base_q: Vec<Quat> = world.particles().orientations().to_vec();
    // 1/sqrt(mass) per degree of freedom; 0 for fixed ones.
    let weights: Vec<Real> = {
        let p = world.particles();
        (0..6 * n)
            .map(|k| {
                let s = k / 6;
                let flags = p.flags()[s];
                if k % 6 < 3 {
                    if flags.contains(Flags::FIXED_POSITION) {
                        0.0
                    } else {
                        p.inv_masses()[s].sqrt()
                    }
                } else if flags.contains(Flags::FIXED_ORIENTATION) {
                    0.0
                } else {
                    1.0 / p.inertias()[s][k % 3].sqrt()
                }
            })
            .map(|w| if w.is_finite() { w } else { 0.0 })
            .collect()
    };
    let length = spacing_scale(&base_p);
    let set = |world: &mut World, u: &[Real], h: Real| {
        let p = world.particles_mut();
        for s in 0..n {
            let dx = Vec3::new(u[6 * s], u[6 * s + 1], u[6 * s + 2]) * h;
            let dr = Vec3::new(u[6 * s + 3], u[6 * s + 4], u[6 * s + 5]) * h;
            p.set_position(s, base_p[s] + dx);
            p.set_orientation(s, Quat::from_scaled_axis(dr) * base_q[s]);
        }
    };
    // A fixed pseudo-random start (same estimate every time).
    let mut v: Vec<Real> = (0..6 * n)
        .map(|k| {
            let x = ((k as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 11) as Real;
            (x / (1u64 << 53) as Real - 0.5) * weights[k].signum()
        })
        .collect();
    let mut lambda = 0.0;
    for _ in 0..ITERATIONS {
        let norm = v.iter().map(|x| x * x).sum::<Real>().sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            break;
        }
        v.iter_mut().for_each(|x| *x /= norm);
        let u: Vec<Real> = v.iter().zip(&weights).map(|(a, w)| a * w).collect();
        let umax = u.iter().fold(0.0, |m: Real, x| m.max(x.abs()));
        if umax == 0.0 {
            break;
        }
        // Displacements of 1e-6 of the spacing (and radians) at most.
        let h = 1e-6 * length.min(1.0) / umax;
        let mut grad = [vec![0.0; 6 * n], vec![0.0; 6 * n]];
        for (side, sign) in [-1.0, 1.0].into_iter().enumerate() {
            set(world, &u, sign * h);
            let (f, t, _) = world.evaluate_forces();
            for s in 0..n {
                for c in 0..3 {
                    grad[side][6 * s + c] = -f[s][c];
                    grad[side][6 * s + 3 + c] = -t[s][c];
                }
            }
        }
        let y: Vec<Real> = (0..6 * n)
            .map(|k| weights[k] * (grad[1][k] - grad[0][k]) / (2.0 * h))
            .collect();
        lambda = v.iter().zip(&y).map(|(a, b)| a * b).sum::<Real>().abs();
        v = y;
    }
    let p = world.particles_mut();
    for s in 0..n {
        p.set_position(s, base_p[s]);
        p.set_orientation(s, base_q[s]);
    }
    let slot = (0..n).max_by(|&a, &b| {
        let m = |s: usize| (0..6).map(|c| v[6 * s + c].abs()).fold(0.0, Real::max);
        m(a).total_cmp(&m(b))
    });
    (if lambda.is_finite() { lambda } else { 0.0 }, slot)
}

/// A length scale of a point set: its mean nearest-neighbour distance over
/// a few points, or 1 when it has fewer than two.
fn spacing_scale(points: &[Point3]) -> Real {
    let take = points.len().min(32);
    let d: Vec<Real> = (0..take)
        .filter_map(|a| {
            points
                .iter()
                .enumerate()
                .filter(|(b, _)| *b != a)
                .map(|(_, x)| (x - points[a]).norm())
                .filter(|d| *d > 0.0)
                .min_by(|x, y| x.total_cmp(y))
        })
        .collect();
    if d.is_empty() {
        1.0
    } else {
        d.iter().sum::<Real>() / d.len() as Real
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scheme_bounds() {
        let l = 100.0;
        assert_eq!(
            largest_stable_step(&Scheme::VelocityVerlet, l, 0.0),
            Some(0.2)
        );
        assert_eq!(
            largest_stable_step(&Scheme::ExplicitEuler, l, 1.0),
            Some(0.01)
        );
        assert_eq!(largest_stable_step(&Scheme::VelocityVerlet, 0.0, 0.0), None);
    }

    /// A thousand chains on top of each other: eight particles each would
    /// be 8,000 particles within one cut-off of each other, 32 million
    /// pairs at every power iteration (`opsim check` of such a scene ran
    /// past a minute); the sample keeps its first objects only, within
    /// the total and the pairs.
    #[test]
    fn objects_on_top_of_each_other_are_sampled_in_their_first_ones() {
        let chains: Vec<String> = (0..1000)
            .map(|k| {
                format!(r#"(name: "c{k}", material: "m", generator: Chain(count: 40, spacing: 1))"#)
            })
            .collect();
        let text = format!(
            r#"(name: "stack", world: (dt: 0.001, duration: 1),
            materials: {{"m": (spacing: Cohesion((e: 1, r0: 1, alpha: 16, cutoff: 1.5)))}},
            objects: [{}])"#,
            chains.join(",")
        );
        let mut scene =
            crate::load::parse_unvalidated(&text, crate::Format::Ron, "<stack.ron>").unwrap();
        scene.limits = crate::WorkLimits::unlimited();
        let s = sample(&scene, None).unwrap();
        let world = s.built.world();
        let pairs = world.neighbours().map_or(0, |l| l.pairs().num_pairs());
        assert!(
            world.particles().len() <= SAMPLE_TOTAL,
            "{}",
            world.particles().len()
        );
        assert!(pairs <= SAMPLE_PAIRS, "{pairs} pairs");
        assert!(world.particles().len() >= SAMPLE_PARTICLES_MIN);
        assert!(s.estimate.lambda > 0.0);
    }
}

//! Typing and membership (seed 002 §5): two spiral parts joined by a hinge
//! move as one object; two objects collide and repel without merging.
//!
//! Particle types: a hinge interacts completely with every standard
//! particle, a standard particle with its own type and with hinges; other
//! pairs only repel. Objects: complete interactions inside an object,
//! repulsion between objects, so collisions come for free.

use op_dynamics::diagnostics::rest_shape_rms;
use op_dynamics::{Flags, ParticleType, Point3, Real, Vec3};
use op_scene::{BuiltScene, Scene};

/// Positions of `ids` in the current state of `b`'s world.
fn positions(b: &BuiltScene, ids: &[u32]) -> Vec<Point3> {
    let p = b.world().particles();
    ids.iter()
        .map(|&id| p.positions()[p.slot_of(id).expect("id of the scene")])
        .collect()
}

fn centroid(pts: &[Point3]) -> Vec3 {
    pts.iter().map(|p| p.coords).sum::<Vec3>() / pts.len().max(1) as Real
}

/// What [`run_hinge`] measured.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HingeRun {
    /// Position of the hinge in the object's particle order.
    pub hinge: usize,
    /// Number of particles in each part (standard types in order).
    pub part_sizes: Vec<usize>,
    /// True when the hinge particle is unoriented (a free joint).
    pub hinge_unoriented: bool,
    /// Longest distance between consecutive particles (along the chain)
    /// over the run, over the rest spacing.
    pub max_bond: Real,
    /// Longest distance between the hinge and its two chain neighbours
    /// over the run, over the rest spacing.
    pub max_hinge_bond: Real,
    /// Each part's own rest shape error (hinge excluded) at the end.
    pub part_errors_final: Vec<Real>,
    /// Each part's own largest rest shape error over the run.
    pub part_errors_max: Vec<Real>,
    /// The whole object's largest rest shape error.
    pub object_error_max: Real,
    /// The whole object's rest shape error at the end.
    pub object_error_final: Real,
    /// Angle (degrees) at the hinge between its two neighbours, at rest
    /// and at the end.
    pub hinge_angle: (Real, Real),
    /// Distance between the parts' centroids at rest and at the end, over
    /// the rest spacing.
    pub part_distance: (Real, Real),
    /// Wall-clock seconds.
    pub wall_seconds: f64,
}

/// Runs a hinged spiral scene (one object: standard parts joined by one
/// hinge, particles in chain order) through its settle phase and to its
/// end, frame by frame.
///
/// # Errors
///
/// A message when the scene does not build, has no hinge inside the chain,
/// or diverges.
pub fn run_hinge(scene: &Scene) -> Result<HingeRun, String> {
    let clock = std::time::Instant::now();
    let mut b = scene.build(None, None).map_err(|e| e.to_string())?;
    b.settle().map_err(|e| format!("while settling: {e}"))?;
    let object = b.objects()[0].clone();
    let ids = &object.ids;
    let (kinds, unoriented): (Vec<ParticleType>, Vec<bool>) = {
        let p = b.world().particles();
        ids.iter()
            .map(|&id| {
                let s = p.slot_of(id).expect("id of the scene");
                (p.kinds()[s], p.flags()[s].contains(Flags::UNORIENTED))
            })
            .unzip()
    };
    let hinge = kinds
        .iter()
        .position(|k| *k == ParticleType::Hinge)
        .filter(|&h| h > 0 && h + 1 < ids.len())
        .ok_or("no hinge inside the chain")?;
    let mut types: Vec<u16> = kinds
        .iter()
        .filter_map(|k| match k {
            ParticleType::Standard(t) => Some(*t),
            ParticleType::Hinge => None,
        })
        .collect();
    types.sort_unstable();
    types.dedup();
    let parts: Vec<Vec<usize>> = types
        .iter()
        .map(|t| {
            (0..ids.len())
                .filter(|&i| kinds[i] == ParticleType::Standard(*t))
                .collect()
        })
        .collect();
    let r0 = object.rest_spacing;
    let angle = |p: &[Point3]| {
        (p[hinge - 1] - p[hinge])
            .angle(&(p[hinge + 1] - p[hinge]))
            .to_degrees()
    };
    let part_distance = |p: &[Point3]| {
        let c: Vec<Vec3> = parts
            .iter()
            .map(|idx| centroid(&idx.iter().map(|&i| p[i]).collect::<Vec<_>>()))
            .collect();
        if c.len() >= 2 {
            (c[1] - c[0]).norm() / r0
        } else {
            0.0
        }
    };
    let mut run = HingeRun {
        hinge,
        part_sizes: parts.iter().map(Vec::len).collect(),
        hinge_unoriented: unoriented[hinge],
        part_errors_max: vec![0.0; parts.len()],
        part_errors_final: vec![0.0; parts.len()],
        hinge_angle: (angle(&object.rest), 0.0),
        part_distance: (part_distance(&object.rest), 0.0),
        ..HingeRun::default()
    };
    let frames = (b.duration() * b.frame_rate()).round() as usize;
    let t0 = b.world().time();
    let frame_rate = b.frame_rate();
    for k in 0..=frames {
        if k > 0 {
            b.world_mut()
                .advance_to(t0 + k as Real / frame_rate)
                .map_err(|e| e.to_string())?;
        }
        let p = positions(&b, ids);
        for w in p.windows(2) {
            run.max_bond = run.max_bond.max((w[1] - w[0]).norm() / r0);
        }
        for j in [hinge - 1, hinge + 1] {
            run.max_hinge_bond = run.max_hinge_bond.max((p[j] - p[hinge]).norm() / r0);
        }
        for (k, idx) in parts.iter().enumerate() {
            let rest: Vec<Point3> = idx.iter().map(|&i| object.rest[i]).collect();
            let now: Vec<Point3> = idx.iter().map(|&i| p[i]).collect();
            let e = rest_shape_rms(&rest, &now) / r0;
            run.part_errors_max[k] = run.part_errors_max[k].max(e);
            run.part_errors_final[k] = e;
        }
        let e = rest_shape_rms(&object.rest, &p) / r0;
        run.object_error_max = run.object_error_max.max(e);
        run.object_error_final = e;
        run.hinge_angle.1 = angle(&p);
        run.part_distance.1 = part_distance(&p);
    }
    run.wall_seconds = clock.elapsed().as_secs_f64();
    Ok(run)
}

/// What [`run_collision`] measured.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CollisionRun {
    /// Smallest distance between particles of the two objects over the
    /// run, over the rest spacing.
    pub min_distance: Real,
    /// Scene time of the closest approach.
    pub closest_at: Real,
    /// Largest repulsive component of the net force of the second object
    /// on the first, along the line of their centroids.
    pub max_repulsion: Real,
    /// Largest attractive component of that force (0 when it never
    /// attracts).
    pub max_attraction: Real,
    /// Distance between the objects (closest particles) at the end, over
    /// the rest spacing.
    pub final_distance: Real,
    /// Centroid separation at the closest approach and at the end, over
    /// the rest spacing.
    pub separation: (Real, Real),
    /// Each object's rest shape error at the end.
    pub final_errors: Vec<Real>,
    /// Each object's largest rest shape error.
    pub max_errors: Vec<Real>,
    /// Number of samples.
    pub samples: usize,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
}

/// Runs a scene of two objects through its settle phase and to its end,
/// sampling every `sample_dt` (scene time): their closest distance, the
/// net force of the second object on the first once every force window is
/// over (all of each object's particle forces summed, with the linear
/// damping force taken out: internal forces of an object cancel, so what
/// remains is the interaction between the objects), and their rest shape
/// errors.
///
/// # Errors
///
/// A message when the scene does not build, has fewer than two objects,
/// or diverges.
pub fn run_collision(scene: &Scene, sample_dt: Real) -> Result<CollisionRun, String> {
    let clock = std::time::Instant::now();
    let mut b = scene.build(None, None).map_err(|e| e.to_string())?;
    if b.objects().len() < 2 {
        return Err("needs two objects".into());
    }
    b.settle().map_err(|e| format!("while settling: {e}"))?;
    let (oa, ob) = (b.objects()[0].clone(), b.objects()[1].clone());
    let r0 = oa.rest_spacing;
    let beta = b.world().params().external.linear_damping;
    let forces_end = scene.forces.iter().map(|f| f.end).fold(0.0, Real::max);
    let mut run = CollisionRun {
        min_distance: Real::INFINITY,
        max_errors: vec![0.0; 2],
        final_errors: vec![0.0; 2],
        ..CollisionRun::default()
    };
    let samples = (b.duration() / sample_dt).round() as usize;
    let t0 = b.world().time();
    for k in 0..=samples {
        if k > 0 {
            b.world_mut()
                .advance_to(t0 + k as Real * sample_dt)
                .map_err(|e| e.to_string())?;
        }
        let (pa, pb) = (positions(&b, &oa.ids), positions(&b, &ob.ids));
        let d = pa
            .iter()
            .flat_map(|x| pb.iter().map(move |y| (x - y).norm()))
            .fold(Real::INFINITY, Real::min)
            / r0;
        let (ca, cb) = (centroid(&pa), centroid(&pb));
        if d < run.min_distance {
            run.min_distance = d;
            run.closest_at = b.scene_time();
            run.separation.0 = (ca - cb).norm() / r0;
        }
        run.final_distance = d;
        run.separation.1 = (ca - cb).norm() / r0;
        for (o, obj) in [&oa, &ob].into_iter().enumerate() {
            let e = op_scene::run::rest_shape_error(&b, obj);
            run.max_errors[o] = run.max_errors[o].max(e);
            run.final_errors[o] = e;
        }
        if b.scene_time() > forces_end {
            let slots: Vec<usize> = {
                let p = b.world().particles();
                oa.ids
                    .iter()
                    .map(|&id| p.slot_of(id).expect("id"))
                    .collect()
            };
            let momentum: Vec3 = {
                let p = b.world().particles();
                slots.iter().map(|&s| p.velocities()[s]).sum()
            };
            let (f, _, _) = b.world_mut().evaluate_forces();
            let net: Vec3 = slots.iter().map(|&s| f[s]).sum::<Vec3>() + beta * momentum;
            let along = net.dot(&(ca - cb).normalize());
            run.max_repulsion = run.max_repulsion.max(along);
            run.max_attraction = run.max_attraction.max(-along);
        }
        run.samples += 1;
    }
    run.wall_seconds = clock.elapsed().as_secs_f64();
    Ok(run)
}

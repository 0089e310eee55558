//! Worlds in mixed precision (`WorldParams::precision`): one 12-6
//! Lennard-Jones spacing material runs the cluster kernel in `f32` lanes.
//! The same bits at any thread count, forces within the `f32` bound of
//! the double-precision ones, and energy kept as well as in double
//! precision over a run.

use op_dynamics::interactions::{LennardJonesParams, Spacing};
use op_dynamics::{
    Material, ParticleDesc, Particles, Point3, Precision, Real, Vec3, World, WorldParams,
};
use op_test_support::{in_pool, Rng};

/// A jittered cubic block of `side³` particles of spacing 1.1 with random
/// velocities (a warm Lennard-Jones solid about to melt), offset far from
/// the origin so that absolute `f32` coordinates would lose digits;
/// `mirror`: reflected through the plane x = 0.
fn block(side: usize, mirror: bool) -> Particles {
    let mut rng = Rng::new(31);
    let mut p = Particles::new();
    for k in 0..side * side * side {
        let (i, j, l) = (k % side, (k / side) % side, k / (side * side));
        let at = Point3::new(i as Real, j as Real, l as Real) * 1.1 + rng.vec3(0.1);
        let mut at = at + Vec3::new(1000.0, -500.0, 250.0);
        if mirror {
            at.x = -at.x;
        }
        let mut d = ParticleDesc::at(at);
        d.velocity = rng.vec3(0.5);
        p.push(d).unwrap();
    }
    p
}

fn lj() -> Material {
    Material {
        spacing: Some(Spacing::LennardJones(LennardJonesParams {
            r0: (2.0 as Real).powf(1.0 / 6.0),
            taper: 0.1,
            ..Default::default()
        })),
        ..Material::empty()
    }
}

fn world(precision: Precision) -> World {
    let params = WorldParams {
        dt: 2e-3,
        precision,
        ..Default::default()
    };
    World::new(block(12, false), &[lj()], params).unwrap()
}

/// Positions and velocities, as bits.
fn bits(w: &World) -> Vec<u64> {
    let p = w.particles();
    p.positions()
        .iter()
        .map(|x| x.coords)
        .chain(p.velocities().iter().copied())
        .flat_map(|v| [v.x, v.y, v.z])
        .map(Real::to_bits)
        .collect()
}

#[test]
fn mixed_precision_gives_the_same_bits_at_any_thread_count() {
    let run = |threads| {
        in_pool(threads, || {
            let mut w = world(Precision::Mixed);
            for _ in 0..40 {
                w.step().unwrap();
            }
            bits(&w)
        })
    };
    let one = run(1);
    assert_eq!(one, run(2), "1 vs 2 threads");
    assert_eq!(one, run(3), "1 vs 3 threads");
}

/// The forces of a mixed-precision world are the double-precision ones
/// within the `f32` bound: a pair force `U'(r) r̂` of the 12-6 potential
/// changes by about `13 |F| δr / r` for an error `δr` of the distance, and
/// `δr` is one `f32` rounding of the coordinates relative to the block's
/// corner (extent `L`, about 13 here), so `δF / |F| <= 13 L eps32 / r`
/// with `r >= 0.8`; the `f32` arithmetic adds a few tens of roundings.
/// Per particle the bound applies to the largest force.
#[test]
fn mixed_forces_are_double_forces_within_f32_rounding() {
    let forces = |precision| {
        let mut w = world(precision);
        let (f, t, e) = w.evaluate_forces();
        (f.to_vec(), t.to_vec(), e)
    };
    let (fd, _, ed) = forces(Precision::Double);
    let (fm, tm, em) = forces(Precision::Mixed);
    let scale = fd.iter().fold(0.0, |a: Real, f| a.max(f.norm()));
    assert!(scale > 1.0, "{scale}");
    let eps = Real::from(f32::EPSILON);
    let bound = (13.0 * 13.5 / 0.8 + 50.0) * eps * scale;
    let worst = fd
        .iter()
        .zip(&fm)
        .fold(0.0, |a: Real, (d, m)| a.max((d - m).norm()));
    assert!(
        worst <= bound,
        "largest force difference {worst}, bound {bound}"
    );
    assert!(worst > 0.0, "mixed precision ran the double kernel");
    assert!(tm.iter().all(|t| *t == Vec3::zeros()));
    assert!((ed - em).abs() <= 1e-5 * ed.abs(), "energy {ed} vs {em}");
}

/// Over 500 steps the total energy of the mixed-precision world drifts no
/// more than a few times the double-precision world's (velocity Verlet:
/// both oscillate at the size the step sets); a force inconsistent with
/// the energy would drift by orders of magnitude more.
#[test]
fn mixed_precision_keeps_the_energy_of_double_precision() {
    let drift = |precision| {
        let mut w = world(precision);
        let e0 = w.diagnostics().total;
        let mut worst: Real = 0.0;
        for _ in 0..500 {
            w.step().unwrap();
            worst = worst.max((w.diagnostics().total - e0).abs());
        }
        (worst, e0)
    };
    let (double, e0) = drift(Precision::Double);
    let (mixed, _) = drift(Precision::Mixed);
    assert!(
        double > 0.0 && double < 1e-2 * e0.abs(),
        "double: {double} of {e0}"
    );
    assert!(mixed <= 3.0 * double, "mixed {mixed} vs double {double}");
}

/// A world restored to the state of another world whose neighbour list
/// has the same build count, particle count and pair count (the block
/// mirrored: the same pairs under other indices) steps exactly as a new
/// world restored to that state: the cluster pairs derived from its own
/// list are dropped, not reused.
#[test]
fn restoring_another_state_forgets_the_cluster_pairs() {
    let params = WorldParams {
        dt: 2e-3,
        precision: Precision::Mixed,
        ..Default::default()
    };
    let mirrored = || World::new(block(12, true), &[lj()], params.clone()).unwrap();
    let mut a = world(Precision::Mixed);
    a.step().unwrap();
    let mut b = mirrored();
    b.step().unwrap();
    let other = b.state();
    let run = |w: &mut World| {
        for _ in 0..20 {
            w.step().unwrap();
        }
        bits(w)
    };
    a.restore(other.clone()).unwrap();
    let mut fresh = mirrored();
    fresh.restore(other).unwrap();
    assert_eq!(run(&mut a), run(&mut fresh));
}

/// Which worlds run in mixed precision: the 12-6 block that asked; not
/// the same block in double precision, nor a mixed one of another spacing
/// potential (cohesion) or with orientation terms, which run in double.
#[test]
fn only_spacing_only_12_6_worlds_run_mixed() {
    assert!(world(Precision::Mixed).runs_mixed_precision());
    assert!(!world(Precision::Double).runs_mixed_precision());
    let params = WorldParams {
        precision: Precision::Mixed,
        ..Default::default()
    };
    let oriented = Material {
        coplanarity: 1.0,
        ..lj()
    };
    let cohesion = op_test_support::spacing_material();
    for m in [oriented, cohesion] {
        let w = World::new(block(4, false), &[m], params.clone()).unwrap();
        assert!(!w.runs_mixed_precision(), "{m:?}");
    }
}

/// A mixed world never searches the particle rows of its neighbour list
/// (the cluster kernel searches its own from the reference positions);
/// asking for them ([`World::neighbour_pairs`]) gives the list a search
/// of the reference positions gives, and leaves the trajectory unchanged.
/// A double world keeps its rows.
#[test]
fn mixed_worlds_search_particle_rows_only_on_request() {
    let mut quiet = world(Precision::Mixed);
    let mut asked = world(Precision::Mixed);
    for step in 0..300 {
        quiet.step().unwrap();
        asked.step().unwrap();
        if step % 25 != 0 {
            continue;
        }
        let rows = asked.neighbour_pairs().unwrap().clone();
        let list = asked.neighbours().unwrap();
        assert!(list.has_rows());
        let mut want = op_dynamics::neighbours::PairList::new();
        op_dynamics::neighbours::search(
            list.backend(),
            list.reference_positions(),
            list.radius(),
            &mut want,
        );
        assert_eq!(
            rows.iter_pairs().collect::<Vec<_>>(),
            want.iter_pairs().collect::<Vec<_>>()
        );
    }
    let list = quiet.neighbours().unwrap();
    assert!(list.rebuilds() > 2, "{} rebuilds", list.rebuilds());
    assert!(!list.has_rows(), "a mixed world searched its particle rows");
    assert_eq!(list.pairs().num_pairs(), 0);
    assert_eq!(bits(&quiet), bits(&asked));
    let mut double = world(Precision::Double);
    for _ in 0..10 {
        double.step().unwrap();
        assert!(double.neighbours().unwrap().has_rows());
    }
}

/// A mixed world saved mid-run (its list without particle rows), encoded,
/// decoded and restored into a new world steps bit for bit as the world
/// that went on.
#[test]
fn a_saved_mixed_world_resumes_bit_for_bit() {
    let mut a = world(Precision::Mixed);
    for _ in 0..120 {
        a.step().unwrap();
    }
    assert!(!a.neighbours().unwrap().has_rows());
    let bytes = op_dynamics::checkpoint::encode(&a.state());
    let mut b = world(Precision::Mixed);
    b.restore(op_dynamics::checkpoint::decode(&bytes).unwrap())
        .unwrap();
    for _ in 0..120 {
        a.step().unwrap();
        b.step().unwrap();
    }
    assert_eq!(bits(&a), bits(&b));
}

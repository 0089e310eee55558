//! Plasticity of the remembered curvature (`op_dynamics::plasticity`, seed
//! 000 fig. 12b): the current-curvature estimate on exact spheres and
//! circles, the yield band, the exact relaxation to the band edge,
//! determinism at 1 and 2 threads, particle insertion and removal, and the
//! stage running only when a material asks for it.

use op_dynamics::interactions::{CohesionParams, Spacing, WeightParams};
use op_dynamics::neighbours::NeighbourList;
use op_dynamics::plasticity::{current_curvature, Plasticity};
use op_dynamics::{
    ExternalParams, Flags, ForceWindow, Material, NeighbourBackend, ParticleDesc, Particles,
    Point3, Real, Vec3, World, WorldParams,
};
use op_test_support::{desc_of, in_pool, Rng};

const RADIUS: Real = 4.0;

/// `n` points on the sphere of radius `RADIUS` (Fibonacci spiral).
fn sphere_points(n: usize) -> Vec<Vec3> {
    let golden = std::f64::consts::PI * (3.0 - (5.0 as Real).sqrt());
    (0..n)
        .map(|k| {
            let z = 1.0 - 2.0 * (k as Real + 0.5) / n as Real;
            let rho = (1.0 - z * z).sqrt();
            let phi = golden * k as Real;
            Vec3::new(rho * phi.cos(), rho * phi.sin(), z)
        })
        .collect()
}

/// A shell of `RADIUS` with spacing about 1 (200 particles), normals
/// `sign` times the outward ones, rest curvature `kappa`, `flags` on every
/// particle.
fn shell(sign: Real, kappa: Real, flags: Flags) -> Particles {
    let mut p = Particles::new();
    for u in sphere_points(200) {
        let mut d = ParticleDesc::at(Point3::from(u * RADIUS)).with_normal(u * sign);
        d.curvature = kappa;
        d.flags = flags;
        p.push(d).unwrap();
    }
    p
}

/// Cohesion spacing (cut-off 1.5 r0), form, a little co-planarity, and
/// optionally plasticity.
fn material(plasticity: Option<Plasticity>) -> Material {
    Material {
        spacing: Some(Spacing::Cohesion(CohesionParams {
            e: 200.0,
            alpha: 16.0,
            cutoff: Some(1.5),
            ..Default::default()
        })),
        weight: WeightParams {
            cutoff: 1.5,
            ..Default::default()
        },
        form: 2.0,
        coplanarity: 0.2,
        plasticity,
        ..Default::default()
    }
}

fn params() -> WorldParams {
    WorldParams {
        dt: 2e-3,
        external: ExternalParams {
            linear_damping: 1.0,
            angular_damping: 1.0,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// `κ̂` of every particle, with a list built for the current positions.
fn estimates(p: &Particles, m: &Material) -> Vec<Option<Real>> {
    let prepared = [m.prepare().unwrap()];
    let mut list = NeighbourList::new(NeighbourBackend::AllPairs, 1.5, 0.0);
    list.rebuild(p.positions());
    (0..p.len())
        .map(|i| current_curvature(p, &prepared, &list, i, None))
        .collect()
}

#[test]
fn current_curvature_of_a_sphere_is_one_over_its_radius() {
    let m = material(None);
    for (sign, expected) in [(1.0, 1.0 / RADIUS), (-1.0, -1.0 / RADIUS)] {
        let p = shell(sign, 0.3, Flags::empty());
        let est = estimates(&p, &m);
        for (i, k) in est.iter().enumerate() {
            let k = k.unwrap_or_else(|| panic!("particle {i} has neighbours"));
            assert!((k - expected).abs() < 1e-12, "{i}: {k} vs {expected}");
        }
    }
    // An unoriented particle has no estimate.
    let p = shell(1.0, 0.25, Flags::UNORIENTED);
    assert!(estimates(&p, &m).iter().all(Option::is_none));
}

#[test]
fn current_curvature_of_a_circle_is_one_over_its_radius() {
    let m = material(None);
    for radius in [2.0, 5.0] {
        let n = (2.0 * std::f64::consts::PI * radius / 0.9).round() as usize;
        let mut p = Particles::new();
        for k in 0..n {
            let t = 2.0 * std::f64::consts::PI * k as Real / n as Real;
            let u = Vec3::new(t.cos(), t.sin(), 0.0);
            p.push(ParticleDesc::at(Point3::from(u * radius)).with_normal(u))
                .unwrap();
        }
        for k in estimates(&p, &m) {
            assert!((k.unwrap() - 1.0 / radius).abs() < 1e-12, "{k:?}");
        }
    }
}

/// A shell settling under cohesion, form and co-planarity (the Fibonacci
/// sampling is not at rest: cohesion shrinks it from radius 4 to about
/// 3.66 by t = 4, where the form term, remembering 1/4, balances it): the
/// estimates follow the shell's current radius, not the remembered one.
/// One ring of neighbours on an irregular sampling makes each estimate
/// noisy (measured: κ̂ × radius from 0.70 to 1.59, RMS 0.15 about the
/// mean), so the claim is on the mean: 1.02, where the remembered
/// curvature would give 3.66 / 4 = 0.915.
#[test]
fn a_settling_shell_is_estimated_by_its_current_radius() {
    let kappa = 1.0 / RADIUS;
    let mut w = World::new(
        shell(1.0, kappa, Flags::empty()),
        &[material(None)],
        params(),
    )
    .unwrap();
    w.advance_to(4.0).unwrap();
    let p = w.particles();
    let n = p.len() as Real;
    let c = p.positions().iter().map(|x| x.coords).sum::<Vec3>() / n;
    let radius = p
        .positions()
        .iter()
        .map(|x| (x.coords - c).norm())
        .sum::<Real>()
        / n;
    let scaled: Vec<Real> = estimates(p, &material(None))
        .into_iter()
        .map(|k| k.expect("every particle has neighbours") * radius)
        .collect();
    let mean = scaled.iter().sum::<Real>() / n;
    let rms = (scaled.iter().map(|k| (k - mean).powi(2)).sum::<Real>() / n).sqrt();
    println!("mean radius {radius:.3}: κ̂ × radius mean {mean:.4}, rms {rms:.4}");
    assert!(radius < 0.97 * RADIUS, "the shell shrank: {radius}");
    assert!((mean - 1.0).abs() < 0.05, "{mean}");
}

/// A frozen shell (every particle fixed) keeps `κ̂ = 1/R`: a remembered
/// curvature within the band stays put, one beyond it decays exactly
/// exponentially to the band edge and stops there.
#[test]
fn beyond_the_yield_band_the_memory_relaxes_to_its_edge() {
    let fixed = Flags::FIXED_POSITION | Flags::FIXED_ORIENTATION;
    let hat = 1.0 / RADIUS;
    let rule = Plasticity {
        yield_curvature: 0.05,
        rate: 3.0,
    };
    // Within the band: the same bits.
    let inside = hat + 0.04;
    let mut w = World::new(shell(1.0, inside, fixed), &[material(Some(rule))], params()).unwrap();
    w.advance_to(1.0).unwrap();
    assert!(w.particles().curvatures().iter().all(|&k| k == inside));

    // Beyond it, both signs of the excess.
    for start in [hat + 0.25, hat - 0.25] {
        let mut w =
            World::new(shell(1.0, start, fixed), &[material(Some(rule))], params()).unwrap();
        let s = (start - hat).signum();
        for t in [0.1, 0.5, 1.0] {
            w.advance_to(t).unwrap();
            let expected = hat + s * (0.05 + 0.2 * (-3.0 * t).exp());
            for &k in w.particles().curvatures() {
                assert!((k - expected).abs() < 1e-12, "t = {t}: {k} vs {expected}");
            }
        }
        w.advance_to(20.0).unwrap();
        for &k in w.particles().curvatures() {
            let e = (k - hat) * s;
            assert!((e - 0.05).abs() < 1e-12, "stops at the band edge: {e}");
        }
    }
}

/// A pushed shell with plasticity: its remembered curvature changes where
/// it is pushed, the same bits at 1 and 2 threads.
fn pushed(threads: usize) -> (Vec<u64>, Vec<Real>) {
    in_pool(threads, || {
        let mut rng = Rng::new(3);
        let mut p = shell(1.0, 1.0 / RADIUS, Flags::empty());
        for i in 0..p.len() {
            let x = p.positions()[i] + rng.vec3(0.05);
            p.set_position(i, x);
        }
        let top: Vec<u32> = (0..p.len() as u32)
            .filter(|&i| p.positions()[i as usize].z > 3.3)
            .collect();
        let mut params = params();
        params.external.forces = vec![ForceWindow {
            particles: top,
            force: [0.0, 0.0, -8.0],
            start: 0.0,
            end: 0.4,
            ramp: 0.1,
        }];
        let rule = Plasticity {
            yield_curvature: 0.02,
            rate: 20.0,
        };
        let mut w = World::new(p, &[material(Some(rule))], params).unwrap();
        w.advance_to(0.8).unwrap();
        let p = w.particles();
        let mut by_id = vec![0.0; p.len()];
        for (s, &id) in p.ids().iter().enumerate() {
            by_id[id as usize] = p.curvatures()[s];
        }
        let bits = p
            .positions()
            .iter()
            .flat_map(|x| x.coords.iter().copied().collect::<Vec<_>>())
            .chain(p.curvatures().iter().copied())
            .map(Real::to_bits)
            .collect();
        (bits, by_id)
    })
}

#[test]
fn plastic_update_is_the_same_at_one_and_two_threads() {
    let (one, kappas) = pushed(1);
    let (two, _) = pushed(2);
    assert_eq!(one, two);
    let moved = kappas
        .iter()
        .filter(|&&k| (k - 1.0 / RADIUS).abs() > 1e-9)
        .count();
    println!("{moved} of {} remembered curvatures changed", kappas.len());
    assert!(moved > 0, "the push yields somewhere");
}

/// Removing and inserting particles keeps the plastic stage working: after
/// the edit, stepping gives the same bits (remembered curvatures included)
/// as a world built directly from the edited set, and a plastic particle
/// inserted into an elastic world switches the stage on.
#[test]
fn insertion_and_removal_keep_plasticity_working() {
    let rule = Plasticity {
        yield_curvature: 0.0,
        rate: 5.0,
    };
    let materials = [material(Some(rule)), material(None)];
    let mut a = World::new(shell(1.0, 0.3, Flags::empty()), &materials, params()).unwrap();
    for _ in 0..20 {
        a.step().unwrap();
    }
    assert_eq!(a.remove_particles(&[5, 77, 150]).unwrap(), 3);
    let mut d = ParticleDesc::at(Point3::new(0.0, 0.0, RADIUS + 0.1)).with_normal(Vec3::z());
    d.curvature = 0.5;
    let fresh = a.insert_particles(&[d]).unwrap();
    let p = a.particles();
    // The direct world's id k is the edited world's slot k at the edit.
    let ids_at_edit = p.ids().to_vec();
    let descs: Vec<_> = (0..p.len()).map(|s| desc_of(p, s)).collect();
    let mut direct = Particles::new();
    for d in descs {
        direct.push(d).unwrap();
    }
    // `push` renormalizes orientations: copy the exact bits.
    for s in 0..p.len() {
        direct.set_orientation(s, p.orientations()[s]);
    }
    let mut b = World::new(direct, &materials, params()).unwrap();
    for _ in 0..30 {
        a.step().unwrap();
        b.step().unwrap();
    }
    let (pa, pb) = (a.particles(), b.particles());
    for (k, &id) in ids_at_edit.iter().enumerate() {
        let (sa, sb) = (pa.slot_of(id).unwrap(), pb.slot_of(k as u32).unwrap());
        assert_eq!(pa.positions()[sa], pb.positions()[sb], "particle {id}");
        assert_eq!(
            pa.curvatures()[sa].to_bits(),
            pb.curvatures()[sb].to_bits(),
            "particle {id}"
        );
    }
    let s = a.particles().slot_of(fresh[0]).unwrap();
    assert_ne!(
        a.particles().curvatures()[s],
        0.5,
        "the new particle yields"
    );

    // An elastic world gains the stage when a plastic particle arrives.
    let mut c = World::new(
        shell(1.0, 0.25, Flags::empty()),
        &[material(None), material(Some(rule))],
        params(),
    )
    .unwrap();
    c.step().unwrap();
    assert_eq!(c.last_report().seconds_of("plasticity"), 0.0);
    assert!(!c.enabled().contains(&"term:plasticity".to_string()));
    let mut d = ParticleDesc::at(Point3::new(0.0, 0.0, RADIUS + 0.3)).with_normal(Vec3::z());
    d.material = 1;
    d.curvature = 2.0;
    let id = c.insert_particles(&[d]).unwrap()[0];
    assert!(c.enabled().contains(&"term:plasticity".to_string()));
    c.step().unwrap();
    let s = c.particles().slot_of(id).unwrap();
    assert!(c.particles().curvatures()[s] < 2.0);
    // The elastic particles' memory stays.
    let p = c.particles();
    assert!((0..p.len())
        .filter(|&i| i != s)
        .all(|i| p.curvatures()[i] == 0.25));
}

#[test]
fn plasticity_needs_the_form_term_and_valid_values() {
    let rule = Plasticity {
        yield_curvature: 0.1,
        rate: 1.0,
    };
    let no_form = Material {
        form: 0.0,
        ..material(Some(rule))
    };
    let e = World::new(shell(1.0, 0.25, Flags::empty()), &[no_form], params())
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("materials[0].plasticity") && e.contains("form > 0"),
        "{e}"
    );
    let bad = material(Some(Plasticity { rate: -1.0, ..rule }));
    let e = bad.prepare().unwrap_err().to_string();
    assert!(e.contains("plasticity.rate") && e.contains("must"), "{e}");
}

/// In a bonded material the estimate counts only bonded pairs, as the
/// force evaluation does: a stray particle of the same object near the
/// shell but beyond the bond radius (it only repels) does not bend the
/// estimate of its neighbours.
#[test]
fn bonded_materials_estimate_over_bonded_pairs_only() {
    let bonded = Material {
        bonds: Some(op_dynamics::bonds::BondParams {
            radius: 1.2,
            break_length: None,
        }),
        ..material(Some(Plasticity {
            yield_curvature: 0.0,
            rate: 1.0,
        }))
    };
    let mut p = shell(1.0, 1.0 / RADIUS, Flags::empty());
    // 1.3 above the north pole particle, beyond the bond radius of every
    // shell particle but within the interaction cut-off of the pole's.
    let pole = p.positions()[0];
    let stray = pole + pole.coords.normalize() * 1.3;
    p.push(ParticleDesc::at(stray).with_normal(pole.coords.normalize()))
        .unwrap();
    let w = World::new(p, &[bonded], params()).unwrap();
    let bonds = w.bonds().expect("a bonded material");
    assert!(
        !bonds.contains(0, 200),
        "the stray is not bonded to the pole"
    );
    let mut list = NeighbourList::new(NeighbourBackend::AllPairs, 1.5, 0.0);
    let q = w.particles();
    list.rebuild(q.positions());
    let pole_slot = q.slot_of(0).unwrap();
    let with = current_curvature(q, w.materials(), &list, pole_slot, Some(bonds)).unwrap();
    let without = current_curvature(q, w.materials(), &list, pole_slot, None).unwrap();
    assert!(
        (with - 1.0 / RADIUS).abs() < 1e-9,
        "bonded pairs only: {with} (the shell's 1/R is {})",
        1.0 / RADIUS
    );
    assert!(
        (without - with).abs() > 0.05,
        "the stray would bend the estimate: {without} against {with}"
    );
}

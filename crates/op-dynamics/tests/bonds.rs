//! Explicit bonds (`op_dynamics::bonds`, `Material::bonds`): which pairs
//! form, how they couple (complete when bonded, repulsion only otherwise),
//! forces still the gradient of the energy with some bonds broken, momentum
//! conserved, breaking deterministic at 1 and 2 threads and any slot order,
//! bonds kept by id through insertion and removal.

use op_dynamics::bonds::BondParams;
use op_dynamics::{
    ExternalParams, ForceWindow, Material, ParticleDesc, Particles, Point3, Real, World,
    WorldParams,
};
use op_test_support::{
    assert_energy_gradients, assert_momentum_conserved, full_material, hex_sheet, in_pool,
    random_cluster, spacing_material, Rng,
};

fn bonded(m: Material, radius: Real, break_length: Real) -> Material {
    Material {
        bonds: Some(BondParams {
            radius,
            break_length: Some(break_length),
        }),
        ..m
    }
}

fn sheet(nx: usize, ny: usize) -> Particles {
    let mut p = Particles::new();
    for x in hex_sheet(nx, ny, 1.0) {
        p.push(ParticleDesc::at(x)).unwrap();
    }
    p
}

fn energy(w: &mut World) -> Real {
    w.evaluate_forces().2
}

/// A hexagonal sheet of spacing 1 bonded within 1.2 bonds exactly its
/// nearest neighbours: `ny (nx - 1)` along the rows and `2 nx - 1` between
/// consecutive rows. Particles of another object, or another standard
/// type, do not bond. Worlds without bonded materials have no store and
/// list no bond term.
#[test]
fn a_sheet_bonds_its_nearest_neighbours() {
    let (nx, ny) = (7, 5);
    let m = bonded(full_material(false, 0.0), 1.2, 1.4);
    let w = World::new(sheet(nx, ny), &[m], WorldParams::default()).unwrap();
    let b = w.bonds().expect("a bonded material makes a store");
    assert_eq!(b.len(), ny * (nx - 1) + (ny - 1) * (2 * nx - 1));
    assert_eq!(b.broken(), 0);
    // Every bond is a nearest-neighbour pair, listed once, sorted by id.
    let p = w.particles();
    for &(a, c) in b.pairs() {
        assert!(a < c);
        let d =
            (p.positions()[p.slot_of(a).unwrap()] - p.positions()[p.slot_of(c).unwrap()]).norm();
        assert!((d - 1.0).abs() < 1e-9, "bond ({a}, {c}) of length {d}");
        assert!(b.contains(a, c) && b.contains(c, a));
    }
    assert!(b.pairs().windows(2).all(|w| w[0] < w[1]));
    assert!(w.enabled().contains(&"term:bonds".to_string()));
    assert!(w.enabled().contains(&"term:repulsion".to_string()));

    // Two objects side by side (rows alternate objects): bonds only within
    // rows.
    let mut two = Particles::new();
    for (k, x) in hex_sheet(nx, ny, 1.0).into_iter().enumerate() {
        let mut d = ParticleDesc::at(x);
        d.object = ((k / nx) % 2) as u32;
        two.push(d).unwrap();
    }
    let w2 = World::new(two, &[m], WorldParams::default()).unwrap();
    assert_eq!(w2.bonds().unwrap().len(), ny * (nx - 1));

    // Without bonds one object does not repel itself.
    let plain = World::new(
        sheet(nx, ny),
        &[full_material(false, 0.0)],
        WorldParams::default(),
    )
    .unwrap();
    assert!(plain.bonds().is_none());
    assert!(!plain
        .enabled()
        .iter()
        .any(|t| t.contains("bonds") || t.contains("repulsion")));
}

/// A bonded pair has exactly the energy of the same pair without bonds
/// (complete interaction); a bond-governed pair that is not bonded has
/// exactly the energy of the same pair in two objects (repulsion only).
#[test]
fn bonded_pairs_interact_completely_others_only_repel() {
    let mut rng = Rng::new(3);
    let pair = |objects: [u32; 2], rng: &mut Rng| {
        let mut p = Particles::new();
        for (k, x) in [Point3::origin(), Point3::new(1.05, 0.1, -0.05)]
            .into_iter()
            .enumerate()
        {
            let mut d = ParticleDesc::at(x);
            d.orientation = rng.quat(0.3);
            d.object = objects[k];
            p.push(d).unwrap();
        }
        p
    };
    for base in [full_material(false, 0.0), spacing_material()] {
        let p1 = pair([0, 0], &mut rng);
        let p2 = {
            // Same state, two objects.
            let mut p = p1.clone();
            let mut q = Particles::new();
            for s in 0..2 {
                let mut d = ParticleDesc::at(p.positions()[s]);
                d.orientation = p.orientations()[s];
                d.object = s as u32;
                q.push(d).unwrap();
            }
            std::mem::swap(&mut p, &mut q);
            p
        };
        let e = |p: &Particles, m: Material| {
            let mut w = World::new(p.clone(), &[m], WorldParams::default()).unwrap();
            energy(&mut w)
        };
        let complete = e(&p1, base);
        let repulsion = e(&p2, base);
        assert!(
            (complete - repulsion).abs() > 1e-3,
            "the case must tell them apart: {complete} vs {repulsion}"
        );
        assert_eq!(e(&p1, bonded(base, 1.2, 2.0)).to_bits(), complete.to_bits());
        assert_eq!(
            e(&p1, bonded(base, 1.0, 2.0)).to_bits(),
            repulsion.to_bits()
        );
    }
}

/// Stretches a bonded cluster so that some of its bonds exceed their break
/// length, and takes one tiny step: those bonds break, the others stay.
fn partly_broken(material: Material, objects: u32) -> World {
    let mut rng = Rng::new(17);
    let p = random_cluster(&mut rng, 64, objects);
    let params = WorldParams {
        dt: 1e-9,
        ..Default::default()
    };
    let mut w = World::new(p, &[bonded(material, 1.25, 1.3)], params).unwrap();
    let formed = w.bonds().unwrap().len();
    for s in 0..w.particles().len() {
        let x = w.particles().positions()[s];
        w.particles_mut()
            .set_position(s, Point3::from(x.coords * 1.08));
    }
    let report = w.step().unwrap().clone();
    let b = w.bonds().unwrap();
    assert!(report.bonds_broken > 0, "some bonds break");
    assert_eq!(b.broken(), report.bonds_broken as u64);
    assert_eq!(b.len() + report.bonds_broken, formed);
    assert!(b.len() > formed / 4, "many stay: {} of {formed}", b.len());
    w
}

/// With some bonds broken, forces and torques are still the gradient of
/// the world's energy (central differences through the whole pipeline).
#[test]
fn forces_are_energy_gradients_with_broken_bonds() {
    for (case, material, objects) in [
        ("full isotropic", full_material(false, 0.0), 1),
        ("full anisotropic, two objects", full_material(true, 0.0), 2),
        ("spacing only", spacing_material(), 1),
    ] {
        let mut w = partly_broken(material, objects);
        assert_energy_gradients(&mut w, &[0usize, 9, 22, 41, 63], case);
    }
}

/// Internal forces of a partly broken bonded world (with friction)
/// conserve linear and angular momentum.
#[test]
fn broken_bonds_conserve_momentum() {
    for (material, objects) in [
        (full_material(true, 2.0), 1),
        (full_material(false, 0.0), 2),
        (spacing_material(), 1),
    ] {
        let mut w = partly_broken(material, objects);
        assert_momentum_conserved(&mut w, "partly broken");
    }
}

/// A bonded strip pulled at both ends by force windows: its bonds break.
/// The run gives the same bits and the same bonds at 1 and 2 threads; the
/// same particles stored in another slot order (ids kept) form the same
/// bonds and break the same ones.
#[test]
fn breaking_is_deterministic_at_any_thread_count_and_slot_order() {
    let (nx, ny) = (12, 4);
    let ends = |col: usize| -> Vec<u32> { (0..ny).map(|r| (r * nx + col) as u32).collect() };
    let params = WorldParams {
        dt: 2e-3,
        external: ExternalParams {
            linear_damping: 0.5,
            forces: vec![
                ForceWindow {
                    particles: ends(0),
                    force: [-3.0, 0.0, 0.0],
                    start: 0.0,
                    end: Real::INFINITY,
                    ramp: 0.0,
                },
                ForceWindow {
                    particles: ends(nx - 1),
                    force: [3.0, 0.0, 0.0],
                    start: 0.0,
                    end: Real::INFINITY,
                    ramp: 0.0,
                },
            ],
            ..Default::default()
        },
        ..Default::default()
    };
    let material = bonded(full_material(false, 0.5), 1.2, 1.3);
    let run = |p: Particles, threads: usize| {
        in_pool(threads, || {
            let mut w = World::new(p, &[material], params.clone()).unwrap();
            let formed = w.bonds().unwrap().pairs().to_vec();
            let mut broken = 0;
            for _ in 0..1500 {
                broken += w.step().unwrap().bonds_broken;
            }
            let p = w.particles();
            let state: Vec<[u64; 3]> = (0..p.id_bound() as u32)
                .map(|id| {
                    let x = p.positions()[p.slot_of(id).unwrap()];
                    [x.x.to_bits(), x.y.to_bits(), x.z.to_bits()]
                })
                .collect();
            let b = w.bonds().unwrap();
            assert_eq!(broken as u64, b.broken());
            (formed, b.pairs().to_vec(), broken, state)
        })
    };
    let one = run(sheet(nx, ny), 1);
    let two = run(sheet(nx, ny), 2);
    assert!(one.2 > 0, "the pull breaks bonds");
    assert_eq!(one, two);
    // Reversed slot order, same ids.
    let mut shuffled = sheet(nx, ny);
    let order: Vec<u32> = (0..shuffled.len() as u32).rev().collect();
    shuffled.permute(&order);
    let other = run(shuffled, 2);
    assert_eq!(other.0, one.0, "same bonds formed");
    assert_eq!(other.1, one.1, "same bonds left");
    println!("{} bonds formed, {} broken by the pull", one.0.len(), one.2);
}

/// Removing a particle drops its bonds and no other; inserting one bonds
/// it to the live particles within the radius, by id, and a broken bond
/// between old particles stays broken.
#[test]
fn bonds_follow_insertion_and_removal_by_id() {
    let (nx, ny) = (6, 5);
    let m = bonded(spacing_material(), 1.2, 1.5);
    let mut w = World::new(sheet(nx, ny), &[m], WorldParams::default()).unwrap();
    let before = w.bonds().unwrap().pairs().to_vec();
    // An interior particle (row 2, column 2) has six bonds.
    let victim = (2 * nx + 2) as u32;
    let degree = before
        .iter()
        .filter(|&&(a, b)| a == victim || b == victim)
        .count();
    assert_eq!(degree, 6);
    let x = w.particles().positions()[w.particles().slot_of(victim).unwrap()];
    w.remove_particles(&[victim]).unwrap();
    let after: Vec<(u32, u32)> = w.bonds().unwrap().pairs().to_vec();
    let expected: Vec<(u32, u32)> = before
        .iter()
        .copied()
        .filter(|&(a, b)| a != victim && b != victim)
        .collect();
    assert_eq!(after, expected);
    // Steps re-sort the slots; bonds are by id and do not change.
    for _ in 0..5 {
        w.step().unwrap();
    }
    assert_eq!(w.bonds().unwrap().pairs(), &expected[..]);
    // Put a particle back in the hole: it bonds to the six around it.
    let new = w.insert_particles(&[ParticleDesc::at(x)]).unwrap()[0];
    let b = w.bonds().unwrap();
    assert_eq!(b.len(), before.len());
    let partners: Vec<u32> = b
        .pairs()
        .iter()
        .filter_map(|&(a, c)| (c == new).then_some(a))
        .collect();
    let old_partners: Vec<u32> = before
        .iter()
        .filter_map(|&(a, c)| {
            (a == victim || c == victim).then_some(if a == victim { c } else { a })
        })
        .collect();
    assert_eq!(partners, old_partners);
    // A world whose particles had no bonded material gets a store when a
    // bonded particle is inserted, with bonds to it only.
    let plain = Material {
        bonds: None,
        ..spacing_material()
    };
    let mut w = World::new(sheet(nx, ny), &[plain, m], WorldParams::default()).unwrap();
    assert!(w.bonds().is_none());
    let mut d = ParticleDesc::at(Point3::new(-1.0, 0.0, 0.0));
    d.material = 1;
    let new = w.insert_particles(&[d]).unwrap()[0];
    assert_eq!(w.bonds().unwrap().pairs(), &[(0, new)]);
}

/// Two bonded particles pulled apart: the step that takes them beyond the
/// break length reports one broken bond, and from then on the pair only
/// repels (its energy is the repulsion's, positive, no longer the
/// spacing potential's, negative).
#[test]
fn an_over_stretched_bond_breaks_once() {
    let mut p = Particles::new();
    p.push(ParticleDesc::at(Point3::origin())).unwrap();
    p.push(ParticleDesc::at(Point3::new(1.0, 0.0, 0.0)))
        .unwrap();
    let params = WorldParams {
        dt: 1e-3,
        external: ExternalParams {
            forces: vec![
                ForceWindow {
                    particles: vec![0],
                    force: [-20.0, 0.0, 0.0],
                    start: 0.0,
                    end: Real::INFINITY,
                    ramp: 0.0,
                },
                ForceWindow {
                    particles: vec![1],
                    force: [20.0, 0.0, 0.0],
                    start: 0.0,
                    end: Real::INFINITY,
                    ramp: 0.0,
                },
            ],
            ..Default::default()
        },
        ..Default::default()
    };
    let break_length = 1.25;
    let mut w = World::new(p, &[bonded(spacing_material(), 1.2, break_length)], params).unwrap();
    assert!(energy(&mut w) < 0.0, "bonded: in the spacing well");
    let mut reports = Vec::new();
    for _ in 0..2000 {
        let broken = w.step().unwrap().bonds_broken;
        let x = w.particles().positions();
        let d = (x[1] - x[0]).norm();
        reports.push((broken, d));
        if w.bonds().unwrap().is_empty() && d > 1.4 {
            break;
        }
    }
    let at = reports.iter().position(|r| r.0 > 0).expect("it breaks");
    assert_eq!(reports[at].0, 1);
    assert!(reports[at].1 > break_length, "{:?}", reports[at]);
    assert!(at == 0 || reports[at - 1].1 <= break_length);
    assert!(reports[at + 1..].iter().all(|r| r.0 == 0));
    assert_eq!(w.bonds().unwrap().broken(), 1);
    assert!(energy(&mut w) >= 0.0, "unbonded: repulsion only");
}

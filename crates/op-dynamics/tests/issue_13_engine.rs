//! Issue 13, item 7: engine defects pinned at the world level (neighbour
//! radius errors instead of panics).

use op_dynamics::interactions::{LennardJonesParams, RepulsionParams, Spacing, WeightParams};
use op_dynamics::{
    Material, NeighbourParams, ParticleDesc, Particles, Point3, Real, Vec3, World, WorldParams,
};

fn two_particles(objects: [u32; 2]) -> Particles {
    let mut p = Particles::new();
    for (k, o) in objects.into_iter().enumerate() {
        let mut d = ParticleDesc::at(Point3::new(1.1 * k as Real, 0.0, 0.0));
        d.object = o;
        d.angular_velocity = Vec3::new(0.1, 0.0, 0.2);
        p.push(d).unwrap();
    }
    p
}

fn with_skin(skin: Real) -> WorldParams {
    WorldParams {
        neighbours: NeighbourParams {
            skin,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// A cut-off or skin of 1e308 passed validation and panicked inside
/// `NeighbourList::new`; now the skin is bounded by `validate()` and a
/// cut-off whose neighbour radius overflows is a typed error.
#[test]
fn issue_13_huge_cutoff_or_skin_is_an_error_not_a_panic() {
    // The skin alone: refused by validate, saying what is allowed.
    let e = WorldParams::validate(&with_skin(1e308), 2)
        .unwrap_err()
        .to_string();
    assert!(e.contains("neighbours.skin") && e.contains("<= 10"), "{e}");
    let e = World::new(
        two_particles([0, 0]),
        &[Material::default()],
        with_skin(1e308),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("neighbours.skin"), "{e}");

    // Each cut-off at 1e308: fine with the default skin (finite radius
    // 1.2e308, the world steps), an error when the radius overflows.
    let huge = 1e308;
    let materials = [
        (
            "weight",
            Material {
                weight: WeightParams {
                    cutoff: huge,
                    ..Default::default()
                },
                coplanarity: 1.0,
                ..Material::empty()
            },
            [0, 0],
        ),
        (
            "repulsion",
            Material {
                repulsion: RepulsionParams {
                    cutoff: huge,
                    ..Default::default()
                },
                ..Material::empty()
            },
            [0, 1],
        ),
        (
            "lennard-jones",
            Material {
                spacing: Some(Spacing::LennardJones(LennardJonesParams {
                    cutoff: huge,
                    ..Default::default()
                })),
                ..Material::empty()
            },
            [0, 0],
        ),
    ];
    for (name, m, objects) in materials {
        let mut w = World::new(two_particles(objects), &[m], with_skin(0.2)).unwrap();
        assert_eq!(w.neighbours().unwrap().cutoff(), huge, "{name}");
        for _ in 0..3 {
            w.step().unwrap();
        }
        let e = World::new(two_particles(objects), &[m], with_skin(1.0))
            .err()
            .unwrap_or_else(|| panic!("{name}: accepted an infinite neighbour radius"))
            .to_string();
        assert!(
            e.contains("materials[0]") && e.contains("not a finite number"),
            "{name}: {e}"
        );
        // Also when the material is not used by any particle yet (it could
        // be by inserted particles).
        let e = World::new(
            two_particles(objects),
            &[Material::default(), m],
            with_skin(1.0),
        )
        .err()
        .unwrap()
        .to_string();
        assert!(e.contains("materials[1]"), "{name}: {e}");
    }
}

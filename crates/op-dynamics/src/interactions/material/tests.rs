//! Tests of the material module.

use super::*;
use crate::interactions::cohesion::CohesionParams;
use crate::interactions::lennard_jones::LennardJonesParams;
use crate::interactions::weight::WeightShape;

#[test]
fn default_material_is_valid_spacing_only() {
    let m = Material::default().prepare().unwrap();
    assert_eq!(m.enabled_terms(), vec!["cohesion", "repulsion"]);
    assert!(!m.has_orientation_terms());
    assert!((m.spacing_cutoff() - 2.08).abs() < 0.01);
    assert_eq!(m.cutoff(), m.spacing_cutoff());
    assert_eq!(m.orientation_cutoff(), 0.0);
    assert_eq!(m.friction(), 0.0);
    assert_eq!(
        Material::empty().prepare().unwrap().enabled_terms(),
        Vec::<&str>::new()
    );
    assert_eq!(Material::empty().prepare().unwrap().cutoff(), 0.0);
}

#[test]
fn cutoff_is_the_largest_enabled_one() {
    let m = Material {
        spacing: Some(Spacing::LennardJones(LennardJonesParams::default())),
        weight: WeightParams {
            cutoff: 3.0,
            ..Default::default()
        },
        coplanarity: 1.0,
        spin: 0.5,
        friction: 0.2,
        ..Material::default()
    }
    .prepare()
    .unwrap();
    assert_eq!(m.cutoff(), 3.0);
    assert_eq!(m.spacing_cutoff(), 2.5);
    assert_eq!(m.repulsion_cutoff(), 2.0);
    assert_eq!(m.friction(), 0.2);
    assert_eq!(
        m.enabled_terms(),
        vec!["lennard_jones", "coplanarity", "spin", "repulsion"]
    );
    // Disabled orientation terms do not widen the radius.
    let n = Material {
        weight: WeightParams {
            cutoff: 9.0,
            ..Default::default()
        },
        ..Material::default()
    }
    .prepare()
    .unwrap();
    assert!(n.cutoff() < 2.1);
}

#[test]
fn validation_names_the_field_path() {
    let d = Material::default();
    let cases: Vec<(Material, &str)> = vec![
        (
            Material {
                coplanarity: Real::NAN,
                ..d
            },
            "`coplanarity` = NaN",
        ),
        (
            Material {
                conormality: -1.0,
                ..d
            },
            "`conormality` = -1",
        ),
        (
            Material {
                cocircularity: Real::INFINITY,
                ..d
            },
            "cocircularity",
        ),
        (Material { form: -0.5, ..d }, "`form`"),
        (
            Material {
                spin: Real::NAN,
                ..d
            },
            "`spin`",
        ),
        (
            Material {
                friction: -0.1,
                ..d
            },
            "`friction`",
        ),
        (
            Material {
                spacing: Some(Spacing::Cohesion(CohesionParams {
                    alpha: Real::NAN,
                    ..Default::default()
                })),
                ..d
            },
            "`spacing.cohesion.alpha` = NaN",
        ),
        (
            Material {
                spacing: Some(Spacing::LennardJones(LennardJonesParams {
                    m: 20.0,
                    ..Default::default()
                })),
                ..d
            },
            "`spacing.lennard_jones.n`",
        ),
        (
            Material {
                weight: WeightParams {
                    shape: WeightShape::Anisotropic { b: -1.0 },
                    ..Default::default()
                },
                ..d
            },
            "`weight.shape.b`",
        ),
        (
            Material {
                repulsion: RepulsionParams {
                    lambda: 0.0,
                    ..Default::default()
                },
                ..d
            },
            "`repulsion.lambda`",
        ),
        (
            Material {
                bonds: Some(BondParams {
                    radius: 1.2,
                    break_length: Some(1.0),
                }),
                ..d
            },
            "`bonds.break_length` = 1",
        ),
    ];
    for (m, needle) in cases {
        let e = m.prepare().unwrap_err().to_string();
        assert!(e.contains(needle), "{needle}: {e}");
        assert!(
            e.contains("must") || e.contains(">"),
            "says what is allowed: {e}"
        );
    }
}

/// Normalized co-planarity and co-circularity depend on `r` only
/// through its direction: a pair passing close to coincidence saw its
/// energy jump by up to `4 α ψ` per side between two steps, and a free
/// sphere of the first `elastic_shell` preset (cohesion and co-circularity)
/// gained energy by bursts and tore
/// apart. Below `r_near` they now fade to zero: energy and gradients
/// vanish at coincidence, stay bounded (`~ α/r_near`, not `~ α/|r|`) and
/// match finite differences; from `r_near` on nothing changes.
#[test]
fn normalized_direction_terms_fade_to_zero_at_coincidence() {
    use crate::interactions::cohesion::CohesionParams as Cp;
    use crate::interactions::pair::{evaluate_pair, Coupling};
    use crate::interactions::test_support::{check_fd, check_momentum, geometry, Rng};
    let (w_p, w_c) = (0.7, 5.0);
    let shell = Material {
        spacing: Some(Spacing::Cohesion(Cp {
            cutoff: Some(1.5),
            ..Default::default()
        })),
        coplanarity: w_p,
        cocircularity: w_c,
        ..Material::default()
    }
    .prepare()
    .unwrap();
    let bare = Material {
        weight: WeightParams {
            a: 0.8,
            shape: WeightShape::Anisotropic { b: 0.5 },
            ..Default::default()
        },
        coplanarity: w_p,
        cocircularity: w_c,
        ..Material::empty()
    }
    .prepare()
    .unwrap();
    // r_near: a quarter of the well's position (about r0), or of `a`.
    let r_w = shell.spacing_well().0;
    assert!((r_w - 1.0).abs() < 1e-6, "{r_w}");
    assert_eq!(shell.near_radius(), NEAR_FRACTION * r_w);
    assert_eq!(bare.near_radius(), NEAR_FRACTION * 0.8);
    let c = Coupling::Complete { oriented: true };
    let mut rng = Rng::new(41);
    for m in [&shell, &bare] {
        let near = m.near_radius();
        let mut worst: Real = 0.0;
        for k in 0..400 {
            let dist = near * (k as Real + 0.5) / 400.0;
            let (bi, bj) = crate::interactions::test_support::random_pair(&mut rng, dist);
            // Finite differences (steps 1e-4) need |r| well above the step.
            if k % 8 == 4 && k >= 40 {
                check_fd(m, m, &bi, &bj, c);
                check_momentum(m, m, &bi, &bj, c);
            }
            let r = bj.p - bi.p;
            let g = geometry(r, bi.normal(), bj.normal(), bi.tangent(), 0.0);
            let o = m.orientation(&g);
            // Bounded: |d(Sφ)/dr| <= (max S' φ + max S/r |∇φ|) ψ <= 17.1 α / r_near.
            worst = worst.max(o.d_r.norm() * near / (w_p + w_c));
            let res = evaluate_pair(&bi.view(m), &bj.view(m), c);
            assert!(res.force_i.norm().is_finite());
        }
        assert!(worst < 18.0, "gradient {worst} alpha / r_near");
        // At coincidence: no energy, no force, no torque.
        for _ in 0..50 {
            let (bi, bj) = crate::interactions::test_support::random_pair(&mut rng, 1e-9);
            let g = geometry(bj.p - bi.p, bi.normal(), bj.normal(), bi.tangent(), 0.0);
            let o = m.orientation(&g);
            // (Unfaded, |∂φ/∂r| would be up to 8 α ψ / |r| ~ 1e11 here.)
            assert!(o.energy.abs() < 1e-20, "{o:?}");
            assert!(o.d_r.norm() < 1e-12 && o.d_ni.norm() < 1e-20, "{o:?}");
        }
        // From r_near on: the terms exactly as before.
        for k in 1..50 {
            let dist = near * (1.0 + k as Real / 10.0);
            let (bi, bj) = crate::interactions::test_support::random_pair(&mut rng, dist);
            let g = geometry(bj.p - bi.p, bi.normal(), bj.normal(), bi.tangent(), 0.0);
            let psi = m.orientation_weight(&g.r, g.dist, &g.n_i);
            let (p, q) = (coplanarity::normalized(&g), cocircularity::normalized(&g));
            let phi = (0.0 + w_p * p.energy) + w_c * q.energy;
            assert_eq!(m.orientation(&g).energy, psi * phi);
        }
    }
}

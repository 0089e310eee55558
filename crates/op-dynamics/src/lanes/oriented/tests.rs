use super::*;
use crate::interactions::test_support::{check_fd, random_pair, Rng};
use crate::interactions::{
    evaluate_pair, Coupling, LennardJonesParams, Material, PreparedMaterial, Spacing, WeightParams,
    WeightShape,
};
use pulp::Simd;

const COMPLETE: Coupling = Coupling::Complete { oriented: true };

/// A material the oriented lanes take: 12-6 Lennard-Jones spacing with
/// every orientation term but spin.
fn material(normalized: bool, anisotropic: bool, form: Real) -> PreparedMaterial {
    Material {
        spacing: Some(Spacing::LennardJones(LennardJonesParams {
            r0: (2.0 as Real).powf(1.0 / 6.0),
            taper: 0.1,
            ..Default::default()
        })),
        weight: WeightParams {
            cutoff: 2.5,
            shape: if anisotropic {
                WeightShape::Anisotropic { b: 0.6 }
            } else {
                WeightShape::Isotropic
            },
            ..Default::default()
        },
        coplanarity: 0.7,
        conormality: 0.4,
        cocircularity: 0.3,
        form,
        normalized,
        ..Material::empty()
    }
    .prepare()
    .unwrap()
}

/// Bits of a result, signed zeros made `+0` (they add alike).
fn bits(o: Option<OrientedResult>) -> Option<[u64; 10]> {
    o.map(|(f, ti, tj, e)| {
        [f.x, f.y, f.z, ti.x, ti.y, ti.z, tj.x, tj.y, tj.z, e].map(|x| (x + 0.0).to_bits())
    })
}

/// The dispatched oriented lanes give the scalar pair's bits
/// (`evaluate_pair` of a complete oriented pair, `None` beyond the
/// cut-off) on random pairs: spread over the range, near coincidence
/// (inside the fade), across both tapers, at and just beyond the
/// cut-off, coincident and NaN; normalized and raw terms, isotropic and
/// anisotropic weights, with and without the form term, zero curvatures
/// among them; rows of every length mod `LANES`.
#[test]
fn oriented_lanes_equal_the_scalar_pair_bit_for_bit() {
    let mut rng = Rng::new(181);
    let mut checked = 0;
    for normalized in [true, false] {
        for anisotropic in [false, true] {
            for form in [0.0, 0.9] {
                let m = material(normalized, anisotropic, form);
                let c = m.oriented_lane_constants().expect("lane material");
                let rc = m.cutoff();
                let cutoff2 = rc * rc;
                let mut dists: Vec<Real> = (0..90).map(|_| rng.range(0.05, 2.7)).collect();
                dists.extend([
                    0.01,
                    0.2,
                    m.near_radius(),
                    2.25,
                    2.4999,
                    rc,
                    rc * (1.0 + 1e-12),
                ]);
                let (bi, _) = random_pair(&mut rng, 1.0);
                let mut p = vec![bi.p];
                let mut normals = vec![bi.normal()];
                let mut kappa = vec![bi.kappa];
                for (k, &d) in dists.iter().enumerate() {
                    let (_, bj) = random_pair(&mut rng, d);
                    let dir = rng.unit_vector();
                    p.push(bi.p + dir * d);
                    normals.push(bj.normal());
                    kappa.push(if k % 7 == 0 { 0.0 } else { bj.kappa });
                }
                p.push(bi.p);
                normals.push(rng.unit_vector());
                kappa.push(0.3);
                p.push(Point3::new(Real::NAN, 0.0, 0.0));
                normals.push(rng.unit_vector());
                kappa.push(0.3);
                let n = p.len();
                let input = OrientedInput {
                    c: &c,
                    cutoff2,
                    p: &p,
                    normals: &normals,
                    curvatures: &kappa,
                };
                let mut out = OrientedRow::default();
                for len in [1, 7, 8, 9, 17, n - 1] {
                    let row: Vec<u32> = (1..n).rev().take(len).map(|j| j as u32).collect();
                    oriented_row(pulp::Arch::new(), &input, 0, &row, &mut out);
                    for (k, &j) in row.iter().enumerate() {
                        let j = j as usize;
                        let view = |q: usize| crate::interactions::ParticleView {
                            position: p[q],
                            normal: normals[q],
                            tangent: Vec3::zeros(),
                            kappa: kappa[q],
                            material: &m,
                        };
                        let d2 = (p[j] - p[0]).norm_squared();
                        let scalar = (d2 <= cutoff2 || d2.is_nan()).then(|| {
                            let r = evaluate_pair(&view(0), &view(j), COMPLETE);
                            (r.force_j, r.torque_i, r.torque_j, r.energy)
                        });
                        assert_eq!(
                            bits(scalar),
                            bits(out.get(k, cutoff2)),
                            "pair (0, {j}) at {}, normalized {normalized}, \
                             anisotropic {anisotropic}, form {form}",
                            d2.sqrt()
                        );
                        checked += usize::from(scalar.is_some_and(|s| s.3 != 0.0));
                    }
                }
            }
        }
    }
    assert!(checked > 800, "{checked}");
}

/// The material the lanes evaluate is the one whose forces and torques
/// match finite differences of its energy (the scalar pair the lanes
/// equal bit for bit): every lane material, pairs over the whole range.
#[test]
fn lane_materials_match_finite_differences() {
    let mut rng = Rng::new(182);
    for normalized in [true, false] {
        for anisotropic in [false, true] {
            let m = material(normalized, anisotropic, 0.9);
            for _ in 0..20 {
                let d = rng.range(0.9, 2.45);
                let (bi, bj) = random_pair(&mut rng, d);
                check_fd(&m, &m, &bi, &bj, COMPLETE);
            }
        }
    }
}

/// Spin, other spacings and materials without orientation terms stay on
/// the scalar kernel.
#[test]
fn only_lane_materials_have_lane_constants() {
    let base = Material {
        spacing: Some(Spacing::LennardJones(LennardJonesParams::default())),
        coplanarity: 0.5,
        ..Material::empty()
    };
    assert!(base.prepare().unwrap().oriented_lane_constants().is_some());
    for m in [
        Material { spin: 0.3, ..base },
        Material {
            spacing: Some(Spacing::default()),
            ..base
        },
        Material {
            coplanarity: 0.0,
            ..base
        },
        Material {
            spacing: Some(Spacing::LennardJones(LennardJonesParams {
                n: 10.0,
                m: 4.0,
                ..Default::default()
            })),
            ..base
        },
    ] {
        assert!(m.prepare().unwrap().oriented_lane_constants().is_none());
    }
}

/// Every instruction set the lanes compile for gives the same bits: the
/// dispatched one, AVX2 (`x86-64-v3`, 4 lanes) when the CPU has it, and
/// pulp's scalar fallback, on one row of random pairs of every material
/// shape.
#[test]
fn every_instruction_set_gives_the_same_bits() {
    let mut rng = Rng::new(184);
    for (normalized, anisotropic) in [(true, false), (false, true)] {
        let m = material(normalized, anisotropic, 0.9);
        let c = m.oriented_lane_constants().unwrap();
        let rc = m.cutoff();
        let n = 60;
        let p: Vec<Point3> = (0..n)
            .map(|k| {
                let d = if k == 0 {
                    0.0
                } else {
                    rng.range(0.05, 1.1 * rc)
                };
                Point3::origin() + rng.unit_vector() * d
            })
            .collect();
        let normals: Vec<Vec3> = (0..n).map(|_| rng.unit_vector()).collect();
        let kappa: Vec<Real> = (0..n).map(|_| rng.range(-1.0, 1.0)).collect();
        let input = OrientedInput {
            c: &c,
            cutoff2: rc * rc,
            p: &p,
            normals: &normals,
            curvatures: &kappa,
        };
        let row: Vec<u32> = (1..n as u32).collect();
        let run = |isa: &dyn Fn(Row<'_, '_>)| {
            let mut out = OrientedRow::default();
            out.resize(row.len());
            isa(Row {
                input: &input,
                i: 0,
                row: &row,
                out: &mut out,
            });
            (0..row.len())
                .map(|k| bits(out.get(k, rc * rc)))
                .collect::<Vec<_>>()
        };
        let dispatched = run(&|r| pulp::Arch::new().dispatch(r));
        assert!(dispatched.iter().flatten().count() > 20);
        assert_eq!(
            dispatched,
            run(&|r| Simd::vectorize(pulp::Scalar::new(), r))
        );
        #[cfg(target_arch = "x86_64")]
        if let Some(v3) = pulp::x86::V3::try_new() {
            assert_eq!(dispatched, run(&|r| Simd::vectorize(v3, r)));
        }
    }
}

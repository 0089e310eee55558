//! The generators make what they promise: counts, spacings, curvature
//! laws, normals pointing outward, particles on their surfaces.

use op_dynamics::{Point3, Real, Vec3};
use op_scene::{parse_scene, BuiltScene, CurvatureLaw, Format, Generator};
use op_test_support::scenes_dir;

/// A scene from RON text, validated and built without a directory.
fn build_ron(text: &str) -> BuiltScene {
    let scene = parse_scene(text, Format::Ron, "<test>").unwrap_or_else(|e| panic!("{e}"));
    scene.build(None, None).unwrap_or_else(|e| panic!("{e}"))
}

fn generate(g: &Generator) -> op_scene::generators::Generated {
    g.generate(None, "<test>", "generator")
        .unwrap_or_else(|e| panic!("{e}"))
}

fn assert_unit_normals(normals: &[Vec3]) {
    for n in normals {
        assert!((n.norm() - 1.0).abs() < 1e-12, "{n}");
    }
}

#[test]
fn spiral_has_its_count_spacing_curvatures_and_outward_normals() {
    let (count, h, k0, k1) = (41, 0.5, 0.4, 0.1);
    let g = generate(&Generator::Spiral {
        count,
        spacing: h,
        curvature_start: k0,
        curvature_end: k1,
        law: CurvatureLaw::Linear,
        center: [1.0, -2.0, 0.5],
        normal: [0.0, 1.0, 1.0],
    });
    assert_eq!(g.len(), count);
    assert_unit_normals(&g.normals);
    let plane = Vec3::new(0.0, 1.0, 1.0).normalize();
    let centroid = g.positions.iter().map(|p| p.coords).sum::<Vec3>() / count as Real;
    assert!((centroid - Vec3::new(1.0, -2.0, 0.5)).norm() < 1e-12);
    for i in 0..count {
        let k = k0 + (k1 - k0) * i as Real / (count - 1) as Real;
        assert!((g.curvatures[i] - k).abs() < 1e-12);
        assert!(
            g.normals[i].dot(&plane).abs() < 1e-12,
            "normal in the plane"
        );
        assert!(
            ((g.positions[i] - g.positions[0]).dot(&plane)).abs() < 1e-12,
            "planar"
        );
        if i + 1 < count {
            // Arc length h between neighbours: chord h (1 - κ²h²/24 + ...).
            let chord = (g.positions[i + 1] - g.positions[i]).norm();
            let km = k.max(g.curvatures[i + 1]);
            assert!(
                (chord - h).abs() <= h * km * km * h * h / 24.0 * 1.01 + 1e-9,
                "{i}: {chord}"
            );
        }
        if i > 0 && i + 1 < count {
            // The curve bends away from the normal (towards p - n/κ).
            let second =
                g.positions[i + 1] + g.positions[i - 1].coords - g.positions[i].coords * 2.0;
            let bend = second.coords.dot(&g.normals[i]);
            assert!(bend < 0.0, "{i}: normal not outward");
            // Discrete curvature |second| / h² matches κ to O(h).
            assert!((second.coords.norm() / (h * h) - k).abs() < 0.01, "{i}");
            let tangent = g.positions[i + 1] - g.positions[i - 1];
            assert!(tangent.normalize().dot(&g.normals[i]).abs() < 1e-3);
        }
    }
}

#[test]
fn geometric_spiral_curvature_grows_by_a_constant_ratio() {
    let (count, h, k0, k1) = (13, 1.0, 0.2, 0.8);
    let g = generate(&Generator::Spiral {
        count,
        spacing: h,
        curvature_start: k0,
        curvature_end: k1,
        law: CurvatureLaw::Geometric,
        center: [0.0; 3],
        normal: [0.0, 0.0, 1.0],
    });
    assert_eq!(g.len(), count);
    assert_unit_normals(&g.normals);
    let ratio = (k1 / k0).powf(1.0 / (count - 1) as Real);
    for i in 0..count {
        let k = k0 * ratio.powi(i as i32);
        assert!((g.curvatures[i] - k).abs() < 1e-12, "{i}");
        if i + 1 < count {
            let chord = (g.positions[i + 1] - g.positions[i]).norm();
            assert!(chord < h && chord > h * (1.0 - 0.8 * 0.8 / 24.0) - 1e-9);
        }
        if i > 0 && i + 1 < count {
            let second =
                g.positions[i + 1] + g.positions[i - 1].coords - g.positions[i].coords * 2.0;
            assert!(second.coords.dot(&g.normals[i]) < 0.0, "{i}: outward");
            // Discrete curvature: κ (1 - κ²h²/12) to leading order.
            let discrete = second.coords.norm() / (h * h);
            assert!((discrete - k).abs() < 0.06 * k, "{i}: {discrete} vs {k}");
        }
    }
    // Mixed signs have no geometric law.
    let bad = Generator::Spiral {
        count,
        spacing: h,
        curvature_start: 0.2,
        curvature_end: -0.2,
        law: CurvatureLaw::Geometric,
        center: [0.0; 3],
        normal: [0.0, 0.0, 1.0],
    };
    let e = bad.validate(None, "<t>", "g").unwrap_err().to_string();
    assert!(e.contains("g.Spiral.law") && e.contains("same sign"), "{e}");
}

#[test]
fn sphere_shell_particles_lie_on_the_sphere_with_outward_normals() {
    let (radius, spacing) = (3.0, 0.5);
    let c = [1.0, 2.0, 3.0];
    let g = generate(&Generator::SphereShell {
        radius,
        spacing,
        center: c,
    });
    let expected = (4.0 * std::f64::consts::PI * radius * radius * 2.0
        / (3f64.sqrt() * spacing * spacing))
        .round() as usize;
    assert_eq!(g.len(), expected);
    assert_unit_normals(&g.normals);
    for ((p, n), k) in g.positions.iter().zip(&g.normals).zip(&g.curvatures) {
        let r = p - Point3::from(c);
        assert!((r.norm() - radius).abs() < 1e-12);
        assert!((r / radius - n).norm() < 1e-12);
        assert_eq!(*k, 1.0 / radius);
    }
    let built = build_ron(
        "(name: \"s\", materials: {\"m\": ()}, objects: [(name: \"s\", material: \"m\", generator: SphereShell(radius: 3, spacing: 0.5))])",
    );
    let r0 = built.objects()[0].rest_spacing;
    assert!(r0 > 0.8 * spacing && r0 < 1.1 * spacing, "{r0}");
}

#[test]
fn hex_sheet_chain_torus_list_and_points_generators() {
    let g = generate(&Generator::HexSheet {
        nx: 7,
        ny: 5,
        spacing: 0.3,
        center: [0.0, 0.0, 1.0],
        normal: [1.0, 0.0, 0.0],
        noise: 0.0,
        seed: 0,
    });
    assert_eq!(g.len(), 35);
    for (i, p) in g.positions.iter().enumerate() {
        assert!((p.x - 0.0).abs() < 1e-12, "in the plane x = 0");
        assert_eq!(g.normals[i], Vec3::x());
        let nearest = g
            .positions
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != i)
            .map(|(_, q)| (q - p).norm())
            .fold(Real::INFINITY, Real::min);
        assert!((nearest - 0.3).abs() < 1e-12);
    }
    let noisy = |seed| {
        generate(&Generator::HexSheet {
            nx: 4,
            ny: 4,
            spacing: 1.0,
            center: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
            noise: 0.2,
            seed,
        })
    };
    assert_eq!(noisy(3), noisy(3), "seeded");
    assert_ne!(noisy(3), noisy(4));
    assert!(noisy(3).positions.iter().any(|p| p.z.abs() > 1e-3));

    let g = generate(&Generator::Chain {
        count: 4,
        spacing: 2.0,
        start: [1.0, 0.0, 0.0],
        direction: [0.0, 3.0, 0.0],
        normal: [0.0, 0.0, -1.0],
    });
    assert_eq!(g.positions[3], Point3::new(1.0, 6.0, 0.0));
    assert_eq!(g.normals[0], -Vec3::z());

    let (major, minor) = (4.0, 1.5);
    let g = generate(&Generator::TorusShell {
        major,
        minor,
        spacing: 0.5,
        center: [0.0; 3],
        axis: [0.0, 0.0, 1.0],
    });
    let area = 4.0 * std::f64::consts::PI.powi(2) * major * minor;
    let ideal = area * 2.0 / (3f64.sqrt() * 0.25);
    assert!(
        (g.len() as Real - ideal).abs() < 0.1 * ideal,
        "{} vs {ideal}",
        g.len()
    );
    assert_unit_normals(&g.normals);
    for (p, n) in g.positions.iter().zip(&g.normals) {
        let tube = p - n * minor;
        assert!(tube.z.abs() < 1e-12 && ((tube.x.hypot(tube.y)) - major).abs() < 1e-12);
    }

    let g = generate(&Generator::List {
        particles: vec![
            op_scene::generators::ListParticle {
                position: [0.0; 3],
                normal: None,
                curvature: None,
            },
            op_scene::generators::ListParticle {
                position: [1.0, 0.0, 0.0],
                normal: Some([0.0, 2.0, 0.0]),
                curvature: Some(0.5),
            },
        ],
    });
    assert_eq!(g.normals, vec![Vec3::z(), Vec3::y()]);
    assert_eq!(g.curvatures, vec![0.0, 0.5]);

    let g = Generator::Points {
        path: "data/patch.xyz".into(),
    }
    .generate(Some(&scenes_dir()), "<test>", "generator")
    .unwrap();
    assert_eq!(g.len(), 55);
    assert_unit_normals(&g.normals);
    assert!(
        g.normals.iter().any(|n| n.z < 0.99),
        "normals read from the file"
    );
}

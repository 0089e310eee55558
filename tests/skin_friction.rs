//! Coulomb friction of a skin on a rigid collider (`op_implicit::friction`,
//! the `friction` of an `Obstacle` tool met by skins).
//!
//! A block on an incline: one particle of mass 1 carrying a point skin
//! rests on a level box under gravity tilted by `θ` (the incline's frame:
//! the same as a box tilted by `θ` under vertical gravity). With friction
//! coefficient `μ = tan φ` it sticks for `θ < φ` and slides for `θ > φ`,
//! reaching the terminal velocity `g (sin θ - μ cos θ) / β` of the linear
//! damping `β` along the slope.

use oriented_particles::op_scene::{parse_scene, BuiltScene, Format};

const G: f64 = 1.0;
const BETA: f64 = 0.5;

fn block(theta: f64, mu: f64) -> BuiltScene {
    let (gx, gz) = (G * theta.sin(), -G * theta.cos());
    let text = format!(
        r#"(name: "incline", world: (dt: {DT}, duration: 8, frame_rate: 5,
                gravity: ({gx}, 0, {gz}), linear_damping: {BETA}, angular_damping: 0.1),
            materials: {{"m": ()}},
            objects: [(name: "block", material: "m",
                       generator: Chain(count: 1, spacing: 1, start: (0, 0, 0.6)),
                       skin: Some((primitive: Point, radius: 0.8, cell_size: 0.1, stiffness: 100)))],
            tools: [(name: "floor", shape: Cuboid(half_extents: (100, 100, 1)),
                     path: [(time: 0, position: (0, 0, -1))],
                     role: Obstacle(stiffness: 100, damping: 2, friction: {mu}))])"#
    );
    let scene = parse_scene(&text, Format::Ron, "<incline>").unwrap();
    scene.build(None, None).unwrap()
}

/// Position along the slope, velocity along it and height of the block
/// at each of `times`, in one run.
fn run(theta: f64, mu: f64, times: &[f64]) -> Vec<(f64, f64, f64)> {
    let mut b = block(theta, mu);
    times
        .iter()
        .map(|&t| {
            b.advance_to(t).unwrap();
            let p = b.world().particles();
            (p.positions()[0].x, p.velocities()[0].x, p.positions()[0].z)
        })
        .collect()
}

const DT: f64 = 0.004;

/// Below the friction angle the block lands, comes to rest (the obstacle's
/// normal damping ends the bounce) and sticks: the interval bound of the
/// friction stops its sliding each step and gravity along the slope
/// restarts it, so it creeps at `g sin θ dt` (module docs of
/// `op_implicit::friction`); above it slides at the terminal velocity of
/// Coulomb's law; without friction it slides on any slope.
#[test]
fn a_block_sticks_below_the_friction_angle_and_slides_above() {
    let phi: f64 = 30f64.to_radians();
    let mu = phi.tan();
    for deg in [10.0, 20.0, 27.0] {
        let theta: f64 = f64::to_radians(deg);
        let s = run(theta, mu, &[6.0, 8.0]);
        let ((x6, _, z), (x8, v8, _)) = (s[0], s[1]);
        let creep = G * theta.sin() * DT;
        eprintln!(
            "θ = {deg}° < φ = 30°: x(8) - x(6) = {:.2e}, v(8) = {v8:.2e} (g sin θ dt = {creep:.2e}), z = {z:.3}",
            x8 - x6
        );
        // Resting on the floor.
        assert!(z > 0.0 && z < 0.6, "{z}");
        assert!(v8.abs() <= 1.01 * creep, "{deg}°: {v8} vs {creep}");
        assert!(
            (x8 - x6).abs() <= 1.01 * creep * 2.0,
            "{deg}°: crept {}",
            x8 - x6
        );
    }
    for deg in [35.0, 45.0] {
        let theta: f64 = f64::to_radians(deg);
        let v8 = run(theta, mu, &[8.0])[0].1;
        let terminal = G * (theta.sin() - mu * theta.cos()) / BETA;
        let frictionless = G * theta.sin() / BETA;
        eprintln!("θ = {deg}° > φ: v(8) = {v8:.4}, g (sin θ - μ cos θ)/β = {terminal:.4} (no friction {frictionless:.4})");
        assert!(
            (v8 / terminal - 1.0).abs() < 0.1,
            "{deg}°: {v8} vs {terminal}"
        );
    }
    let theta = f64::to_radians(10.0);
    let v8 = run(theta, 0.0, &[8.0])[0].1;
    let free = G * theta.sin() / BETA;
    eprintln!("θ = 10°, no friction: v(8) = {v8:.4}, g sin θ / β = {free:.4}");
    assert!((v8 / free - 1.0).abs() < 0.1, "{v8} vs {free}");
}

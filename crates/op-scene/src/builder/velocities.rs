//! Initial velocities of an object's particles beyond its uniform
//! velocity: read from a file or drawn at a temperature.

use std::path::Path;

use op_dynamics::{ParticleDesc, Real, Vec3};

use crate::error::SceneError;
use crate::schema::ObjectSpec;

/// Adds the object's per-particle initial velocities
/// ([`crate::schema::Velocities`]) to `descs`.
pub(super) fn add_velocities(
    o: &ObjectSpec,
    descs: &mut [ParticleDesc],
    base_dir: Option<&Path>,
    file: &str,
    path: &str,
) -> Result<(), SceneError> {
    use crate::schema::Velocities;
    let at = format!("{path}.velocities.File");
    match &o.velocities {
        None => {}
        Some(Velocities::File(p)) => {
            let v = crate::generators::read_velocities(base_dir, p, file, &at)?;
            if v.len() != descs.len() {
                return Err(SceneError::invalid(
                    file,
                    at,
                    format!(
                        "holds {} velocities; the generator made {} particles",
                        v.len(),
                        descs.len()
                    ),
                ));
            }
            for (d, v) in descs.iter_mut().zip(v) {
                d.velocity += v;
            }
        }
        Some(Velocities::Temperature { t, seed }) => {
            let masses: Vec<Real> = descs.iter().map(|d| d.mass).collect();
            for (d, v) in descs.iter_mut().zip(thermal_velocities(&masses, *t, *seed)) {
                d.velocity += v;
            }
        }
    }
    Ok(())
}

/// Maxwell-Boltzmann velocities at temperature `t` for particles of these
/// masses (`k_B = 1`), from `seed`: net momentum removed, then scaled to a
/// kinetic temperature of exactly `t` over `3N - 3` degrees of freedom
/// (zero for a single particle).
pub(crate) fn thermal_velocities(masses: &[Real], t: Real, seed: u64) -> Vec<Vec3> {
    let mut state = seed ^ 0x9E37_79B9_7F4A_7C15;
    let mut uniform = || {
        // splitmix64
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as Real + 0.5) / (1u64 << 53) as Real
    };
    let mut normal = || {
        let (u, v) = (uniform(), uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    };
    let mut v: Vec<Vec3> = masses
        .iter()
        .map(|&m| Vec3::new(normal(), normal(), normal()) * (t / m).sqrt())
        .collect();
    let n = masses.len();
    let mass: Real = masses.iter().sum();
    let momentum = masses
        .iter()
        .zip(&v)
        .fold(Vec3::zeros(), |s, (&m, v)| s + v * m);
    let drift = momentum / mass;
    v.iter_mut().for_each(|x| *x -= drift);
    let dof = 3.0 * n as Real - 3.0;
    let twice_kinetic: Real = masses
        .iter()
        .zip(&v)
        .map(|(&m, v)| m * v.norm_squared())
        .sum();
    let scale = if dof > 0.0 && twice_kinetic > 0.0 {
        (t * dof / twice_kinetic).sqrt()
    } else {
        0.0
    };
    v.iter_mut().for_each(|x| *x *= scale);
    v
}

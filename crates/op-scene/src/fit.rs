//! Point-set fitting in scenes and for `opsim fit` (seed 000 §7): the fit
//! itself is op-modeling's ([`op_modeling::fit`], re-exported here); this
//! module adds a scene's fit state ([`SceneFit`], `creation.fit`) and the
//! mesh's OBJ output ([`write_obj`]).

use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

use op_dynamics::Real;
use rayon::prelude::*;

pub use op_modeling::fit::*;

/// A fit running in a scene (`creation.fit`, [`crate::schema::fit`]): the
/// creation rules act only in [`SceneFit::near`] and only before
/// [`SceneFit::release_time`], when the seeds are freed.
#[derive(Clone, Debug)]
pub struct SceneFit {
    /// Index of the object holding the samples.
    pub object: usize,
    /// Where particles may be created.
    pub near: DataNeighbourhood,
    /// World time of the release (after the settle phase, if any).
    pub release_time: Real,
    /// True once the seeds were released.
    pub released: bool,
}

/// Writes the mesh as OBJ (`v`, `vn`, `f v//vn`), atomically.
pub fn write_obj(path: &Path, fit: &Fit) -> std::io::Result<()> {
    let mesh = &fit.mesh;
    crate::export::write_atomically(path, |w: &mut dyn Write| {
        writeln!(
            w,
            "# opsim fit: {} vertices, {} faces, spacing {}",
            mesh.vertices.len(),
            mesh.faces.len(),
            fit.spacing
        )?;
        write_lines(w, &mesh.vertices, |s, v| {
            writeln!(s, "v {} {} {}", v.x, v.y, v.z)
        })?;
        write_lines(w, &mesh.normals, |s, n| {
            writeln!(s, "vn {} {} {}", n.x, n.y, n.z)
        })?;
        write_lines(w, &mesh.faces, |s, f| {
            let [a, b, c] = f.map(|k| k + 1);
            writeln!(s, "f {a}//{a} {b}//{b} {c}//{c}")
        })
    })
}

/// Lines formatted per parallel task by [`write_lines`].
const LINES_PER_CHUNK: usize = 16_384;

/// Writes one line per item of `items` (`line` appends it to a string):
/// chunks of lines are formatted in parallel, a bounded window at a time,
/// and written in order, so the bytes are those of a serial loop.
fn write_lines<T: Sync>(
    w: &mut dyn Write,
    items: &[T],
    line: impl Fn(&mut String, &T) -> std::fmt::Result + Sync,
) -> std::io::Result<()> {
    let chunk = |c: &[T]| {
        let mut s = String::with_capacity(48 * c.len());
        for x in c {
            line(&mut s, x).map_err(std::io::Error::other)?;
        }
        Ok::<_, std::io::Error>(s)
    };
    for window in items.chunks(16 * LINES_PER_CHUNK) {
        let texts: Vec<String> = if window.len() > LINES_PER_CHUNK {
            window
                .par_chunks(LINES_PER_CHUNK)
                .map(chunk)
                .collect::<Result<_, _>>()?
        } else {
            vec![chunk(window)?]
        };
        for t in texts {
            w.write_all(t.as_bytes())?;
        }
    }
    Ok(())
}

/// The figures of a fit as one line of JSON, what `opsim fit` prints:
/// `particles`, `vertices`, `faces`, `euler_characteristic`,
/// `boundary_loops`, `pieces` (sets of triangles joined through shared
/// vertices), `closed` (triangles and no boundary loop), `rms_distance`,
/// `max_distance` (samples to mesh), `spacing`, `normals` (`"given"` by
/// the file or `"estimated"`; zero normals count as none),
/// `dropped_outliers` (samples dropped as outliers before seeding),
/// `noise_estimate` (the samples' estimated noise, a standard deviation in
/// their units, like `spacing`), `approximated` (whether the particles
/// were seeded on a smoothed estimate of noisy samples rather than on the
/// samples), `open` (fitted as open data: given, or a boundary found in
/// the samples) and `thin_features` (`centre`, `samples`,
/// `thickness`; largest first). A non-finite figure is `null`.
pub fn figures_json(fit: &Fit) -> String {
    let number = |x: Real| {
        if x.is_finite() {
            // Exponent notation for very large or small values.
            format!("{x:?}")
        } else {
            "null".to_string()
        }
    };
    // The thin features: where the two sides lie within the
    // triangulation radius (ears, fingers), largest first.
    let thin: Vec<String> = fit
        .thin_features
        .iter()
        .map(|t| {
            format!(
                "{{\"centre\": [{}, {}, {}], \"samples\": {}, \"thickness\": {}}}",
                number(t.centre.x),
                number(t.centre.y),
                number(t.centre.z),
                t.samples,
                number(t.thickness)
            )
        })
        .collect();
    format!(
        "{{\"particles\": {}, \"vertices\": {}, \"faces\": {}, \"euler_characteristic\": {}, \"boundary_loops\": {}, \"pieces\": {}, \"closed\": {}, \"rms_distance\": {}, \"max_distance\": {}, \"spacing\": {}, \"normals\": \"{}\", \"dropped_outliers\": {}, \"noise_estimate\": {}, \"approximated\": {}, \"open\": {}, \"thin_features\": [{}]}}",
        fit.particles,
        fit.mesh.vertices.len(),
        fit.mesh.faces.len(),
        fit.mesh.euler_characteristic,
        fit.mesh.boundary_loops,
        fit.pieces(),
        fit.closed(),
        number(fit.mesh.rms_distance),
        number(fit.mesh.max_distance),
        number(fit.spacing),
        if fit.normals_given { "given" } else { "estimated" },
        fit.dropped_outliers,
        number(fit.noise_estimate),
        fit.approximated,
        fit.open,
        thin.join(", ")
    )
}

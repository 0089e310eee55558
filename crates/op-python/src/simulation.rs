//! `Simulation`: a built scene stepped from Python.
//!
//! It advances as `opsim run` does: through the scene's driver (creation,
//! skin contact and the other stages act between the world's steps), and
//! through every frame time on the way (the runner advances from frame to
//! frame, and where an interval ends changes what an interval-wise stage
//! such as skin contact does), so the particles at a frame time are those
//! of the run's frame. Time is scene time: 0 is frame 0, after the settle
//! phase, which [`PySimulation::build`] runs.

use std::collections::BTreeMap;
use std::sync::{Mutex, MutexGuard, TryLockError};

use numpy::{PyArray2, PyArrayMethods};
use op_dynamics::{Point3, Real, Vec3};
use op_scene::export::geometry;
use op_scene::BuiltScene;
use pyo3::exceptions::{PyKeyError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::arrays;
use crate::runner::{on_pool, pool, watch, Progress};
use crate::scene::PyScene;
use crate::{divergence_error, scene_error};

/// The simulation's state, behind [`PySimulation`]'s lock.
struct Sim {
    built: BuiltScene,
    /// The rayon pool of its steps (None: the global pool).
    pool: Option<rayon::ThreadPool>,
    /// World time of frame 0 (the end of the settle phase).
    t0: Real,
}

impl Sim {
    /// Advances to world time `t` through the driver, on the pool.
    fn advance_world(&mut self, t: Real) -> Result<(), op_dynamics::driver::DriveError> {
        let Sim { built, pool, .. } = self;
        on_pool(pool.as_ref(), || built.advance_to(t))
    }

    /// World time of frame `k`, as the runner computes it.
    fn frame_time(&self, k: usize) -> Real {
        self.t0 + k as Real / self.built.frame_rate()
    }

    /// The first frame after world time `t`.
    fn next_frame(&self, t: Real) -> usize {
        let eps = 1e-9 / self.built.frame_rate();
        let k = ((t - self.t0) * self.built.frame_rate()).floor().max(0.0) as usize;
        (k..)
            .find(|&k| self.frame_time(k) > t + eps)
            .unwrap_or(usize::MAX)
    }

    /// Index of the object `name`, or a `KeyError` naming the objects.
    fn object(&self, name: &str) -> PyResult<usize> {
        let objects = self.built.objects();
        objects.iter().position(|o| o.name == name).ok_or_else(|| {
            let names: Vec<&str> = objects.iter().map(|o| o.name.as_str()).collect();
            PyKeyError::new_err(format!(
                "no object {name:?} in scene {:?}; its objects: {names:?}",
                self.built.name()
            ))
        })
    }

    /// The slots of the object `name`'s live particles, in the order of
    /// its arrays (generation order, then created particles).
    fn slots(&self, name: &str) -> PyResult<Vec<usize>> {
        let o = &self.built.objects()[self.object(name)?];
        let p = self.built.world().particles();
        Ok(o.all_ids().filter_map(|id| p.slot_of(id)).collect())
    }
}

/// A divergence while stepping, as a `DivergenceError` without summary.
fn diverged(py: Python<'_>, e: op_dynamics::driver::DriveError) -> PyErr {
    divergence_error(py, e.to_string(), py.None())
}

/// A scene built into a world, stepped from Python (`Scene.build()`).
///
/// Arrays are per object, in the object's particle order (generation
/// order, then particles the creation rules added), float64, in scene
/// coordinates (z-up): new arrays each call (an object's particles are not
/// contiguous in the world's storage, so no view of them exists).
#[pyclass(name = "Simulation", module = "oriented_particles", frozen)]
pub struct PySimulation {
    state: Mutex<Sim>,
}

impl PySimulation {
    /// `Scene.build`: builds `scene`, settles it and poses its skins
    /// (frame 0 of a run), with the GIL released.
    pub fn build(py: Python<'_>, scene: &PyScene, threads: Option<usize>) -> PyResult<Self> {
        let pool = pool(threads)?;
        let base = scene.base_dir.as_deref();
        let built = py
            .detach(|| {
                on_pool(pool.as_ref(), || {
                    scene.scene.build(base, scene.source.clone())
                })
            })
            .map_err(scene_error)?;
        let mut sim = Sim {
            built,
            pool,
            t0: 0.0,
        };
        let Sim { built, pool, .. } = &mut sim;
        py.detach(|| {
            on_pool(pool.as_ref(), || {
                built.settle()?;
                // Frame 0 poses the skins on the settled particles.
                let t = built.world().time();
                built.advance_to(t)
            })
        })
        .map_err(|e| divergence_error(py, format!("while settling: {e}"), py.None()))?;
        sim.t0 = sim.built.world().time();
        Ok(PySimulation {
            state: Mutex::new(sim),
        })
    }

    /// The state, or a `RuntimeError` while another thread steps it (the
    /// lock is never waited for with the GIL held).
    fn lock(&self) -> PyResult<MutexGuard<'_, Sim>> {
        match self.state.try_lock() {
            Ok(g) => Ok(g),
            Err(TryLockError::WouldBlock) => Err(PyRuntimeError::new_err(
                "the simulation is being advanced by another thread",
            )),
            // A panic while stepping is a bug; the state may be partial.
            Err(TryLockError::Poisoned(p)) => Ok(p.into_inner()),
        }
    }

    /// The rows of `rows(world, slot)` over the object `name`'s particles.
    fn rows<T>(
        &self,
        name: &str,
        row: impl Fn(&op_dynamics::Particles, usize) -> T,
    ) -> PyResult<Vec<T>> {
        let sim = self.lock()?;
        let p = sim.built.world().particles();
        Ok(sim.slots(name)?.into_iter().map(|s| row(p, s)).collect())
    }

    /// Writes `values` (one row per particle of `name`) with `set`.
    fn set_rows(
        &self,
        name: &str,
        values: &Bound<'_, PyAny>,
        what: &str,
        set: impl Fn(&mut op_dynamics::Particles, usize, Vec3),
    ) -> PyResult<()> {
        let rows = arrays::read_vectors(values, what)?;
        let mut sim = self.lock()?;
        let slots = sim.slots(name)?;
        if rows.len() != slots.len() {
            return Err(PyValueError::new_err(format!(
                "{what}: {} rows for the {} particles of object {name:?}",
                rows.len(),
                slots.len()
            )));
        }
        let p = sim.built.world_mut().particles_mut();
        for (s, v) in slots.into_iter().zip(rows) {
            set(p, s, v);
        }
        Ok(())
    }
}

#[pymethods]
impl PySimulation {
    /// Scene time (0 at frame 0; frame k is at k / frame_rate).
    #[getter]
    fn time(&self) -> PyResult<Real> {
        let sim = self.lock()?;
        Ok(sim.built.world().time() - sim.t0)
    }

    /// Steps taken, the settle phase's included.
    #[getter]
    fn steps(&self) -> PyResult<u64> {
        Ok(self.lock()?.built.world().steps())
    }

    /// The time step (`world.dt`; the largest step of the adaptive scheme).
    #[getter]
    fn dt(&self) -> PyResult<Real> {
        Ok(self.lock()?.built.world().params().dt)
    }

    /// Frames per unit of scene time (`world.frame_rate`).
    #[getter]
    fn frame_rate(&self) -> PyResult<Real> {
        Ok(self.lock()?.built.frame_rate())
    }

    /// The scene's duration (`world.duration`, after the settle phase).
    #[getter]
    fn duration(&self) -> PyResult<Real> {
        Ok(self.lock()?.built.duration())
    }

    /// The object names, in scene order.
    #[getter]
    fn object_names(&self) -> PyResult<Vec<String>> {
        let sim = self.lock()?;
        Ok(sim.built.objects().iter().map(|o| o.name.clone()).collect())
    }

    /// Advances to scene time `t` (not before the current time), through
    /// every frame time on the way as a run does, with the GIL released:
    /// at a frame time the particles are those of the run's frame. Ctrl-C
    /// stops it at the next frame time and raises `KeyboardInterrupt`.
    ///
    /// Raises `DivergenceError` when the world diverges (a NaN or
    /// infinity, a speed above `world.divergence.max_speed`) or a stage
    /// fails; the run's energy and explosion watches are `Scene.run`'s.
    fn advance(&self, py: Python<'_>, t: Real) -> PyResult<()> {
        let mut sim = self.lock()?;
        let now = sim.built.world().time();
        let target = sim.t0 + t;
        if !target.is_finite() || target < now - 1e-12 * sim.built.world().params().dt {
            return Err(PyValueError::new_err(format!(
                "advance({t}): the simulation is at time {}; it only goes forward",
                now - sim.t0
            )));
        }
        let first = sim.next_frame(now);
        let sim = &mut *sim;
        let mut display = Progress::new(None, "");
        let (result, interrupt) = watch(py, &mut display, |stop, _, _| {
            let mut k = first;
            while sim.frame_time(k) < target {
                sim.advance_world(sim.frame_time(k))?;
                if stop.load(std::sync::atomic::Ordering::Relaxed) {
                    return Ok(());
                }
                k += 1;
            }
            sim.advance_world(target)
        });
        result.map_err(|e| diverged(py, e))?;
        interrupt.map_or(Ok(()), Err)
    }

    /// Advances by one step of `world.dt` (through the scene's stages).
    fn step(&self, py: Python<'_>) -> PyResult<()> {
        let mut sim = self.lock()?;
        let t = sim.built.world().time() + sim.built.world().params().dt;
        let sim = &mut *sim;
        py.detach(|| sim.advance_world(t))
            .map_err(|e| diverged(py, e))
    }

    /// The particle ids of the object `name` (stable over the run), one
    /// per row of its arrays.
    fn ids(&self, name: &str) -> PyResult<Vec<u32>> {
        self.rows(name, |p, s| p.ids()[s])
    }

    /// Positions of the object `name`'s particles, shape (n, 3).
    fn positions<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let rows = self.rows(name, |p, s| p.positions()[s].coords)?;
        Ok(arrays::vectors(py, &rows))
    }

    /// Orientations of the object `name`'s particles as unit quaternions
    /// `(w, x, y, z)`, shape (n, 4).
    fn orientations<'py>(
        &self,
        py: Python<'py>,
        name: &str,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let rows = self.rows(name, |p, s| p.orientations()[s])?;
        Ok(arrays::quaternions(py, &rows))
    }

    /// Unit normals of the object `name`'s particles, shape (n, 3).
    fn normals<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let rows = self.rows(name, |p, s| p.normal(s))?;
        Ok(arrays::vectors(py, &rows))
    }

    /// Velocities of the object `name`'s particles, shape (n, 3).
    fn velocities<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let rows = self.rows(name, |p, s| p.velocities()[s])?;
        Ok(arrays::vectors(py, &rows))
    }

    /// Moves the object `name`'s particles to `positions`, shape (n, 3)
    /// (one row per particle, in the order of `positions(name)`).
    fn set_positions(&self, name: &str, positions: &Bound<'_, PyAny>) -> PyResult<()> {
        self.set_rows(name, positions, "positions", |p, s, v| {
            p.set_position(s, Point3::from(v))
        })
    }

    /// Sets the velocities of the object `name`'s particles, shape (n, 3)
    /// (particles with a fixed position keep theirs).
    fn set_velocities(&self, name: &str, velocities: &Bound<'_, PyAny>) -> PyResult<()> {
        self.set_rows(name, velocities, "velocities", |p, s, v| {
            p.set_velocity(s, v)
        })
    }

    /// Adds `force` (three numbers; world frame) and `torque` (default
    /// none) to each particle of the object `name`, or to the rows
    /// `particles` of its arrays: they act during the next step only (the
    /// world's pending forces), so call it before each `step()` to hold a
    /// force. For a force over a time window put a `forces` entry in the
    /// scene.
    #[pyo3(signature = (name, force, *, torque = None, particles = None))]
    fn add_force(
        &self,
        name: &str,
        force: &Bound<'_, PyAny>,
        torque: Option<&Bound<'_, PyAny>>,
        particles: Option<Vec<usize>>,
    ) -> PyResult<()> {
        let f = arrays::read_vector(force, "force")?;
        let t = match torque {
            Some(t) => arrays::read_vector(t, "torque")?,
            None => Vec3::zeros(),
        };
        let mut sim = self.lock()?;
        let slots = sim.slots(name)?;
        let rows: Vec<usize> = particles.unwrap_or_else(|| (0..slots.len()).collect());
        if let Some(&bad) = rows.iter().find(|&&r| r >= slots.len()) {
            return Err(PyValueError::new_err(format!(
                "particles: row {bad} of object {name:?}, which has {} particles",
                slots.len()
            )));
        }
        let world = sim.built.world_mut();
        for r in rows {
            let id = world.particles().ids()[slots[r]];
            world.add_external_force(id, f, t);
        }
        Ok(())
    }

    /// Adds `forces`, shape (n, 3), one per particle of the object `name`
    /// (in the order of `positions(name)`), for the next step only, as
    /// `add_force`.
    fn add_forces(&self, name: &str, forces: &Bound<'_, PyAny>) -> PyResult<()> {
        let rows = arrays::read_vectors(forces, "forces")?;
        let mut sim = self.lock()?;
        let slots = sim.slots(name)?;
        if rows.len() != slots.len() {
            return Err(PyValueError::new_err(format!(
                "forces: {} rows for the {} particles of object {name:?}",
                rows.len(),
                slots.len()
            )));
        }
        let world = sim.built.world_mut();
        for (s, f) in slots.into_iter().zip(rows) {
            let id = world.particles().ids()[s];
            world.add_external_force(id, f, Vec3::zeros());
        }
        Ok(())
    }

    /// The implicit skin of the object `name` (`skin:` in the scene) as a
    /// triangle mesh, as the frames write it (`<name>_skin`, deformed by
    /// contact, clipped by obstacles): `(vertices, faces)`, float64 (m, 3)
    /// and int64 (k, 3), scene coordinates. Polygonized with the GIL
    /// released. Raises `ValueError` when the object has no skin.
    fn skin_mesh<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyTuple>> {
        let sim = self.lock()?;
        let o = sim.object(name)?;
        let b = &sim.built;
        let skin = b
            .skins()
            .iter()
            .find(|s| s.object == o)
            .ok_or_else(|| PyValueError::new_err(format!("object {name:?} has no skin")))?;
        let (skins, tools, t) = (b.skins(), b.skin_tools(), b.world().time());
        let pool = sim.pool.as_ref();
        let mesh = py
            .detach(|| on_pool(pool, || skin.mesh_in(skins, tools, t)))
            .map_err(|e| {
                PyRuntimeError::new_err(format!("cannot polygonize {}: {e}", skin.name))
            })?;
        mesh_tuple(py, geometry::mesh_geometry(&skin.name, mesh))
    }

    /// The triangulation of the object `name`'s particles (seed 000 §5,
    /// what `outputs: (triangulation: true)` writes as `<name>_surface`):
    /// `(vertices, faces)`, float64 (m, 3) and int64 (k, 3), scene
    /// coordinates.
    fn surface_mesh<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyTuple>> {
        let sim = self.lock()?;
        let b = &sim.built;
        let object = &b.objects()[sim.object(name)?];
        let (world, outputs, gap) = (b.world(), b.outputs(), b.sheet_gap());
        let pool = sim.pool.as_ref();
        let mesh = py.detach(|| {
            on_pool(pool, || {
                geometry::surface_geometry(world, object, outputs, gap)
            })
        });
        mesh_tuple(py, mesh)
    }

    /// Seconds spent per stage so far (the scene's `build`, the world's
    /// stages, the scene's stages), as summary.json's `stages`.
    fn stage_seconds(&self) -> PyResult<BTreeMap<String, f64>> {
        let sim = self.lock()?;
        let mut table = BTreeMap::new();
        for (name, seconds) in sim.built.timings() {
            *table.entry(name).or_insert(0.0) += seconds;
        }
        Ok(table)
    }

    /// The world's energies now, as metrics.csv gives them per frame:
    /// `kinetic`, `potential`, `total`, `oscillation`, `max_speed`.
    fn energies<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let mut sim = self.lock()?;
        let Sim { built, pool, .. } = &mut *sim;
        let d = py.detach(|| on_pool(pool.as_ref(), || built.world_mut().diagnostics()));
        let out = PyDict::new(py);
        out.set_item("kinetic", d.kinetic_translational + d.kinetic_rotational)?;
        out.set_item("potential", d.potential)?;
        out.set_item("total", d.total)?;
        out.set_item("oscillation", d.oscillation)?;
        out.set_item("max_speed", d.max_speed)?;
        Ok(out)
    }

    fn __repr__(&self) -> PyResult<String> {
        let sim = self.lock()?;
        Ok(format!(
            "Simulation(scene={:?}, time={}, particles={})",
            sim.built.name(),
            sim.built.world().time() - sim.t0,
            sim.built.world().particles().len()
        ))
    }
}

/// `(vertices, faces)` of a frame mesh.
fn mesh_tuple<'py>(py: Python<'py>, mesh: geometry::FrameMesh) -> PyResult<Bound<'py, PyTuple>> {
    let vertices = arrays::vectors(py, &mesh.vertices);
    let faces = arrays::triangles(py, &mesh.triangles);
    debug_assert!(vertices.readonly().as_array().nrows() == mesh.vertices.len());
    PyTuple::new(py, [vertices.into_any(), faces.into_any()])
}

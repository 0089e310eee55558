//! The spiral that uncoils and recovers (seed 002 §5, fig. 5; docs/model.md §6-7).
//!
//! A planar spiral of oriented particles held by cohesion, the form
//! (shape memory) term, co-planarity and inter-particle friction is pulled
//! apart by opposing forces on its two end particles until its internal
//! forces balance them, then released: it must return to its rest shape.
//!
//! [`SpiralRecipe`] turns a [`SpiralShape`] into a complete [`Scene`] from
//! one set of dimensionless constants, so every spiral of the experiment
//! (the seed spiral, spirals of 8 and 13 particles with other curvature
//! laws, the seed spiral scaled by 10) gets its parameters from the same
//! rule instead of per-case tuning. [`run_spiral`] runs a scene and
//! records the rest shape error and the end-to-end distance over time.
//!
//! **What the recipe has to get right** (docs/model.md §7, measured in
//! `reports/shape_memory.md`):
//!
//! - *Reach.* Cohesion and the orientation weight are cut off at 1.5 rest
//!   spacings: only next neighbours along the spiral interact (particle
//!   `i+2` is at least `2 sin(1) ≈ 1.68` spacings away when `|κ| L <= 1`,
//!   and turns must stay apart: at most one turn).
//! - *Settle.* A spiral made from its analytic curvature is close to, not
//!   at, rest; the scene settles first and the settled shape is the
//!   reference (`world.settle`).
//! - *Load.* Opposing end forces of 0.45 of the maximum cohesion
//!   attraction, ramped up and down: step loads overshoot (a step of 0.7
//!   `f_max` breaks a bond the same ramped force does not).
//! - *Damping in a window.* Linear damping 0.3: with much less the spiral
//!   is still ringing at the end of the run, with much more it creeps back
//!   too slowly.
//! - *Planarity.* With the normals in the spiral's plane (the form term is
//!   zero on the circle of radius `1/κ` with outward normals), no term
//!   holds the particles in that plane: turning particle `j` and its frame
//!   about the normal axis of its neighbour `i` (the axis through `p_i`
//!   along `n_i`) leaves cohesion, form and co-planarity (`(n_i · r)²`) of
//!   the pair unchanged, so every bond has an out-of-plane zero mode, and
//!   co-planarity with in-plane normals only straightens the spiral a
//!   little in its plane. A planar state stays planar by symmetry, but
//!   round-off out of the plane grows during the recoil (to about 4e-3
//!   spacings for the seed spiral, enough to make runs that should be
//!   identical differ by 1e-4). The recipe therefore gives the particles
//!   the in-plane body normal axis `+x` (see [`SpiralRecipe::object`]):
//!   every frame is then a rotation about `z` and the motion stays planar
//!   bit for bit.

use op_dynamics::interactions::{CohesionParams, RepulsionParams, Spacing, WeightParams};
use op_dynamics::{Material, Point3, Real, Scheme, Vec3};
use op_scene::outputs::{Outputs, ParticleOutput};
use op_scene::{CurvatureLaw, ForceSpec, Generator, ObjectSpec, Scene, Selection, WorldSettings};

/// The geometry of a spiral: [`Generator::Spiral`] in the plane z = 0,
/// centred on the origin, from its outer end (`curvature_start`) to its
/// inner end (`curvature_end`).
#[derive(Clone, Debug, PartialEq)]
pub struct SpiralShape {
    /// Number of particles.
    pub count: usize,
    /// Arc length between neighbours: the rest spacing `r0` and the length
    /// unit of the recipe.
    pub spacing: Real,
    /// Curvature at the outer end (first particle).
    pub curvature_start: Real,
    /// Curvature at the inner end (last particle).
    pub curvature_end: Real,
    /// How the curvature grows from one end to the other.
    pub law: CurvatureLaw,
}

impl SpiralShape {
    /// The seed spiral (seed 002 fig. 5): ten particles one unit apart,
    /// curvature growing linearly from 0.25 to 0.85 towards the inside,
    /// 0.79 of a turn.
    pub fn seed() -> SpiralShape {
        SpiralShape {
            count: 10,
            spacing: 1.0,
            curvature_start: 0.25,
            curvature_end: 0.85,
            law: CurvatureLaw::Linear,
        }
    }

    /// The same shape scaled by `s` in length (curvatures divided by `s`).
    pub fn scaled(&self, s: Real) -> SpiralShape {
        SpiralShape {
            spacing: self.spacing * s,
            curvature_start: self.curvature_start / s,
            curvature_end: self.curvature_end / s,
            ..self.clone()
        }
    }

    /// A spiral of `count` particles one unit apart whose curvature follows
    /// `law` from `κ` to `ratio κ` (a constant curvature for `ratio = 1`),
    /// `κ` chosen for `turns` turns (the turning is proportional to `κ`)
    /// but no larger than keeps `|κ| <= 0.9` everywhere (the generator
    /// needs `|κ| L <= 1`).
    ///
    /// # Errors
    ///
    /// The generator's message for a count below 2 or a ratio that is not
    /// finite and positive.
    pub fn with_turns(
        count: usize,
        law: CurvatureLaw,
        ratio: Real,
        turns: Real,
    ) -> Result<SpiralShape, String> {
        let unit = SpiralShape {
            count,
            spacing: 1.0,
            curvature_start: 0.1,
            curvature_end: 0.1 * ratio,
            law,
        };
        unit.generator()
            .generate(None, "<spiral>", "generator")
            .map_err(|e| e.to_string())?;
        let kappa = (0.1 * turns / unit.turns()).min(0.9 / ratio.max(1.0));
        Ok(SpiralShape {
            curvature_start: kappa,
            curvature_end: kappa * ratio,
            ..unit
        })
    }

    /// Its generator.
    pub fn generator(&self) -> Generator {
        Generator::Spiral {
            count: self.count,
            spacing: self.spacing,
            curvature_start: self.curvature_start,
            curvature_end: self.curvature_end,
            law: self.law,
            center: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
        }
    }

    /// Total turning angle of the tangent from end to end, in turns.
    pub fn turns(&self) -> Real {
        let g = self
            .generator()
            .generate(None, "<spiral>", "generator")
            .expect("a valid spiral");
        let n = &g.normals;
        let mut angle = 0.0;
        for w in n.windows(2) {
            angle += w[0].cross(&w[1]).z.atan2(w[0].dot(&w[1]));
        }
        angle / std::f64::consts::TAU
    }
}

/// The spirals of the experiment, by scene name: the seed spiral
/// (`spiral`), 8 particles with a linear law from 0.3 to 0.9 (`spiral_8`),
/// 13 particles with a geometric law from 0.2 to 0.8 (`spiral_13`), and the
/// seed spiral scaled by 10 in length (`spiral_x10`). Each is the shape of
/// `scenes/<name>.ron`.
pub fn experiment_shapes() -> Vec<(&'static str, SpiralShape)> {
    let seed = SpiralShape::seed();
    vec![
        ("spiral", seed.clone()),
        (
            "spiral_8",
            SpiralShape {
                count: 8,
                curvature_start: 0.3,
                curvature_end: 0.9,
                ..seed.clone()
            },
        ),
        (
            "spiral_13",
            SpiralShape {
                count: 13,
                curvature_start: 0.2,
                curvature_end: 0.8,
                law: CurvatureLaw::Geometric,
                ..seed.clone()
            },
        ),
        ("spiral_x10", seed.scaled(10.0)),
    ]
}

/// The units a [`SpiralRecipe`] is expressed in: the rest spacing, the
/// particle mass and a time unit. Every parameter of the scene is one of
/// the recipe's dimensionless constants times the product of these that
/// gives it its dimension.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Units {
    /// Length unit `L`: the spiral's spacing.
    pub length: Real,
    /// Mass unit `M`: the particle mass.
    pub mass: Real,
    /// Time unit `T`.
    pub time: Real,
}

impl Units {
    /// Length `L` = the shape's spacing, `M = T = 1`.
    pub fn of(shape: &SpiralShape) -> Units {
        Units {
            length: shape.spacing,
            mass: 1.0,
            time: 1.0,
        }
    }

    /// Energy unit `M L²/T²`.
    pub fn energy(&self) -> Real {
        self.mass * self.length * self.length / (self.time * self.time)
    }

    /// Force unit `M L/T²`.
    pub fn force(&self) -> Real {
        self.mass * self.length / (self.time * self.time)
    }
}

/// One parameter recipe for every spiral (not tuned to one case;
/// docs/model.md §7): dimensionless constants, each multiplied by the [`Units`]
/// that give it its dimension. The defaults are the documented recipe.
///
/// | constant | scene parameter | unit |
/// |---|---|---|
/// | `cohesion_e` = 200 | cohesion `E` | `M/(L T²)` |
/// | `cohesion_alpha` = 16 | cohesion `α` | `1/L²` |
/// | `cutoff` = 1.5 | cohesion and orientation-weight cut-off | `L` |
/// | `form` = 2 | form weight `α_F` (normalized term) | `M L²/T²` |
/// | `coplanarity` = 0.2 | co-planarity weight `α_P` (normalized) | `M L²/T²` |
/// | `friction` = 1 | inter-particle friction | `M/T` |
/// | `linear_damping` = 0.3 | `β0` | `M/T` |
/// | `angular_damping` = 0.05 | `β1` | `M L²/T` |
/// | `inertia` = 0.1 | moments of inertia | `M L²` |
/// | `pull` = 0.45 | end force, times the cohesion maximum attraction `f_max` | force |
/// | `dt` = 0.005 | time step (velocity Verlet) | `T` |
/// | `settle` = 40, `ramp` = 10, `hold` = 20, `recovery` = 40 | schedule | `T` |
/// | `frame_rate` = 2 | frames | `1/T` |
/// | (fixed) | typing repulsion: strength 1, `σ = L`, `λ = 0.1 L`, cut-off `1.5 L` | `M L²/T²`, `L` |
///
/// The orientation weight is isotropic with width `a = L` and amplitude 1.
/// Both cut-offs are `1.5 L`: cohesion and the orientation terms act on
/// next neighbours along the spiral only (particle `i+2` is at least
/// `2 sin(1) L ≈ 1.68 L` away for `|κ| L <= 1`, docs/model.md §7).
#[derive(Clone, Debug, PartialEq)]
pub struct SpiralRecipe {
    /// Cohesion scaling factor `E`, in `M/(L T²)`.
    pub cohesion_e: Real,
    /// Cohesion Gaussian decay `α`, in `1/L²`.
    pub cohesion_alpha: Real,
    /// Cut-off of cohesion and of the orientation weight, in `L`.
    pub cutoff: Real,
    /// Form weight, in `M L²/T²`.
    pub form: Real,
    /// Co-planarity weight, in `M L²/T²`.
    pub coplanarity: Real,
    /// Inter-particle friction, in `M/T`.
    pub friction: Real,
    /// Linear damping `β0`, in `M/T`.
    pub linear_damping: Real,
    /// Angular damping `β1`, in `M L²/T`.
    pub angular_damping: Real,
    /// Principal moments of inertia, in `M L²`.
    pub inertia: Real,
    /// End force as a fraction of the cohesion maximum attraction.
    pub pull: Real,
    /// Time step, in `T`.
    pub dt: Real,
    /// Settle phase before frame 0, in `T`.
    pub settle: Real,
    /// Duration of the linear loading ramp and of the unloading ramp, in `T`.
    pub ramp: Real,
    /// Time at full load between the ramps, in `T`.
    pub hold: Real,
    /// Time after the unloading ramp, in `T`.
    pub recovery: Real,
    /// Frames per `T`.
    pub frame_rate: Real,
}

impl Default for SpiralRecipe {
    fn default() -> Self {
        SpiralRecipe {
            cohesion_e: 200.0,
            cohesion_alpha: 16.0,
            cutoff: 1.5,
            form: 2.0,
            coplanarity: 0.2,
            friction: 1.0,
            linear_damping: 0.3,
            angular_damping: 0.05,
            inertia: 0.1,
            pull: 0.45,
            dt: 0.005,
            settle: 40.0,
            ramp: 10.0,
            hold: 20.0,
            recovery: 40.0,
            frame_rate: 2.0,
        }
    }
}

/// `x` rounded to `digits` significant digits.
pub fn round_significant(x: Real, digits: i32) -> Real {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let scale = 10f64.powi(digits - 1 - x.abs().log10().floor() as i32);
    (x * scale).round() / scale
}

/// When the load acts, in scene time (after the settle phase).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Schedule {
    /// Settle phase before frame 0.
    pub settle: Real,
    /// The loading ramp starts (scene time 0).
    pub load_start: Real,
    /// Full load reached.
    pub full_load: Real,
    /// Unloading starts: the end of the hold, where the balanced state is
    /// measured.
    pub unload_start: Real,
    /// No load any more.
    pub unloaded: Real,
    /// End of the run.
    pub end: Real,
}

impl SpiralRecipe {
    /// The cohesion parameters for `units`.
    pub fn cohesion(&self, units: &Units) -> CohesionParams {
        let l = units.length;
        CohesionParams {
            e: self.cohesion_e * units.mass / (l * units.time * units.time),
            r0: l,
            alpha: self.cohesion_alpha / (l * l),
            cutoff: Some(self.cutoff * l),
            ..CohesionParams::default()
        }
    }

    /// The material for `units`.
    pub fn material(&self, units: &Units) -> Material {
        let l = units.length;
        Material {
            spacing: Some(Spacing::Cohesion(self.cohesion(units))),
            weight: WeightParams {
                k: 1.0,
                a: l,
                cutoff: self.cutoff * l,
                ..WeightParams::default()
            },
            coplanarity: self.coplanarity * units.energy(),
            form: self.form * units.energy(),
            friction: self.friction * units.mass / units.time,
            repulsion: RepulsionParams {
                strength: units.energy(),
                sigma: l,
                lambda: 0.1 * l,
                cutoff: self.cutoff * l,
                ..RepulsionParams::default()
            },
            ..Material::default()
        }
    }

    /// The schedule, in scene time, for `units`.
    pub fn schedule(&self, units: &Units) -> Schedule {
        let t = units.time;
        Schedule {
            settle: self.settle * t,
            load_start: 0.0,
            full_load: self.ramp * t,
            unload_start: (self.ramp + self.hold) * t,
            unloaded: (2.0 * self.ramp + self.hold) * t,
            end: (2.0 * self.ramp + self.hold + self.recovery) * t,
        }
    }

    /// The magnitude of each end force.
    pub fn pull_force(&self, units: &Units) -> Real {
        let (_, f_max) = self.cohesion(units).max_attraction();
        self.pull * f_max
    }

    /// The world settings for `units`.
    pub fn world(&self, units: &Units) -> WorldSettings {
        let s = self.schedule(units);
        WorldSettings {
            integrator: Scheme::VelocityVerlet,
            dt: self.dt * units.time,
            duration: s.end,
            settle: s.settle,
            frame_rate: self.frame_rate / units.time,
            linear_damping: (self.linear_damping * units.mass / units.time).into(),
            angular_damping: self.angular_damping * units.mass * units.length * units.length
                / units.time,
            ..WorldSettings::default()
        }
    }

    /// The object of `shape` named `name` with material `material`.
    ///
    /// Its body-frame normal axis is `+x`, in the plane of the spiral: the
    /// shortest rotation from it to an in-plane normal is a rotation about
    /// `z`, whose quaternion has exactly zero `x` and `y` parts, so every
    /// normal, force and torque stays exactly in (or, for torques,
    /// exactly perpendicular to) the plane, bit for bit. With the default
    /// `+z` axis the normals carry round-off out of the plane, which the
    /// recoil amplifies (to about 4e-3 r0 for the seed spiral): no term
    /// restores planarity (see the module docs).
    pub fn object(
        &self,
        name: &str,
        material: &str,
        shape: &SpiralShape,
        units: &Units,
    ) -> ObjectSpec {
        ObjectSpec {
            mass: units.mass,
            inertia: [self.inertia * units.mass * units.length * units.length; 3],
            // In the plane of the spiral: see `SpiralRecipe::object`.
            normal_axis: [1.0, 0.0, 0.0],
            ..ObjectSpec::new(name, material, shape.generator())
        }
    }

    /// The two opposing end forces on object `object` (its first and last
    /// particles), along the line through the ends of the generated shape,
    /// pulling them apart with ramped loading and unloading. Components
    /// are rounded to 6 significant digits (so scene files can hold them
    /// exactly).
    pub fn end_forces(&self, object: &str, shape: &SpiralShape, units: &Units) -> Vec<ForceSpec> {
        let g = shape
            .generator()
            .generate(None, "<spiral>", "generator")
            .expect("a valid spiral");
        let u: Vec3 = (g.positions[g.len() - 1] - g.positions[0]).normalize();
        let f = (u * self.pull_force(units)).map(|c| round_significant(c, 6));
        let s = self.schedule(units);
        let window = |particles: Selection, force: Vec3| ForceSpec {
            object: object.into(),
            particles,
            force: [force.x, force.y, force.z],
            start: s.load_start,
            end: s.unloaded,
            ramp: s.full_load - s.load_start,
        };
        vec![
            window(Selection::First(1), -f),
            window(Selection::Last(1), f),
        ]
    }

    /// The complete scene of the experiment for `shape`, in the units of
    /// the shape ([`Units::of`]).
    pub fn scene(&self, name: &str, shape: &SpiralShape) -> Scene {
        let units = Units::of(shape);
        let mut materials = std::collections::BTreeMap::new();
        materials.insert("memory".to_string(), self.material(&units));
        Scene {
            name: name.into(),
            world: self.world(&units),
            materials,
            objects: vec![self.object("spiral", "memory", shape, &units)],
            forces: self.end_forces("spiral", shape, &units),
            tools: Vec::new(),
            features: Vec::new(),
            outputs: Outputs {
                particles: ParticleOutput::Discs,
                ..Outputs::default()
            },
            creation: None,
            origin: String::new(),
            limits: Default::default(),
            frames_override: None,
            expected_warnings: Vec::new(),
        }
    }
}

/// What [`run_spiral`] measured, frame by frame (scene time, after the
/// settle phase) and in summary.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SpiralRun {
    /// Scene time of each frame.
    pub times: Vec<Real>,
    /// Rest shape error of the first object at each frame (RMS distance to
    /// the settled shape after the best rigid alignment, over the rest
    /// spacing; as in `summary.json`).
    pub errors: Vec<Real>,
    /// Distance between the first object's end particles at each frame,
    /// over the rest spacing.
    pub end_to_end: Vec<Real>,
    /// Largest particle speed at each frame, in rest spacings per time
    /// unit.
    pub max_speed: Vec<Real>,
    /// End-to-end distance of the settled shape, over the rest spacing.
    pub rest_end_to_end: Real,
    /// Largest rest shape error while loaded (frames up to the end of the
    /// unloading ramp).
    pub max_error_loaded: Real,
    /// Largest rest shape error over the run.
    pub max_error: Real,
    /// Rest shape error at the last frame.
    pub final_error: Real,
    /// End-to-end distance at the balanced state (the last frame before
    /// unloading starts), over the rest spacing.
    pub balanced_end_to_end: Real,
    /// Largest particle speed at the balanced state, in rest spacings per
    /// time unit.
    pub balanced_max_speed: Real,
    /// Smallest distance between particles that are not next neighbours
    /// along the spiral (same object), over the run, over the rest spacing.
    pub min_non_adjacent: Real,
    /// Longest distance between next neighbours along the spiral over the
    /// run, over the rest spacing (a bond stretched beyond the distance of
    /// the maximum cohesion attraction, 1.294 r0 for the recipe, gives way
    /// under a constant load).
    pub max_bond: Real,
    /// Largest distance of a particle from the plane z = 0 over the run,
    /// over the rest spacing (the scene is planar: this stays at
    /// round-off level, see the module docs).
    pub max_out_of_plane: Real,
    /// Positions of the first object's particles at each frame, in
    /// generation order.
    pub positions: Vec<Vec<Point3>>,
    /// Their world normals at each frame.
    pub normals: Vec<Vec<Vec3>>,
    /// Steps taken, settle phase included.
    pub steps: u64,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
}

/// Builds `scene`, runs its settle phase, then steps it frame by frame to
/// its end, measuring what [`SpiralRun`] holds. `schedule` says where the
/// balanced state and the end of the load are. The first object is the
/// spiral (its particles in generation order along the curve).
///
/// # Errors
///
/// A message when the scene does not build or the run diverges.
pub fn run_spiral(scene: &Scene, schedule: &Schedule) -> Result<SpiralRun, String> {
    let clock = std::time::Instant::now();
    let mut built = scene.build(None, None).map_err(|e| e.to_string())?;
    built.settle().map_err(|e| format!("while settling: {e}"))?;
    let object = built.objects()[0].clone();
    let n = object.ids.len();
    let r0 = object.rest_spacing;
    let rest_end_to_end = (object.rest[n - 1] - object.rest[0]).norm() / r0;
    let frames = (built.duration() * built.frame_rate()).round() as usize;
    let t0 = built.world().time();
    let mut run = SpiralRun {
        rest_end_to_end,
        min_non_adjacent: Real::INFINITY,
        ..SpiralRun::default()
    };
    for k in 0..=frames {
        if k > 0 {
            let t = t0 + k as Real / built.frame_rate();
            built.world_mut().advance_to(t).map_err(|e| e.to_string())?;
        }
        let time = built.scene_time();
        let p = built.world().particles();
        let slots: Vec<usize> = object
            .ids
            .iter()
            .map(|&id| p.slot_of(id).expect("id of the scene"))
            .collect();
        let pos: Vec<Point3> = slots.iter().map(|&k| p.positions()[k]).collect();
        run.normals
            .push(slots.iter().map(|&k| p.normal(k)).collect());
        let error = op_scene::run::rest_shape_error(&built, &object);
        let e2e = (pos[n - 1] - pos[0]).norm() / r0;
        let speed = p
            .velocities()
            .iter()
            .map(|v| v.norm() / r0)
            .fold(0.0, Real::max);
        for w in pos.windows(2) {
            run.max_bond = run.max_bond.max((w[1] - w[0]).norm() / r0);
        }
        for q in &pos {
            run.max_out_of_plane = run.max_out_of_plane.max(q.z.abs() / r0);
        }
        for i in 0..n {
            for j in i + 2..n {
                run.min_non_adjacent = run.min_non_adjacent.min((pos[j] - pos[i]).norm() / r0);
            }
        }
        if time <= schedule.unload_start + 1e-9 {
            run.balanced_end_to_end = e2e;
            run.balanced_max_speed = speed;
        }
        if time <= schedule.unloaded + 1e-9 {
            run.max_error_loaded = run.max_error_loaded.max(error);
        }
        run.max_error = run.max_error.max(error);
        run.final_error = error;
        run.times.push(time);
        run.errors.push(error);
        run.end_to_end.push(e2e);
        run.max_speed.push(speed);
        run.positions.push(pos);
    }
    run.steps = built.world().steps();
    run.wall_seconds = clock.elapsed().as_secs_f64();
    Ok(run)
}

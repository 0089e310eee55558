//! Stepping the world: one step ([`World::step`]) and its stages, and
//! advancing to a time.

use super::{AfterStep, Divergence, StepReport, World};
use crate::contributors::Contributor;
use crate::forces::Kernel;
use crate::math::Real;
use crate::neighbours::{cluster_order, copy_positions, spatial_order, CLUSTER};

impl World {
    /// Advances by one step: the configured `dt`, or the adaptive
    /// controller's suggestion (at most `dt`).
    ///
    /// Stages, in order: (1) re-sort particles in spatial order when the
    /// neighbour list is about to be rebuilt (Morton order, or column
    /// order in worlds on the cluster kernel,
    /// [`World::runs_mixed_precision`]); (2) integrate, each force
    /// evaluation updating the neighbour list (list-only rebuild when a
    /// stage moved particles past the skin bound), running the pair kernel
    /// and gathering per particle, adding external actions; (3) clear the
    /// pending external forces; (4) advance the temperatures
    /// ([`crate::heat`], when the world has heat); (5) break the bonds
    /// stretched beyond their break length ([`crate::bonds`]); (6) with
    /// plastic materials only, flow the remembered offsets of bond memories
    /// ([`crate::bond_memory`]) and update the remembered curvatures
    /// ([`crate::plasticity`]; the neighbour list is brought up to date for
    /// the new positions first); (7) erasers remove particles; (8) check
    /// for divergence (the oscillation measure is computed on demand from
    /// the positions before and after the step).
    ///
    /// A world of more than 1024 particles takes the step on a thread of
    /// the current rayon pool (the calling thread waits), so that the
    /// step's parallel passes fork and join by work stealing.
    pub fn step(&mut self) -> Result<&StepReport, Divergence> {
        let dt = self.dt_next.min(self.params.dt);
        let n = self.particles.len();
        on_pool(n, || self.step_by(dt, false, &[], &mut []).map(|_| ()))?;
        Ok(&self.report)
    }

    /// Advances until `t_end`, landing on it exactly: the last step is
    /// shortened (a shortened step does not change the adaptive
    /// controller's suggestion for the next one).
    pub fn advance_to(&mut self, t_end: Real) -> Result<(), Divergence> {
        self.advance_to_with(t_end, &[], &mut [])
    }

    /// [`World::advance_to`] with `extra` contributors acting in every force
    /// evaluation of the interval (after the pending forces, before the
    /// force windows; [`crate::contributors`]) and `after_steps` actions run
    /// after every step, after the world's own after-step stages
    /// ([`AfterStep`]): what a driver's stages lend
    /// ([`crate::driver::Stage::lend`]). An explicit coupling evaluated
    /// once per interval acts over all of it, also when an adaptive scheme
    /// takes several steps. Cached forces are dropped when the interval
    /// ends if one of them was active and does not
    /// [`Contributor::follows_state`]: the next interval's contributions
    /// differ. Each one's time is in [`World::interval_seconds`]. The steps
    /// run on a pool thread as [`World::step`]'s do.
    pub fn advance_to_with(
        &mut self,
        t_end: Real,
        extra: &[&dyn Contributor],
        after_steps: &mut [&mut dyn AfterStep],
    ) -> Result<(), Divergence> {
        if extra.iter().any(|c| c.is_active() && c.adds_torque()) {
            self.may_rotate = true;
        }
        let held = extra.iter().any(|c| c.is_active() && !c.follows_state());
        let seconds = &mut self.model.scratch.extra_seconds;
        seconds.clear();
        seconds.resize(extra.len(), 0.0);
        let seconds = &mut self.model.scratch.lent_after_step_seconds;
        seconds.clear();
        seconds.resize(after_steps.len(), 0.0);
        let n = self.particles.len();
        on_pool(n, || self.advance_steps(t_end, extra, after_steps, held))
    }

    /// The steps of [`World::advance_to_with`] (on a pool thread).
    fn advance_steps(
        &mut self,
        t_end: Real,
        extra: &[&dyn Contributor],
        after_steps: &mut [&mut dyn AfterStep],
        held: bool,
    ) -> Result<(), Divergence> {
        loop {
            let remaining = t_end - self.time;
            if remaining <= 1e-12 * self.params.dt {
                if held {
                    self.integrator.invalidate_forces();
                }
                return Ok(());
            }
            let h = self.dt_next.min(self.params.dt);
            // A step within 1e-6 of the remaining time takes all of it, so
            // round-off in the accumulated time never leaves a sliver step.
            if remaining <= h * (1.0 + 1e-6) {
                self.step_by(remaining, true, extra, after_steps)?;
                if self.time < t_end && self.report.dt == remaining {
                    // Land exactly despite round-off in `time + dt`.
                    self.time = t_end;
                }
            } else {
                self.step_by(h, false, extra, after_steps)?;
            }
        }
    }

    fn step_by(
        &mut self,
        dt: Real,
        clipped: bool,
        extra: &[&dyn Contributor],
        after_steps: &mut [&mut dyn AfterStep],
    ) -> Result<&StepReport, Divergence> {
        // The last report's buffer, to time this step's stages in.
        let mut seconds = std::mem::take(&mut self.report.seconds);
        seconds.clear();
        let mut report = StepReport {
            seconds,
            ..StepReport::default()
        };
        let clock = std::time::Instant::now();
        let positions = self.particles.positions();
        let due = self.params.neighbours.reorder
            && self
                .model
                .neighbours
                .as_mut()
                .is_some_and(|list| list.rebuild_due(positions));
        if due {
            // Worlds on the cluster kernel keep compact clusters; the
            // others keep Morton order.
            let clustered = self.runs_mixed_precision();
            if let Some(list) = self.model.neighbours.as_mut() {
                let p = self.particles.positions();
                let order = if clustered {
                    cluster_order(p, CLUSTER)
                } else {
                    spatial_order(p, list.cutoff() + list.skin())
                };
                self.particles.permute(&order);
                list.rebuild_reference(self.particles.positions());
                self.integrator.permute(&order);
                report.reordered = true;
            }
        }
        copy_positions(&mut self.prev_positions, self.particles.positions());
        report
            .seconds
            .push(("reorder", clock.elapsed().as_secs_f64()));

        let clock = std::time::Instant::now();
        let neighbour_before = self.model.scratch.neighbour_seconds;
        let extra_before: f64 = self.model.scratch.extra_seconds.iter().sum();
        // Spacing-only worlds that nothing set spinning never rotate.
        let rotating = self.model.kernel == Kernel::Oriented || self.may_rotate;
        self.integrator.set_translation_only(!rotating);
        let (state, bodies, attributes) = self.particles.split();
        let mut ctx =
            self.model
                .context(attributes, &self.params.external, &self.accumulator, extra);
        ctx.step_start = Some(self.time);
        let info = self
            .integrator
            .step(&mut ctx, &bodies, self.time, dt, state);
        let neighbour_seconds = self.model.scratch.neighbour_seconds - neighbour_before;
        // The interval's contributors are timed on their own
        // (World::interval_seconds): their callers' stages report them.
        let extra_seconds = self.model.scratch.extra_seconds.iter().sum::<f64>() - extra_before;
        report.seconds.push(("neighbours", neighbour_seconds));
        report.seconds.push((
            "integrate",
            clock.elapsed().as_secs_f64() - neighbour_seconds - extra_seconds,
        ));
        report.dt = info.dt_taken;
        report.rejected = info.rejected;
        report.force_evaluations = info.force_evaluations;
        self.time += info.dt_taken;
        self.steps += 1;
        self.forced_in_a_row = match info.tolerance_met() {
            true => 0,
            false => self.forced_in_a_row.saturating_add(1),
        };
        if !clipped || info.dt_taken < dt {
            self.dt_next = info.dt_next;
        }
        if self.accumulator.is_active() {
            self.accumulator.clear();
            self.integrator.invalidate_forces();
        }
        // The after-step stages, in order; their effects applied once and
        // kept for the driver.
        let effects = self.run_after_step_stages(info.dt_taken, &mut report, after_steps);
        self.effects.merge(effects);

        let clock = std::time::Instant::now();
        let check = self
            .check_divergence()
            .and_then(|()| self.check_progress(&info));
        report
            .seconds
            .push(("check", clock.elapsed().as_secs_f64()));
        for &(name, s) in &report.seconds {
            match self.stage_seconds.iter_mut().find(|(n, _)| *n == name) {
                Some(total) => total.1 += s,
                None => self.stage_seconds.push((name, s)),
            }
        }
        self.report = report;
        check?;
        Ok(&self.report)
    }
}

/// Runs `f`, the steps of a world of `n` particles, on a thread of the
/// current rayon pool: on the calling thread when it is one (inside
/// [`rayon::ThreadPool::install`]), else on one of the global pool's
/// threads while the caller waits. A step has several parallel passes
/// (the neighbour list's motion check, the integrator's kick and drift,
/// the pair passes, the divergence check): entered from a pool thread,
/// each fork-join hands its work to the other threads by work stealing;
/// entered from outside the pool, each one injects a job, wakes a pool
/// thread and puts the caller to sleep until it is done, two thread
/// wake-ups per pass. Worlds of one accumulation block (fewer than
/// [`crate::forces::SPLIT_MIN`] particles, so also one integrator chunk,
/// [`crate::integrators::per_particle::CHUNK`]) have no parallel pass and stay on the
/// caller's thread. Same work, same bits: only the thread that runs the
/// serial parts changes.
///
/// Measured (the performance report's spacing child, 97,556 particles, 10
/// steps, 3 interleaved pairs against the caller's thread): 1 thread 0.49
/// against 0.51 s, 2 threads 0.26-0.29 s either way. It costs memory: what
/// the steps allocate comes from the pool thread's malloc arena, not the
/// caller's, and peak memory was 10% higher at 1 thread (133 against 120
/// MB) and 4% at 2.
fn on_pool<R: Send>(n: usize, f: impl FnOnce() -> R + Send) -> R {
    if n < crate::forces::SPLIT_MIN || rayon::current_thread_index().is_some() {
        return f();
    }
    rayon::scope(|_| f())
}

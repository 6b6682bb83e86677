//! Stepping a [`Coupling`] to a time, within a budget of internal steps and wall clock.

use super::{engine, Coupling, CouplingError};

/// What one `step_to` did (for solver logging).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepReport {
    pub steps: u64,
    pub dt_min: f64,
    pub dt_max: f64,
    /// Set when a [`StepBudget`] ran out before the target time: the state is then that of
    /// the last whole internal step (`Coupling::time`).
    pub stopped: Option<StepLimit>,
}

/// Which budget stopped a bounded step, and how much of it was used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StepLimit {
    /// Internal steps taken.
    Steps(u64),
    /// Wall-clock seconds spent.
    Seconds(f64),
}

/// Bounds on one [`Coupling::step_within`] (None: unbounded) and a progress callback,
/// called on the caller's thread with (time, internal steps, wall seconds) after every second
/// of wall clock the step takes.
#[derive(Default)]
pub struct StepBudget<'a> {
    pub max_steps: Option<u64>,
    pub max_seconds: Option<f64>,
    pub progress: Option<&'a mut dyn FnMut(f64, u64, f64)>,
}

impl Coupling {
    /// Advance to time `t` exactly (sub-steps with the solver's own time step; the last one
    /// lands on t). `t` must not lie before the current time.
    pub fn step_to(&mut self, t: f64) -> Result<StepReport, CouplingError> {
        self.step_within(t, &mut StepBudget::default())
    }

    /// [`Self::step_to`] within a budget of internal steps and wall-clock seconds: when one
    /// runs out first, the report says which (`stopped`) and the state is that of the last
    /// whole internal step, short of `t`. A solver failure is an error as in `step_to`.
    pub fn step_within(
        &mut self,
        t: f64,
        budget: &mut StepBudget,
    ) -> Result<StepReport, CouplingError> {
        let now = self.time();
        if !t.is_finite() || t < now {
            return Err(CouplingError(format!(
                "step_to: target time must be finite and ≥ the current time {now}, got {t}"
            )));
        }
        // in chunks of at most a second of wall clock, each inside the pool, so the progress
        // callback runs on the caller's thread (an FMU's logger belongs to the master's)
        let clock = std::time::Instant::now();
        let mut total = StepReport {
            dt_min: f64::INFINITY,
            ..StepReport::default()
        };
        loop {
            let spent = clock.elapsed().as_secs_f64();
            let chunk = engine::Chunk {
                max_steps: budget.max_steps.map(|m| m.saturating_sub(total.steps)),
                max_seconds: Some(budget.max_seconds.map_or(1.0, |m| (m - spent).min(1.0))),
            };
            let engine = &mut self.engine;
            let r = self
                .pool
                .install(|| engine.advance_to(t, &chunk))
                .map_err(|e| CouplingError(e.to_string()))?;
            total.steps += r.steps;
            if r.steps > 0 {
                total.dt_min = total.dt_min.min(r.dt_min);
                total.dt_max = total.dt_max.max(r.dt_max);
            }
            let spent = clock.elapsed().as_secs_f64();
            if r.stopped.is_none() {
                break;
            }
            if budget.max_steps.is_some_and(|m| total.steps >= m) {
                total.stopped = Some(StepLimit::Steps(total.steps));
                break;
            }
            if budget.max_seconds.is_some_and(|m| spent >= m) {
                total.stopped = Some(StepLimit::Seconds(spent));
                break;
            }
            if let Some(f) = budget.progress.as_mut() {
                f(self.time(), total.steps, spent);
            }
        }
        if total.steps == 0 {
            total.dt_min = 0.0;
        }
        Ok(total)
    }
}

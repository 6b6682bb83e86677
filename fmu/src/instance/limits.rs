//! The `limits.*` parameters: caps on the size of the run (checked when the solver is built,
//! before anything is allocated: `sphfmu::case::Case::check_resources`) and on the work of one
//! doStep (internal steps, wall-clock seconds). All are off (0) by default.
//!
//! A doStep that runs out of its budget stops after the last whole internal step and returns
//! Discard, with `lastSuccessfulTime` (FMI 3.0) / `fmi2LastSuccessfulTime` (FMI 2.0) at the
//! time it reached and a log line saying how far it got. The instance stays in step mode: the
//! master may restore an earlier FMU state, or go on from the time reached.

use super::{err, CallResult};

/// Which limit a parameter sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LimitParam {
    MaxParticles,
    MaxMemory,
    MaxInternalSteps,
    MaxStepSeconds,
}

#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Limits {
    /// Particles (0: the case's `[limits]`, else none).
    pub max_particles: i64,
    /// Bytes (0: the case's `[limits]`, else the machine's available memory).
    pub max_memory: f64,
    /// Internal steps per doStep (0: unbounded).
    pub max_internal_steps: i64,
    /// Wall-clock seconds per doStep (0: unbounded).
    pub max_step_seconds: f64,
}

/// The rows of the variable table: name, Int64 or not, unit, description.
pub const ROWS: [(&str, LimitParam, bool, Option<&str>, &str); 4] = [
    (
        "limits.max_particles",
        LimitParam::MaxParticles,
        true,
        None,
        "Most particles the run may have; a case that needs more is refused when the solver is built, before any allocation (0 = the case's [limits], else the solver's own limit)",
    ),
    (
        "limits.max_memory",
        LimitParam::MaxMemory,
        false,
        None,
        "Most memory the solver may hold, in bytes (2e9 = 2 GB); a case estimated to need more is refused when the solver is built (0 = the case's [limits], else the memory the machine has available)",
    ),
    (
        "limits.max_internal_steps",
        LimitParam::MaxInternalSteps,
        true,
        None,
        "Most internal steps one doStep may take; past it doStep returns Discard at the time reached (0 = no limit)",
    ),
    (
        "limits.max_step_seconds",
        LimitParam::MaxStepSeconds,
        false,
        Some("s"),
        "Most wall-clock seconds one doStep may take; past it doStep returns Discard at the time reached (0 = no limit)",
    ),
];

impl Limits {
    pub fn set_i64(&mut self, which: LimitParam, value: i64) -> CallResult<()> {
        if value < 0 {
            return err(format!(
                "{}: must be ≥ 0 (0 = no limit), got {value}",
                name(which)
            ));
        }
        match which {
            LimitParam::MaxParticles => self.max_particles = value,
            LimitParam::MaxInternalSteps => self.max_internal_steps = value,
            _ => return err(format!("{}: is a Float64", name(which))),
        }
        Ok(())
    }

    pub fn set_f64(&mut self, which: LimitParam, value: f64) -> CallResult<()> {
        if !(value.is_finite() && value >= 0.0) {
            return err(format!(
                "{}: must be a finite number ≥ 0 (0 = no limit), got {value}",
                name(which)
            ));
        }
        match which {
            LimitParam::MaxMemory => self.max_memory = value,
            LimitParam::MaxStepSeconds => self.max_step_seconds = value,
            _ => return err(format!("{}: is an Int64", name(which))),
        }
        Ok(())
    }

    pub fn get(&self, which: LimitParam) -> f64 {
        match which {
            LimitParam::MaxParticles => self.max_particles as f64,
            LimitParam::MaxMemory => self.max_memory,
            LimitParam::MaxInternalSteps => self.max_internal_steps as f64,
            LimitParam::MaxStepSeconds => self.max_step_seconds,
        }
    }

    /// The size limits as the core takes them (None where the parameter is 0).
    pub fn size(&self) -> sphfmu::case::Limits {
        sphfmu::case::Limits {
            max_particles: (self.max_particles > 0).then_some(self.max_particles as u64),
            max_memory: (self.max_memory > 0.0).then_some(self.max_memory),
        }
    }

    /// The budget of one doStep, with `progress` called after every second of wall clock.
    pub fn budget<'a>(
        &self,
        progress: &'a mut dyn FnMut(f64, u64, f64),
    ) -> sphfmu::coupling::StepBudget<'a> {
        sphfmu::coupling::StepBudget {
            max_steps: (self.max_internal_steps > 0).then_some(self.max_internal_steps as u64),
            max_seconds: (self.max_step_seconds > 0.0).then_some(self.max_step_seconds),
            progress: Some(progress),
        }
    }
}

pub fn name(which: LimitParam) -> &'static str {
    ROWS.iter().find(|r| r.1 == which).map_or("limits", |r| r.0)
}

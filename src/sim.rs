//! The driver: a system, a scheme and an integrator, advanced with a global time step.

use crate::integrate::{Integrator, IntegratorKind};
use crate::particles::{Particles, Vector};
use crate::scheme::Scheme;
use crate::system::System;
use rayon::prelude::*;
use serde::Serialize;
use std::fmt;

/// Time-step control (`[time]` in case files).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepControl {
    /// Courant factor on h/v_sig, with v_sig = max_b(c_a + c_b − 3 min(0, v_ab·r̂_ab)).
    pub cfl: f64,
    /// Factor on sqrt(h/|a|).
    pub cfl_accel: f64,
    /// A step below this stops the run (instability).
    pub dt_min: f64,
    pub dt_max: f64,
    /// Largest growth of dt from one step to the next.
    pub max_growth: f64,
}

impl Default for StepControl {
    fn default() -> Self {
        Self {
            cfl: 0.3,
            cfl_accel: 0.25,
            dt_min: 1e-12,
            dt_max: f64::INFINITY,
            max_growth: 1.5,
        }
    }
}

/// Why a run stopped early.
#[derive(Debug, Clone, PartialEq)]
pub enum SolverError {
    NonFinite {
        field: &'static str,
        particle: u32,
        time: f64,
        step: u64,
    },
    DtCollapse {
        dt: f64,
        dt_min: f64,
        time: f64,
        step: u64,
    },
    Scheme {
        message: String,
        time: f64,
        step: u64,
    },
}

impl fmt::Display for SolverError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SolverError::NonFinite { field, particle, time, step } => write!(
                f,
                "unstable: non-finite {field} on particle {particle} at t = {time:.6e} (step {step})"
            ),
            SolverError::DtCollapse { dt, dt_min, time, step } => write!(
                f,
                "unstable: time step {dt:.3e} fell below time.dt_min = {dt_min:.3e} at t = {time:.6e} (step {step})"
            ),
            SolverError::Scheme { message, time, step } => {
                write!(f, "scheme failed at t = {time:.6e} (step {step}): {message}")
            }
        }
    }
}

impl std::error::Error for SolverError {}

/// Conserved totals and step facts at one instant.
#[derive(Debug, Clone, Copy, Serialize, Default)]
pub struct Diagnostics {
    pub time: f64,
    pub step: u64,
    pub dt: f64,
    /// All particles: fluid, walls and port buffers.
    pub particles: usize,
    /// Fluid particles (neither wall nor port buffer): ports create and delete particles.
    pub fluid_particles: usize,
    /// Fluid mass (walls and port buffers excluded).
    pub mass: f64,
    pub momentum: [f64; 3],
    pub angular_momentum: [f64; 3],
    pub kinetic_energy: f64,
    pub internal_energy: f64,
    /// Energy in uniform gravity, −Σ m g·x (zero without gravity; zero in a moving `[frame]`,
    /// where the body force also holds the frame's acceleration and has no fixed potential).
    pub potential_energy: f64,
    /// Kinetic + internal + potential.
    pub total_energy: f64,
    /// The largest Lorentz factor of the fluid (1 in Newtonian runs).
    pub max_lorentz: f64,
}

/// How a run's particles are shared among processes (`parallel`): the driver asks it to
/// agree on the time step and on every step's outcome, to renew the halo before each step,
/// and to total the diagnostics. `None` in a single-process run.
pub trait Layout<const D: usize>: Send + Sync {
    /// The step every rank takes, from this rank's stability limit.
    fn agree_dt(&self, local: f64) -> Result<f64, String>;
    /// Ok on every rank, or every rank's copy of the first failure.
    fn agree(&self, result: Result<(), String>) -> Result<(), String>;
    /// Before a step of `dt`: hand particles that left this rank's region to their new
    /// owners, rebalance when due, and build the halo the step needs.
    fn before_step(&mut self, sys: &mut System<D>, dt: f64) -> Result<(), String>;
    /// At a step's end: particles crossing port openings ([`System::exchange_port_particles`]
    /// over the ranks).
    fn after_step(&mut self, sys: &mut System<D>) -> Result<(), String>;
    /// Make the halo fit for an evaluation outside a step (inputs moved walls, or a state
    /// was restored): hand particles to their owners and build the halo anew; `dt` is the
    /// motion's time scale (the last step).
    fn refresh(&mut self, sys: &mut System<D>, dt: f64) -> Result<(), String>;
    /// Every rank's own particles, ordered by id (a collective; every rank gets them all).
    fn gather(&self, sys: &System<D>) -> Result<Particles<D>, String>;
    /// Replace the run's particles by `all` (a whole case's, as [`Self::gather`] gives):
    /// this rank keeps those in its region, and builds its halo before the next evaluation.
    fn replace(&mut self, sys: &mut System<D>, all: Particles<D>);
    /// Totals over the ranks of this rank's diagnostics.
    fn totals(&self, local: Diagnostics) -> Result<Diagnostics, String>;
    /// Element-wise sums over the ranks.
    fn sum(&self, x: &[f64]) -> Result<Vec<f64>, String>;
    /// What the ranks exchanged so far (this rank's counters), and how many ranks there are.
    fn exchange(&self) -> (usize, crate::parallel::ExchangeStats);
}

pub struct Simulation<const D: usize> {
    pub sys: System<D>,
    pub scheme: Box<dyn Scheme<D>>,
    pub integrator: Integrator<D>,
    pub control: StepControl,
    pub time: f64,
    pub steps: u64,
    pub last_dt: f64,
    /// Reorder particles along the grid every this many steps (cache locality); 0 = never.
    pub reorder_every: u64,
    /// Set in a distributed run (`parallel::Distributed`).
    pub layout: Option<Box<dyn Layout<D>>>,
}

impl<const D: usize> Simulation<D> {
    /// Initialise the scheme and evaluate the derivatives of the initial state.
    pub fn new(
        mut sys: System<D>,
        mut scheme: Box<dyn Scheme<D>>,
        kind: IntegratorKind,
        control: StepControl,
    ) -> Result<Self, SolverError> {
        sys.place_bodies(0.0);
        sys.apply_drives().map_err(|message| SolverError::Scheme {
            message,
            time: 0.0,
            step: 0,
        })?;
        scheme.init(&mut sys);
        scheme.evaluate(&mut sys).map_err(|e| SolverError::Scheme {
            message: e.0,
            time: 0.0,
            step: 0,
        })?;
        sys.hold_constrained();
        let sim = Self {
            sys,
            scheme,
            integrator: Integrator::new(kind),
            control,
            time: 0.0,
            steps: 0,
            last_dt: 0.0,
            reorder_every: 20,
            layout: None,
        };
        sim.check_finite()?;
        Ok(sim)
    }

    /// The step the stability criteria allow now (on every rank, in a distributed run: a
    /// failed agreement gives NaN, which stops the run as a collapsed step).
    pub fn stable_dt(&self) -> f64 {
        self.stable_dt_and_cause().0
    }

    /// [`Self::stable_dt`], and whether the scheme's own limit ([`Scheme::step_limit`]) set
    /// it on this process.
    fn stable_dt_and_cause(&self) -> (f64, bool) {
        let (dt, by_scheme) = self.local_stable_dt();
        let agreed = match &self.layout {
            Some(l) => l.agree_dt(dt).unwrap_or(f64::NAN),
            None => dt,
        };
        (agreed, by_scheme && agreed == dt)
    }

    /// [`Self::stable_dt`] over this process's own particles.
    fn local_stable_dt(&self) -> (f64, bool) {
        let p = &self.sys.particles;
        let c = &self.control;
        let mut dt = (0..self.sys.owned())
            .into_par_iter()
            .with_min_len(crate::threads::LIGHT)
            .map(|a| {
                let h = p.h[a];
                let mut dt = f64::INFINITY;
                if p.v_sig[a] > 0.0 {
                    dt = dt.min(c.cfl * h / p.v_sig[a]);
                }
                let amag = p.acc[a].norm();
                if amag > 0.0 {
                    dt = dt.min(c.cfl_accel * (h / amag).sqrt());
                }
                dt
            })
            .reduce(|| f64::INFINITY, f64::min)
            .min(c.dt_max);
        if self.last_dt > 0.0 {
            dt = dt.min(c.max_growth * self.last_dt);
        }
        let own = self.scheme.step_limit(&self.sys);
        (dt.min(own), own < dt)
    }

    fn check_finite(&self) -> Result<(), SolverError> {
        if let Some((i, field)) = self.sys.first_non_finite() {
            return Err(SolverError::NonFinite {
                field,
                particle: self.sys.particles.id[i],
                time: self.time,
                step: self.steps,
            });
        }
        Ok(())
    }

    /// One step of at most `dt_cap`. Returns the step taken.
    pub fn step(&mut self, dt_cap: f64) -> Result<f64, SolverError> {
        let stable = self.stable_dt_and_cause();
        self.step_with(stable, dt_cap)
    }

    /// [`Self::step`] with the stability limit already computed.
    /// `stable` comes with whether the scheme's own limit set it (counted in the stats when
    /// the step is that long).
    ///
    /// Compiled in this crate once per dimension (`crate::monomorphic`).
    fn step_with(&mut self, stable: (f64, bool), dt_cap: f64) -> Result<f64, SolverError> {
        crate::monomorphic::step_with(self, stable, dt_cap)
    }

    /// [`Self::step_with`]'s work, generic over D.
    pub(crate) fn step_with_generic(
        &mut self,
        stable: (f64, bool),
        dt_cap: f64,
    ) -> Result<f64, SolverError> {
        let (stable, by_scheme) = stable;
        if by_scheme && stable <= dt_cap {
            self.sys.stats.steps_set_by_scheme += 1;
        }
        let mut dt = stable.min(dt_cap);
        if !(dt.is_finite()) {
            dt = dt_cap;
        }
        // A dt cap (output time, end time) may be tiny; only the stability limit can collapse.
        if stable.is_nan() || stable < self.control.dt_min {
            return Err(SolverError::DtCollapse {
                dt: stable,
                dt_min: self.control.dt_min,
                time: self.time,
                step: self.steps,
            });
        }
        if let Some(layout) = &mut self.layout {
            layout
                .before_step(&mut self.sys, dt)
                .map_err(|message| self.ranks_failed(message))?;
        } else if self.reorder_every > 0 && self.steps > 0 && self.steps % self.reorder_every == 0 {
            self.reorder();
        }
        // the integrator gives each evaluation its stage's time from the step's end time
        self.sys.time = self.time + dt;
        let (integrator, sys, scheme) = (&mut self.integrator, &mut self.sys, &mut self.scheme);
        let mut step = || integrator.step(sys, scheme.as_mut(), dt);
        // A distributed run's ranks may share cores (mpirun --oversubscribe, or a pool of
        // one thread per core in each rank): a spinning partner would take CPU from another
        // rank, so only a single process keeps its partner thread awake.
        let result = if self.layout.is_none() {
            crate::threads::with_partner_awake(step)
        } else {
            step()
        };
        result.map_err(|e| SolverError::Scheme {
            message: e.0,
            time: self.time,
            step: self.steps,
        })?;
        self.scheme.end_step(&mut self.sys, dt);
        self.time += dt;
        // walls land exactly on their body's pose (the integrator moved them approximately)
        self.sys.place_bodies(self.time);
        self.sys.time = self.time;
        // particles cross the port openings: fluid in, fluid out, buffers refilled
        match &mut self.layout {
            Some(layout) => {
                if let Err(message) = layout.after_step(&mut self.sys) {
                    return Err(self.ranks_failed(message));
                }
            }
            None => {
                self.sys.exchange_port_particles();
            }
        }
        self.steps += 1;
        if dt < dt_cap || self.last_dt == 0.0 {
            self.last_dt = dt;
        }
        self.agreed(self.check_finite())?;
        Ok(dt)
    }

    /// `result` where every rank agrees it is Ok; else this rank's own error, or the first
    /// failing rank's.
    fn agreed(&self, result: Result<(), SolverError>) -> Result<(), SolverError> {
        let Some(layout) = &self.layout else {
            return result;
        };
        let shared = layout.agree(result.as_ref().map(|_| ()).map_err(|e| e.to_string()));
        result.and(shared.map_err(|m| self.ranks_failed(m)))
    }

    /// A distributed run's failure as a solver error at the current step.
    fn ranks_failed(&self, message: String) -> SolverError {
        SolverError::Scheme {
            message: format!("distributed run: {message}"),
            time: self.time,
            step: self.steps,
        }
    }

    /// Advance to time t exactly (the last step is shortened to land on t).
    pub fn advance_to(
        &mut self,
        t: f64,
        mut on_step: impl FnMut(&Self),
    ) -> Result<(), SolverError> {
        self.advance_while(t, |s| {
            on_step(s);
            true
        })
    }

    /// Advance towards time t like [`Self::advance_to`], asking `go_on` after every step
    /// whether to take the next: a bounded co-simulation step stops where its step count or
    /// wall-clock budget runs out (then `self.time < t`, and the state is a whole step's).
    pub fn advance_while(
        &mut self,
        t: f64,
        mut go_on: impl FnMut(&Self) -> bool,
    ) -> Result<(), SolverError> {
        while self.time < t {
            let remaining = t - self.time;
            // Avoid a sliver step: split the last two steps evenly.
            let (stable, by_scheme) = self.stable_dt_and_cause();
            let cap = if remaining > stable && remaining < 2.0 * stable {
                0.5 * remaining
            } else {
                remaining
            };
            self.step_with((stable, by_scheme), cap)?;
            if (t - self.time).abs() <= 1e-12 * t.abs().max(1.0) {
                self.time = t;
            }
            if !go_on(self) && self.time < t {
                break;
            }
        }
        Ok(())
    }

    /// Evaluate the derivatives again at the current state (after an input changed: gravity,
    /// or the pose of an externally driven body, whose walls are placed first).
    ///
    /// Compiled in this crate once per dimension (`crate::monomorphic`).
    pub fn reevaluate(&mut self) -> Result<(), SolverError> {
        crate::monomorphic::reevaluate(self)
    }

    /// [`Self::reevaluate`]'s work, generic over D.
    pub(crate) fn reevaluate_generic(&mut self) -> Result<(), SolverError> {
        self.sys.place_bodies(self.time);
        self.sys.time = self.time;
        self.sys
            .apply_drives()
            .map_err(|message| SolverError::Scheme {
                message,
                time: self.time,
                step: self.steps,
            })?;
        if let Some(layout) = &mut self.layout {
            // the walls may have jumped to a master's pose, or the particles come from a
            // restored state: the halo is built for them (a collective: every rank's inputs
            // are the same, so every rank reevaluates)
            layout
                .refresh(&mut self.sys, self.last_dt)
                .map_err(|message| self.ranks_failed(message))?;
        }
        self.scheme
            .evaluate(&mut self.sys)
            .map_err(|e| SolverError::Scheme {
                message: e.0,
                time: self.time,
                step: self.steps,
            })?;
        self.sys.hold_constrained();
        self.check_finite()
    }

    /// Sort particles by grid cell for memory locality.
    pub fn reorder(&mut self) {
        let perm = self.sys.grid.sorted.clone();
        if perm.len() == self.sys.particles.len() {
            self.sys.permute_particles(&perm);
        }
    }

    /// The conserved totals (over every rank in a distributed run; NaN totals if the ranks
    /// could not agree).
    pub fn diagnostics(&self) -> Diagnostics {
        let local = self.local_diagnostics();
        match &self.layout {
            Some(l) => l.totals(local).unwrap_or(Diagnostics {
                total_energy: f64::NAN,
                ..local
            }),
            None => local,
        }
    }

    /// [`Self::diagnostics`] over this process's own particles.
    fn local_diagnostics(&self) -> Diagnostics {
        if let Some(sr) = self.sys.relativistic {
            return self.relativistic_diagnostics(sr);
        }
        let p = &self.sys.particles;
        let g = if self.sys.frame.is_none() {
            self.sys.gravity
        } else {
            Vector::<D>::zeros()
        };
        let mut d = self.totals(|range| {
            let mut d = Diagnostics::default();
            for a in range {
                // the fluid only: wall particles belong to bodies, whose loads are reported
                // apart, and port buffers are outside the domain
                if p.body[a] != 0 || p.port[a] != 0 {
                    continue;
                }
                d.fluid_particles += 1;
                let m = p.mass[a];
                let v = p.vel[a];
                let x = p.pos[a];
                d.mass += m;
                for k in 0..D {
                    d.momentum[k] += m * v[k];
                }
                let (x3, v3) = (to3(&x), to3(&v));
                let l = x3.cross(&v3) * m;
                for k in 0..3 {
                    d.angular_momentum[k] += l[k];
                }
                d.kinetic_energy += 0.5 * m * v.norm_squared();
                d.internal_energy += m * p.u[a];
                d.potential_energy -= m * g.dot(&x);
            }
            d
        });
        d.total_energy = d.kinetic_energy + d.internal_energy + d.potential_energy;
        d
    }

    /// Time, step and particle count, with the totals of `block` over the owned particles,
    /// summed in fixed blocks ([`crate::threads::block_reduce`]: in parallel, and
    /// the same bits on any thread count).
    fn totals(&self, block: impl Fn(std::ops::Range<usize>) -> Diagnostics + Sync) -> Diagnostics {
        let t = crate::threads::block_reduce(
            self.sys.owned(),
            block,
            |a, b| Diagnostics {
                fluid_particles: a.fluid_particles + b.fluid_particles,
                mass: a.mass + b.mass,
                momentum: std::array::from_fn(|k| a.momentum[k] + b.momentum[k]),
                angular_momentum: std::array::from_fn(|k| {
                    a.angular_momentum[k] + b.angular_momentum[k]
                }),
                kinetic_energy: a.kinetic_energy + b.kinetic_energy,
                internal_energy: a.internal_energy + b.internal_energy,
                potential_energy: a.potential_energy + b.potential_energy,
                total_energy: a.total_energy + b.total_energy,
                max_lorentz: a.max_lorentz.max(b.max_lorentz),
                ..a
            },
            Diagnostics::default(),
        );
        Diagnostics {
            time: self.time,
            step: self.steps,
            dt: self.last_dt,
            particles: self.sys.owned(),
            // 1 in Newtonian runs (their blocks leave it 0)
            max_lorentz: t.max_lorentz.max(1.0),
            ..t
        }
    }

    /// The conserved totals of a special-relativistic run (Rosswog (2015) Eqs. 54, 56):
    /// momentum Σ ν S, angular momentum Σ ν x × S, and energy Σ ν (ε − 1), the rest-mass
    /// energy Σ ν left out so that it tends to the Newtonian Σ m(½v² + u). Of it, kinetic is
    /// Σ ν (γ − 1) and internal the rest.
    fn relativistic_diagnostics(&self, sr: crate::scheme::rosswog::sr::SrSlots) -> Diagnostics {
        let p = &self.sys.particles;
        let (s, eps, lorentz) = (
            &p.extra_vectors[sr.momentum],
            &p.extra_scalars[sr.energy],
            &p.extra_scalars[sr.lorentz],
        );
        let mut d = self.totals(|range| {
            let mut d = Diagnostics::default();
            for a in range {
                d.fluid_particles += 1;
                let nu = p.mass[a];
                d.mass += nu;
                for (m, s_k) in d.momentum.iter_mut().zip(s[a].iter()) {
                    *m += nu * s_k;
                }
                let l = to3(&p.pos[a]).cross(&to3(&s[a])) * nu;
                for k in 0..3 {
                    d.angular_momentum[k] += l[k];
                }
                d.total_energy += nu * (eps[a] - 1.0);
                d.kinetic_energy += nu * (lorentz[a] - 1.0);
                d.max_lorentz = d.max_lorentz.max(lorentz[a]);
            }
            d
        });
        d.internal_energy = d.total_energy - d.kinetic_energy;
        d
    }
}

fn to3<const D: usize>(v: &Vector<D>) -> nalgebra::Vector3<f64> {
    let mut o = nalgebra::Vector3::zeros();
    for k in 0..D {
        o[k] = v[k];
    }
    o
}

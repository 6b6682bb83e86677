//! Pressure ports (issue 6): openings in a body's wall through which the fluid connects to an
//! outside model (a pipe network, a reservoir) that sets the pressure and receives the flow.
//!
//! An opening is a segment (2D), disk or rectangle (3D) on a body surface with a unit normal n
//! into the fluid. Behind it, where the body's wall layers were, sits a buffer of particles in
//! the style of Tafuni, Domínguez, Vacondio & Crespo (2018, CMAME 342, 604): buffer particles
//! take part in every SPH sum like fluid, but their state is set each evaluation by the
//! port condition instead of evolving:
//!
//! * **Pressure**: P_b = 2 P_s − P̂(x_m), with x_m = x_b − 2 d_b n the mirror image of the buffer
//!   particle (d_b = (x_b − x_c)·n < 0) in the fluid, P̂ the Shepard-interpolated fluid
//!   pressure there and P_s = P_port + ρ̂ g·t_b the port pressure carried along the opening
//!   hydrostatically (t_b: the tangential offset from the port centre). This continues the
//!   fluid's pressure field linearly through the opening so it takes the value P_s on the
//!   opening plane — *decision*: Tafuni et al. prescribe the buffer pressure itself (zero-
//!   order); a uniform buffer at P_port leaves the fluid's first rows feeling a pressure jump
//!   at the plane, which shortens a channel's effective pressure drop by about a kernel radius
//!   at each end. With the linear continuation a hydrostatic column through a bottom port
//!   (P_port = ρgH) stays at rest and a linear pressure drop runs straight into the buffer.
//! * **Density** from the EOS at P_b (so the buffer reads the liquid's compression), mass
//!   ρ_b V_b with the body's particle volume (as for the walls, `boundary::bodies`).
//! * **Velocity**: the normal part of the Shepard-interpolated fluid velocity at x_m (zero
//!   normal gradient, Tafuni et al.'s pressure outlet). *Decision*: the tangential part is
//!   dropped so that buffer particles advance along n only and never drift into the wall next
//!   to the opening.
//! * Buffer particles feel no forces (dv/dt = 0): they move at the velocity they are given.
//!
//! At the end of each step (`exchange`): a buffer particle that crossed the plane into the
//! fluid becomes fluid (its mass counts as `mass_in`) and a copy of it enters the buffer one
//! buffer depth behind, so the buffer stays full under inflow; a fluid particle that crossed
//! the plane within the opening becomes a buffer particle (`mass_out`); a buffer particle
//! beyond the buffer depth is deleted. So the fluid mass is the initial mass + Σ mass_in −
//! Σ mass_out exactly. Ports sit on fixed bodies; a moving tank with ports runs in its own
//! frame (`[frame]`).

use crate::particles::Vector;
use crate::system::System;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// `pressure = { type = ..., ... }` of a `[[port]]`: the port pressure over time (the same
/// gauge as the solver's pressure: 0 at the EOS reference density).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum PortPressure {
    Constant {
        value: f64,
    },
    /// mean + amplitude·sin(2π f t + phase).
    Sinusoid {
        mean: f64,
        amplitude: f64,
        frequency: f64,
        #[serde(default)]
        phase: f64,
    },
    /// `from` until `start`, linear to `to` over `duration`, then `to` (duration 0: a step).
    Ramp {
        from: f64,
        to: f64,
        #[serde(default)]
        start: f64,
        duration: f64,
    },
    /// Values at increasing times, linear in between, held outside.
    Table {
        time: Vec<f64>,
        value: Vec<f64>,
    },
    /// Set by the master through the Coupling API (`initial` until the first set).
    External {
        #[serde(default)]
        initial: f64,
    },
}

impl Default for PortPressure {
    fn default() -> Self {
        PortPressure::Constant { value: 0.0 }
    }
}

impl PortPressure {
    /// Check the entries; `key` names the field (e.g. `port[0].pressure`).
    pub fn validate(&self, key: &str) -> Result<(), String> {
        let finite = |name: &str, v: f64| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(format!("{key}.{name}: must be finite, got {v}"))
            }
        };
        let non_negative = |name: &str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(format!(
                    "{key}.{name}: must be a finite number ≥ 0, got {v}"
                ))
            }
        };
        match self {
            PortPressure::Constant { value } => finite("value", *value),
            PortPressure::Sinusoid {
                mean,
                amplitude,
                frequency,
                phase,
            } => {
                finite("mean", *mean)?;
                finite("amplitude", *amplitude)?;
                finite("phase", *phase)?;
                non_negative("frequency", *frequency)
            }
            PortPressure::Ramp {
                from,
                to,
                start,
                duration,
            } => {
                finite("from", *from)?;
                finite("to", *to)?;
                finite("start", *start)?;
                non_negative("duration", *duration)
            }
            PortPressure::Table { time, value } => {
                if time.is_empty() || time.len() != value.len() {
                    return Err(format!(
                        "{key}: time and value need the same number of entries (≥ 1), got {} and {}",
                        time.len(),
                        value.len()
                    ));
                }
                if !time.iter().chain(value).all(|x| x.is_finite())
                    || time.windows(2).any(|w| w[1] <= w[0])
                {
                    return Err(format!(
                        "{key}.time: must be finite and strictly increasing, with finite values"
                    ));
                }
                Ok(())
            }
            PortPressure::External { initial } => finite("initial", *initial),
        }
    }

    /// The port pressure at time t (`external`: the value the master set last).
    pub fn at(&self, t: f64, external: f64) -> f64 {
        match self {
            PortPressure::Constant { value } => *value,
            PortPressure::Sinusoid {
                mean,
                amplitude,
                frequency,
                phase,
            } => mean + amplitude * (2.0 * std::f64::consts::PI * frequency * t + phase).sin(),
            PortPressure::Ramp {
                from,
                to,
                start,
                duration,
            } => {
                if t <= *start {
                    *from
                } else if *duration <= 0.0 || t >= start + duration {
                    *to
                } else {
                    from + (to - from) * (t - start) / duration
                }
            }
            PortPressure::Table { time, value } => {
                let k = time.partition_point(|&x| x <= t);
                if k == 0 {
                    value[0]
                } else if k == time.len() {
                    value[k - 1]
                } else {
                    let s = (t - time[k - 1]) / (time[k] - time[k - 1]);
                    value[k - 1] + (value[k] - value[k - 1]) * s
                }
            }
            PortPressure::External { .. } => external,
        }
    }
}

/// The opening in the port's plane, about its centre.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Opening<const D: usize> {
    /// 2D: |t| ≤ half_width.
    Segment { half_width: f64 },
    /// 3D: |t| ≤ radius.
    Disk { radius: f64 },
    /// 3D: |t·e1| ≤ a, |t·e2| ≤ b, e2 = n × e1.
    Rectangle {
        e1: Vector<D>,
        e2: Vector<D>,
        a: f64,
        b: f64,
    },
}

impl<const D: usize> Opening<D> {
    /// Does the tangential offset t (from the centre, in the plane) fall in the opening?
    pub fn contains(&self, t: &Vector<D>) -> bool {
        const TOL: f64 = 1e-9;
        match self {
            Opening::Segment { half_width: r } | Opening::Disk { radius: r } => {
                t.norm() <= r * (1.0 + TOL)
            }
            Opening::Rectangle { e1, e2, a, b } => {
                t.dot(e1).abs() <= a * (1.0 + TOL) && t.dot(e2).abs() <= b * (1.0 + TOL)
            }
        }
    }

    /// Largest distance of a point of the opening from its centre.
    pub fn reach(&self) -> f64 {
        match self {
            Opening::Segment { half_width: r } | Opening::Disk { radius: r } => *r,
            Opening::Rectangle { a, b, .. } => a.hypot(*b),
        }
    }

    /// Area (2D: length per metre of depth).
    pub fn area(&self) -> f64 {
        match self {
            Opening::Segment { half_width } => 2.0 * half_width,
            Opening::Disk { radius } => std::f64::consts::PI * radius * radius,
            Opening::Rectangle { a, b, .. } => 4.0 * a * b,
        }
    }
}

/// One port at run time.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Port<const D: usize> {
    pub name: String,
    /// From the case, so not part of a saved state (`coupling::state` puts it back; postcard
    /// cannot carry an internally tagged enum either).
    #[serde(skip)]
    pub pressure: PortPressure,
    /// The value the master set last (`PortPressure::External`).
    pub external: f64,
    pub center: Vector<D>,
    /// Unit normal into the fluid.
    pub normal: Vector<D>,
    pub opening: Opening<D>,
    /// Buffer depth behind the plane (the body's wall thickness, one kernel support).
    pub depth: f64,
    /// Volume of one buffer particle (the body's spacing^D): its mass is ρ_b times this.
    pub particle_volume: f64,
    /// Points on the opening, one per buffer lattice cell, where the outputs are sampled.
    pub samples: Vec<Vector<D>>,
    /// Fluid mass that entered / left through the port since t = 0.
    pub mass_in: f64,
    pub mass_out: f64,
}

impl<const D: usize> Port<D> {
    /// Signed distance from the plane (positive in the fluid) and tangential offset of x.
    pub fn split(&self, x: &Vector<D>) -> (f64, Vector<D>) {
        let r = x - self.center;
        let d = r.dot(&self.normal);
        (d, r - self.normal * d)
    }

    /// The port pressure at time t.
    pub fn pressure_at(&self, t: f64) -> f64 {
        self.pressure.at(t, self.external)
    }
}

/// Shepard sums of the fluid around one point: Σ V W, Σ V W (P, ρ, u, v).
#[derive(Clone, Copy)]
struct FluidSums<const D: usize> {
    w: f64,
    p: f64,
    rho: f64,
    u: f64,
    v: Vector<D>,
}

impl<const D: usize> System<D> {
    /// The port condition on every buffer particle (see the module comment): P, ρ, c, u, m and
    /// v from the fluid at the mirror point. Called before the wall condition, which then
    /// sees the buffer as fluid.
    pub fn apply_port_condition(&mut self, t: f64) {
        if self.ports.is_empty() {
            return;
        }
        let g = self.uniform_body_force();
        let eos = self.eos;
        for (k, port) in self.ports.iter().enumerate() {
            let tag = k as u16 + 1;
            let p = &self.particles;
            let kern = &self.kernel;
            let reach = self.kernel.radius(self.h_max);
            // fluid particles that can reach a mirror point (the buffer's mirror lies within
            // one buffer depth in front of the plane)
            let mut near: Vec<usize> = (0..p.len())
                .filter(|&f| p.body[f] == 0 && p.port[f] == 0)
                .filter(|&f| {
                    let (d, t) = port.split(&p.pos[f]);
                    d > -reach && d < port.depth + reach && t.norm() <= port.opening.reach() + reach
                })
                .collect();
            if self.canonical_order {
                // the sums below in the order of the ids, as the neighbour rows (`parallel`)
                near.sort_unstable_by_key(|&f| p.id[f]);
            }
            let p_port = port.pressure_at(t);
            let shepard = |x: &Vector<D>, h: f64| {
                let mut s = FluidSums {
                    w: 0.0,
                    p: 0.0,
                    rho: 0.0,
                    u: 0.0,
                    v: Vector::zeros(),
                };
                for &f in &near {
                    let r = (x - p.pos[f]).norm();
                    if r >= kern.radius(h) {
                        continue;
                    }
                    let vw = p.mass[f] / p.rho[f] * kern.w(r, h);
                    s.w += vw;
                    s.p += vw * p.pressure[f];
                    s.rho += vw * p.rho[f];
                    s.u += vw * p.u[f];
                    s.v += p.vel[f] * vw;
                }
                (s.w > 0.0).then_some(s)
            };
            let n = port.normal;
            // per buffer particle: the fluid at its mirror point (P, ρ, u) and the fluid's
            // normal velocity one h in front of the plane at its tangential offset — the same
            // for a whole column of the buffer, so columns move rigidly and keep their spacing
            let updates: Vec<(usize, Option<FluidSums<D>>, f64)> = (0..p.len())
                .into_par_iter()
                .filter(|&i| p.port[i] == tag)
                .map(|i| {
                    let (d, tan) = port.split(&p.pos[i]);
                    let xm = p.pos[i] - n * (2.0 * d.min(0.0));
                    let xv = port.center + tan + n * p.h[i];
                    let vn = shepard(&xv, p.h[i]).map_or(0.0, |s| s.v.dot(&n) / s.w);
                    (i, shepard(&xm, p.h[i]), vn)
                })
                .collect();
            let p = &mut self.particles;
            for (i, s, vn) in updates {
                let (d, tan) = port.split(&p.pos[i]);
                let (pf, rho_f, u) = match s {
                    Some(s) => (s.p / s.w, s.rho / s.w, s.u / s.w),
                    // no fluid in reach (a drained port): hold the port pressure
                    None => (p_port, p.rho[i], p.u[i]),
                };
                // P_s: the port pressure carried hydrostatically along the opening plane
                let ps = p_port + rho_f * g.dot(&tan);
                let pb = if s.is_some() {
                    2.0 * ps - pf
                } else {
                    ps + rho_f * g.dot(&(n * d))
                };
                let rho = eos.density_at(pb, u).unwrap_or(p.rho[i]);
                p.pressure[i] = pb;
                p.rho[i] = rho;
                p.u[i] = u;
                p.sound_speed[i] = crate::eos::Eos::sound_speed(&eos, rho, u);
                p.mass[i] = rho * port.particle_volume;
                p.vel[i] = n * vn;
                // kept apart: the integrators' last kick rebuilds v from the start of the step,
                // `exchange_port_particles` puts this one back
                p.vel_wall[i] = p.vel[i];
            }
        }
    }

    /// Buffer particles feel no force: they move at the velocity the port condition gives.
    pub fn hold_ports(&mut self) {
        if self.ports.is_empty() {
            return;
        }
        let p = &mut self.particles;
        for i in 0..p.len() {
            if p.port[i] != 0 {
                p.acc[i] = Vector::zeros();
                p.dudt[i] = 0.0;
                p.drhodt[i] = 0.0;
            }
        }
    }

    /// End of a step: buffer particles take back the velocity of the latest port condition
    /// (the integrators' final kick rebuilds every v from the start of the step), buffer
    /// particles that crossed into the fluid become fluid (a copy
    /// refills the buffer one depth behind), fluid particles that crossed out through an
    /// opening join its buffer, buffer particles past the buffer depth are deleted. Returns
    /// whether particles were created or deleted (the neighbour lists are then rebuilt).
    pub fn exchange_port_particles(&mut self) -> bool {
        if self.ports.is_empty() {
            return false;
        }
        let crossings = self.cross_ports(self.particles.len());
        for (port, [mass_in, mass_out]) in self.ports.iter_mut().zip(&crossings.flow) {
            port.mass_in += mass_in;
            port.mass_out += mass_out;
        }
        if !crossings.changed {
            return false;
        }
        // fresh ids after the largest in use (ids stay unique and stable)
        let next_id = self.particles.id.iter().copied().max().map_or(0, |m| m + 1);
        let ids: Vec<u32> = (0..crossings.copies.len() as u32)
            .map(|j| next_id + j)
            .collect();
        self.apply_port_crossings(crossings, &ids);
        true
    }

    /// The first part of [`Self::exchange_port_particles`] on particles `0..n` (a distributed
    /// run's own): buffer velocities restored and fluid and buffer tags updated; the mass
    /// that crossed each port (for its counters), which particles stay and which are copied
    /// are returned, for [`Self::apply_port_crossings`].
    pub fn cross_ports(&mut self, n: usize) -> PortCrossings {
        {
            let p = &mut self.particles;
            for i in 0..n {
                if p.port[i] != 0 {
                    p.vel[i] = p.vel_wall[i];
                }
            }
        }
        let mut keep: Vec<u32> = Vec::with_capacity(n + 16);
        let mut copies: Vec<(u32, usize)> = Vec::new();
        let mut deleted = false;
        // mass in and out per port, summed exactly and merged over a distributed run's ranks
        // (`parallel::exact`), so the counters are the same bits on any number of ranks
        let mut sums = crate::parallel::exact::registers(2 * self.ports.len());
        for i in 0..n {
            let p = &mut self.particles;
            if p.body[i] != 0 {
                keep.push(i as u32);
                continue;
            }
            if p.port[i] != 0 {
                let k = p.port[i] as usize - 1;
                let port = &self.ports[k];
                let (d, _) = port.split(&p.pos[i]);
                if d > 0.0 {
                    p.port[i] = 0;
                    sums[2 * k].add(p.mass[i]);
                    copies.push((i as u32, k));
                } else if d < -port.depth {
                    deleted = true;
                    continue;
                }
                keep.push(i as u32);
                continue;
            }
            for (k, port) in self.ports.iter().enumerate() {
                let (d, t) = port.split(&p.pos[i]);
                if d <= 0.0 && d >= -port.depth && port.opening.contains(&t) {
                    p.port[i] = k as u16 + 1;
                    sums[2 * k + 1].add(p.mass[i]);
                    break;
                }
            }
            keep.push(i as u32);
        }
        if let Some(ranks) = &self.ranks {
            ranks.merge_in_place(&mut sums);
        }
        let flow = sums
            .chunks_exact(2)
            .map(|s| [s[0].value(), s[1].value()])
            .collect();
        let changed = deleted || !copies.is_empty();
        PortCrossings {
            keep,
            copies,
            changed,
            flow,
        }
    }

    /// Keep what `crossings` keeps (every other particle, a distributed run's halo included,
    /// is dropped) and append its copies with the given `ids`, one buffer depth behind their
    /// source.
    pub fn apply_port_crossings(&mut self, crossings: PortCrossings, ids: &[u32]) {
        let PortCrossings {
            mut keep, copies, ..
        } = crossings;
        let first_copy = keep.len();
        keep.extend(copies.iter().map(|&(i, _)| i));
        let p = &mut self.particles;
        p.permute(&keep);
        for (j, &(_, k)) in copies.iter().enumerate() {
            let c = first_copy + j;
            let port = &self.ports[k];
            p.pos[c] -= port.normal * port.depth;
            p.rest[c] = p.pos[c];
            p.port[c] = k as u16 + 1;
            p.id[c] = ids[j];
        }
        self.halo = 0;
        self.reset_neighbours();
    }
}

/// What particles crossing the port openings do at a step's end ([`System::cross_ports`]).
pub struct PortCrossings {
    /// The particles that stay, in order.
    keep: Vec<u32>,
    /// (index of the source, port) of each copy that refills a buffer.
    pub copies: Vec<(u32, usize)>,
    /// Particles were created or deleted.
    pub changed: bool,
    /// Mass that entered and left the fluid through each port, over every rank of a
    /// distributed run.
    pub flow: Vec<[f64; 2]>,
}

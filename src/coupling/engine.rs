//! The dimension-generic half of the Coupling: a `Simulation<D>` behind an object-safe trait,
//! so `Coupling` itself is not generic.

use super::{
    sampling, state, BodyKinematics, BodyLoads, CouplingError, ParticleKind, ParticleState,
    PatchMembers, PatchValue, PortValue, ProbeValue, StepLimit, StepReport,
};
use crate::boundary::geometry::Shape;
use crate::boundary::kinematics::{HeldPose, Pose};
use crate::case::Case;
use crate::parallel::comm::Comm;
use crate::parallel::exact::registers;
use crate::particles::Particles;
use crate::particles::Vector;
use crate::sim::{Diagnostics, Simulation, SolverError};
use std::borrow::Cow;
use std::sync::Arc;

pub(super) trait Engine: Send + Sync {
    fn time(&self) -> f64;
    fn gravity(&self) -> [f64; 3];
    fn set_gravity(&mut self, g: &[f64; 3]);
    fn body(&self, b: usize) -> BodyKinematics;
    fn set_body(&mut self, b: usize, k: &BodyKinematics);
    fn frame(&self) -> Option<BodyKinematics>;
    fn set_frame(&mut self, k: &BodyKinematics);
    fn advance_to(&mut self, t: f64, chunk: &Chunk) -> Result<StepReport, SolverError>;
    fn loads(&self) -> Vec<BodyLoads>;
    fn set_port_pressure(&mut self, k: usize, p: f64);
    fn ports(&self) -> Vec<PortValue>;
    fn particles(&self, stride: usize) -> Vec<ParticleState>;
    fn probes(&self, points: &[[f64; 3]]) -> Vec<ProbeValue>;
    fn markers(&self, markers: &[(usize, [f64; 3])]) -> Vec<f64>;
    fn patch_members(&self, specs: &[PatchSpec]) -> Vec<PatchMembers>;
    fn patches(&self, members: &[PatchMembers]) -> Vec<PatchValue>;
    fn diagnostics(&self) -> Diagnostics;
    fn write_vtu(&self, path: &std::path::Path) -> std::io::Result<()>;
    fn save(&self, fingerprint: u64) -> Result<Vec<u8>, String>;
    fn restore(&mut self, bytes: &[u8], fingerprint: u64) -> Result<(), String>;
}

/// The kinematics a master reads of a pose about `reference`.
fn kinematics_of<const D: usize>(reference: &Vector<D>, p: &Pose<D>) -> BodyKinematics {
    BodyKinematics {
        position: array(&(reference + p.displacement)),
        orientation: super::orientation::to_array(&p.rotation),
        velocity: array(&p.velocity),
        angular_velocity: p.angular_velocity.into(),
        acceleration: array(&p.acceleration),
        angular_acceleration: p.angular_acceleration.into(),
    }
}

/// The pose a master's kinematics set at `time` (checked by `Coupling::check_body_kinematics`:
/// its quaternion is within 1e-6 of unit length).
fn held_pose<const D: usize>(time: f64, reference: &Vector<D>, k: &BodyKinematics) -> HeldPose<D> {
    let q = super::orientation::unit_quaternion("orientation", &k.orientation).expect("checked");
    HeldPose {
        time,
        pose: Pose {
            displacement: vector::<D>(&k.position) - reference,
            velocity: vector::<D>(&k.velocity),
            rotation: super::orientation::to_unit(&q),
            angular_velocity: k.angular_velocity.into(),
            acceleration: vector::<D>(&k.acceleration),
            angular_acceleration: k.angular_acceleration.into(),
        },
    }
}

/// The solver of `case`, in this process alone or shared among `ranks` (`parallel`).
pub(super) fn build(
    case: &Case,
    ranks: Option<Arc<dyn Comm>>,
) -> Result<Box<dyn Engine>, CouplingError> {
    fn sim<const D: usize>(
        case: &Case,
        ranks: Option<Arc<dyn Comm>>,
    ) -> Result<Simulation<D>, CouplingError> {
        Ok(match ranks {
            None => case.build::<D>()?,
            Some(comm) => case.distributed::<D>(comm)?,
        })
    }
    Ok(match case.case.dimension {
        1 => Box::new(Coupled::new(sim::<1>(case, ranks)?)),
        2 => Box::new(Coupled::new(sim::<2>(case, ranks)?)),
        3 => Box::new(Coupled::new(sim::<3>(case, ranks)?)),
        d => {
            return Err(CouplingError(format!(
                "case.dimension: must be 1, 2 or 3, got {d}"
            )))
        }
    })
}

/// How much of a bounded step one call of [`Engine::advance_to`] may take (plain numbers, so
/// it crosses into the pool's threads).
pub(super) struct Chunk {
    pub max_steps: Option<u64>,
    pub max_seconds: Option<f64>,
}

/// A patch as the case gives it, resolved to its body.
pub(super) struct PatchSpec {
    pub body: usize,
    pub min: [f64; 3],
    pub max: [f64; 3],
    /// The body's wall spacing (the surface layer is −Δx ≤ φ < 0).
    pub spacing: f64,
    pub shape: Shape,
}

pub(super) struct Coupled<const D: usize> {
    pub sim: Simulation<D>,
    /// An input changed since the latest evaluation: re-evaluate before the next step.
    pub dirty: bool,
}

impl<const D: usize> Coupled<D> {
    fn new(sim: Simulation<D>) -> Self {
        Self { sim, dirty: false }
    }

    /// The whole case's particles: this process's, or in a distributed run every rank's own,
    /// gathered in id order (a collective). Should the ranks fail to exchange, this rank's
    /// own (the failure stops the next step, where every rank meets it).
    fn whole(&self) -> Cow<'_, Particles<D>> {
        let sys = &self.sim.sys;
        match &self.sim.layout {
            None => Cow::Borrowed(&sys.particles),
            Some(layout) => Cow::Owned(layout.gather(sys).unwrap_or_else(|_| {
                sys.particles
                    .selected(&(0..sys.owned() as u32).collect::<Vec<_>>())
            })),
        }
    }
}

fn vector<const D: usize>(v: &[f64; 3]) -> Vector<D> {
    Vector::<D>::from_fn(|k, _| v[k])
}

fn array<const D: usize>(v: &Vector<D>) -> [f64; 3] {
    let mut o = [0.0; 3];
    o[..D].copy_from_slice(v.as_slice());
    o
}

impl<const D: usize> Engine for Coupled<D> {
    fn time(&self) -> f64 {
        self.sim.time
    }

    fn gravity(&self) -> [f64; 3] {
        array(&self.sim.sys.gravity)
    }

    fn set_gravity(&mut self, g: &[f64; 3]) {
        let g = vector::<D>(g);
        if g != self.sim.sys.gravity {
            self.sim.sys.gravity = g;
            self.dirty = true;
        }
    }

    fn body(&self, b: usize) -> BodyKinematics {
        let body = &self.sim.sys.bodies[b];
        kinematics_of(&body.reference, &body.pose)
    }

    fn set_body(&mut self, b: usize, k: &BodyKinematics) {
        let time = self.sim.time;
        let body = &mut self.sim.sys.bodies[b];
        let held = held_pose(time, &body.reference, k);
        self.dirty |= held.at(time) != body.pose;
        body.held = held;
    }

    fn frame(&self) -> Option<BodyKinematics> {
        let f = self.sim.sys.frame.as_ref()?;
        Some(kinematics_of(&f.reference, &f.pose))
    }

    fn set_frame(&mut self, k: &BodyKinematics) {
        let time = self.sim.time;
        if let Some(f) = &mut self.sim.sys.frame {
            let held = held_pose(time, &f.reference, k);
            self.dirty |= held.at(time) != f.pose;
            f.held = held;
        }
    }

    fn advance_to(&mut self, t: f64, chunk: &Chunk) -> Result<StepReport, SolverError> {
        if self.dirty && t > self.sim.time {
            self.sim.reevaluate()?;
            self.dirty = false;
        }
        let start = self.sim.steps;
        let mut report = StepReport {
            dt_min: f64::INFINITY,
            ..StepReport::default()
        };
        let mut before = self.sim.time;
        let clock = std::time::Instant::now();
        self.sim.advance_while(t, |s| {
            let dt = s.time - before;
            before = s.time;
            report.dt_min = report.dt_min.min(dt);
            report.dt_max = report.dt_max.max(dt);
            let steps = s.steps - start;
            if chunk.max_steps.is_some_and(|m| steps >= m) {
                report.stopped = Some(StepLimit::Steps(steps));
                return false;
            }
            let seconds = clock.elapsed().as_secs_f64();
            let mut out_of_time = chunk.max_seconds.is_some_and(|m| seconds >= m);
            if let (Some(layout), Some(_)) = (&s.layout, chunk.max_seconds) {
                // every rank stops after the same step: when any rank's clock ran out (a
                // failed agreement stops too, and the next step reports it)
                out_of_time = layout
                    .sum(&[f64::from(u8::from(out_of_time))])
                    .map_or(true, |v| v[0] > 0.0);
            }
            if out_of_time {
                report.stopped = Some(StepLimit::Seconds(seconds));
                return false;
            }
            true
        })?;
        if self.sim.time >= t {
            report.stopped = None;
        }
        report.steps = self.sim.steps - start;
        if report.steps == 0 {
            report.dt_min = 0.0;
        }
        Ok(report)
    }

    fn loads(&self) -> Vec<BodyLoads> {
        self.sim
            .sys
            .bodies
            .iter()
            .map(|b| {
                let (force_body, torque_body) = b.loads_in_body_frame();
                BodyLoads {
                    force: array(&b.force),
                    torque: b.torque,
                    force_body: array(&force_body),
                    torque_body: torque_body.into(),
                }
            })
            .collect()
    }

    fn set_port_pressure(&mut self, k: usize, p: f64) {
        let port = &mut self.sim.sys.ports[k];
        if port.external != p {
            port.external = p;
            self.dirty = true;
        }
    }

    fn ports(&self) -> Vec<PortValue> {
        let sys = &self.sim.sys;
        (0..sys.ports.len())
            .map(|k| sampling::port_value(sys, k))
            .collect()
    }

    fn particles(&self, stride: usize) -> Vec<ParticleState> {
        let whole = self.whole();
        let p = &*whole;
        (0..p.len())
            .step_by(stride)
            .map(|i| ParticleState {
                kind: match (p.body[i], p.port[i]) {
                    (0, 0) => ParticleKind::Fluid,
                    (0, k) => ParticleKind::Buffer(k as usize - 1),
                    (b, _) => ParticleKind::Wall(b as usize - 1),
                },
                position: array(&p.pos[i]),
                velocity: array(&p.vel[i]),
                density: p.rho[i],
                pressure: p.pressure[i],
            })
            .collect()
    }

    fn probes(&self, points: &[[f64; 3]]) -> Vec<ProbeValue> {
        points
            .iter()
            .map(|x| sampling::probe(&self.sim.sys, &vector::<D>(x)))
            .collect()
    }

    fn markers(&self, markers: &[(usize, [f64; 3])]) -> Vec<f64> {
        markers
            .iter()
            .map(|(b, x)| sampling::marker_pressure(&self.sim.sys, *b, &vector::<D>(x)))
            .collect()
    }

    fn patch_members(&self, specs: &[PatchSpec]) -> Vec<PatchMembers> {
        let whole = self.whole();
        let p = &*whole;
        specs
            .iter()
            .map(|s| {
                let (mut all, mut surface) = (vec![], vec![]);
                for i in 0..p.len() {
                    let r = p.rest[i];
                    if p.body[i] as usize != s.body + 1
                        || !(0..D).all(|k| r[k] >= s.min[k] && r[k] <= s.max[k])
                    {
                        continue;
                    }
                    all.push(p.id[i]);
                    let phi = s.shape.distance(&r);
                    if phi < 0.0 && phi >= -s.spacing {
                        surface.push(p.id[i]);
                    }
                }
                PatchMembers {
                    all,
                    surface,
                    cell_area: s.spacing.powi(D as i32 - 1),
                }
            })
            .collect()
    }

    fn patches(&self, members: &[PatchMembers]) -> Vec<PatchValue> {
        let sys = &self.sim.sys;
        let p = &sys.particles;
        // stable id → index of this process's own particles (particles are reordered for
        // locality; ports create particles with ids beyond the count; in a distributed run
        // the other ranks hold the rest)
        let own = sys.owned();
        let ids = p.id[..own]
            .iter()
            .copied()
            .max()
            .map_or(0, |m| m as usize + 1);
        let mut index = vec![usize::MAX; ids];
        for (i, &id) in p.id[..own].iter().enumerate() {
            index[id as usize] = i;
        }
        let at = |id: &u32| {
            index
                .get(*id as usize)
                .copied()
                .filter(|&i| i != usize::MAX)
        };
        // per patch: the force (D) and the surface pressures' sum, summed exactly so that
        // the patch reads the same bits on any number of ranks (`parallel::exact`)
        let width = D + 1;
        let mut sums = registers(members.len() * width);
        let mut peaks = vec![f64::NEG_INFINITY; members.len()];
        for (k, m) in members.iter().enumerate() {
            let s = &mut sums[k * width..(k + 1) * width];
            for i in m.all.iter().filter_map(at) {
                for (r, f) in s.iter_mut().zip(p.wall_force[i].iter()) {
                    r.add(*f);
                }
            }
            for i in m.surface.iter().filter_map(at) {
                s[D].add(p.pressure[i]);
                peaks[k] = peaks[k].max(p.pressure[i]);
            }
        }
        if let Some(ranks) = &sys.ranks {
            ranks.merge_in_place(&mut sums);
            ranks.max_in_place(&mut peaks);
        }
        members
            .iter()
            .zip(sums.chunks_exact(width).zip(&peaks))
            .map(|(m, (s, &peak))| PatchValue {
                mean_pressure: s[D].value() / m.surface.len() as f64,
                peak_pressure: peak,
                area: m.surface.len() as f64 * m.cell_area,
                force: {
                    let mut f = [0.0; 3];
                    for (o, r) in f.iter_mut().zip(&s[..D]) {
                        *o = r.value();
                    }
                    f
                },
            })
            .collect()
    }

    fn diagnostics(&self) -> Diagnostics {
        self.sim.diagnostics()
    }

    fn write_vtu(&self, path: &std::path::Path) -> std::io::Result<()> {
        crate::io::write_vtu(path, &self.sim.sys.particles, self.sim.time)
    }

    fn save(&self, fingerprint: u64) -> Result<Vec<u8>, String> {
        state::save(self, fingerprint)
    }

    fn restore(&mut self, bytes: &[u8], fingerprint: u64) -> Result<(), String> {
        state::restore(self, bytes, fingerprint)
    }
}

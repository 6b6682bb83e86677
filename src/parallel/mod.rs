//! Domain decomposition: a run shared among ranks (processes under MPI, or threads in the
//! tests), each owning the particles in its region of space (`regions`), evaluating them
//! with a halo of copies of its neighbours' particles (`halo`), and handing particles that
//! leave its region to their new owner at every step.
//!
//! Every rank's particles come out bit for bit as on one rank, whatever the number of
//! ranks: neighbour rows are summed in the order of the particles' stable ids
//! (`System::canonical_order`), the h solve's result does not depend on the neighbour list's
//! history, the halo is exact for every pass (refreshed between passes, or deep enough; see `halo`), and the time step is a
//! global minimum. Body loads, probes, patches and port flows are exact sums (`exact`): the
//! same bits on any number of ranks. Totals of the diagnostics (energies, momenta) are sums
//! of per-rank sums in rank order: equal to round-off, not to the bit, across rank counts.

pub mod comm;
pub mod exact;
mod halo;
#[cfg(feature = "mpi")]
pub mod mpi;
pub mod refresh;
pub mod regions;

pub use halo::{ExchangeStats, HaloScheme, Link};
pub use refresh::{rows, HaloRow};

use crate::integrate::IntegratorKind;
use crate::particles::{Particles, Vector};
use crate::scheme::Scheme;
use crate::sim::{Diagnostics, Layout, Simulation, SolverError, StepControl};
use crate::system::System;
use comm::{Comm, Reduce};
use regions::Regions;
use std::sync::Arc;

/// Rebalance when the most loaded rank's cost exceeds the mean by this fraction: every rank
/// waits for the slowest at each step's collectives, so a 10 % excess wastes up to 10 % of
/// the others' time, while a rebalance costs one all-gather of the positions and a
/// migration, about a few halo exchanges' worth; checked every `BALANCE_EVERY` steps.
pub const IMBALANCE_LIMIT: f64 = 0.10;
pub const BALANCE_EVERY: u64 = 16;
/// Growth of the largest h within one step that the halo allows for (the h solve's
/// prediction alone may reach 20 %); a step that grows it further is reported, not hidden.
pub const H_GROWTH: f64 = 1.25;
/// The halo is kept over steps while the particles' motion since it was built fits in its
/// skin, this fraction of a kernel support wide (as the neighbour list's own skin,
/// `smoothing::SKIN`): with the same particles in the same order the neighbour lists stay
/// valid, and a step costs no migration and no list rebuild.
pub const HALO_SKIN: f64 = 0.15;

/// The particles of a case shared among ranks: [`Layout`] of a distributed [`Simulation`].
pub struct Decomposition<const D: usize> {
    link: Arc<Link>,
    regions: Regions<D>,
    depth: usize,
    steps: u64,
    /// The largest h the current halo allows for.
    h_allowed: f64,
    /// The current halo's allowance for motion: two particles may have approached by this
    /// much since it was built.
    skin: f64,
    /// The owned particles' positions when the halo was built (empty: build it).
    built_at: Vec<Vector<D>>,
    /// The halo allows for at least this h (the first evaluation's, estimated at the start).
    h_floor: f64,
    /// Particles were created or deleted since the halo was built: rebuild it.
    stale: bool,
}

/// How many kernel supports deep the halo of `sys` run by `scheme` must be: the scheme's
/// own chain of passes ([`Scheme::halo_depth`]), and what the boundary conditions add to it.
/// A wall particle's state comes from the fluid within one support of it (Adami et al.'s
/// eq. 27, `boundary::bodies`); a port buffer particle's from the fluid within one support
/// of its mirror point, up to two supports (two buffer depths) in front of it
/// (`boundary::ports`). (Measured: on the cases of `tests/parallel.rs` the scheme's depth
/// alone already gives the same particles; the additions keep the halo as deep as the
/// dependencies reach rather than as deep as those cases happened to need.)
pub fn halo_depth<const D: usize>(sys: &System<D>, scheme: &dyn Scheme<D>) -> usize {
    let walls = usize::from(!sys.bodies.is_empty());
    let ports = if sys.ports.is_empty() { 0 } else { 3 };
    scheme.halo_depth() + walls.max(ports)
}

/// Start a distributed run. Every rank passes the same whole system (as built from the
/// case); each keeps the particles of its region, and the scheme is wrapped so that its
/// halo is refreshed before every evaluation.
pub fn start<const D: usize>(
    sys: System<D>,
    scheme: Box<dyn Scheme<D>>,
    kind: IntegratorKind,
    control: StepControl,
    comm: Arc<dyn Comm>,
) -> Result<Simulation<D>, SolverError> {
    let depth = halo_depth(&sys, &*scheme);
    start_with_halo(sys, scheme, kind, control, comm, depth)
}

/// [`start`] with a halo `depth` kernel supports deep instead of the scheme's own (the tests
/// show that a thinner halo than the scheme needs changes the particles).
pub fn start_with_halo<const D: usize>(
    mut sys: System<D>,
    scheme: Box<dyn Scheme<D>>,
    kind: IntegratorKind,
    control: StepControl,
    comm: Arc<dyn Comm>,
    depth: usize,
) -> Result<Simulation<D>, SolverError> {
    sys.canonical_order = true;
    sys.halo = 0;
    // The first evaluation solves h from the case's guess, which at free surfaces and
    // density jumps can grow it past any fixed allowance: size the first halo from a solve
    // on the whole system (every rank holds all of it now), and keep the case's guess.
    let guess = sys.particles.h.clone();
    crate::scheme::smoothing::solve_density_and_h(&mut sys);
    let h_first = sys.particles.h.iter().cloned().fold(0.0, f64::max);
    sys.particles.h = guess;
    sys.reset_neighbours();
    let link = Arc::new(Link::new(comm.clone()));
    sys.ranks = Some(link.clone());
    let points: Vec<(Vector<D>, f64)> = sys.particles.pos.iter().map(|x| (*x, 1.0)).collect();
    let regions = Regions::bisect(&points, comm.size(), &sys.domain);
    let mine: Vec<u32> = (0..sys.particles.len() as u32)
        .filter(|&i| regions.owner(&sys.particles.pos[i as usize]) == comm.rank())
        .collect();
    sys.particles.permute(&mine);
    let mut layout = Decomposition {
        link: link.clone(),
        regions,
        depth,
        steps: 0,
        h_allowed: 0.0,
        h_floor: h_first,
        skin: 0.0,
        built_at: vec![],
        stale: true,
    };
    let fail = |message: String| SolverError::Scheme {
        message: format!("distributed run: {message}"),
        time: 0.0,
        step: 0,
    };
    layout.build_halo(&mut sys, 0.0).map_err(fail)?;
    let wrapped = Box::new(HaloScheme {
        inner: scheme,
        link: link.clone(),
    });
    let mut sim = Simulation::new(sys, wrapped, kind, control)?;
    sim.reorder_every = 0;
    sim.layout = Some(Box::new(layout));
    Ok(sim)
}

impl<const D: usize> Decomposition<D> {
    fn comm(&self) -> &dyn Comm {
        &*self.link.comm
    }

    /// Copy the owned particles near other ranks' regions to them, and append theirs.
    fn build_halo(&mut self, sys: &mut System<D>, dt: f64) -> Result<(), String> {
        let floor = std::mem::take(&mut self.h_floor);
        let comm = self.comm();
        let (me, ranks) = (comm.rank(), comm.size());
        let own = sys.owned();
        let p = &sys.particles;
        let (mut h, mut speed, mut accel) = (0.0_f64, 0.0_f64, 0.0_f64);
        for i in 0..own {
            h = h.max(p.h[i]);
            speed = speed.max(p.vel[i].norm());
            accel = accel.max(p.acc[i].norm());
        }
        let top = comm
            .max_each(&[h, speed, accel])
            .map_err(|e| e.to_string())?;
        let h = top[0].max(floor);
        self.h_allowed = H_GROWTH * h;
        // two particles approach by at most twice the largest displacement: the step's, or
        // the skin's worth of steps
        let step = step_motion(top[1], top[2], dt);
        self.skin = 2.0 * step.max(HALO_SKIN * sys.kernel.radius(h));
        let width = self.depth as f64 * sys.kernel.radius(self.h_allowed) + self.skin;
        let mut send = vec![Vec::new(); ranks];
        for i in 0..own {
            for (r, list) in send.iter_mut().enumerate() {
                if r != me && self.regions.distance(r, &p.pos[i]) < width {
                    list.push(i as u32);
                }
            }
        }
        let parts = send.iter().map(|pick| Some(p.selected(pick))).collect();
        let got = self.link.exchange(parts)?;
        let recv = got.iter().map(|g| g.len()).collect();
        for (r, part) in got.iter().enumerate() {
            if r != me {
                sys.particles.append(part)?;
            }
        }
        sys.halo = sys.particles.len() - own;
        sys.reset_neighbours();
        self.built_at = sys.particles.pos[..own].to_vec();
        self.stale = false;
        *self.link.plan.lock().unwrap_or_else(|e| e.into_inner()) = halo::HaloPlan { send, recv };
        self.link
            .stats
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .halo_particles = sys.halo as u64;
        Ok(())
    }

    /// Drop the halo, and hand every owned particle outside this rank's region to its owner.
    fn migrate(&mut self, sys: &mut System<D>) -> Result<(), String> {
        let comm = self.comm();
        let (me, ranks) = (comm.rank(), comm.size());
        sys.particles.truncate(sys.owned());
        sys.halo = 0;
        let p = &sys.particles;
        let mut leave = vec![Vec::new(); ranks];
        let mut stay = Vec::with_capacity(p.len());
        for i in 0..p.len() {
            match self.regions.owner(&p.pos[i]) {
                r if r == me => stay.push(i as u32),
                r => leave[r].push(i as u32),
            }
        }
        let moved: usize = leave.iter().map(|l| l.len()).sum();
        let parts = leave.iter().map(|pick| Some(p.selected(pick))).collect();
        let got = self.link.exchange(parts)?;
        sys.particles.permute(&stay);
        for (r, part) in got.iter().enumerate() {
            if r != me {
                sys.particles.append(part)?;
            }
        }
        sys.reset_neighbours();
        self.link
            .stats
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .migrated += moved as u64;
        Ok(())
    }

    /// New regions from every rank's particles, weighted by their neighbour counts, when
    /// the load is out of balance by more than [`IMBALANCE_LIMIT`].
    fn rebalance(&mut self, sys: &System<D>) -> Result<(), String> {
        let own = sys.owned();
        let nb = &sys.neighbours;
        let cost = |i: usize| {
            1.0 + if nb.offsets.len() > i + 1 {
                nb.of(i).len() as f64
            } else {
                0.0
            }
        };
        let mine: f64 = (0..own).map(cost).sum();
        let comm = self.comm();
        let loads = comm
            .all_gather(comm::f64_bytes(&[mine]))
            .map_err(|e| e.to_string())?;
        let loads: Vec<f64> = loads.iter().flat_map(|b| comm::bytes_f64(b)).collect();
        let mean = loads.iter().sum::<f64>() / loads.len() as f64;
        let worst = loads.iter().cloned().fold(0.0, f64::max);
        if mean <= 0.0 || worst <= (1.0 + IMBALANCE_LIMIT) * mean {
            return Ok(());
        }
        let p = &sys.particles;
        let mut flat = Vec::with_capacity(own * (D + 1));
        for i in 0..own {
            flat.extend(p.pos[i].iter());
            flat.push(cost(i));
        }
        let all = comm
            .all_gather(comm::f64_bytes(&flat))
            .map_err(|e| e.to_string())?;
        let points: Vec<(Vector<D>, f64)> = all
            .iter()
            .flat_map(|b| {
                comm::bytes_f64(b)
                    .chunks_exact(D + 1)
                    .map(|c| (Vector::<D>::from_fn(|k, _| c[k]), c[D]))
                    .collect::<Vec<_>>()
            })
            .collect();
        self.regions = Regions::bisect(&points, comm.size(), &sys.domain);
        let mut s = self.link.stats.lock().unwrap_or_else(|e| e.into_inner());
        s.rebalances += 1;
        s.bytes_sent += (flat.len() * 8) as u64;
        Ok(())
    }
}

/// How far a particle moves in one step of `dt` at most, with a 10 % margin: |v| dt + ½|a| dt².
fn step_motion(speed: f64, accel: f64, dt: f64) -> f64 {
    1.1 * (speed * dt + 0.5 * accel * dt * dt)
}

impl<const D: usize> Layout<D> for Decomposition<D> {
    fn agree_dt(&self, local: f64) -> Result<f64, String> {
        self.comm().min(local).map_err(|e| e.to_string())
    }

    fn agree(&self, result: Result<(), String>) -> Result<(), String> {
        let failed = self
            .link
            .failure
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take();
        self.link.agree(result.and(failed.map_or(Ok(()), Err)))
    }

    fn before_step(&mut self, sys: &mut System<D>, dt: f64) -> Result<(), String> {
        let own = sys.owned();
        let p = &sys.particles;
        let (mut h, mut speed, mut accel, mut moved) = (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64);
        let built = !self.stale && self.built_at.len() == own;
        for i in 0..own {
            h = h.max(p.h[i]);
            speed = speed.max(p.vel[i].norm());
            accel = accel.max(p.acc[i].norm());
            if built {
                moved = moved.max(
                    sys.domain
                        .separation(&p.pos[i], &self.built_at[i], 0)
                        .norm(),
                );
            }
        }
        let top = self
            .comm()
            .max_each(&[h, speed, accel, moved, (!built) as u8 as f64])
            .map_err(|e| e.to_string())?;
        let (h, moved, any_unbuilt) = (top[0], top[3], top[4] > 0.0);
        // the steps since the halo was built kept h within what it allowed for
        if self.h_allowed > 0.0 && h > self.h_allowed {
            return Err(format!(
                "the largest smoothing length grew to {h:.4e}, past the {:.4e} its halo allowed for ({H_GROWTH} times its value when the halo was built)",
                self.h_allowed
            ));
        }
        self.steps += 1;
        let balance_due = self.steps % BALANCE_EVERY == 0 && self.comm().size() > 1;
        // keep the halo while this step's motion still fits in its skin and h has room to
        // grow by a step's worth (10 %)
        let step = step_motion(top[1], top[2], dt);
        if !any_unbuilt
            && !balance_due
            && 2.0 * (moved + step) <= self.skin
            && 1.1 * h <= self.h_allowed
        {
            return Ok(());
        }
        if balance_due {
            self.rebalance(sys)?;
        }
        self.migrate(sys)?;
        self.build_halo(sys, dt)
    }

    fn after_step(&mut self, sys: &mut System<D>) -> Result<(), String> {
        if sys.ports.is_empty() {
            return Ok(());
        }
        let own = sys.owned();
        let crossings = sys.cross_ports(own);
        let comm = self.comm();
        // the flows are already summed over the ranks, exactly (`System::cross_ports`)
        for (port, f) in sys.ports.iter_mut().zip(&crossings.flow) {
            port.mass_in += f[0];
            port.mass_out += f[1];
        }
        // every rank's next free id, whether it created or deleted particles, and the ids of
        // its copies' sources: a copy's id is the next free one after the largest in use,
        // counted in the order of the sources' ids, as on one rank
        let ids = &sys.particles.id;
        let mut mine = vec![
            ids[..own].iter().max().map_or(0.0, |&m| m as f64 + 1.0),
            f64::from(u8::from(crossings.changed)),
        ];
        mine.extend(
            crossings
                .copies
                .iter()
                .map(|&(i, _)| ids[i as usize] as f64),
        );
        let rows: Vec<Vec<f64>> = comm
            .all_gather(comm::f64_bytes(&mine))
            .map_err(|e| e.to_string())?
            .iter()
            .map(|b| comm::bytes_f64(b))
            .collect();
        if !rows.iter().any(|r| r[1] > 0.0) {
            return Ok(());
        }
        let next_id = rows.iter().map(|r| r[0]).fold(0.0, f64::max) as u32;
        let mut sources: Vec<u32> = rows
            .iter()
            .flat_map(|r| r[2..].iter().map(|&x| x as u32))
            .collect();
        sources.sort_unstable();
        let new_ids: Vec<u32> = crossings
            .copies
            .iter()
            .map(|&(i, _)| {
                let rank = sources.partition_point(|&s| s < ids[i as usize]);
                next_id + rank as u32
            })
            .collect();
        // the halo's copies and plan no longer match their owners': drop it, build anew
        sys.apply_port_crossings(crossings, &new_ids);
        self.stale = true;
        Ok(())
    }

    fn refresh(&mut self, sys: &mut System<D>, dt: f64) -> Result<(), String> {
        self.migrate(sys)?;
        self.build_halo(sys, dt)
    }

    fn gather(&self, sys: &System<D>) -> Result<Particles<D>, String> {
        gather_owned(sys, self.comm())
    }

    fn replace(&mut self, sys: &mut System<D>, all: Particles<D>) {
        let me = self.comm().rank();
        // the new particles' h may exceed what the current halo allowed for: the next halo
        // allows for theirs (h_floor), and nothing is checked against the old one
        self.h_floor = all.h.iter().cloned().fold(0.0, f64::max);
        self.h_allowed = 0.0;
        let mine: Vec<u32> = (0..all.len() as u32)
            .filter(|&i| self.regions.owner(&all.pos[i as usize]) == me)
            .collect();
        sys.particles = all;
        sys.particles.permute(&mine);
        sys.halo = 0;
        sys.reset_neighbours();
        self.built_at.clear();
        self.stale = true;
    }

    fn sum(&self, x: &[f64]) -> Result<Vec<f64>, String> {
        self.comm().sum(x).map_err(|e| e.to_string())
    }

    fn exchange(&self) -> (usize, ExchangeStats) {
        (self.comm().size(), self.link.stats())
    }

    fn totals(&self, d: Diagnostics) -> Result<Diagnostics, String> {
        let local = [
            d.particles as f64,
            d.fluid_particles as f64,
            d.mass,
            d.momentum[0],
            d.momentum[1],
            d.momentum[2],
            d.angular_momentum[0],
            d.angular_momentum[1],
            d.angular_momentum[2],
            d.kinetic_energy,
            d.internal_energy,
            d.potential_energy,
            d.total_energy,
        ];
        let comm = self.comm();
        let t = comm.sum(&local).map_err(|e| e.to_string())?;
        Ok(Diagnostics {
            particles: t[0] as usize,
            fluid_particles: t[1] as usize,
            mass: t[2],
            momentum: [t[3], t[4], t[5]],
            angular_momentum: [t[6], t[7], t[8]],
            kinetic_energy: t[9],
            internal_energy: t[10],
            potential_energy: t[11],
            total_energy: t[12],
            max_lorentz: comm.max(d.max_lorentz).map_err(|e| e.to_string())?,
            ..d
        })
    }
}

/// Every rank's own particles, ordered by id (a collective: every rank calls it, every rank
/// gets them all). For output and for comparing runs on different numbers of ranks.
pub fn gather_particles<const D: usize>(
    sim: &Simulation<D>,
    comm: &dyn Comm,
) -> Result<Particles<D>, String> {
    gather_owned(&sim.sys, comm)
}

fn gather_owned<const D: usize>(sys: &System<D>, comm: &dyn Comm) -> Result<Particles<D>, String> {
    let own = sys
        .particles
        .selected(&(0..sys.owned() as u32).collect::<Vec<_>>());
    let bytes = postcard::to_stdvec(&own).map_err(|e| e.to_string())?;
    let all = comm.all_gather(bytes).map_err(|e| e.to_string())?;
    let mut out = Particles::<D>::default();
    for b in all {
        let part: Particles<D> = postcard::from_bytes(&b).map_err(|e| e.to_string())?;
        if out.is_empty() {
            out = part;
        } else {
            out.append(&part)?;
        }
    }
    let mut order: Vec<u32> = (0..out.len() as u32).collect();
    order.sort_by_key(|&i| out.id[i as usize]);
    out.permute(&order);
    Ok(out)
}

/// The ranks this process was started among by `mpirun` (Open MPI's or MPICH's launcher
/// environment), or `None` when it was started alone. Under mpirun, even on one rank, the
/// run is distributed (so that 1, 2 and 3 ranks give the same particles).
pub fn launched() -> Result<Option<Arc<dyn Comm>>, String> {
    let size = std::env::var("OMPI_COMM_WORLD_SIZE")
        .or_else(|_| std::env::var("PMI_SIZE"))
        .ok();
    let Some(size) = size else {
        return Ok(None);
    };
    #[cfg(feature = "mpi")]
    {
        let _ = size;
        match mpi::MpiComm::init() {
            Some(c) => Ok(Some(Arc::new(c))),
            None => Err("mpirun: MPI could not be initialised".into()),
        }
    }
    #[cfg(not(feature = "mpi"))]
    Err(format!(
        "started by mpirun ({size} ranks), but this sphfmu was built without MPI: build it with \
         `cargo build --release --features mpi` (needs Open MPI: Debian's libopenmpi-dev and openmpi-bin), \
         or run it without mpirun"
    ))
}

/// Worker threads per rank when none are asked for: the cores shared among the ranks on
/// this machine (Open MPI's `OMPI_COMM_WORLD_LOCAL_SIZE`), at least one.
pub fn threads_per_rank() -> Option<usize> {
    let local: usize = std::env::var("OMPI_COMM_WORLD_LOCAL_SIZE")
        .ok()?
        .parse()
        .ok()?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    Some((cores / local.max(1)).max(1))
}

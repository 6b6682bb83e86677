//! The halo: copies of other ranks' particles near this rank's region, refreshed from their
//! owners before every evaluation by [`HaloScheme`], which wraps the run's scheme.
//!
//! Two ways to keep the halo exact, chosen by the scheme ([`crate::scheme::Scheme::halo_depth`]):
//! - **Per-pass refreshes** (issue 23's design; every scheme of ours): one exchange of
//!   whole particles per evaluation, then, between passes, the owners' values of only the
//!   fields the next pass reads of its neighbours (`refresh`). Every
//!   halo copy then holds its owner's bits at any depth, so one support (plus the skin) is
//!   deep enough for the scheme, and the halo's own redundant work is one support's worth.
//! - **A deep halo** (the trait's default, for a scheme that does not refresh): one exchange
//!   per evaluation, the halo as deep as the scheme's chain of dependent passes. Each rank
//!   runs every pass on its halo too; the outer layers come out wrong (their neighbourhoods
//!   are cut), but a pass only reads neighbours one support away, so the error moves inwards
//!   one support per pass and never reaches an owned particle. The scheme needs no refresh calls, at the price of more
//!   halo work, which `make bench` measures (the `MPI:` row).

use super::comm::{Comm, CommError};
use super::exact::{registers, ExactSum};
use crate::particles::Particles;
use crate::scheme::{compatible::PairWork, rosswog::TriggerLevels, Scheme, SchemeError};
use crate::system::System;
use std::sync::{Arc, Mutex};

/// Which owned particles go to which rank, and how many come from each.
#[derive(Debug, Clone, Default)]
pub struct HaloPlan {
    /// Per destination rank, the owned particles it holds copies of.
    pub send: Vec<Vec<u32>>,
    /// Per source rank, how many copies of its particles this rank holds (in rank order
    /// after the owned particles).
    pub recv: Vec<usize>,
}

/// Exchange counters since the run started.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct ExchangeStats {
    /// Bytes this rank sent (halo refreshes, halo builds, migrations, rebalances).
    pub bytes_sent: u64,
    /// Messages (non-empty buffers) this rank sent.
    pub messages: u64,
    /// Wall-clock seconds in exchanges (packing, waiting, unpacking).
    pub seconds: f64,
    /// Halo refreshes (one per evaluation).
    pub refreshes: u64,
    /// Refreshes of some fields between passes (`parallel::refresh`).
    pub field_refreshes: u64,
    /// Halo copies this rank holds now.
    pub halo_particles: u64,
    /// Particles that moved to another rank.
    pub migrated: u64,
    pub rebalances: u64,
}

/// What the decomposition and the wrapped scheme share.
pub struct Link {
    pub comm: Arc<dyn Comm>,
    pub plan: Mutex<HaloPlan>,
    pub stats: Mutex<ExchangeStats>,
    /// The first exchange failure inside a pass that cannot return one (`Scheme::refresh`).
    pub failure: Mutex<Option<String>>,
}

impl std::fmt::Debug for Link {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Link(rank {} of {})", self.comm.rank(), self.comm.size())
    }
}

impl crate::system::RankSums for Link {
    fn merge_in_place(&self, x: &mut [ExactSum]) {
        let mine: Vec<u8> = x.iter().flat_map(|s| s.to_bytes()).collect();
        let merged = self.comm.all_gather(mine).and_then(|all| {
            let mut total = registers(x.len());
            for part in &all {
                let parts = part.chunks_exact(ExactSum::BYTES);
                if parts.len() != x.len() || !parts.remainder().is_empty() {
                    return Err(CommError(format!(
                        "a sum over ranks of {} numbers met a rank with {} bytes",
                        x.len(),
                        part.len()
                    )));
                }
                for (t, b) in total.iter_mut().zip(parts) {
                    t.merge(&ExactSum::from_bytes(b).map_err(CommError)?);
                }
            }
            Ok(total)
        });
        match merged {
            Ok(total) => x.clone_from_slice(&total),
            Err(e) => self.fail(e.to_string()),
        }
    }

    fn max_in_place(&self, x: &mut [f64]) {
        match crate::parallel::comm::Reduce::max_each(&*self.comm, x) {
            Ok(top) => x.copy_from_slice(&top),
            Err(e) => self.fail(e.to_string()),
        }
    }

    fn halo_values(&self, width: usize, pack: &dyn Fn(&[u32]) -> Vec<f64>) -> Option<Vec<f64>> {
        match self.exchange_values(width, pack) {
            Ok(v) => Some(v),
            Err(e) => {
                self.fail(e);
                None
            }
        }
    }
}

impl Link {
    pub fn new(comm: Arc<dyn Comm>) -> Self {
        Self {
            comm,
            plan: Mutex::new(HaloPlan::default()),
            stats: Mutex::new(ExchangeStats::default()),
            failure: Mutex::new(None),
        }
    }

    pub fn stats(&self) -> ExchangeStats {
        *self.stats.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Send `parts[r]` to rank r and return what each rank sent here, counting bytes,
    /// messages and time.
    pub fn exchange<const D: usize>(
        &self,
        parts: Vec<Option<Particles<D>>>,
    ) -> Result<Vec<Particles<D>>, String> {
        let t0 = std::time::Instant::now();
        let me = self.comm.rank();
        let mut bytes = 0u64;
        let mut messages = 0u64;
        let send: Vec<Vec<u8>> = parts
            .iter()
            .enumerate()
            .map(|(r, p)| match p {
                Some(p) if r != me && !p.is_empty() => {
                    let b = postcard::to_stdvec(p).expect("particles serialise");
                    bytes += b.len() as u64;
                    messages += 1;
                    b
                }
                _ => vec![],
            })
            .collect();
        let got = self.comm.all_to_all(send).map_err(|e| e.to_string())?;
        let out = got
            .iter()
            .map(|b| {
                if b.is_empty() {
                    Ok(Particles::default())
                } else {
                    postcard::from_bytes(b)
                        .map_err(|e| format!("a rank sent unreadable particles: {e}"))
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        let mut s = self.stats.lock().unwrap_or_else(|e| e.into_inner());
        s.bytes_sent += bytes;
        s.messages += messages;
        s.seconds += t0.elapsed().as_secs_f64();
        Ok(out)
    }

    /// Send `pack(plan.send[r])` (`width` numbers per particle) to each rank r and return
    /// what the others sent here, joined in the halo's order (rank order).
    fn exchange_values(
        &self,
        width: usize,
        pack: &dyn Fn(&[u32]) -> Vec<f64>,
    ) -> Result<Vec<f64>, String> {
        let t0 = std::time::Instant::now();
        let me = self.comm.rank();
        // packed under the plan's lock, so only the receive counts are copied out of it (not
        // the send index lists, 3–5 times per evaluation)
        let (send, recv): (Vec<Vec<u8>>, Vec<usize>) = {
            let plan = self.plan.lock().unwrap_or_else(|e| e.into_inner());
            let send = plan
                .send
                .iter()
                .enumerate()
                .map(|(r, pick)| {
                    if r == me || pick.is_empty() {
                        vec![]
                    } else {
                        super::comm::f64_bytes(&pack(pick))
                    }
                })
                .collect();
            (send, plan.recv.clone())
        };
        let bytes: usize = send.iter().map(|b| b.len()).sum();
        let messages = send.iter().filter(|b| !b.is_empty()).count();
        let got = self.comm.all_to_all(send).map_err(|e| e.to_string())?;
        let mut out = Vec::with_capacity(recv.iter().sum::<usize>() * width);
        for (r, b) in got.iter().enumerate() {
            if r == me {
                continue;
            }
            let want = recv.get(r).copied().unwrap_or(0) * width;
            if b.len() != want * 8 {
                return Err(format!(
                    "rank {r} sent {} halo values, {want} expected",
                    b.len() / 8
                ));
            }
            out.extend(super::comm::bytes_f64(b));
        }
        let mut s = self.stats.lock().unwrap_or_else(|e| e.into_inner());
        s.bytes_sent += bytes as u64;
        s.messages += messages as u64;
        s.field_refreshes += 1;
        s.seconds += t0.elapsed().as_secs_f64();
        Ok(out)
    }

    /// Overwrite the halo copies with their owners' current particles (every field).
    pub fn refresh_halo<const D: usize>(&self, sys: &mut System<D>) -> Result<(), String> {
        let (parts, recv) = {
            let plan = self.plan.lock().unwrap_or_else(|e| e.into_inner());
            let parts = plan
                .send
                .iter()
                .map(|pick| Some(sys.particles.selected(pick)))
                .collect();
            (parts, plan.recv.clone())
        };
        let got = self.exchange(parts)?;
        let mut at = sys.owned();
        for (r, part) in got.iter().enumerate() {
            if r == self.comm.rank() {
                continue;
            }
            let want = recv.get(r).copied().unwrap_or(0);
            if part.len() != want {
                return Err(format!(
                    "rank {r} sent {} halo particles, {want} expected",
                    part.len()
                ));
            }
            sys.particles.overwrite(at, part)?;
            at += part.len();
        }
        self.stats
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .refreshes += 1;
        Ok(())
    }

    fn fail(&self, why: String) {
        self.failure
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get_or_insert(why);
    }

    /// Whether every rank's `result` is Ok; if not, all ranks return the first failing
    /// rank's message (prefixed with its number).
    pub fn agree(&self, result: Result<(), String>) -> Result<(), String> {
        let mine = match &result {
            Ok(()) => vec![],
            Err(m) => m.clone().into_bytes(),
        };
        let all = self.comm.all_gather(mine).map_err(|e| e.to_string())?;
        match all.iter().enumerate().find(|(_, m)| !m.is_empty()) {
            None => Ok(()),
            Some((r, m)) => Err(format!("rank {r}: {}", String::from_utf8_lossy(m))),
        }
    }
}

/// The run's scheme, with the halo refreshed before every evaluation and the ranks agreeing
/// on its outcome (a rank that failed alone would leave the others waiting).
pub struct HaloScheme<const D: usize> {
    pub inner: Box<dyn Scheme<D>>,
    pub link: Arc<Link>,
}

impl<const D: usize> Scheme<D> for HaloScheme<D> {
    fn name(&self) -> &'static str {
        self.inner.name()
    }
    fn init(&mut self, sys: &mut System<D>) {
        self.inner.init(sys)
    }
    fn evaluate(&mut self, sys: &mut System<D>) -> Result<(), SchemeError> {
        self.link.refresh_halo(sys).map_err(SchemeError)?;
        let result = self.inner.evaluate(sys).map_err(|e| e.0);
        self.link.agree(result).map_err(SchemeError)
    }
    fn refresh(&mut self, sys: &mut System<D>) {
        match self.link.refresh_halo(sys) {
            Ok(()) => self.inner.refresh(sys),
            Err(e) => self.link.fail(e),
        }
    }
    fn end_step(&mut self, sys: &mut System<D>, dt: f64) {
        self.inner.end_step(sys, dt)
    }
    fn trigger_levels(&self) -> Option<TriggerLevels> {
        self.inner.trigger_levels()
    }
    fn pair_work(&self) -> Option<&PairWork<D>> {
        self.inner.pair_work()
    }
    fn total_energy(&self) -> bool {
        self.inner.total_energy()
    }
    fn carried_state(&self) -> Vec<f64> {
        self.inner.carried_state()
    }
    fn set_carried_state(&mut self, state: &[f64]) -> Result<(), String> {
        self.inner.set_carried_state(state)
    }
    fn halo_depth(&self) -> usize {
        self.inner.halo_depth()
    }
}

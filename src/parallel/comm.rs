//! What the distributed run needs of a message-passing layer, and two layers that give it:
//! [`ThreadRanks`] (ranks as threads of one process: the tests run 1, 2 and 3 ranks without
//! mpirun) and, with the `mpi` feature, `MpiComm` (Open MPI through rsmpi). Everything the
//! decomposition exchanges goes through two collectives, an all-to-all and an all-gather of
//! byte buffers; reductions are all-gathers summed in rank order, so a total is the same on
//! every rank.

use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

/// A collective that could not complete (a rank left, or the layer failed).
#[derive(Debug, Clone, PartialEq)]
pub struct CommError(pub String);

impl std::fmt::Display for CommError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0)
    }
}

impl std::error::Error for CommError {}

/// The ranks of one distributed run. Every rank calls the same collectives in the same order.
pub trait Comm: Send + Sync {
    fn rank(&self) -> usize;
    fn size(&self) -> usize;
    /// `send[r]` goes to rank r (`send.len() == size`); returns what each rank sent to this
    /// one, indexed by the sender.
    fn all_to_all(&self, send: Vec<Vec<u8>>) -> Result<Vec<Vec<u8>>, CommError>;
    /// Every rank's `mine`, in rank order.
    fn all_gather(&self, mine: Vec<u8>) -> Result<Vec<Vec<u8>>, CommError>;
}

/// Reductions built on [`Comm::all_gather`].
pub trait Reduce {
    /// Element-wise sums over the ranks, added in rank order.
    fn sum(&self, x: &[f64]) -> Result<Vec<f64>, CommError>;
    fn min(&self, x: f64) -> Result<f64, CommError>;
    /// Element-wise maxima over the ranks.
    fn max_each(&self, x: &[f64]) -> Result<Vec<f64>, CommError>;
    fn max(&self, x: f64) -> Result<f64, CommError>;
    /// Whether every rank passed `true`.
    fn all(&self, ok: bool) -> Result<bool, CommError>;
}

impl<C: Comm + ?Sized> Reduce for C {
    fn sum(&self, x: &[f64]) -> Result<Vec<f64>, CommError> {
        fold_each(self, x, 0.0, |a, b| a + b)
    }
    fn min(&self, x: f64) -> Result<f64, CommError> {
        let all = self.all_gather(f64_bytes(&[x]))?;
        Ok(all
            .iter()
            .flat_map(|b| bytes_f64(b))
            .fold(f64::INFINITY, f64::min))
    }
    fn max_each(&self, x: &[f64]) -> Result<Vec<f64>, CommError> {
        fold_each(self, x, f64::NEG_INFINITY, f64::max)
    }
    fn max(&self, x: f64) -> Result<f64, CommError> {
        let all = self.all_gather(f64_bytes(&[x]))?;
        Ok(all
            .iter()
            .flat_map(|b| bytes_f64(b))
            .fold(f64::NEG_INFINITY, f64::max))
    }
    fn all(&self, ok: bool) -> Result<bool, CommError> {
        let all = self.all_gather(vec![ok as u8])?;
        Ok(all.iter().all(|b| b == &[1]))
    }
}

/// Every rank's `x` folded element-wise with `op` from `init`, in rank order.
fn fold_each<C: Comm + ?Sized>(
    comm: &C,
    x: &[f64],
    init: f64,
    op: impl Fn(f64, f64) -> f64,
) -> Result<Vec<f64>, CommError> {
    let parts = comm.all_gather(f64_bytes(x))?;
    let mut out = vec![init; x.len()];
    for part in parts {
        let v = bytes_f64(&part);
        if v.len() != out.len() {
            return Err(CommError(format!(
                "a reduction over ranks of {} numbers met a rank with {}",
                out.len(),
                v.len()
            )));
        }
        out.iter_mut().zip(v).for_each(|(o, x)| *o = op(*o, x));
    }
    Ok(out)
}

pub fn f64_bytes(x: &[f64]) -> Vec<u8> {
    x.iter().flat_map(|v| v.to_le_bytes()).collect()
}

pub fn bytes_f64(b: &[u8]) -> Vec<f64> {
    b.chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect()
}

/// One process, one rank: the collectives hand back what was given.
#[derive(Debug, Clone, Copy, Default)]
pub struct Solo;

impl Comm for Solo {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn all_to_all(&self, send: Vec<Vec<u8>>) -> Result<Vec<Vec<u8>>, CommError> {
        Ok(send)
    }
    fn all_gather(&self, mine: Vec<u8>) -> Result<Vec<Vec<u8>>, CommError> {
        Ok(vec![mine])
    }
}

/// Ranks as threads of one process, meeting at a rendezvous: for tests of the decomposition
/// without mpirun. A rank whose handle is dropped (it returned or panicked) breaks the
/// rendezvous, and the others' collectives then fail instead of waiting forever.
pub struct ThreadRanks {
    rank: usize,
    shared: Arc<Rendezvous>,
}

struct Rendezvous {
    size: usize,
    state: Mutex<Round>,
    turn: Condvar,
}

struct Round {
    /// Buffers deposited in the round under way, by sender.
    deposited: Vec<Option<Vec<Vec<u8>>>>,
    arrived: usize,
    /// Completed rounds' columns not yet taken, by receiver.
    delivered: Vec<Option<Vec<Vec<u8>>>>,
    generation: u64,
    broken: Option<String>,
}

/// How long a rank waits for the others before it calls the run broken.
const RENDEZVOUS_TIMEOUT: Duration = Duration::from_secs(600);

impl ThreadRanks {
    /// Handles for `size` ranks, one per thread.
    pub fn group(size: usize) -> Vec<ThreadRanks> {
        let shared = Arc::new(Rendezvous {
            size,
            state: Mutex::new(Round {
                deposited: vec![None; size],
                arrived: 0,
                delivered: vec![None; size],
                generation: 0,
                broken: None,
            }),
            turn: Condvar::new(),
        });
        (0..size)
            .map(|rank| ThreadRanks {
                rank,
                shared: shared.clone(),
            })
            .collect()
    }
}

impl Drop for ThreadRanks {
    fn drop(&mut self) {
        if let Ok(mut s) = self.shared.state.lock() {
            s.broken
                .get_or_insert_with(|| format!("rank {} left the run", self.rank));
            self.shared.turn.notify_all();
        }
    }
}

impl Comm for ThreadRanks {
    fn rank(&self) -> usize {
        self.rank
    }
    fn size(&self) -> usize {
        self.shared.size
    }
    fn all_to_all(&self, send: Vec<Vec<u8>>) -> Result<Vec<Vec<u8>>, CommError> {
        let sh = &*self.shared;
        if send.len() != sh.size {
            return Err(CommError(format!(
                "all-to-all with {} buffers among {} ranks",
                send.len(),
                sh.size
            )));
        }
        fn poisoned<T>(_: T) -> CommError {
            CommError("a rank panicked inside a collective".into())
        }
        let mut s = sh.state.lock().map_err(poisoned)?;
        if let Some(why) = &s.broken {
            return Err(CommError(why.clone()));
        }
        s.deposited[self.rank] = Some(send);
        s.arrived += 1;
        let generation = s.generation;
        if s.arrived == sh.size {
            // the last to arrive transposes: column r holds what every rank sent to r
            let mut rows: Vec<Vec<Vec<u8>>> = s
                .deposited
                .iter_mut()
                .map(|d| d.take().unwrap_or_default())
                .collect();
            for r in 0..sh.size {
                let column = rows
                    .iter_mut()
                    .map(|row| std::mem::take(&mut row[r]))
                    .collect();
                s.delivered[r] = Some(column);
            }
            s.arrived = 0;
            s.generation += 1;
            sh.turn.notify_all();
        } else {
            while s.generation == generation {
                if let Some(why) = &s.broken {
                    return Err(CommError(why.clone()));
                }
                let (next, timeout) = sh
                    .turn
                    .wait_timeout(s, RENDEZVOUS_TIMEOUT)
                    .map_err(poisoned)?;
                s = next;
                if timeout.timed_out() && s.generation == generation {
                    return Err(CommError(format!(
                        "rank {} waited {} s for the other ranks",
                        self.rank,
                        RENDEZVOUS_TIMEOUT.as_secs()
                    )));
                }
            }
        }
        s.delivered[self.rank]
            .take()
            .ok_or_else(|| CommError("a collective's result went missing".into()))
    }
    fn all_gather(&self, mine: Vec<u8>) -> Result<Vec<Vec<u8>>, CommError> {
        self.all_to_all(vec![mine; self.size()])
    }
}

//! [`Comm`] over MPI (rsmpi, against the system's Open MPI): the `mpi` feature.

use super::comm::{Comm, CommError};
use mpi::datatype::{Partition, PartitionMut};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use mpi::Count;
use std::sync::Mutex;

/// The world communicator of `mpirun`'s ranks. MPI is initialised at the `Serialized`
/// threading level: any thread may call, one at a time, which the lock guarantees.
pub struct MpiComm {
    world: SimpleCommunicator,
    rank: usize,
    size: usize,
    lock: Mutex<()>,
    // finalises MPI when dropped, after the communicator
    _universe: mpi::environment::Universe,
}

// SAFETY: MPI was initialised with MPI_THREAD_SERIALIZED, and every call goes through `lock`,
// so no two threads are ever inside MPI at once.
unsafe impl Send for MpiComm {}
unsafe impl Sync for MpiComm {}

impl MpiComm {
    /// Initialise MPI, or `None` if it is already initialised or the library refused.
    pub fn init() -> Option<Self> {
        let (universe, _level) = mpi::initialize_with_threading(mpi::Threading::Serialized)?;
        let world = universe.world();
        Some(Self {
            rank: world.rank() as usize,
            size: world.size() as usize,
            world,
            lock: Mutex::new(()),
            _universe: universe,
        })
    }

    fn guard(&self) -> Result<std::sync::MutexGuard<'_, ()>, CommError> {
        self.lock
            .lock()
            .map_err(|_| CommError("a thread panicked inside an MPI call".into()))
    }
}

fn counts(lens: impl Iterator<Item = usize>) -> Result<Vec<Count>, CommError> {
    lens.map(|n| {
        Count::try_from(n)
            .map_err(|_| CommError(format!("a message of {n} bytes is too long for MPI")))
    })
    .collect()
}

fn displacements(c: &[Count]) -> Vec<Count> {
    c.iter()
        .scan(0, |at, &n| {
            let here = *at;
            *at += n;
            Some(here)
        })
        .collect()
}

fn split(buf: Vec<u8>, c: &[Count]) -> Vec<Vec<u8>> {
    let mut at = 0;
    c.iter()
        .map(|&n| {
            let part = buf[at..at + n as usize].to_vec();
            at += n as usize;
            part
        })
        .collect()
}

impl Comm for MpiComm {
    fn rank(&self) -> usize {
        self.rank
    }
    fn size(&self) -> usize {
        self.size
    }
    fn all_to_all(&self, send: Vec<Vec<u8>>) -> Result<Vec<Vec<u8>>, CommError> {
        if send.len() != self.size {
            return Err(CommError(format!(
                "all-to-all with {} buffers among {} ranks",
                send.len(),
                self.size
            )));
        }
        let _g = self.guard()?;
        let send_counts = counts(send.iter().map(|b| b.len()))?;
        let mut recv_counts = vec![0 as Count; self.size];
        self.world
            .all_to_all_into(&send_counts[..], &mut recv_counts[..]);
        // one spare byte each: two empty buffers would share the same dangling address, which
        // Open MPI rejects as an aliased send and receive buffer (MPI_ERR_ARG)
        let mut flat: Vec<u8> = send.concat();
        flat.push(0);
        let send_displs = displacements(&send_counts);
        let recv_displs = displacements(&recv_counts);
        let total: usize = recv_counts.iter().map(|&n| n as usize).sum();
        let mut recv = vec![0u8; total + 1];
        {
            let outgoing = Partition::new(&flat[..], &send_counts[..], &send_displs[..]);
            let mut incoming = PartitionMut::new(&mut recv[..], &recv_counts[..], &recv_displs[..]);
            self.world
                .all_to_all_varcount_into(&outgoing, &mut incoming);
        }
        Ok(split(recv, &recv_counts))
    }
    fn all_gather(&self, mine: Vec<u8>) -> Result<Vec<Vec<u8>>, CommError> {
        // as an all-to-all of the same bytes to every rank: MPI_Allgatherv through rsmpi
        // reported truncation on Open MPI 4.1 with buffers the all-to-all handles
        self.all_to_all(vec![mine; self.size])
    }
}

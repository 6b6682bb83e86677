//! The outputs of a run shared among ranks (`parallel`): rank 0 writes the diagnostics, the
//! summary and the checks; every rank writes its own particles as one piece of each VTU
//! snapshot, which rank 0's `.pvtu` joins into one ParaView dataset.

use super::{io_err, RunError};
use crate::io;
use crate::parallel::comm::Comm;
use crate::sim::{Simulation, SolverError};
use std::path::{Path, PathBuf};

/// Write this rank's piece of VTU snapshot `idx` (its own particles), and on rank 0 the
/// `.pvtu` naming every rank's piece. Returns the `.pvtu`'s path.
pub(super) fn write_vtu_pieces<const D: usize>(
    dir: &Path,
    idx: usize,
    sim: &Simulation<D>,
    comm: &dyn Comm,
) -> Result<PathBuf, RunError> {
    let piece = |r: usize| format!("snapshot_{idx:05}_{r}.vtu");
    let own: Vec<u32> = (0..sim.sys.owned() as u32).collect();
    let path = dir.join(piece(comm.rank()));
    let mine = io::write_vtu(&path, &sim.sys.particles.selected(&own), sim.time)
        .map_err(|e| io_err(&path, e));
    // every piece is on disk before rank 0 names them; a rank that failed to write says so
    // here rather than leave the others waiting at the next exchange
    let everyone = all_ranks_ok(comm, mine.is_ok())?;
    mine?;
    if !everyone {
        return Err(RunError::Io(format!(
            "distributed run: another rank could not write its piece of snapshot {idx}"
        )));
    }
    let joint = dir.join(format!("snapshot_{idx:05}.pvtu"));
    if comm.rank() == 0 {
        let pieces: Vec<String> = (0..comm.size()).map(piece).collect();
        io::write_pvtu(&joint, &pieces, sim.time).map_err(|e| io_err(&joint, e))?;
    }
    Ok(joint)
}

/// Every rank's particles in rank 0's simulation, which leaves the decomposition (the run is
/// over): its checks and summary then see the whole case. A collective.
pub(super) fn gather_to_root<const D: usize>(
    sim: &mut Simulation<D>,
    comm: &dyn Comm,
) -> Result<(), RunError> {
    let all = crate::parallel::gather_particles(sim, comm).map_err(gather_failed(sim))?;
    if comm.rank() == 0 {
        sim.sys.particles = all;
        sim.sys.halo = 0;
        sim.sys.reset_neighbours();
        sim.layout = None;
        sim.sys.ranks = None;
    }
    Ok(())
}

fn gather_failed<const D: usize>(sim: &Simulation<D>) -> impl Fn(String) -> RunError + '_ {
    move |message| {
        RunError::Solver(SolverError::Scheme {
            message: format!("distributed run: gathering the particles: {message}"),
            time: sim.time,
            step: sim.steps,
        })
    }
}

/// Whether every rank passed `ok` (a collective).
fn all_ranks_ok(comm: &dyn Comm, ok: bool) -> Result<bool, RunError> {
    use crate::parallel::comm::Reduce;
    comm.all(ok)
        .map_err(|e| RunError::Io(format!("distributed run: {e}")))
}

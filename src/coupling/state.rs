//! Save / restore of the whole solver state (FMI get/set and serialize FMU state).
//!
//! Saved: everything a continued run reads — the particles (all fields, the scheme's extra
//! slots), the bodies, the ports (their mass counters and last external pressure), gravity, the cell grid and neighbour lists (their order sets the
//! summation order, so they must come back as they were for a bit-exact continuation), the
//! integrator's saved stage state, time, step count, last dt and the pending-input flag.
//! Not saved: what the case fixes (box, kernel, EOS, scheme parameters, step control); the
//! header's case fingerprint makes sure the state goes back into a Coupling of the same
//! case and options. The schemes keep no state between steps outside the particles (their
//! buffers are refilled by every evaluation), which `tests/coupling.rs` checks bit for bit
//! for each scheme family.
//!
//! Encoding: postcard (f64 as its 8 bytes, so the round trip is exact), in an envelope that
//! makes a damaged state a plain error (never a panic in a later step, never a run on silently
//! wrong data): magic bytes, format version, payload length and a CRC-32 of the payload
//! (crc32fast; CRC-32 catches every error burst of up to 32 bits, so every single-byte
//! change), then, once decoded, every invariant a later step relies on (`integrity.rs`).

use super::engine::Coupled;
use crate::boundary::bodies::Body;
use crate::boundary::kinematics::HeldPose;
use crate::boundary::ports::Port;
use crate::case::Case;
use crate::integrate::Integrator;
use crate::neighbours::{CellGrid, NeighbourList};
use crate::particles::{Particles, Vector};
use crate::system::{EvalStats, VerletList};
use serde::{Deserialize, Serialize};

const MAGIC: [u8; 8] = *b"sphfmu\0s";
/// 3: the checksummed envelope. 4: the cell grid keeps a width and a period per axis.
/// 5: body poses are quaternions with angular velocity vectors; the frame's pose a master set.
/// 6: the number of ranks that saved it.
const VERSION: u32 = 6;

#[derive(Serialize, Deserialize)]
struct Header {
    dimension: u32,
    fingerprint: u64,
    particles: u64,
    /// 0: saved by a single process, with its neighbour lists. R ≥ 1: saved by a run on R
    /// ranks (`parallel`): the whole case's particles in id order and no neighbour lists (a
    /// rank's lists index its own particles and halo). Either restores on any number of
    /// ranks: the particles are split anew, and the lists rebuilt.
    ranks: u32,
}

#[derive(Serialize, Deserialize)]
pub(super) struct Saved<const D: usize> {
    pub(super) time: f64,
    pub(super) steps: u64,
    pub(super) last_dt: f64,
    pub(super) dirty: bool,
    pub(super) gravity: Vector<D>,
    pub(super) particles: Particles<D>,
    pub(super) bodies: Vec<Body<D>>,
    /// The pose a master set for an external frame (`None` without a frame).
    pub(super) frame_held: Option<HeldPose<D>>,
    pub(super) ports: Vec<Port<D>>,
    pub(super) grid: CellGrid<D>,
    pub(super) verlet: VerletList<D>,
    pub(super) neighbours: NeighbourList,
    pub(super) stats: EvalStats,
    pub(super) integrator: Integrator<D>,
    pub(super) scheme: Vec<f64>,
}

/// FNV-1a of the case as run (options applied), so a state only goes back into the case it
/// came from.
pub fn fingerprint(case: &Case) -> u64 {
    let text = toml::to_string(case).unwrap_or_default();
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The state of `c`; in a distributed run a collective (every rank calls it and gets the
/// same bytes), which fails when the ranks cannot exchange.
pub(super) fn save<const D: usize>(c: &Coupled<D>, fingerprint: u64) -> Result<Vec<u8>, String> {
    let sim = &c.sim;
    let sys = &sim.sys;
    let (particles, ranks, grid, verlet, neighbours, stats, integrator) = match &sim.layout {
        None => (
            sys.particles.clone(),
            0,
            sys.grid.clone(),
            sys.verlet.clone(),
            sys.neighbours.clone(),
            sys.stats,
            sim.integrator.clone(),
        ),
        // the same bytes on every rank: nothing of one rank's own (its lists, its counters,
        // its integrator's stage arrays, refilled at every step's start)
        Some(layout) => (
            layout
                .gather(sys)
                .map_err(|e| format!("distributed run: {e}"))?,
            layout.exchange().0 as u32,
            CellGrid::default(),
            VerletList::default(),
            NeighbourList::default(),
            EvalStats::default(),
            Integrator::new(sim.integrator.kind),
        ),
    };
    let header = Header {
        dimension: D as u32,
        fingerprint,
        particles: particles.len() as u64,
        ranks,
    };
    let saved = Saved::<D> {
        time: sim.time,
        steps: sim.steps,
        last_dt: sim.last_dt,
        dirty: c.dirty,
        gravity: sys.gravity,
        particles,
        bodies: sys.bodies.clone(),
        frame_held: sys.frame.as_ref().map(|f| f.held),
        ports: sys.ports.clone(),
        grid,
        verlet,
        neighbours,
        stats,
        integrator,
        scheme: sim.scheme.carried_state(),
    };
    let mut payload = postcard::to_stdvec(&header).expect("a header always encodes");
    payload.extend(postcard::to_stdvec(&saved).expect("the solver state always encodes"));
    Ok(seal(&MAGIC, VERSION, &payload))
}

/// `magic | version (u32 LE) | payload length (u64 LE) | CRC-32 of the payload (u32 LE) |
/// payload`: the envelope of a saved solver state (and of the FMU's serialized state).
pub fn seal(magic: &[u8; 8], version: u32, payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(24 + payload.len());
    out.extend_from_slice(magic);
    out.extend_from_slice(&version.to_le_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&crc32fast::hash(payload).to_le_bytes());
    out.extend_from_slice(payload);
    out
}

/// The payload of an envelope written by [`seal`], or why it is not one: `what` names the
/// state in the message.
pub fn open<'a>(
    what: &str,
    magic: &[u8; 8],
    version: u32,
    bytes: &'a [u8],
) -> Result<&'a [u8], String> {
    if bytes.len() < 24 {
        return Err(format!(
            "{what}: not a saved sphfmu state ({} bytes, shorter than the 24-byte envelope)",
            bytes.len()
        ));
    }
    if &bytes[..8] != magic {
        return Err(format!(
            "{what}: not a saved sphfmu state (wrong magic bytes)"
        ));
    }
    let v = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if v != version {
        return Err(format!(
            "{what}: format version {v} (this build reads {version})"
        ));
    }
    let len = u64::from_le_bytes(bytes[12..20].try_into().expect("8 bytes"));
    let payload = &bytes[24..];
    if len != payload.len() as u64 {
        return Err(format!(
            "{what}: damaged (truncated or extended: {} payload bytes, the envelope says {len})",
            payload.len()
        ));
    }
    let crc = u32::from_le_bytes(bytes[20..24].try_into().expect("4 bytes"));
    let actual = crc32fast::hash(payload);
    if crc != actual {
        return Err(format!(
            "{what}: damaged (CRC-32 {actual:08x}, the envelope says {crc:08x})"
        ));
    }
    Ok(payload)
}

pub(super) fn restore<const D: usize>(
    c: &mut Coupled<D>,
    bytes: &[u8],
    fingerprint: u64,
) -> Result<(), String> {
    let payload = open("state", &MAGIC, VERSION, bytes)?;
    let (header, rest): (Header, &[u8]) = postcard::take_from_bytes(payload)
        .map_err(|e| format!("state: not a saved sphfmu state ({e})"))?;
    if header.dimension as usize != D || header.fingerprint != fingerprint {
        return Err(format!(
            "state: saved from another case or other options ({}D, fingerprint {:016x}; this instance: {D}D, {fingerprint:016x})",
            header.dimension, header.fingerprint
        ));
    }
    let saved: Saved<D> =
        postcard::from_bytes(rest).map_err(|e| format!("state: damaged ({e})"))?;
    if saved.particles.len() as u64 != header.particles {
        return Err("state: damaged (particle count does not match its header)".into());
    }
    // every invariant a later step relies on, before anything of the instance changes
    let lists = header.ranks == 0;
    super::integrity::check(&saved, c, lists).map_err(|e| format!("state: damaged ({e})"))?;
    let sim = &mut c.sim;
    sim.scheme
        .set_carried_state(&saved.scheme)
        .map_err(|e| format!("state: damaged ({e})"))?;
    sim.time = saved.time;
    sim.steps = saved.steps;
    sim.last_dt = saved.last_dt;
    sim.integrator = saved.integrator;
    c.dirty = saved.dirty;
    let sys = &mut sim.sys;
    sys.gravity = saved.gravity;
    match &mut sim.layout {
        // split among this run's ranks, whatever the number that saved it
        Some(layout) => layout.replace(sys, saved.particles),
        None => sys.particles = saved.particles,
    }
    let mut bodies = saved.bodies;
    for (b, now) in bodies.iter_mut().zip(&sys.bodies) {
        b.motion = now.motion.clone();
    }
    sys.bodies = bodies;
    let mut ports = saved.ports;
    for (k, now) in ports.iter_mut().zip(&sys.ports) {
        k.pressure = now.pressure.clone();
    }
    sys.ports = ports;
    sys.time = saved.time;
    // a prescribed frame's pose is a function of time; an external one's comes from its held
    // pose (checked against the case's frame by `integrity`)
    if let Some(f) = &mut sys.frame {
        if let Some(h) = saved.frame_held {
            f.held = h;
        }
        f.place(saved.time);
    }
    if lists && sim.layout.is_none() {
        sys.grid = saved.grid;
        sys.verlet = saved.verlet;
        sys.neighbours = saved.neighbours;
    } else {
        // (`replace` cleared them on a run on ranks)
        sys.reset_neighbours();
    }
    sys.stats = saved.stats;
    Ok(())
}

/// serde for `[T; D]` with a const-generic D (serde's own impls stop at fixed lengths).
pub mod const_array {
    use serde::{de::Error, Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer, T: Serialize, const D: usize>(
        v: &[T; D],
        s: S,
    ) -> Result<S::Ok, S::Error> {
        v.as_slice().serialize(s)
    }

    pub fn deserialize<'de, De: Deserializer<'de>, T: Deserialize<'de>, const D: usize>(
        d: De,
    ) -> Result<[T; D], De::Error> {
        let v = Vec::<T>::deserialize(d)?;
        let n = v.len();
        v.try_into()
            .map_err(|_| De::Error::custom(format!("expected {D} entries, got {n}")))
    }
}

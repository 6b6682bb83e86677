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
//! Encoding: postcard (f64 as its 8 bytes, so the round trip is exact).

use super::engine::Coupled;
use crate::boundary::bodies::Body;
use crate::boundary::ports::Port;
use crate::case::Case;
use crate::integrate::Integrator;
use crate::neighbours::{CellGrid, NeighbourList};
use crate::particles::{Particles, Vector};
use crate::system::{EvalStats, VerletList};
use serde::{Deserialize, Serialize};

const MAGIC: [u8; 8] = *b"sphfmu\0s";
const VERSION: u32 = 2;

#[derive(Serialize, Deserialize)]
struct Header {
    magic: [u8; 8],
    version: u32,
    dimension: u32,
    fingerprint: u64,
    particles: u64,
}

#[derive(Serialize, Deserialize)]
struct Saved<const D: usize> {
    time: f64,
    steps: u64,
    last_dt: f64,
    dirty: bool,
    gravity: Vector<D>,
    particles: Particles<D>,
    bodies: Vec<Body<D>>,
    ports: Vec<Port<D>>,
    grid: CellGrid<D>,
    verlet: VerletList<D>,
    neighbours: NeighbourList,
    stats: EvalStats,
    integrator: Integrator<D>,
    scheme: Vec<f64>,
}

/// FNV-1a of the case as run (options applied), so a state only goes back into the case it
/// came from.
pub fn fingerprint(case: &Case) -> u64 {
    let text = toml::to_string(case).unwrap_or_default();
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

pub(super) fn save<const D: usize>(c: &Coupled<D>, fingerprint: u64) -> Vec<u8> {
    let sim = &c.sim;
    let sys = &sim.sys;
    let header = Header {
        magic: MAGIC,
        version: VERSION,
        dimension: D as u32,
        fingerprint,
        particles: sys.particles.len() as u64,
    };
    let saved = Saved::<D> {
        time: sim.time,
        steps: sim.steps,
        last_dt: sim.last_dt,
        dirty: c.dirty,
        gravity: sys.gravity,
        particles: sys.particles.clone(),
        bodies: sys.bodies.clone(),
        ports: sys.ports.clone(),
        grid: sys.grid.clone(),
        verlet: sys.verlet.clone(),
        neighbours: sys.neighbours.clone(),
        stats: sys.stats,
        integrator: sim.integrator.clone(),
        scheme: sim.scheme.carried_state(),
    };
    let mut out = postcard::to_stdvec(&header).expect("a header always encodes");
    out.extend(postcard::to_stdvec(&saved).expect("the solver state always encodes"));
    out
}

pub(super) fn restore<const D: usize>(
    c: &mut Coupled<D>,
    bytes: &[u8],
    fingerprint: u64,
) -> Result<(), String> {
    let (header, rest): (Header, &[u8]) = postcard::take_from_bytes(bytes)
        .map_err(|e| format!("state: not a saved sphfmu state ({e})"))?;
    if header.magic != MAGIC {
        return Err("state: not a saved sphfmu state (wrong magic bytes)".into());
    }
    if header.version != VERSION {
        return Err(format!(
            "state: format version {} (this build reads {VERSION})",
            header.version
        ));
    }
    if header.dimension as usize != D || header.fingerprint != fingerprint {
        return Err(format!(
            "state: saved from another case or other options ({}D, fingerprint {:016x}; this instance: {D}D, {fingerprint:016x})",
            header.dimension, header.fingerprint
        ));
    }
    let saved: Saved<D> =
        postcard::from_bytes(rest).map_err(|e| format!("state: damaged ({e})"))?;
    if saved.particles.len() as u64 != header.particles
        || saved.bodies.len() != c.sim.sys.bodies.len()
        || saved.ports.len() != c.sim.sys.ports.len()
    {
        return Err("state: damaged (particle or body count does not match its header)".into());
    }
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
    sys.particles = saved.particles;
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
    // the frame's pose is a function of time only (no external frame motion)
    if let Some(f) = &mut sys.frame {
        f.place(saved.time);
    }
    sys.grid = saved.grid;
    sys.verlet = saved.verlet;
    sys.neighbours = saved.neighbours;
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

//! The invariants a later step relies on, checked on a decoded saved state before it replaces
//! the instance's (`state::restore`). The envelope's CRC-32 already rejects every accidental
//! change; these checks stop a crafted or mis-assembled state, whose checksum is right, from
//! reaching an index out of bounds, a NaN that spreads, or a division by zero. Each failure
//! names what is wrong, and the instance stays as it was.

use super::engine::Coupled;
use super::state::Saved;
use crate::boundary::kinematics::Pose;
use crate::particles::{Particles, Vector};

fn finite<const D: usize>(what: &str, v: &[Vector<D>]) -> Result<(), String> {
    match v.iter().position(|x| x.iter().any(|c| !c.is_finite())) {
        Some(i) => Err(format!("{what} of particle {i} is not finite")),
        None => Ok(()),
    }
}

fn finite_scalars(what: &str, v: &[f64]) -> Result<(), String> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(format!("{what} of particle {i} is not finite: {}", v[i])),
        None => Ok(()),
    }
}

fn positive(what: &str, v: &[f64]) -> Result<(), String> {
    match v.iter().position(|x| !(x.is_finite() && *x > 0.0)) {
        Some(i) => Err(format!(
            "{what} of particle {i} must be finite and > 0, got {}",
            v[i]
        )),
        None => Ok(()),
    }
}

/// Every per-particle array has `n` entries, with finite values, positive masses, densities
/// and smoothing lengths, body, port and driven-region numbers the case has, and the scheme's extra slots.
fn particles<const D: usize>(
    p: &Particles<D>,
    now: &Particles<D>,
    bodies: usize,
    ports: usize,
    drives: usize,
) -> Result<(), String> {
    let n = p.len();
    let lens = [
        ("pos", p.pos.len()),
        ("vel", p.vel.len()),
        ("u", p.u.len()),
        ("rho", p.rho.len()),
        ("pressure", p.pressure.len()),
        ("sound_speed", p.sound_speed.len()),
        ("h", p.h.len()),
        ("material", p.material.len()),
        ("id", p.id.len()),
        ("frozen", p.frozen.len()),
        ("body", p.body.len()),
        ("port", p.port.len()),
        ("drive", p.drive.len()),
        ("rest", p.rest.len()),
        ("acc", p.acc.len()),
        ("dudt", p.dudt.len()),
        ("drhodt", p.drhodt.len()),
        ("omega", p.omega.len()),
        ("div_v", p.div_v.len()),
        ("curl_v", p.curl_v.len()),
        ("v_sig", p.v_sig.len()),
        ("alpha", p.alpha.len()),
        ("vel_wall", p.vel_wall.len()),
        ("wall_force", p.wall_force.len()),
    ];
    if let Some((what, len)) = lens.iter().find(|(_, l)| *l != n) {
        return Err(format!("{what} has {len} entries for {n} particles"));
    }
    if n == 0 || n > crate::neighbours::MAX_PARTICLES {
        return Err(format!("{n} particles"));
    }
    positive("mass", &p.mass)?;
    positive("density", &p.rho)?;
    positive("smoothing length", &p.h)?;
    for (what, v) in [
        ("u", &p.u),
        ("pressure", &p.pressure),
        ("sound speed", &p.sound_speed),
        ("du/dt", &p.dudt),
        ("drho/dt", &p.drhodt),
        ("omega", &p.omega),
        ("div v", &p.div_v),
        ("curl v", &p.curl_v),
        ("signal speed", &p.v_sig),
        ("alpha", &p.alpha),
    ] {
        finite_scalars(what, v)?;
    }
    for (what, v) in [
        ("position", &p.pos),
        ("velocity", &p.vel),
        ("rest position", &p.rest),
        ("acceleration", &p.acc),
        ("wall velocity", &p.vel_wall),
        ("wall force", &p.wall_force),
    ] {
        finite(what, v)?;
    }
    if let Some(i) = p.body.iter().position(|&b| b as usize > bodies) {
        return Err(format!(
            "particle {i} belongs to body {} of {bodies}",
            p.body[i]
        ));
    }
    if let Some(i) = p.port.iter().position(|&k| k as usize > ports) {
        return Err(format!(
            "particle {i} belongs to port {} of {ports}",
            p.port[i]
        ));
    }
    if let Some(i) = p.drive.iter().position(|&k| k as usize > drives) {
        return Err(format!(
            "particle {i} belongs to driven region {} of {drives}",
            p.drive[i]
        ));
    }
    if p.extra_scalars.len() != now.extra_scalars.len()
        || p.extra_vectors.len() != now.extra_vectors.len()
    {
        return Err("the scheme's per-particle slots differ from this instance's".into());
    }
    for s in &p.extra_scalars {
        if s.len() != n {
            return Err(format!(
                "a scheme slot has {} entries for {n} particles",
                s.len()
            ));
        }
        finite_scalars("a scheme slot", s)?;
    }
    for s in &p.extra_vectors {
        if s.len() != n {
            return Err(format!(
                "a scheme slot has {} entries for {n} particles",
                s.len()
            ));
        }
        finite("a scheme slot", s)?;
    }
    Ok(())
}

fn all_finite<'a>(what: &str, values: impl IntoIterator<Item = &'a f64>) -> Result<(), String> {
    if values.into_iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(format!("{what} is not finite"))
    }
}

/// A pose's numbers are finite and its orientation of unit length.
fn pose_ok<const D: usize>(what: &str, p: &Pose<D>) -> Result<(), String> {
    all_finite(
        what,
        p.displacement
            .iter()
            .chain(&p.velocity)
            .chain(&p.acceleration)
            .chain(p.rotation.coords.iter())
            .chain(&p.angular_velocity)
            .chain(&p.angular_acceleration),
    )?;
    if (p.rotation.norm() - 1.0).abs() > 1e-9 {
        return Err(format!("{what}: orientation not of unit length"));
    }
    Ok(())
}

/// `lists`: the state holds its neighbour lists (saved by a single process).
pub(super) fn check<const D: usize>(
    s: &Saved<D>,
    c: &Coupled<D>,
    lists: bool,
) -> Result<(), String> {
    let sys = &c.sim.sys;
    match (&s.frame_held, &sys.frame) {
        (None, None) => {}
        (Some(h), Some(_)) => {
            pose_ok("frame pose", &h.pose)?;
            all_finite("frame pose", [&h.time])?;
        }
        _ => return Err("the frame: the state and the case disagree on having one".into()),
    }
    let n = s.particles.len();
    if !s.time.is_finite() {
        return Err(format!("time {} is not finite", s.time));
    }
    if !(s.last_dt.is_finite() && s.last_dt >= 0.0) {
        return Err(format!(
            "last time step {} is not finite and ≥ 0",
            s.last_dt
        ));
    }
    all_finite("gravity", s.gravity.iter())?;
    if s.bodies.len() != sys.bodies.len() || s.ports.len() != sys.ports.len() {
        return Err(format!(
            "{} bodies and {} ports, the case has {} and {}",
            s.bodies.len(),
            s.ports.len(),
            sys.bodies.len(),
            sys.ports.len()
        ));
    }
    particles(
        &s.particles,
        &sys.particles,
        s.bodies.len(),
        s.ports.len(),
        sys.drives.len(),
    )?;
    for (b, now) in s.bodies.iter().zip(&sys.bodies) {
        let what = format!("body {:?}", now.name);
        if b.name != now.name {
            return Err(format!("{what} is called {:?} in the state", b.name));
        }
        pose_ok(&format!("{what} pose"), &b.pose)?;
        pose_ok(&format!("{what} pose"), &b.held.pose)?;
        all_finite(&format!("{what} pose"), [&b.held.time])?;
        all_finite(
            &format!("{what} loads"),
            b.reference
                .iter()
                .chain(&b.force)
                .chain(&b.torque)
                .chain(&b.impulse)
                .chain(&b.angular_impulse),
        )?;
        if (b.axis.norm() - 1.0).abs() > 1e-9
            || !(b.particle_volume.is_finite() && b.particle_volume > 0.0)
            || !(b.spacing.is_finite() && b.spacing > 0.0)
        {
            return Err(format!(
                "{what}: axis not a unit vector, or wall volume or spacing not > 0"
            ));
        }
    }
    for (k, now) in s.ports.iter().zip(&sys.ports) {
        let what = format!("port {:?}", now.name);
        if k.name != now.name {
            return Err(format!("{what} is called {:?} in the state", k.name));
        }
        all_finite(
            &what,
            k.center
                .iter()
                .chain(&k.normal)
                .chain(k.samples.iter().flat_map(|x| x.iter()))
                .chain([
                    &k.external,
                    &k.depth,
                    &k.particle_volume,
                    &k.mass_in,
                    &k.mass_out,
                ]),
        )?;
        if !(k.external >= 0.0
            && k.depth > 0.0
            && k.particle_volume > 0.0
            && k.mass_in >= 0.0
            && k.mass_out >= 0.0)
        {
            return Err(format!(
                "{what}: a pressure, depth, volume or mass counter below its range"
            ));
        }
    }
    if lists {
        neighbour_lists(s, n)?;
    }
    if s.integrator.kind != c.sim.integrator.kind {
        return Err(format!(
            "integrator {} (this instance runs {})",
            s.integrator.kind.name(),
            c.sim.integrator.kind.name()
        ));
    }
    s.integrator.check()?;
    all_finite("the scheme's carried state", s.scheme.iter())?;
    Ok(())
}

fn neighbour_lists<const D: usize>(s: &Saved<D>, n: usize) -> Result<(), String> {
    s.grid.check(n)?;
    s.neighbours.check(n)?;
    let v = &s.verlet;
    if !(v.pos.is_empty() && v.reach.is_empty() && v.list.offsets.is_empty()) {
        if v.pos.len() != n || v.reach.len() != n {
            return Err(format!(
                "master list built for {} positions and {} radii, {n} particles",
                v.pos.len(),
                v.reach.len()
            ));
        }
        finite("master-list position", &v.pos)?;
        positive("master-list radius", &v.reach)?;
        v.list.check(n)?;
    }
    Ok(())
}

//! Probe and marker values from the particles (brute force over the fluid: a handful of
//! points per communication step costs one pass over the particles each).

use super::{PortValue, ProbeValue};
use crate::parallel::exact::{registers, ExactSum};
use crate::particles::Vector;
use crate::system::System;
use rayon::prelude::*;

/// Kernel sums over the fluid particles whose support reaches `x` (each with its own h):
/// (Σ V W, Σ V W ρ, Σ V W P, Σ V W v, Σ W, Σ W P, Σ W ρ (x − x_f)), V = m/ρ.
#[derive(Clone, Copy)]
struct Sums<const D: usize> {
    vw: f64,
    rho: f64,
    p: f64,
    v: Vector<D>,
    w: f64,
    wp: f64,
    wr: Vector<D>,
}

/// How many numbers a [`Sums`] holds.
const fn width(d: usize) -> usize {
    5 + 2 * d
}

/// [`Sums`] over this process's fluid particles (a distributed run's halo copies are their
/// owners' to count), over every rank. Each total is summed exactly (`parallel::exact`), so
/// a probe reads the same bits whichever rank owns which particle, in whatever order, and
/// whatever the threads' share of the loop.
fn sums<const D: usize>(sys: &System<D>, x: &Vector<D>) -> Sums<D> {
    let p = &sys.particles;
    let k = &sys.kernel;
    let add = |mut acc: Vec<ExactSum>, f: usize| {
        let r = x - p.pos[f];
        let d = r.norm();
        if p.body[f] != 0 || d >= k.radius(p.h[f]) {
            return acc;
        }
        let w = k.w(d, p.h[f]);
        let vw = p.mass[f] / p.rho[f] * w;
        let terms = [vw, vw * p.rho[f], vw * p.pressure[f], w, w * p.pressure[f]];
        let (v, wr) = (p.vel[f] * vw, r * (w * p.rho[f]));
        let vectors = v.iter().chain(wr.iter()).copied();
        for (s, t) in acc.iter_mut().zip(terms.into_iter().chain(vectors)) {
            s.add(t);
        }
        acc
    };
    let merge = |mut a: Vec<ExactSum>, b: Vec<ExactSum>| {
        a.iter_mut().zip(&b).for_each(|(a, b)| a.merge(b));
        a
    };
    let mut total = (0..sys.owned())
        .into_par_iter()
        .with_min_len(1024)
        .fold(|| registers(width(D)), add)
        .reduce(|| registers(width(D)), merge);
    if let Some(ranks) = &sys.ranks {
        ranks.merge_in_place(&mut total);
    }
    let t: Vec<f64> = total.iter().map(ExactSum::value).collect();
    Sums {
        vw: t[0],
        rho: t[1],
        p: t[2],
        w: t[3],
        wp: t[4],
        v: Vector::from_column_slice(&t[5..5 + D]),
        wr: Vector::from_column_slice(&t[5 + D..]),
    }
}

/// Shepard-interpolated ρ, P, v at a fixed point (normalised by Σ V W, reported as the
/// coverage).
pub fn probe<const D: usize>(sys: &System<D>, x: &Vector<D>) -> ProbeValue {
    let s = sums(sys, x);
    if s.vw <= 0.0 {
        return ProbeValue::default();
    }
    let mut v = [0.0; 3];
    for (k, vk) in v.iter_mut().enumerate().take(D) {
        *vk = s.v[k] / s.vw;
    }
    ProbeValue {
        density: s.rho / s.vw,
        pressure: s.p / s.vw,
        velocity: v,
        coverage: s.vw,
    }
}

/// Wall pressure at the body point that was at `rest` at t = 0, by the same extrapolation as
/// the wall particles (Adami, Hu & Adams 2012, eq. 27): [Σ P_f W + (g − a)·Σ ρ_f r W] / Σ W,
/// with the body's acceleration a there. 0 where no fluid reaches (a dry marker).
pub fn marker_pressure<const D: usize>(sys: &System<D>, body: usize, rest: &Vector<D>) -> f64 {
    let (x, v, a) = sys.bodies[body].point(rest);
    let s = sums(sys, &x);
    if s.w <= 0.0 {
        return 0.0;
    }
    let g = sys.body_force(&sys.uniform_body_force(), &x, &v);
    (s.wp + (g - a).dot(&s.wr)) / s.w
}

/// Flow through port k: the probe values at its sample points on the opening, averaged
/// (see [`PortValue`]).
pub fn port_value<const D: usize>(sys: &System<D>, k: usize) -> PortValue {
    let port = &sys.ports[k];
    let n = port.samples.len().max(1) as f64;
    let (mut pm, mut vn, mut flux) = (0.0, 0.0, 0.0);
    for x in &port.samples {
        let s = probe(sys, x);
        let v = Vector::<D>::from_fn(|a, _| s.velocity[a]).dot(&port.normal);
        pm += s.pressure;
        vn += v;
        flux += s.density * v;
    }
    let area = port.opening.area();
    PortValue {
        pressure: port.pressure_at(sys.time),
        mean_pressure: pm / n,
        velocity: vn / n,
        volume_flow: vn / n * area,
        mass_flow: flux / n * area,
        mass_in: port.mass_in,
        mass_out: port.mass_out,
    }
}

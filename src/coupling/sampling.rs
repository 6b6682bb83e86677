//! Probe and marker values from the particles (brute force over the fluid: a handful of
//! points per communication step costs one pass over the particles each).

use super::{PortValue, ProbeValue};
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

impl<const D: usize> Sums<D> {
    fn zero() -> Self {
        Self {
            vw: 0.0,
            rho: 0.0,
            p: 0.0,
            v: Vector::zeros(),
            w: 0.0,
            wp: 0.0,
            wr: Vector::zeros(),
        }
    }
    fn add(mut self, o: Self) -> Self {
        self.vw += o.vw;
        self.rho += o.rho;
        self.p += o.p;
        self.v += o.v;
        self.w += o.w;
        self.wp += o.wp;
        self.wr += o.wr;
        self
    }
}

/// [`Sums`] over this process's fluid particles (a distributed run's halo copies are their
/// owners' to count), summed over the ranks.
fn sums<const D: usize>(sys: &System<D>, x: &Vector<D>) -> Sums<D> {
    let mine = own_sums(sys, x);
    let Some(ranks) = &sys.ranks else {
        return mine;
    };
    let mut flat = vec![mine.vw, mine.rho, mine.p, mine.w, mine.wp];
    flat.extend(mine.v.iter().chain(mine.wr.iter()));
    ranks.sum_in_place(&mut flat);
    Sums {
        vw: flat[0],
        rho: flat[1],
        p: flat[2],
        w: flat[3],
        wp: flat[4],
        v: Vector::from_column_slice(&flat[5..5 + D]),
        wr: Vector::from_column_slice(&flat[5 + D..]),
    }
}

fn own_sums<const D: usize>(sys: &System<D>, x: &Vector<D>) -> Sums<D> {
    let p = &sys.particles;
    let k = &sys.kernel;
    (0..sys.owned())
        .into_par_iter()
        .with_min_len(1024)
        .filter(|&f| p.body[f] == 0)
        .map(|f| {
            let r = x - p.pos[f];
            let d = r.norm();
            if d >= k.radius(p.h[f]) {
                return Sums::zero();
            }
            let w = k.w(d, p.h[f]);
            let vw = p.mass[f] / p.rho[f] * w;
            Sums {
                vw,
                rho: vw * p.rho[f],
                p: vw * p.pressure[f],
                v: p.vel[f] * vw,
                w,
                wp: w * p.pressure[f],
                wr: r * (w * p.rho[f]),
            }
        })
        .reduce(Sums::zero, Sums::add)
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

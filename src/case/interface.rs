//! `[[interface]]`: a planar jump between two regions smoothed with the logistic profile of
//! Frontiere, Raskin & Owen (2017) Eq. 96, f = f_l + (f_r − f_l)/(1 + e^{−(x − x0)/Δ}) with
//! f_l the state on the low side of the plane (the paper prints "+(ρ_high − ρ_low)", which has
//! the wrong limit; the sign is fixed here).
//!
//! By default only the states are blended (u and v; the masses and positions the lattices
//! gave are kept, so the summed density stays a sharp step). With `stretch = true` the
//! particles are also moved along the axis so that their fixed masses reproduce the smoothed
//! density, the paper's "adjust the x spacing of the points to reproduce the smoothed
//! profiles" (§4.3.1, its 3D Sod): each particle goes where the profile holds the same mass
//! on its low side as the sharp step did.

use super::{Case, CaseError};
use crate::domain::Domain;
use crate::eos::Eos;
use crate::particles::{Particles, Vector};

/// ln(1 + e^t) without overflow.
fn softplus(t: f64) -> f64 {
    if t > 0.0 {
        t + (-t).exp().ln_1p()
    } else {
        t.exp().ln_1p()
    }
}

/// The logistic weight of Eq. 96 at t widths from the plane (0 on the low side, 1 beyond).
fn logistic(t: f64) -> f64 {
    1.0 / (1.0 + (-t).exp())
}

/// Beyond this many widths from the plane the move is below e^{−36} ≈ 2e-16 of a width: the
/// particle stays put, so lattices far from the plane stay exact.
const FAR: f64 = 36.0;

/// The stretched position t' (in widths from the plane) of a particle at t under the sharp
/// step ρ_l | ρ_r. Mass per unit cross-section left of the plane, counted from far on its low
/// side and in units of Δ: the sharp step holds M(t) = ρ_l t (t < 0) or ρ_r t (t ≥ 0); the
/// smooth profile of Eq. 96 holds ρ_l t' + (ρ_r − ρ_l) ln(1 + e^{t'}) (its integral, which
/// agrees with the step's far from the plane on either side). The smooth mass rises
/// monotonically (its slope is the profile, between ρ_l and ρ_r), and it differs from the
/// step's by at most |ρ_r − ρ_l| ln 2, so t' lies within that over min(ρ_l, ρ_r) of t:
/// a Newton solve kept inside that bracket.
pub fn stretched(t: f64, rho_l: f64, rho_r: f64) -> f64 {
    if t.abs() > FAR {
        return t;
    }
    let target = if t < 0.0 { rho_l * t } else { rho_r * t };
    let g = |s: f64| rho_l * s + (rho_r - rho_l) * softplus(s) - target;
    let reach = (rho_r - rho_l).abs() * std::f64::consts::LN_2 / rho_l.min(rho_r);
    let (mut lo, mut hi) = (t - reach - 1e-12, t + reach + 1e-12);
    let mut s = t;
    for _ in 0..200 {
        let gs = g(s);
        if gs == 0.0 {
            return s;
        }
        if gs < 0.0 {
            lo = s;
        } else {
            hi = s;
        }
        let slope = rho_l + (rho_r - rho_l) * logistic(s);
        let newton = s - gs / slope;
        let next = if newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if (next - s).abs() <= 1e-15 * (1.0 + s.abs()) || hi - lo <= 1e-15 * (1.0 + s.abs()) {
            return next;
        }
        s = next;
    }
    s
}

/// (ρ, u, v) a region prescribes at a point.
pub(super) type RegionState<const D: usize> = (f64, f64, Vector<D>);

/// How the particle loop reads a region: its index at a point and its state there.
pub(super) struct RegionLookup<'a, const D: usize> {
    pub region_at: &'a dyn Fn(&Vector<D>) -> Option<usize>,
    /// (ρ, u, v) region i prescribes at x
    pub state: &'a dyn Fn(usize, &Vector<D>) -> Result<RegionState<D>, CaseError>,
}

/// Apply every `[[interface]]` of the case, in file order.
pub(super) fn apply<const D: usize>(
    case: &Case,
    p: &mut Particles<D>,
    domain: &Domain<D>,
    look: &RegionLookup<'_, D>,
) -> Result<(), CaseError> {
    for f in &case.interfaces {
        for i in 0..p.len() {
            let mut x = p.pos[i];
            let mut xl = x;
            let mut xr = x;
            xl[f.axis] = f.position - 1e-9 * (1.0 + f.position.abs());
            xr[f.axis] = f.position + 1e-9 * (1.0 + f.position.abs());
            let (Some(il), Some(ir)) = ((look.region_at)(&xl), (look.region_at)(&xr)) else {
                continue;
            };
            if il == ir {
                continue;
            }
            if f.stretch {
                // validated: both sides have a uniform density
                let (rho_l, rho_r) = ((look.state)(il, &x)?.0, (look.state)(ir, &x)?.0);
                let t = (x[f.axis] - f.position) / f.width;
                x[f.axis] = f.position + f.width * stretched(t, rho_l, rho_r);
                let mut v = Vector::<D>::zeros();
                domain.enforce(&mut x, &mut v);
                p.pos[i] = x;
            }
            let (sl, sr) = ((look.state)(il, &x)?, (look.state)(ir, &x)?);
            let w = logistic((x[f.axis] - f.position) / f.width);
            let rho = sl.0 + (sr.0 - sl.0) * w;
            // an interface smooths within one material: the particle's own EOS
            let eos = case.eos_of(p.material[i]);
            let pl = eos.pressure(sl.0, sl.1);
            let pr = eos.pressure(sr.0, sr.1);
            let pres = pl + (pr - pl) * w;
            p.u[i] = match (case.regions[il].pressure, case.regions[ir].pressure) {
                (Some(_), Some(_)) => eos.internal_energy(rho, pres),
                _ => sl.1 + (sr.1 - sl.1) * w,
            };
            p.vel[i] = sl.2 + (sr.2 - sl.2) * w;
            if f.stretch {
                // the particle now sits where the profile's density is ρ
                p.rho[i] = rho;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stretched positions hold the smooth profile's mass: between two neighbouring sharp
    /// positions the step's mass equals the profile's integral between their images, and far
    /// from the plane nothing moves.
    #[test]
    fn stretched_positions_carry_the_profiles_mass() {
        let (rl, rr) = (1.0, 0.25);
        let smooth_mass = |s: f64| rl * s + (rr - rl) * softplus(s);
        for &t in &[-50.0, -3.0, -0.7, -1e-3, 0.0, 0.4, 2.5, 9.0, 40.0] {
            let s = stretched(t, rl, rr);
            let sharp = if t < 0.0 { rl * t } else { rr * t };
            assert!(
                (smooth_mass(s) - sharp).abs() < 1e-12 * (1.0 + sharp.abs()),
                "t = {t}: {s}"
            );
        }
        assert_eq!(stretched(-50.0, rl, rr), -50.0);
        assert_eq!(stretched(40.0, rr, rl), 40.0);
        // monotone: the order of the particles along the axis is kept
        let ts: Vec<f64> = (-400..=400).map(|k| k as f64 * 0.05).collect();
        let ss: Vec<f64> = ts.iter().map(|&t| stretched(t, rl, rr)).collect();
        assert!(ss.windows(2).all(|w| w[0] < w[1]));
        // equal densities: no move
        assert_eq!(stretched(0.3, 2.0, 2.0), 0.3);
    }
}

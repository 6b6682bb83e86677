//! Radially symmetric exact solutions (Sedov–Taylor blast, Noh implosion; Frontiere, Raskin & Owen (2017) §4.3.2)
//! and the errors of a particle set against them: L1 of ρ, the shock position from the binned
//! density profile, and the mean post-shock density.

use super::sedov::Sedov;
use serde::Serialize;

/// ρ, radial velocity and P at radius r.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RadialState {
    pub rho: f64,
    pub v: f64,
    pub p: f64,
}

/// An exact radial solution at a fixed time.
#[derive(Debug, Clone)]
pub enum RadialExact {
    /// Sedov–Taylor with whole-space energy `energy` into still gas of density `rho0`.
    Sedov {
        solution: Sedov,
        energy: f64,
        rho0: f64,
        t: f64,
    },
    /// Noh (1987): cold gas of density `rho0` falling in at `speed`, dimension `dim`.
    Noh {
        gamma: f64,
        dim: usize,
        rho0: f64,
        speed: f64,
        t: f64,
    },
}

impl RadialExact {
    pub fn shock_radius(&self) -> f64 {
        match self {
            RadialExact::Sedov {
                solution,
                energy,
                rho0,
                t,
            } => solution.shock_radius(*energy, *rho0, *t),
            // the shock moves out at (γ−1)/2 times the inflow speed
            RadialExact::Noh {
                gamma, speed, t, ..
            } => 0.5 * (gamma - 1.0) * speed * t,
        }
    }

    pub fn at(&self, r: f64) -> RadialState {
        match *self {
            RadialExact::Sedov {
                ref solution,
                energy,
                rho0,
                t,
            } => {
                let s = solution.at(r, energy, rho0, t);
                RadialState {
                    rho: s.rho,
                    v: s.v,
                    p: s.p,
                }
            }
            RadialExact::Noh {
                gamma,
                dim,
                rho0,
                speed,
                t,
            } => {
                let nu = dim as i32;
                if r < self.shock_radius() {
                    // all inflow kinetic energy turned into heat: u = v0²/2 (Frontiere, Raskin & Owen (2017) §4.3.3)
                    let rho = rho0 * ((gamma + 1.0) / (gamma - 1.0)).powi(nu);
                    RadialState {
                        rho,
                        v: 0.0,
                        p: (gamma - 1.0) * rho * 0.5 * speed * speed,
                    }
                } else {
                    // pre-shock compression (1 + v0 t/r)^{ν−1} (Frontiere, Raskin & Owen (2017), a point the paper leaves open (decided here))
                    RadialState {
                        rho: rho0 * (1.0 + speed * t / r.max(1e-300)).powi(nu - 1),
                        v: -speed,
                        p: 0.0,
                    }
                }
            }
        }
    }
}

/// Errors of particles (r, ρ) against a radial solution.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct RadialErrors {
    /// Mean |ρ − ρ_exact(r)| over the particles with r < r_max.
    pub l1_density: f64,
    pub particles: usize,
    pub shock_radius_exact: f64,
    /// Where the binned density falls to halfway between the exact pre-shock density and the
    /// binned peak, outside the peak (NaN if the profile never falls that far).
    pub shock_radius: f64,
    /// Mean density of the particles with r in [0.3, 0.8]·r_s, and the exact one at the same
    /// radii (flat for Noh).
    pub post_shock_density: f64,
    pub post_shock_density_exact: f64,
    /// Peak of the binned density profile.
    pub peak_density: f64,
}

/// Compare particles `(r, ρ)` with `exact`; `bin` is the radial bin width (about one particle
/// spacing), `r_max` limits the L1 norm.
pub fn radial_errors(
    exact: &RadialExact,
    samples: &[(f64, f64)],
    bin: f64,
    r_max: f64,
) -> RadialErrors {
    let rs = exact.shock_radius();
    let sel: Vec<&(f64, f64)> = samples.iter().filter(|s| s.0 < r_max).collect();
    let l1 = sel
        .iter()
        .map(|&&(r, rho)| (rho - exact.at(r).rho).abs())
        .sum::<f64>()
        / sel.len().max(1) as f64;
    // mean over the particles in [0.3, 0.8] r_s, measured and exact at the same radii
    let post: Vec<(f64, f64)> = samples
        .iter()
        .filter(|s| s.0 >= 0.3 * rs && s.0 <= 0.8 * rs)
        .map(|s| (s.1, exact.at(s.0).rho))
        .collect();
    let count = post.len().max(1) as f64;
    let post_mean = post.iter().map(|p| p.0).sum::<f64>() / count;
    let post_exact = post.iter().map(|p| p.1).sum::<f64>() / count;
    // binned profile out to 2 r_s
    let nbins = ((2.0 * rs / bin).ceil() as usize).max(4);
    let mut sums = vec![(0.0, 0usize); nbins];
    for &(r, rho) in samples {
        let k = (r / bin) as usize;
        if k < nbins {
            sums[k].0 += rho;
            sums[k].1 += 1;
        }
    }
    let prof: Vec<(f64, f64)> = sums
        .iter()
        .enumerate()
        .filter(|(_, s)| s.1 > 0)
        .map(|(k, s)| ((k as f64 + 0.5) * bin, s.0 / s.1 as f64))
        .collect();
    let (kpeak, peak) = prof
        .iter()
        .enumerate()
        .fold((0, f64::NEG_INFINITY), |acc, (k, p)| {
            if p.1 > acc.1 {
                (k, p.1)
            } else {
                acc
            }
        });
    let mut shock = f64::NAN;
    for k in kpeak..prof.len().saturating_sub(1) {
        let threshold = 0.5 * (exact.at(prof[k + 1].0.max(rs * 1.0001)).rho + peak);
        let (a, b) = (prof[k], prof[k + 1]);
        if a.1 >= threshold && b.1 < threshold {
            shock = a.0 + (b.0 - a.0) * (a.1 - threshold) / (a.1 - b.1);
            break;
        }
    }
    RadialErrors {
        l1_density: l1,
        particles: sel.len(),
        shock_radius_exact: rs,
        shock_radius: shock,
        post_shock_density: post_mean,
        post_shock_density_exact: post_exact,
        peak_density: peak,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_exact_profile_gives_zero_error_and_the_true_shock() {
        let noh = RadialExact::Noh {
            gamma: 5.0 / 3.0,
            dim: 2,
            rho0: 1.0,
            speed: 1.0,
            t: 0.6,
        };
        let samples: Vec<(f64, f64)> = (0..2000)
            .map(|i| {
                let r = (i as f64 + 0.5) * 5e-4;
                (r, noh.at(r).rho)
            })
            .collect();
        let e = radial_errors(&noh, &samples, 0.005, 1.0);
        assert!(e.l1_density < 1e-12);
        assert!((e.shock_radius - 0.2).abs() < 0.005, "{}", e.shock_radius);
        assert!((e.post_shock_density - 16.0).abs() < 1e-12);
    }
}

//! Verification against exact solutions, shared by tests, the CLI and tools.

pub mod lattice;
pub mod radial;
pub mod riemann;
pub mod sedov;
pub mod sr_riemann;
pub mod vortex;

/// Errors of a 1D shock-tube profile against the exact Riemann solution.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct ShockTubeErrors {
    pub l1_density: f64,
    pub l1_velocity: f64,
    pub l1_pressure: f64,
    pub particles: usize,
}

/// Compare particles (x, ρ, v, P) with an exact solution `exact(x)` = (ρ, v, P) (a
/// Riemann solution at the run's time), counting particles with x in [x_lo, x_hi].
pub fn shock_tube_errors(
    exact: &dyn Fn(f64) -> (f64, f64, f64),
    particles: &[(f64, f64, f64, f64)],
    x_lo: f64,
    x_hi: f64,
) -> ShockTubeErrors {
    let sel: Vec<_> = particles
        .iter()
        .filter(|p| p.0 >= x_lo && p.0 <= x_hi)
        .collect();
    let n = sel.len().max(1) as f64;
    let mut e = ShockTubeErrors {
        l1_density: 0.0,
        l1_velocity: 0.0,
        l1_pressure: 0.0,
        particles: sel.len(),
    };
    for &&(x, rho, v, p) in &sel {
        let (er, ev, ep) = exact(x);
        e.l1_density += (rho - er).abs() / n;
        e.l1_velocity += (v - ev).abs() / n;
        e.l1_pressure += (p - ep).abs() / n;
    }
    e
}

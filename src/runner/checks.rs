//! The `[verify]` comparisons after a run: shock tubes against the exact Riemann solution,
//! the Gresho vortex, and radial blasts and implosions (Sedov, Noh) against their similarity
//! solutions, each with the norms in the summary and, where it helps, a PNG profile.

use super::{io_err, RunError, RunSummary};
use crate::case::{Case, CaseError, Verify};
use crate::io::plot::{profile_png, Panel};
use crate::sim::Simulation;
use crate::verify::radial::{radial_errors, RadialExact};
use crate::verify::riemann::{ExactRiemann, Primitive};
use crate::verify::sedov::Sedov;
use crate::verify::shock_tube_errors;
use crate::verify::sr_riemann::{SrPrimitive, SrRiemann};
use std::path::Path;

pub(super) fn verify<const D: usize>(
    case: &Case,
    v: &Verify,
    sim: &Simulation<D>,
    out: &Path,
    summary: &mut RunSummary,
) -> Result<(), RunError> {
    match v {
        Verify::Riemann {
            x0,
            left,
            right,
            x_min,
            x_max,
        } => {
            let v = RiemannCheck {
                x0: *x0,
                left: *left,
                right: *right,
                x_min: *x_min,
                x_max: *x_max,
            };
            verify_riemann(case, &v, sim, out, summary)
        }
        Verify::Gresho(g) => {
            let p = &sim.sys.particles;
            let pts: Vec<([f64; 2], [f64; 2])> = (0..p.len())
                .map(|i| {
                    (
                        [p.pos[i][0], p.pos[i][1.min(D - 1)]],
                        [p.vel[i][0], p.vel[i][1.min(D - 1)]],
                    )
                })
                .collect();
            summary.vortex_l1 = Some(g.l1(&pts));
            Ok(())
        }
        Verify::Sedov {
            energy,
            rho0,
            center,
            r_max,
        } => {
            let gamma = crate::eos::Eos::gamma(&case.eos);
            let exact = RadialExact::Sedov {
                solution: Sedov::new(gamma, D),
                energy: *energy,
                rho0: *rho0,
                t: sim.time,
            };
            verify_radial(case, &exact, center, *r_max, sim, out, summary)
        }
        Verify::Noh {
            rho0,
            speed,
            center,
            r_max,
        } => {
            let exact = RadialExact::Noh {
                gamma: crate::eos::Eos::gamma(&case.eos),
                dim: D,
                rho0: *rho0,
                speed: *speed,
                t: sim.time,
            };
            verify_radial(case, &exact, center, *r_max, sim, out, summary)
        }
    }
}

/// Radial norms and a PNG of ρ, v_r, P and u against r with the exact curves.
fn verify_radial<const D: usize>(
    case: &Case,
    exact: &RadialExact,
    center: &[f64],
    r_max: Option<f64>,
    sim: &Simulation<D>,
    out: &Path,
    summary: &mut RunSummary,
) -> Result<(), RunError> {
    let p = &sim.sys.particles;
    let c = crate::particles::Vector::<D>::from_iterator(center.iter().cloned());
    let radius = |i: usize| (p.pos[i] - c).norm();
    let v_r = |i: usize| {
        let d = p.pos[i] - c;
        let r = d.norm();
        if r > 0.0 {
            p.vel[i].dot(&d) / r
        } else {
            0.0
        }
    };
    let samples: Vec<(f64, f64)> = (0..p.len()).map(|i| (radius(i), p.rho[i])).collect();
    // bin width: the median particle spacing (m/ρ)^{1/D}
    let mut spacing: Vec<f64> = (0..p.len())
        .map(|i| (p.mass[i] / p.rho[i]).powf(1.0 / D as f64))
        .collect();
    spacing.sort_by(f64::total_cmp);
    let bin = spacing[spacing.len() / 2];
    let errs = radial_errors(exact, &samples, bin, r_max.unwrap_or(f64::INFINITY));
    summary.radial = Some(errs);
    let r_end = samples.iter().map(|s| s.0).fold(0.0, f64::max);
    let curve = |f: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
        (0..=2000)
            .map(|k| {
                let r = r_end * k as f64 / 2000.0;
                (r, f(r))
            })
            .collect()
    };
    let gamma = crate::eos::Eos::gamma(&case.eos);
    let er = curve(&|r| exact.at(r).rho);
    let ev = curve(&|r| exact.at(r).v);
    let ep = curve(&|r| exact.at(r).p);
    let eu = curve(&|r| {
        let s = exact.at(r);
        s.p / ((gamma - 1.0) * s.rho)
    });
    // Sedov's exact u diverges at the centre: it is drawn whole and runs off the panel
    // (see io::plot's axis ranges)
    let caption = format!(
        "{} at t = {:.3}: {} particles, shock r = {:.4} (exact {:.4}), L1(rho) = {:.3e}  [sphfmu run]",
        case.case.name,
        sim.time,
        p.len(),
        errs.shock_radius,
        errs.shock_radius_exact,
        errs.l1_density
    );
    write_profile(
        sim,
        out,
        &caption,
        "r (m)",
        &radius,
        &v_r,
        ["density against r", "radial velocity"],
        [&er, &ev, &ep, &eu],
        summary,
    )
}

/// `profile.png`: ρ, a velocity, P and u of every particle against `x(i)` with the exact curves.
#[allow(clippy::too_many_arguments)]
fn write_profile<const D: usize>(
    sim: &Simulation<D>,
    out: &Path,
    caption: &str,
    x_desc: &str,
    x: &dyn Fn(usize) -> f64,
    velocity: &dyn Fn(usize) -> f64,
    titles: [&str; 2],
    exact: [&[(f64, f64)]; 4],
    summary: &mut RunSummary,
) -> Result<(), RunError> {
    let p = &sim.sys.particles;
    let col = |f: &dyn Fn(usize) -> f64| -> Vec<(f64, f64)> {
        (0..p.len()).map(|i| (x(i), f(i))).collect()
    };
    let (pr, pv, pp, pu) = (
        col(&|i| p.rho[i]),
        col(velocity),
        col(&|i| p.pressure[i]),
        col(&|i| p.u[i]),
    );
    let panel = |title, particles, exact, y_desc| Panel {
        title,
        particles,
        exact,
        x_desc,
        y_desc,
        line_label: "exact",
    };
    let panels = [
        panel(titles[0], &pr, exact[0], "density (kg/m3)"),
        panel(titles[1], &pv, exact[1], "velocity (m/s)"),
        panel("pressure", &pp, exact[2], "pressure (Pa)"),
        panel("specific internal energy", &pu, exact[3], "u (J/kg)"),
    ];
    let png = out.join("profile.png");
    profile_png(&png, caption, &panels).map_err(|e| io_err(&png, e))?;
    summary.plot = Some(png);
    Ok(())
}

struct RiemannCheck {
    x0: f64,
    left: [f64; 3],
    right: [f64; 3],
    x_min: Option<f64>,
    x_max: Option<f64>,
}

fn verify_riemann<const D: usize>(
    case: &Case,
    v: &RiemannCheck,
    sim: &Simulation<D>,
    out: &Path,
    summary: &mut RunSummary,
) -> Result<(), RunError> {
    let gamma = crate::eos::Eos::gamma(&case.eos);
    let state = |s: [f64; 3]| Primitive {
        rho: s[0],
        u: s[1],
        p: s[2],
    };
    let bad = |e: String| RunError::Case(CaseError(format!("verify: {e}")));
    // SR runs give rest-frame [n, v, P] and compare the computing-frame N = γ n that the
    // particles carry (Rosswog (2015) Eq. 46)
    let solution: Box<dyn Fn(f64) -> (f64, f64, f64) + Sync> = if case.scheme.relativistic() {
        let sr = |s: [f64; 3]| SrPrimitive {
            n: s[0],
            vx: s[1],
            vt: 0.0,
            p: s[2],
        };
        let rs = SrRiemann::new(sr(v.left), sr(v.right), gamma).map_err(bad)?;
        let (x0, t) = (v.x0, sim.time);
        Box::new(move |x| {
            let s = rs.at(x, x0, t);
            (s.lorentz() * s.n, s.vx, s.p)
        })
    } else {
        let rs = ExactRiemann::new(state(v.left), state(v.right), gamma).map_err(bad)?;
        let (x0, t) = (v.x0, sim.time);
        Box::new(move |x| {
            let s = rs.at(x, x0, t);
            (s.rho, s.u, s.p)
        })
    };
    let p = &sim.sys.particles;
    let samples: Vec<(f64, f64, f64, f64)> = (0..p.len())
        .map(|i| (p.pos[i][0], p.rho[i], p.vel[i][0], p.pressure[i]))
        .collect();
    let (lo, hi) = (
        v.x_min.unwrap_or(f64::NEG_INFINITY),
        v.x_max.unwrap_or(f64::INFINITY),
    );
    let errs = shock_tube_errors(&*solution, &samples, lo, hi);
    summary.shock_tube = Some(errs);
    let (x0, x1) = (case.domain.min[0], case.domain.max[0]);
    let exact = |f: fn(&(f64, f64, f64)) -> f64| -> Vec<(f64, f64)> {
        (0..=2000)
            .map(|i| {
                let x = x0 + (x1 - x0) * i as f64 / 2000.0;
                (x, f(&solution(x)))
            })
            .collect()
    };
    let (er, eu, ep) = (exact(|s| s.0), exact(|s| s.1), exact(|s| s.2));
    // u = P/((Γ − 1) n) with the rest-frame n = N/γ in SR runs
    let relativistic = case.scheme.relativistic();
    let ee: Vec<(f64, f64)> = er
        .iter()
        .zip(ep.iter().zip(&eu))
        .map(|(&(x, r), (&(_, pp), &(_, vx)))| {
            let n = if relativistic {
                r * (1.0 - vx * vx).sqrt()
            } else {
                r
            };
            (
                x,
                if n > 0.0 {
                    pp / ((gamma - 1.0) * n)
                } else {
                    0.0
                },
            )
        })
        .collect();
    let caption = format!(
        "{} at t = {:.3}: {} particles, L1(rho) = {:.3e}  [sphfmu run]",
        case.case.name,
        sim.time,
        p.len(),
        errs.l1_density
    );
    write_profile(
        sim,
        out,
        &caption,
        "x (m)",
        &|i| p.pos[i][0],
        &|i| p.vel[i][0],
        ["density", "velocity"],
        [&er, &eu, &ep, &ee],
        summary,
    )
}

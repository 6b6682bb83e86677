//! CRKSPH against the paper's tests (Frontiere, Raskin & Owen (2017)): Sedov 2D (conservation to round-off,
//! shock radius), Noh 2D (post-shock density and shock position), the hydrostatic square
//! (exact density, no motion), and the 1D acoustic wave's convergence order.

use crate::common;

use sphfmu::case::Case;
use sphfmu::runner::run_case;

fn model(name: &str) -> Case {
    Case::load(&common::model_path(name)).unwrap()
}

/// The case at `resolution` times its spacing refinement (1 = the model file's).
fn refined(name: &str, resolution: f64) -> Case {
    let options = sphfmu::coupling::CouplingOptions {
        resolution,
        ..Default::default()
    };
    options.apply(&model(name)).unwrap()
}

/// Sedov 2D on the quadrant, spike E0/4 on the particle at the origin: energy to round-off,
/// shock radius within `tol`.
fn sedov_2d(resolution: f64, tol: f64) {
    let case = refined("sedov2d-crksph.toml", resolution);
    let out = tempfile::tempdir().unwrap();
    let s = run_case(&case, out.path(), &mut |_| {}).unwrap();
    let r = s.radial.expect("sedov check");
    let de = (s.last.total_energy - s.initial.total_energy).abs() / s.initial.total_energy;
    println!(
        "Sedov 2D, {} particles: {} steps, energy change {de:.3e}, shock {:.4} (exact {:.4}), L1(ρ) {:.4e}",
        s.last.particles, s.steps, r.shock_radius, r.shock_radius_exact, r.l1_density
    );
    // measured 4e-14 at 100² (the compatible update conserves Σ m(½v² + u) to round-off); the
    // issue allows 1e-10
    assert!(de < 1e-10, "energy drift {de:e}");
    assert!(
        (r.shock_radius / r.shock_radius_exact - 1.0).abs() < tol,
        "shock at {}",
        r.shock_radius
    );
}

#[test]
fn sedov_2d_conserves_energy_and_places_the_shock() {
    // 50² in the default tier (22 s with Noh below, against about 150 s for both at 100²):
    // measured shock 0.8218 against 0.8 (2.7 %), energy 4.2e-14; the issue's 3 % is checked at
    // its 100² in make verify
    sedov_2d(0.5, 0.04);
}

#[test]
#[ignore = "the paper's 100² (about a minute on 2 cores): make verify"]
fn sedov_2d_100_conserves_energy_and_places_the_shock() {
    // measured 0.8088 against 0.8 (1.1 %, half-height of the binned front); the issue: 3 %
    sedov_2d(1.0, 0.03);
}

#[test]
fn sedov_in_a_periodic_box_conserves_momentum_and_energy_to_round_off() {
    // Without walls nothing but the scheme changes the momentum: the blast in the middle of a
    // periodic box, the spike on one of the four central particles (so the flow is not
    // symmetric and momentum conservation is not a symmetry accident).
    let text = format!(
        r#"{header}[scheme]
name = "crksph"
[time]
t_end = 0.04
[[region]]
spacing = 0.025
density = 1.0
pressure = 1.0e-6
[blast]
energy = 0.25
center = [0.0, 0.0]
"#,
        header = common::header(2, -0.5, 0.5, "periodic", 5.0 / 3.0)
    );
    let case = Case::parse(&text).unwrap();
    let mut sim = case.build::<2>().unwrap();
    let d0 = sim.diagnostics();
    let mut p_scale: f64 = 0.0;
    sim.advance_to(0.04, |s| {
        let p = &s.sys.particles;
        p_scale = p_scale.max((0..p.len()).map(|i| p.mass[i] * p.vel[i].norm()).sum());
    })
    .unwrap();
    let d = sim.diagnostics();
    let dp = (0..2)
        .map(|k| (d.momentum[k] - d0.momentum[k]).abs())
        .fold(0.0, f64::max)
        / p_scale;
    let de = (d.total_energy - d0.total_energy).abs() / d0.total_energy;
    println!(
        "periodic Sedov: {} steps, momentum {dp:.3e} of max Σm|v|, energy {de:.3e}",
        sim.steps
    );
    // measured: momentum 6e-17, energy 8e-14; the issue asks ≤ 1e-10 over the run
    assert!(dp < 1e-10 && de < 1e-10, "momentum {dp:e}, energy {de:e}");
}

/// Noh 2D on the quadrant: post-shock density within `tol_rho` of 16, shock at 0.2 ± `tol_r`.
fn noh_2d(resolution: f64, tol_rho: f64, tol_r: f64) {
    let case = refined("noh2d-crksph.toml", resolution);
    let out = tempfile::tempdir().unwrap();
    let s = run_case(&case, out.path(), &mut |_| {}).unwrap();
    let r = s.radial.expect("noh check");
    println!(
        "Noh 2D, {} particles: post-shock ρ {:.3} (exact 16), shock {:.4} (exact 0.2), L1(ρ, r < 0.5) {:.4e}",
        s.last.particles, r.post_shock_density, r.shock_radius, r.l1_density
    );
    assert!((r.post_shock_density / 16.0 - 1.0).abs() < tol_rho);
    assert!(
        (r.shock_radius - 0.2).abs() < tol_r,
        "shock at {}",
        r.shock_radius
    );
}

#[test]
fn noh_2d_reaches_the_post_shock_density() {
    // 50² in the default tier: measured post-shock ρ 15.35 (4.1 % low), shock 0.2054
    noh_2d(0.5, 0.10, 0.01);
}

#[test]
#[ignore = "the paper's 100² (about two minutes on 2 cores): make verify"]
fn noh_2d_100_reaches_the_post_shock_density() {
    // measured 15.69 and 0.2025; the issue: within 10 % of 16, shock at 0.2
    noh_2d(1.0, 0.10, 0.01);
}

/// The Saitoh–Makino square: ρ = 4 in [1/4, 3/4]², 1 around it, P = 1, equal spacing on one
/// lattice (the square's particles are 4× heavier, a second material), periodic.
fn hydrostatic_square(scheme: &str, n: usize) -> String {
    let dx = 1.0 / n as f64;
    format!(
        r#"{header}[scheme]
name = "{scheme}"
[time]
t_end = 7.0
[[region]]
spacing = {dx:?}
density = 1.0
pressure = 1.0
[[region]]
min = [0.25, 0.25]
max = [0.75, 0.75]
spacing = {dx:?}
density = 4.0
pressure = 1.0
material = 1
"#,
        header = common::header(2, 0.0, 1.0, "periodic", 1.5)
    )
}

#[test]
fn hydrostatic_square_keeps_its_shape_and_exact_density() {
    // 48² so that the square's edges fall between lattice rows; to t = 2.5 here (the paper's
    // t = 7 at 100² is `make verify`'s row crksph-8, models/verify/hydrostatic-square.toml
    // with every scheme; 48² to t = 7 measured the same round-off)
    square_survives(48, 2.5);
}

fn square_survives(n: usize, t_end: f64) {
    let case = Case::parse(&hydrostatic_square("crksph", n)).unwrap();
    let mut sim = case.build::<2>().unwrap();
    let x0 = sim.sys.particles.pos.clone();
    let id0 = sim.sys.particles.id.clone();
    let check_density = |sim: &sphfmu::sim::Simulation<2>| {
        let p = &sim.sys.particles;
        // eq 76 on the lattice: ρ = m_i/V with one V everywhere, so the two values differ by
        // exactly the mass ratio 4
        let (inside, outside): (Vec<usize>, Vec<usize>) =
            (0..p.len()).partition(|&i| p.material[i] == 1);
        let spread = |set: &[usize]| {
            let (lo, hi) = set.iter().fold((f64::INFINITY, 0.0_f64), |(a, b), &i| {
                (a.min(p.rho[i]), b.max(p.rho[i]))
            });
            (hi - lo) / hi
        };
        let ratio = p.rho[inside[0]] / p.rho[outside[0]];
        (spread(&inside).max(spread(&outside)), (ratio - 4.0).abs())
    };
    let (s0, r0) = check_density(&sim);
    sim.advance_to(t_end, |_| {}).unwrap();
    let (s1, r1) = check_density(&sim);
    let p = &sim.sys.particles;
    let moved = (0..p.len())
        .map(|i| {
            let k = id0.iter().position(|&id| id == p.id[i]).unwrap();
            (p.pos[i] - x0[k]).norm()
        })
        .fold(0.0, f64::max);
    println!(
        "hydrostatic square {n}², t = {t_end} ({} steps): density spread {s0:.1e} -> {s1:.1e}, ratio error {r0:.1e} -> {r1:.1e}, largest displacement {:.2e} spacings",
        sim.steps,
        moved * n as f64
    );
    // measured at 100² (make verify): spread 1.3e-12, ratio error 2.8e-12, displacement 5.8e-12
    // spacings. Before the h solve took its Newton step on a converged h (a converged h then
    // stayed bit for bit; the step adds a round-off move of h at every stage): 3.3e-13,
    // 8.1e-13 and 8e-13. Round-off over 3,430 steps either way; the bounds keep a factor of
    // about 3. The default tier's 48² passes them too.
    assert!(
        s1 < 5e-12 && r1 < 1e-11,
        "density spread {s1:e}, ratio {r1:e}"
    );
    assert!(moved < 2e-11 / n as f64, "a particle moved {moved:e}");
}

/// L1 of the density perturbation of the 1D acoustic wave (Frontiere, Raskin & Owen (2017) §4.1) after `periods` periods
/// with N equal-mass particles: Σ|ρ_i − ρ̄ − A sin 2πx_i|/N. The mean ρ̄ is taken out because
/// summation density carries a uniform offset on a lattice (cubic spline, η = 1.2: 1.8e-3 in
/// 1D), a thousand times the wave's amplitude and no part of the wave.
fn acoustic_l1(scheme: &str, n: usize, periods: f64) -> f64 {
    use std::f64::consts::PI;
    let (gamma, amp) = (5.0 / 3.0, 1e-6);
    let p0 = 1.0 / gamma; // c = 1
    let text = format!(
        r#"{header}[scheme]
name = "{scheme}"
[time]
t_end = {periods:?}
[[region]]
spacing = {dx:?}
density = 1.0
pressure = {p0:?}
"#,
        header = common::header(1, 0.0, 1.0, "periodic", gamma),
        dx = 1.0 / n as f64
    );
    let case = Case::parse(&text).unwrap();
    let mut sys = case.system::<1>().unwrap();
    // equal masses: x_i solves x + (A/2π)(1 − cos 2πx) = (i + ½)/N
    let p = &mut sys.particles;
    for i in 0..p.len() {
        let target = (i as f64 + 0.5) / n as f64;
        let mut x = target;
        for _ in 0..20 {
            let f = x + amp / (2.0 * PI) * (1.0 - (2.0 * PI * x).cos()) - target;
            x -= f / (1.0 + amp * (2.0 * PI * x).sin());
        }
        let delta = amp * (2.0 * PI * x).sin();
        p.pos[i][0] = x;
        p.vel[i][0] = delta;
        p.u[i] = (p0 + delta) / ((gamma - 1.0) * (1.0 + delta));
    }
    let mut sim = case.simulation(sys).unwrap();
    sim.advance_to(periods, |_| {}).unwrap();
    let p = &sim.sys.particles;
    let mean = p.rho.iter().sum::<f64>() / p.len() as f64;
    (0..p.len())
        .map(|i| (p.rho[i] - mean - amp * (2.0 * PI * p.pos[i][0]).sin()).abs())
        .sum::<f64>()
        / p.len() as f64
}

fn order(ns: &[usize], errs: &[f64]) -> f64 {
    let k = ns.len() - 1;
    (errs[0] / errs[k]).ln() / (ns[k] as f64 / ns[0] as f64).ln()
}

#[test]
fn acoustic_wave_converges_at_second_order() {
    let ns = [32, 64, 128, 256];
    let errs: Vec<f64> = ns.iter().map(|&n| acoustic_l1("crksph", n, 5.0)).collect();
    let p = order(&ns, &errs);
    let std_errs: Vec<f64> = ns
        .iter()
        .map(|&n| acoustic_l1("standard", n, 5.0))
        .collect();
    let p_std = order(&ns, &std_errs);
    println!("acoustic wave, t = 5, N = {ns:?}");
    println!("  CRKSPH   L1(ρ) = {errs:?}, order {p:.2}");
    println!("  standard L1(ρ) = {std_errs:?}, order {p_std:.2}");
    // measured 1.86 and 0.84; the issue: CRKSPH ≥ 1.8 (the paper: 2), standard SPH about 1
    assert!(p >= 1.8, "CRKSPH order {p}");
    assert!(p_std < 1.5, "standard SPH order {p_std}");
}

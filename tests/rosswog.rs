//! Rosswog (2015) formulations: IA gradient accuracy on lattices, conservation of F1–F4, Sod.

use crate::common;

use sphfmu::case::Case;
use sphfmu::particles::Vector;
use sphfmu::runner::run_case;
use sphfmu::scheme::rosswog::gradients::{field_gradient, GradientEstimator};

fn hex_box(perturb: f64) -> String {
    format!(
        r#"
{header}[kernel]
name = "cubic-spline"
eta = 1.2
[scheme]
name = "rosswog-f3"
[time]
t_end = 1.0
[[region]]
lattice = "hexagonal"
spacing = 0.025
density = 1.0
pressure = 1.0
[perturbation]
amplitude = {perturb}
seed = 5
"#,
        header = common::header(2, 0.0, 1.0, "periodic", 1.6666666666666667)
    )
}

/// Mean |∇f − x̂| for f = x with each estimator of Rosswog (2015) Sec. 3.2–3.6 (kernel, CE, LE, fIA, IA).
fn gradient_errors(perturb: f64) -> [f64; 5] {
    use GradientEstimator::*;
    let sim = Case::parse(&hex_box(perturb))
        .unwrap()
        .build::<2>()
        .unwrap();
    let p = &sim.sys.particles;
    let f: Vec<f64> = p.pos.iter().map(|x| x[0]).collect();
    let mut out = [0.0; 5];
    for (i, est) in [Kernel, ConstantExact, LinearExact, FullIntegral, Integral]
        .into_iter()
        .enumerate()
    {
        // f at neighbour b through the periodic image: f_a − dx
        let (g, fallbacks) =
            field_gradient(&sim.sys, est, &f, |a, _b, dx: &Vector<2>| f[a] - dx[0]);
        assert_eq!(fallbacks, 0);
        out[i] = g
            .iter()
            .map(|v| (v - Vector::<2>::new(1.0, 0.0)).norm())
            .sum::<f64>()
            / g.len() as f64;
    }
    out
}

#[test]
fn ia_gradient_is_exact_on_a_perfect_lattice_and_loses_the_edge_when_perturbed() {
    let [sph, ce, le, fia, ia] = gradient_errors(0.0);
    println!("perfect hex lattice, M4 η=1.2: kernel {sph:.2e}, CE {ce:.2e}, LE {le:.2e}, fIA {fia:.2e}, IA {ia:.2e}");
    // Rosswog (2015) Sec. 3.6; also Sec. 4.2.3: kernel gradient ~2.6e-2 (M4, η = 1.2), CE = kernel on a perfect lattice,
    // LE/fIA exact, IA ~10 orders better than the kernel gradient.
    assert!(sph > 5e-3, "kernel gradient unexpectedly exact: {sph:e}");
    assert!((ce - sph).abs() < 1e-3 * sph, "CE {ce:e} vs kernel {sph:e}");
    assert!(
        ia <= 1e-10 && fia <= 1e-10 && le <= 1e-10,
        "IA {ia:e}, fIA {fia:e}, LE {le:e}"
    );
    // 1e-3 r_s (r_s = spacing/2): amplitude 5e-4 of the spacing.
    let [sph_p, ce_p, le_p, fia_p, ia_p] = gradient_errors(5e-4);
    println!("perturbed by 1e-3 r_s: kernel {sph_p:.2e}, CE {ce_p:.2e}, LE {le_p:.2e}, fIA {fia_p:.2e}, IA {ia_p:.2e}");
    assert!(
        ia_p > 1e3 * ia.max(1e-16),
        "IA keeps its edge under perturbation: {ia_p:e}"
    );
    assert!(
        ia_p > 0.01 * sph_p,
        "IA should degrade towards the kernel gradient: {ia_p:e} vs {sph_p:e}"
    );
    assert!(
        fia_p <= 1e-10 && le_p <= 1e-10,
        "fIA and LE are linearly exact on any set: {fia_p:e}, {le_p:e}"
    );
}

fn random_box(scheme: &str) -> String {
    common::random_box(&format!("name = \"{scheme}\""), "", (0.03, 0.025))
}

#[test]
fn f1_to_f4_conserve_momentum_to_round_off_and_energy_to_integrator_accuracy() {
    for scheme in ["rosswog-f1", "rosswog-f2", "rosswog-f3", "rosswog-f4"] {
        let mut sim = Case::parse(&random_box(scheme))
            .unwrap()
            .build::<2>()
            .unwrap();
        let de = common::momentum_exact_energy_drift(&mut sim, 20, scheme);
        let d = sim.diagnostics();
        println!(
            "{scheme}: 20 SSP-RK3 steps to t = {:.4}: relative energy change {de:.2e}",
            d.time
        );
        // Measured over these 20 steps at the presets' CFL 0.5 (t ≈ 0.21; F4 0.12):
        // F1 3.8e-4, F2 3.9e-4, F3 3.5e-4, F4 8.3e-5 — a time-stepping error: it falls with
        // the step (f1_energy_error_is_time_integration_error). 2x headroom.
        assert!(de < 8e-4, "{scheme}: energy drift {de:e}");
    }
}

#[test]
fn sod_with_f1_rpsph_and_standard() {
    let dir = tempfile::tempdir().unwrap();
    let mut rows = Vec::new();
    for model in ["sod.toml", "sod-rosswog-f1.toml", "sod-rpsph.toml"] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("models")
            .join(model);
        let case = Case::load(&path).unwrap();
        let s = run_case(&case, &dir.path().join(model), &mut |_| {}).unwrap();
        let e = s.shock_tube.unwrap();
        println!(
            "{model}: L1 rho {:.3e}, v {:.3e}, P {:.3e}",
            e.l1_density, e.l1_velocity, e.l1_pressure
        );
        rows.push(e.l1_density);
    }
    // measured: standard 1.84e-3, F1 1.96e-3, rpSPH (symmetrised gradient) 3.53e-3. While
    // the lattices started dense by their kernel-sum error (0.18 % for M4 at η = 1.2, 1e-4
    // for F1's C6 at η = 2.2) standard SPH gave 2.75e-3 and F1 looked 1.4x better; with
    // initial conditions at the requested density the two are within 7 % on this 1D tube.
    assert!(
        rows[0] <= 2.0e-3 && rows[1] <= 2.2e-3 && rows[2] <= 3.9e-3,
        "{rows:?}"
    );
    assert!(
        rows[1] < 1.15 * rows[0],
        "F1 against standard SPH: {rows:?}"
    );
}

#[test]
fn f1_energy_error_is_time_integration_error() {
    // Halving the Courant number must cut the energy error by about 2³ (SSP-RK3).
    let mut errs = Vec::new();
    for cfl in [0.5, 0.25] {
        let text =
            random_box("rosswog-f1").replace("t_end = 1.0", &format!("t_end = 1.0\ncfl = {cfl}"));
        let mut sim = Case::parse(&text).unwrap().build::<2>().unwrap();
        sim.control.max_growth = 1e9;
        let e0 = sim.diagnostics().total_energy;
        sim.advance_to(0.1, |_| {}).unwrap();
        errs.push((sim.diagnostics().total_energy - e0).abs() / e0);
    }
    println!("F1 energy error to t = 0.1 at CFL 0.5, 0.25: {errs:?}");
    // measured 2.15e-4 → 4.89e-5 (×4.4: the once-per-step K update is first order in time)
    assert!(errs[1] < errs[0] / 3.0, "{errs:?}");
}

fn gresho_l1(model: &str, spacing: f64) -> f64 {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("models")
        .join(model);
    let text = std::fs::read_to_string(path)
        .unwrap()
        .replace("spacing = 0.015625", &format!("spacing = {spacing}"));
    let case = Case::parse(&text).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let s = run_case(&case, dir.path(), &mut |_| {}).unwrap();
    s.vortex_l1.unwrap()
}

#[test]
fn gresho_f1_converges_f4_does_not() {
    // Rosswog (2015) Sec. 7.4: F1 ∝ N_1D^-1, F4 does not converge. Resolutions 32 and 64 per unit
    // length (1216 and 4736 particles on the hexagonal lattice), t = 1, P0 = 5.
    let f1 = [
        gresho_l1("gresho-f1.toml", 1.0 / 32.0),
        gresho_l1("gresho-f1.toml", 1.0 / 64.0),
    ];
    let f4 = [
        gresho_l1("gresho-f4.toml", 1.0 / 32.0),
        gresho_l1("gresho-f4.toml", 1.0 / 64.0),
    ];
    let order = |e: [f64; 2]| (e[0] / e[1]).log2();
    println!(
        "Gresho L1(v): F1 {:.4e} -> {:.4e} (order {:.2}); F4 {:.4e} -> {:.4e} (order {:.2})",
        f1[0],
        f1[1],
        order(f1),
        f4[0],
        f4[1],
        order(f4)
    );
    // measured: F1 8.63e-2 -> 5.26e-2 (order 0.72); F4 1.89e-1 -> 1.41e-1 (order 0.42). F1
    // had 8.34e-2 -> 4.80e-2 (0.80) while the h solve kept a converged h: the noise that let
    // grow fed the noise trigger, whose dissipation lowered L1 (without the trigger, n_noise =
    // 1e6, both give 5.31e-2 at 64; `sphfmu run models/gresho-f1.toml`).
    assert!(order(f1) >= 0.65, "F1 order {}", order(f1));
    assert!(order(f4) <= 0.55, "F4 order {}", order(f4));
    assert!(
        f1[1] < 0.5 * f4[1],
        "F1 should be far more accurate than F4: {f1:?} vs {f4:?}"
    );
}

#[test]
fn singular_ia_matrix_falls_back_to_the_kernel_gradient_without_nan() {
    // One row of particles in 2D: τ has no y extent, so every particle's IA matrix is singular.
    let text = r#"
[case]
name = "row"
dimension = 2
[domain]
min = [0.0, 0.0]
max = [1.0, 1.0]
boundary = ["periodic", "open"]
[eos]
type = "ideal-gas"
gamma = 1.4
[scheme]
name = "rosswog-f1"
[time]
t_end = 1.0
[[region]]
min = [0.0, 0.49]
max = [1.0, 0.51]
spacing = 0.02
density = 1.0
pressure = 1.0
velocity = [0.0, 0.1]
"#;
    let mut sim = Case::parse(text).unwrap().build::<2>().unwrap();
    let n = sim.sys.particles.len() as u64;
    assert_eq!(n, 50);
    assert_eq!(
        sim.sys.stats.ia_fallbacks, n,
        "every particle of a single row should fall back"
    );
    sim.step(f64::INFINITY).unwrap();
    assert!(sim.sys.first_non_finite().is_none());
    assert!(sim.sys.stats.ia_fallbacks_total >= n);
}

/// F1 on the 2D Noh implosion (cold gas, |v| = 1, free edge). The dissipation used to follow
/// the paper's total-energy form (u from de − v·dv), whose IA cross-axis term scales with
/// the lab-frame velocity: it drove u negative at the free edge and the time step collapsed at
/// step 3 (t = 1.1e-2, on 100²). With the pairwise heating split (Galilean invariant) the run
/// goes on, u stays positive, and the post-shock plateau forms.
#[test]
fn f1_runs_the_cold_noh_implosion() {
    let text = common::model_text("noh2d.toml")
        .replace("spacing = 0.02", "spacing = 0.04")
        .replace("snapshot_every = 0.0", "snapshot_every = 1.0");
    let case = Case::parse(&text)
        .unwrap()
        .with_scheme("rosswog-f1")
        .unwrap();
    let mut sim = case.build::<2>().unwrap();
    sim.advance_to(0.6, |_| {}).unwrap();
    let p = &sim.sys.particles;
    let u_min = p.u.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(u_min > 0.0, "internal energy went to {u_min}");
    // exact plateau 16 inside r < t/3 = 0.2; measured 12.3 at this resolution (mean over
    // 0.05 < r < 0.15, the wall-heating dip at the centre excluded)
    let inner: Vec<f64> = (0..p.len())
        .filter(|&i| (0.05..0.15).contains(&p.pos[i].norm()))
        .map(|i| p.rho[i])
        .collect();
    let mean = inner.iter().sum::<f64>() / inner.len() as f64;
    println!("F1 Noh 50²: mean density {mean} over 0.05 < r < 0.15, u_min {u_min}");
    assert!(mean > 11.0, "post-shock density {mean} (exact 16)");
}

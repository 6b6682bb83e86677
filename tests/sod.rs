//! Sod shock tube (the foundation issue's acceptance case): L1(ρ) against the exact Riemann
//! solution, energy conservation with mirror walls, and the output files.

use sphfmu::case::Case;
use sphfmu::runner::run_case;
use std::path::Path;

#[test]
fn sod_1d_standard_sph_l1_density() {
    let case = Case::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/models/sod.toml"
    )))
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let s = run_case(&case, dir.path(), &mut |_| {}).unwrap();
    let e = s.shock_tube.unwrap();
    println!(
        "Sod: N = {}, steps = {}, L1 rho {:.4e} v {:.4e} P {:.4e}",
        s.particles, s.steps, e.l1_density, e.l1_velocity, e.l1_pressure
    );
    // 721, not 720: the 1D M4 lattice sum at η = 1.2 is 1.76e-3 above 1/V, so the case's
    // equal masses need that much closer spacing to sum to ρ (ics::lattice_density_factor)
    assert_eq!(s.particles, 721);
    // Measured 1.84e-3 (2.75e-3 while the lattice started 0.18 % dense); the bound
    // was 3.0e-3 (PySPH tsph: 1.75e-3, adke 2.81e-3).
    assert!(e.l1_density <= 2.2e-3, "L1(rho) = {}", e.l1_density);
    assert!(e.l1_pressure <= 2.2e-3, "L1(P) = {}", e.l1_pressure);
    // Mirror walls do no work: total energy to integrator accuracy (measured 1.3e-6).
    let de = (s.last.total_energy - s.initial.total_energy).abs() / s.initial.total_energy;
    assert!(de < 1e-5, "energy drift {de}");
    for f in [
        "diagnostics.csv",
        "profile.png",
        "summary.json",
        "snapshots.pvd",
        "snapshot_00003.vtu",
        "snapshot_00003.csv",
    ] {
        assert!(dir.path().join(f).exists(), "missing {f}");
    }
    // diagnostics: one row per step plus the initial and final rows
    let rows = std::fs::read_to_string(dir.path().join("diagnostics.csv"))
        .unwrap()
        .lines()
        .count();
    assert_eq!(rows as u64, s.steps + 3);
}

#[test]
fn sod_table_of_every_scheme() {
    // One Sod setup (models/sod.toml: 721 equal-mass particles, γ = 1.4, t = 0.15) for every
    // preset, each with its own kernel and integrator (`Case::with_scheme`; the foundation's
    // standard SPH row keeps the case's conductivity, rpSPH and F1 their model files).
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    let sod = Case::load(&dir.join("sod.toml")).unwrap();
    // (row, case, largest L1(ρ) allowed: the measured value with ~20 % headroom)
    let rows: Vec<(&str, Case, f64)> = vec![
        ("standard", sod.clone(), 3.0e-3),
        (
            "rpsph",
            Case::load(&dir.join("sod-rpsph.toml")).unwrap(),
            5.3e-3,
        ),
        (
            "rosswog-f1",
            Case::load(&dir.join("sod-rosswog-f1.toml")).unwrap(),
            2.4e-3,
        ),
        ("rosswog-f4", sod.with_scheme("rosswog-f4").unwrap(), 3.9e-3),
        ("crksph", sod.with_scheme("crksph").unwrap(), 1.6e-3),
        ("compsph", sod.with_scheme("compsph").unwrap(), 2.7e-3),
        (
            "compsph-cullen",
            sod.with_scheme("compsph-cullen").unwrap(),
            3.7e-3,
        ),
        ("psph", sod.with_scheme("psph").unwrap(), 4.2e-3),
    ];
    println!("| scheme | L1(ρ) | L1(v) | L1(P) | steps | energy change |");
    println!("|---|---|---|---|---|---|");
    for (name, case, bound) in rows {
        let out = tempfile::tempdir().unwrap();
        let s = run_case(&case, out.path(), &mut |_| {}).unwrap();
        let e = s.shock_tube.unwrap();
        let de = (s.last.total_energy - s.initial.total_energy) / s.initial.total_energy;
        println!(
            "| {name} | {:.3e} | {:.3e} | {:.3e} | {} | {de:.1e} |",
            e.l1_density, e.l1_velocity, e.l1_pressure, s.steps
        );
        assert!(e.l1_density < bound, "{name}: L1(ρ) {}", e.l1_density);
    }
}

#[test]
fn crksph_with_continuity_density_reproduces_sod_and_conserves_energy() {
    // `scheme.density = "continuity"` evolves ρ by eq 79 (Frontiere, Raskin & Owen (2017); their
    // App B's choice) instead of eq 76 at every evaluation. Same Sod, same preset otherwise.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/sod.toml");
    let run = |density: &str| {
        let sets = [format!("scheme.density=\"{density}\"")];
        let case = Case::load_with(&path, Some("crksph"), &sets).unwrap();
        let out = tempfile::tempdir().unwrap();
        run_case(&case, out.path(), &mut |_| {}).unwrap()
    };
    let (sum, cont) = (run("summation"), run("continuity"));
    let (es, ec) = (sum.shock_tube.unwrap(), cont.shock_tube.unwrap());
    println!(
        "CRKSPH Sod L1(ρ): summation {:.4e}, continuity {:.4e}",
        es.l1_density, ec.l1_density
    );
    // measured 1.40e-3 (summation 1.31e-3); ~20 % headroom
    assert!(ec.l1_density < 1.7e-3, "L1(ρ) {}", ec.l1_density);
    // a different density estimate gives a different profile: the key took effect
    assert!((ec.l1_density - es.l1_density).abs() > 1e-5);
    // the compatible update conserves energy to round-off either way (measured 2.6e-15)
    let de = (cont.last.total_energy - cont.initial.total_energy).abs() / cont.initial.total_energy;
    assert!(de < 1e-12, "energy change {de}");
}

//! The Cullen–Dehnen switch (Frontiere, Raskin & Owen (2017) App F): α rises at a shock and stays at α_min where
//! the flow neither starts to converge nor shears it on; and the corrected gradient it uses is
//! exact for a linear field.

use crate::common;

use sphfmu::case::Case;
use std::path::Path;

#[test]
fn alpha_rises_at_the_sod_shock_and_rests_at_the_floor_ahead_of_it() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    let case = Case::load(&dir.join("sod.toml"))
        .unwrap()
        .with_scheme("compsph-cullen")
        .unwrap();
    let mut sim = case.build::<1>().unwrap();
    sim.advance_to(0.1, |_| {}).unwrap();
    let p = &sim.sys.particles;
    // exact shock position at t = 0.1: x_s = 1.7522·0.1 (Sod, γ = 1.4)
    let xs = 0.17522;
    let near: f64 = (0..p.len())
        .filter(|&i| (p.pos[i][0] - xs).abs() < 0.02)
        .map(|i| p.alpha[i])
        .fold(0.0, f64::max);
    let ahead: f64 = (0..p.len())
        .filter(|&i| p.pos[i][0] > xs + 0.05)
        .map(|i| p.alpha[i])
        .fold(0.0, f64::max);
    let behind_rarefaction: f64 = (0..p.len())
        .filter(|&i| p.pos[i][0] < -0.25)
        .map(|i| p.alpha[i])
        .fold(0.0, f64::max);
    println!("α at the shock {near:.3}, ahead {ahead:.3}, in the still left state {behind_rarefaction:.3}");
    // measured: 0.58 at the shock; exactly α_min = 0.02 in the undisturbed gas
    assert!(near > 0.3, "α at the shock {near}");
    assert!(ahead <= 0.02 + 1e-12 && behind_rarefaction <= 0.02 + 1e-12);
}

#[test]
fn alpha_stays_at_the_floor_in_steady_shear() {
    // v_x = 0.1 sin(2πy): a steady shear layer (∇·v = 0 on the lattice), which the
    // unlimited Monaghan–Gingold viscosity would damp; the switch must not turn on.
    let case = unit_square_gas("periodic", 0.03125);
    let mut sys = case.system::<2>().unwrap();
    for i in 0..sys.particles.len() {
        let y = sys.particles.pos[i][1];
        sys.particles.vel[i][0] = 0.1 * (2.0 * std::f64::consts::PI * y).sin();
    }
    let mut sim = case.simulation(sys).unwrap();
    sim.advance_to(0.05, |_| {}).unwrap();
    let amax = sim.sys.particles.alpha.iter().cloned().fold(0.0, f64::max);
    println!("shear layer: largest α after {} steps {amax:.4}", sim.steps);
    // measured: α_min = 0.02 everywhere
    assert!(amax <= 0.02 + 1e-9, "α = {amax}");
}

#[test]
fn the_switch_measures_the_divergence_of_a_linear_flow_exactly_on_a_disordered_set() {
    // v = A x on jittered particles: the corrected gradient (E.4 with E.6) is exact for a
    // linear field wherever a particle has its full neighbourhood, while the plain SPH
    // estimate is off by the disorder (measured: 9.9e-2 uncorrected, 6.7e-16 corrected).
    let case = unit_square_gas("open", 0.05);
    let mut sys = case.system::<2>().unwrap();
    let a = [[0.3, -0.2], [0.5, -0.7]];
    let mut seed = 12345u64;
    let mut jitter = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.02
    };
    for i in 0..sys.particles.len() {
        for d in 0..2 {
            sys.particles.pos[i][d] += jitter();
        }
        let x = sys.particles.pos[i];
        for (v, row) in sys.particles.vel[i].iter_mut().zip(&a) {
            *v = row[0] * x[0] + row[1] * x[1];
        }
    }
    let sim = case.simulation(sys).unwrap();
    let p = &sim.sys.particles;
    let mut worst: f64 = 0.0;
    let mut inside = 0;
    for i in 0..p.len() {
        let x = p.pos[i];
        let margin = 2.5 * p.h[i];
        if x.iter().all(|&c| c > margin && c < 1.0 - margin) {
            worst = worst.max((p.div_v[i] - (a[0][0] + a[1][1])).abs());
            inside += 1;
        }
    }
    println!("∇·v of a linear flow on {inside} interior particles: largest error {worst:.3e}");
    assert!(inside > 50, "{inside} interior particles");
    // round-off of sums of ~20 terms of size |A| (measured 6.7e-16)
    assert!(worst < 1e-12, "∇·v error {worst}");
}

/// compsph-cullen on a lattice of still gas (ρ = 1, P = 1, γ = 5/3) in the unit square.
fn unit_square_gas(boundary: &str, spacing: f64) -> Case {
    let text = format!(
        r#"{header}[scheme]
name = "compsph-cullen"
[time]
t_end = 0.05
[[region]]
spacing = {spacing:?}
density = 1.0
pressure = 1.0
"#,
        header = common::header(2, 0.0, 1.0, boundary, 5.0 / 3.0)
    );
    Case::parse(&text).unwrap()
}

//! Static tests of Rosswog's formulations: the hydrostatic square (X = P^k removes the spurious
//! surface tension that X = m creates) and the noise box (a lattice at rest, no dissipation).

use crate::common;
use sphfmu::case::Case;
use std::collections::HashMap;

/// Mean displacement (in lattice spacings) of all particles after running to t_end.
fn square_displacement(name: &str) -> f64 {
    let mut sim = Case::parse(&common::model_text(name))
        .unwrap()
        .build::<2>()
        .unwrap();
    let start: HashMap<u32, (f64, f64)> = (0..sim.sys.particles.len())
        .map(|i| {
            (
                sim.sys.particles.id[i],
                (sim.sys.particles.pos[i][0], sim.sys.particles.pos[i][1]),
            )
        })
        .collect();
    sim.advance_to(5.0, |_| {}).unwrap();
    let p = &sim.sys.particles;
    let mut sum = 0.0;
    for i in 0..p.len() {
        let (x0, y0) = start[&p.id[i]];
        let (mut dx, mut dy) = (p.pos[i][0] - x0, p.pos[i][1] - y0);
        dx -= dx.round(); // periodic unit box
        dy -= dy.round();
        sum += dx.hypot(dy);
    }
    sum / p.len() as f64 / 0.03125
}

#[test]
fn hydrostatic_square_f1_keeps_it_f3_deforms() {
    let f1 = square_displacement("square-f1.toml");
    let f3 = square_displacement("square-f3.toml");
    println!("hydrostatic square, t = 5: mean displacement F1 {f1:.2e}, F3 {f3:.2e} spacings");
    // measured: F1 6.4e-11 (round-off), F3 4.9 spacings (the square rounds off)
    assert!(f1 < 2e-10, "F1 moved the square: {f1:e} spacings");
    assert!(f3 > 0.5, "F3 should deform the square: {f3:e} spacings");
}

fn noise(kernel: &str, eta: f64) -> f64 {
    // three sound-crossing times (τ_s = 0.0775)
    let text = common::model_text("noise-box.toml")
        .replace("t_end = 0.775", "t_end = 0.2325")
        .replace(
            "name = \"wendland-c6\"\neta = 2.2",
            &format!("name = \"{kernel}\"\neta = {eta}"),
        );
    let mut sim = Case::parse(&text).unwrap().build::<2>().unwrap();
    sim.advance_to(0.2325, |_| {}).unwrap();
    let p = &sim.sys.particles;
    let moving: Vec<usize> = (0..p.len()).filter(|&i| !p.frozen[i]).collect();
    moving
        .iter()
        .map(|&i| p.vel[i].norm() / p.sound_speed[i])
        .sum::<f64>()
        / moving.len() as f64
}

/// Mean |v|/c_s of a periodic noise box (no frozen layer: the lattice is an exact
/// equilibrium and only round-off moves it) after one and after three sound-crossing times.
fn periodic_noise(scheme: &str) -> (f64, f64) {
    let text = common::model_text("noise-box.toml")
        .replace(
            "boundary = [\"open\", \"open\"]",
            "boundary = [\"periodic\", \"periodic\"]",
        )
        .replace("frozen_margin = 0.17", "frozen_margin = 0.0")
        .replace("name = \"rosswog-f1\"", &format!("name = \"{scheme}\""))
        .replace("spacing = 0.02", "spacing = 0.04");
    let mut sim = Case::parse(&text).unwrap().build::<2>().unwrap();
    let mean = |sim: &sphfmu::sim::Simulation<2>| {
        let p = &sim.sys.particles;
        (0..p.len())
            .map(|i| p.vel[i].norm() / p.sound_speed[i])
            .sum::<f64>()
            / p.len() as f64
    };
    sim.advance_to(0.0775, |_| {}).unwrap();
    let one = mean(&sim);
    sim.advance_to(0.2325, |_| {}).unwrap();
    (one, mean(&sim))
}

/// The h solve takes its Newton step even where the density already meets the tolerance
/// (`solve_one` in src/scheme/smoothing.rs). Kept h let round-off grow ×8 per sound
/// crossing on the lattice at rest with SSP-RK3 at CFL 0.5, for F1 and F3 alike.
#[test]
fn round_off_on_a_periodic_lattice_at_rest_does_not_grow() {
    for scheme in ["rosswog-f1", "rosswog-f3"] {
        let (one, three) = periodic_noise(scheme);
        println!(
            "periodic noise box, {scheme}: <|v|>/c_s {one:.2e} at 1 τ_s, {three:.2e} at 3 τ_s"
        );
        // measured here (725 particles): F1 2.0e-15 -> 2.7e-15, F3 2.0e-15 -> 2.8e-15; with h
        // kept, ×5.6 and ×6.1 over the two crossings (×8 per crossing at 2,900 particles)
        assert!(three < 3.0 * one, "{scheme}: {one:e} -> {three:e}");
        assert!(three < 1e-12, "{scheme}: {three:e}");
    }
}

#[test]
fn noise_box_lattice_stays_quiet() {
    let c6 = noise("wendland-c6", 2.2);
    let m4 = noise("cubic-spline", 1.2);
    println!("noise box, 3 τ_s: <|v|>/c_s  Wendland C6 {c6:.2e}, M4 {m4:.2e} (paper, CP lattice: W3,3 ≈ 5e-7, M4 ≈ 1e-4)");
    // measured: C6 8.2e-9, M4 1.2e-13 (2.6e-7 and 1.0e-10 while the h solve kept a
    // converged h, see round_off_on_a_periodic_lattice_at_rest_does_not_grow); a lattice that
    // left its positions (pairing, the paper's ~1e-2 for unstable kernels) would exceed 1e-3.
    assert!(c6 < 5e-8 && m4 < 1e-9, "C6 {c6:e}, M4 {m4:e}");
    assert!(c6 > 0.0 && m4 > 0.0);
}

//! Initial states beyond uniform lattices: concentric rings (the Yee vortex), Rosswog's
//! equal-mass quasi-close-packed rows following a density profile, frozen regions, and a
//! pressure set from the scheme's own summed density (`[[field]] stage = "density"`).

use crate::common;

use sphfmu::case::Case;
use sphfmu::eos::Eos;
use std::f64::consts::PI;

fn rings_case(extra: &str) -> String {
    format!(
        r#"{header}[time]
t_end = 1.0
[[region]]
shape = "sphere"
center = [0.0, 0.0]
radius = 1.0
lattice = "rings"
spacing = 0.1
density = 2.0
pressure = 1.0
{extra}"#,
        header = common::header(2, -2.0, 2.0, "open", 1.4)
    )
}

#[test]
fn rings_hold_their_annulus_mass_at_the_right_radii() {
    let sim = Case::parse(&rings_case("")).unwrap().build::<2>().unwrap();
    let p = &sim.sys.particles;
    // ring i at (i + ½)Δr with round(2πr/Δr) points, each holding ρ 2πrΔr / n
    let mut total = 0;
    for i in 0..10 {
        let r = (i as f64 + 0.5) * 0.1;
        let n = (2.0 * PI * r / 0.1).round() as usize;
        let on: Vec<usize> = (0..p.len())
            .filter(|&a| (p.pos[a].norm() - r).abs() < 1e-12)
            .collect();
        assert_eq!(on.len(), n, "ring {i}");
        for &a in &on {
            let m = 2.0 * 2.0 * PI * r * 0.1 / n as f64;
            assert!(
                (p.mass[a] - m).abs() < 1e-14 * m,
                "ring {i}: {} vs {m}",
                p.mass[a]
            );
        }
        total += n;
    }
    assert_eq!(total, p.len());
    // the rings hold the disk's mass ρπR²
    let mass: f64 = p.mass.iter().sum();
    assert!((mass - 2.0 * PI).abs() < 1e-12, "{mass}");
}

#[test]
fn a_frozen_region_keeps_still() {
    // a ring of frozen gas at high pressure around a free core at low pressure: the core moves,
    // the frozen ring does not
    let text = rings_case(
        r#"[[region]]
shape = "sphere"
center = [0.0, 0.0]
radius = 0.5
lattice = "rings"
spacing = 0.1
density = 1.0
pressure = 0.1
"#,
    )
    .replace("pressure = 1.0\n", "pressure = 1.0\nfrozen = true\n");
    let mut sim = Case::parse(&text).unwrap().build::<2>().unwrap();
    let before = sim.sys.particles.clone();
    sim.step(1e-2).unwrap();
    sim.step(1e-2).unwrap();
    let p = &sim.sys.particles;
    let (mut moved, mut frozen) = (0, 0);
    for a in 0..p.len() {
        let b = (0..before.len())
            .find(|&b| before.id[b] == p.id[a])
            .unwrap();
        if p.frozen[a] {
            frozen += 1;
            assert_eq!(p.pos[a], before.pos[b]);
            assert_eq!(p.u[a], before.u[b]);
        } else if (p.pos[a] - before.pos[b]).norm() > 0.0 {
            moved += 1;
        }
    }
    assert!(frozen > 0 && moved > 0, "frozen {frozen}, moved {moved}");
}

fn rows_case(scheme: &str, stage: &str) -> String {
    format!(
        r#"{header}[scheme]
name = "{scheme}"
[time]
t_end = 1.0
[[region]]
lattice = "quasi-hexagonal"
particle_mass = 2.5e-4
density_profile = {{ expression = "(a - b)/(exp((y - 0.5)/w) + 1) + b", parameters = {{ a = 1.0, b = 2.0, w = 0.02 }} }}
pressure = 2.5
[[field]]
quantity = "pressure"
expression = "2.5"
{stage}
"#,
        header = common::header(2, 0.0, 1.0, "periodic", 5.0 / 3.0)
    )
}

#[test]
fn quasi_hexagonal_rows_hold_equal_masses_at_the_profile_density() {
    let case = Case::parse(&rows_case("standard", "")).unwrap();
    let sim = case.build::<2>().unwrap();
    let p = &sim.sys.particles;
    assert!(p.mass.iter().all(|&m| m == 2.5e-4));
    // the box holds ∫ρ dA / m = 1.5 / 2.5e-4 = 6000 particles (the rows round to whole numbers)
    assert!((p.len() as f64 / 6000.0 - 1.0).abs() < 0.02, "{}", p.len());
    // twice the density, twice the particles per area: count them over whole rows away from
    // the step (a window cutting rows would count ±1 row)
    let rows = |lo: f64, hi: f64| {
        let mut ys: Vec<f64> = p
            .pos
            .iter()
            .map(|x| x[1])
            .filter(|&y| y > lo && y < hi)
            .collect();
        ys.sort_by(f64::total_cmp);
        ys.dedup();
        let (first, last) = (ys[0], ys[ys.len() - 1]);
        let n = p
            .pos
            .iter()
            .filter(|x| x[1] >= first && x[1] < last)
            .count() as f64;
        n / (last - first)
    };
    let ratio = rows(0.6, 0.95) / rows(0.05, 0.4);
    assert!((ratio - 2.0).abs() < 0.01, "{ratio}");
    // and the summed density follows the profile within the lattice's own error
    let mut worst: f64 = 0.0;
    for a in 0..p.len() {
        let y = p.pos[a][1];
        if (y - 0.5).abs() > 0.15 && (0.1..0.9).contains(&y) {
            let want = if y > 0.5 { 2.0 } else { 1.0 };
            worst = worst.max((p.rho[a] / want - 1.0).abs());
        }
    }
    // measured 4.9e-3: the rows are not a perfect lattice (whole numbers per row, the stretch)
    println!("quasi-hexagonal rows: largest summed-density error away from the step {worst:.3e}");
    assert!(worst < 0.01, "{worst}");
}

#[test]
fn density_stage_sets_the_pressure_from_the_summed_density() {
    // with the entry at the density stage the pressure is uniform to round-off, though the
    // summed density of the rows departs from the profile (most at the step); with X = P^k
    // volume elements (rosswog-f1) the density depends on P and the entry is re-applied
    for scheme in ["standard", "rosswog-f1"] {
        let stage = "stage = \"density\"";
        for (text, uniform) in [
            (rows_case(scheme, stage), true),
            (rows_case(scheme, ""), false),
        ] {
            let case = Case::parse(&text).unwrap();
            let eos = case.eos;
            let sim = case.build::<2>().unwrap();
            let p = &sim.sys.particles;
            let spread = (0..p.len())
                .map(|a| (eos.pressure(p.rho[a], p.u[a]) / 2.5 - 1.0).abs())
                .fold(0.0, f64::max);
            if uniform {
                assert!(spread < 1e-12, "{scheme}: {spread}");
            } else {
                // measured 3.5 % (standard) at the step
                assert!(spread > 1e-3, "{scheme}: {spread}");
            }
        }
    }
}

#[test]
fn bad_lattices_and_profiles_are_named() {
    let rows = rows_case("standard", "");
    for (from, to, says) in [
        (
            "lattice = \"quasi-hexagonal\"\nparticle_mass = 2.5e-4",
            "lattice = \"quasi-hexagonal\"\nspacing = 0.02",
            "\"quasi-hexagonal\" is a 2D lattice of equal masses",
        ),
        (
            "pressure = 2.5\n[[field]]",
            "pressure = 2.5\ndensity = 1.0\n[[field]]",
            "give exactly one of density and density_profile",
        ),
        (
            "(a - b)/(exp((y - 0.5)/w) + 1) + b",
            "(a - b)/(exp((q - 0.5)/w) + 1) + b",
            "region[0].density_profile.expression: unknown name `q`",
        ),
        (
            "expression = \"2.5\"",
            "expression = \"2.5\"\nquantity = \"density\"",
            "duplicate key",
        ),
        (
            "expression = \"2.5\"",
            "expression = \"2.5\"\nstage = \"density\"\nregions = [0]",
            "field[0].regions: a stage = \"density\" entry",
        ),
    ] {
        let text = rows.replacen(from, to, 1);
        assert_ne!(text, rows, "{from}");
        let e = Case::parse(&text)
            .and_then(|c| c.build::<2>().map(|_| ()))
            .unwrap_err()
            .0;
        assert!(e.contains(says), "{to}: {e}");
    }
    let text = rows_case("standard", "")
        .replace(
            "expression = \"2.5\"",
            "expression = \"2.5\"\nstage = \"density\"",
        )
        .replace("quantity = \"pressure\"", "quantity = \"velocity.x\"");
    let e = Case::parse(&text).unwrap_err().0;
    assert!(
        e.contains("field[0].stage: \"density\" sets pressure or internal_energy only"),
        "{e}"
    );
    let e = Case::parse(&rings_case("").replace(
        "shape = \"sphere\"\ncenter = [0.0, 0.0]\nradius = 1.0\n",
        "",
    ))
    .unwrap_err()
    .0;
    assert!(
        e.contains("\"rings\" is a 2D lattice of a shape = \"sphere\" region"),
        "{e}"
    );
    // a profile that is not positive somewhere is named where it fails
    let text = rows.replace("b = 2.0", "b = -2.0");
    let e = Case::parse(&text)
        .unwrap()
        .build::<2>()
        .map(|_| ())
        .unwrap_err()
        .0;
    assert!(
        e.contains("region[0].density_profile: gives") && e.contains("must be finite and > 0"),
        "{e}"
    );
}

fn two_gases(scheme: &str, gamma_b: f64) -> String {
    format!(
        r#"{header}[[material]]
id = 1
eos = {{ type = "ideal-gas", gamma = {gamma_b:?} }}
[scheme]
name = "{scheme}"
[time]
t_end = 0.1
[[region]]
min = [0.0, 0.0]
max = [1.0, 1.0]
spacing = 0.05
density = 1.0
pressure = 1.0
[[region]]
min = [0.5, 0.0]
max = [1.0, 1.0]
spacing = 0.05
density = 1.0
pressure = 1.0
material = 1
"#,
        header = common::header(2, 0.0, 1.0, "periodic", 1.4)
    )
}

#[test]
fn two_materials_each_take_their_own_gamma() {
    // gas of γ = 1.4 beside gas of γ = 1.67 at the same ρ and P: u differs by the ratio of
    // (γ − 1), the pressures agree, so the box stays at rest (with one EOS for both the
    // second half would start at P = 1.67 and push)
    for scheme in ["crksph", "standard"] {
        let mut sim = Case::parse(&two_gases(scheme, 5.0 / 3.0))
            .unwrap()
            .build::<2>()
            .unwrap();
        let p = &sim.sys.particles;
        for a in 0..p.len() {
            let g = if p.material[a] == 1 { 5.0 / 3.0 } else { 1.4 };
            assert!((p.u[a] - 1.0 / (g - 1.0)).abs() < 1e-12, "u {}", p.u[a]);
            // measured: P within 3e-16 of 1 on this uniform lattice
            assert!(
                (p.pressure[a] - 1.0).abs() < 1e-9,
                "{scheme} P {}",
                p.pressure[a]
            );
        }
        sim.advance_to(0.1, |_| {}).unwrap();
        let vmax = sim
            .sys
            .particles
            .vel
            .iter()
            .map(|v| v.norm())
            .fold(0.0, f64::max);
        println!("{scheme}: two gases at equal pressure, |v| max {vmax:.2e} at t = 0.1");
        assert!(vmax < 1e-9, "{scheme}: {vmax}");
    }
}

#[test]
fn materials_are_checked() {
    for (from, to, want) in [
        ("id = 1", "id = 0", "material[0].id: must be in [1, 255]"),
        (
            "gamma = 1.6666666666666667 }",
            "gamma = 0.5 }",
            "material[0].eos.gamma",
        ),
    ] {
        let text = two_gases("crksph", 5.0 / 3.0);
        assert!(text.contains(from), "{from}");
        let e = Case::parse(&text.replacen(from, to, 1)).unwrap_err().0;
        assert!(e.contains(want), "{e}");
    }
    let e = Case::parse(&two_gases("psph", 5.0 / 3.0)).unwrap_err().0;
    assert!(e.contains("material[0].eos") && e.contains("psph"), "{e}");
}

/// `[[interface]] stretch = true` on the 1D Sod (equal masses, ρ 1 | 0.125): every particle sits
/// where the smoothed profile of Frontiere, Raskin & Owen (2017) Eq. 96 holds the mass to its
/// left, ∫ρ dx = Σ_{b left of a} m_b + m_a/2, and carries that profile's pressure.
#[test]
fn a_stretched_interface_puts_the_masses_on_the_smooth_profile() {
    const SOD: &str = include_str!("../models/sod.toml");
    let width = 0.003125;
    let text = format!(
        "{SOD}\n[[interface]]\naxis = 0\nposition = 0.0\nwidth = {width}\nstretch = true\n"
    );
    let case = Case::parse(&text).unwrap();
    let sim = case.build::<1>().unwrap();
    let p = &sim.sys.particles;
    let eos = case.eos_of(0);
    let mut order: Vec<usize> = (0..p.len()).collect();
    order.sort_by(|&a, &b| p.pos[a][0].total_cmp(&p.pos[b][0]));
    let softplus = |t: f64| {
        if t > 0.0 {
            t + (-t).exp().ln_1p()
        } else {
            t.exp().ln_1p()
        }
    };
    let (rl, rr) = (1.0, 0.125);
    // ∫ρ dx of Eq. 96 up to x, from the first particle on. The lattices are spaced so that
    // the kernel sum gives ρ, i.e. their ρ = m/spacing is the regions' over a common factor c
    // (`lattice_density_factor`), which the stretch (a function of ρ_l/ρ_r) does not see.
    let (x0, x1) = (p.pos[order[0]][0], p.pos[order[1]][0]);
    let c = p.mass[order[0]] / (rl * (x1 - x0));
    let integral = |x: f64| c * (rl * x + (rr - rl) * width * softplus(x / width));
    let mass_left = |x: f64| 0.5 * p.mass[order[0]] + integral(x) - integral(x0);
    let (mut cum, mut worst) = (0.0, 0.0f64);
    for &a in &order {
        let x = p.pos[a][0];
        let m = p.mass[a];
        worst = worst.max((cum + 0.5 * m - mass_left(x)).abs());
        cum += m;
        let w = 1.0 / (1.0 + (-x / width).exp());
        let (rho, pres) = (rl + (rr - rl) * w, 1.0 + (0.1 - 1.0) * w);
        assert!(
            (eos.pressure(rho, p.u[a]) - pres).abs() < 1e-12,
            "P at x = {x}"
        );
    }
    // measured: 1.1e-14 (the running sum's round-off; the solve's tolerance is 1e-15 of a width)
    assert!(
        worst < 1e-13,
        "mass left of a particle off the profile's by {worst}"
    );
    // far from the plane (e^{-36} of a width) the lattices are untouched, near it they are not
    let (mut kept, mut moved) = (0, 0);
    for w in order.windows(2) {
        let (xa, xb) = (p.pos[w[0]][0], p.pos[w[1]][0]);
        let lattice = p.mass[w[0]] / (c * if xa < 0.0 { rl } else { rr });
        let on = ((xb - xa) - lattice).abs() < 1e-9 * lattice;
        if xa.abs().min(xb.abs()) > 36.0 * width {
            assert!(on, "gap {} at x = {xa} (lattice {lattice})", xb - xa);
            kept += 1;
        } else {
            moved += !on as usize;
        }
    }
    assert!(
        kept > 100 && moved > 4,
        "{kept} gaps on the lattice, {moved} stretched"
    );
}

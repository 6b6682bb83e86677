//! Boundary bodies (issue 5, first part): wall particles with the Adami et al. (2012) wall
//! condition carry a liquid at rest; the load on the body is the reaction of the pair forces.

use crate::common;
use sphfmu::case::Case;

fn closed_tank() -> Case {
    Case::load(&common::model_path("closed-tank2d.toml")).unwrap()
}

#[test]
fn a_closed_tank_carries_the_weight_of_its_water() {
    let case = closed_tank();
    let mut sim = case.build::<2>().unwrap();
    let weight = sim.diagnostics().mass * 9.81;
    let n_fluid = (0..sim.sys.particles.len())
        .filter(|&i| sim.sys.particles.body[i] == 0)
        .count();
    // time averages over t ∈ [0.5, 1]: the weakly damped acoustic oscillation (±5 % of the
    // force, period ≈ 4H/c) averages out
    let (mut f_sum, mut dp_sum, mut samples) = (0.0, 0.0, 0usize);
    let dx = 0.02;
    while sim.time < 1.0 {
        sim.step(1.0 - sim.time).unwrap();
        if sim.time < 0.5 {
            continue;
        }
        f_sum += -sim.sys.bodies[0].force[1];
        dp_sum += wall_layer_pressure(&sim, -0.5 * dx) - wall_layer_pressure(&sim, 0.5 + 0.5 * dx);
        samples += 1;
    }
    let force = f_sum / samples as f64;
    let dp = dp_sum / samples as f64;
    // exact: the first wall layers sit Δx/2 outside the box, H + Δx = 0.52 apart; mean ρ of
    // the Tait water between 2e4 and 2.5e4 Pa is 1032.6 kg/m³
    let dp_exact = 1032.6 * 9.81 * 0.52;
    println!(
        "closed tank: vertical force / weight {:.4}, floor − lid wall pressure {dp:.1} Pa (exact {dp_exact:.1}), {samples} samples",
        force / weight
    );
    // measured: force 0.9995 of the weight, pressure difference 1.5 % low; issue: 1 % and 2 %
    assert!(
        (force / weight - 1.0).abs() < 0.01,
        "force/weight {}",
        force / weight
    );
    assert!((dp / dp_exact - 1.0).abs() < 0.02, "Δp {dp} vs {dp_exact}");
    // nothing leaves the box
    let p = &sim.sys.particles;
    let inside = (0..p.len())
        .filter(|&i| p.body[i] == 0)
        .all(|i| (0..2).all(|k| p.pos[i][k] > 0.0 && p.pos[i][k] < [1.0, 0.5][k]));
    assert!(inside && n_fluid == 1250);
}

#[test]
fn bad_bodies_are_clear_errors() {
    let base = common::model_text("closed-tank2d.toml");
    let cases = [
        // a block in the middle of the water
        (
            r#"shape = { type = "block", min = [0.4, 0.1], max = [0.6, 0.2] }"#,
            "body[0]: overlaps the fluid",
        ),
        (
            r#"shape = { type = "closed-box", min = [0.0, 0.0], max = [1.0, 0.0] }"#,
            "body[0].max: must exceed min",
        ),
        (
            r#"shape = { type = "closed-box", min = [0.0, 0.0], max = [1.0, 0.5] }
motion = { type = "sinusoid", amplitude = [0.01, nan], frequency = 1.0 }"#,
            "body[0].motion.amplitude: entries must be finite",
        ),
    ];
    for (shape, msg) in cases {
        let text = base.replace(
            r#"shape = { type = "closed-box", min = [0.0, 0.0], max = [1.0, 0.5] }"#,
            shape,
        );
        let err = match Case::parse(&text) {
            Err(e) => e.0,
            Ok(c) => c.build::<2>().err().expect("must fail").0,
        };
        assert!(err.contains(msg), "{err}");
    }
    // rpSPH gives no load on a body: refused by name
    let err = Case::parse(&base.replace("name = \"standard\"", "name = \"rpsph\""))
        .expect_err("rpsph with a body must fail")
        .0;
    assert!(err.contains("scheme.name: \"rpsph\""), "{err}");
}

#[test]
fn a_slow_piston_feels_the_adiabatic_pressure() {
    let worst = gas_spring_worst_deviation(&common::model_text("piston2d.toml"));
    println!("gas spring: largest deviation from P0 (L0/L)^γ A over one period {worst:.4}");
    // measured 0.72 % (every step after t = 0.5; Wendland C4, models/piston2d.toml). Most of
    // it is physics the adiabatic law leaves out: the gas column accelerates with the piston,
    // so the pressure on the piston differs from the mean by −ρ a L/3 (up to 0.42 % of P at the
    // turning points); the one-second means of the deviation follow that term within 0.2 %.
    // The issue: 1 % at all phases.
    assert!(worst < 0.01, "deviation {worst}");
}

/// The gas spring (models/piston2d.toml as `text`) over its 20 s period: the largest relative
/// deviation of the piston force from P0 (L0/L)^γ A at any step after t = 0.5 (the first
/// sound crossings).
pub(crate) fn gas_spring_worst_deviation(text: &str) -> f64 {
    let mut sim = Case::parse(text).unwrap().build::<2>().unwrap();
    let mut worst: f64 = 0.0;
    while sim.time < 20.0 {
        sim.step(20.0 - sim.time).unwrap();
        if sim.time < 0.5 {
            continue;
        }
        let piston = &sim.sys.bodies[1];
        let len = 1.1 + piston.pose.displacement[0];
        let exact = len.powf(-1.4) * 0.2;
        worst = worst.max((piston.force[0] / exact - 1.0).abs());
    }
    worst
}

/// Mean pressure of the wall particles at height y (0.2 < x < 0.8).
fn wall_layer_pressure(sim: &sphfmu::sim::Simulation<2>, y: f64) -> f64 {
    let p = &sim.sys.particles;
    let v: Vec<f64> = (0..p.len())
        .filter(|&i| {
            p.body[i] != 0
                && (p.pos[i][1] - y).abs() < 1e-9
                && p.pos[i][0] > 0.2
                && p.pos[i][0] < 0.8
        })
        .map(|i| p.pressure[i])
        .collect();
    v.iter().sum::<f64>() / v.len() as f64
}

#[test]
fn an_open_tank_carries_its_water_and_follows_doubled_gravity() {
    // Continuity density, free surface at P = 0 (models/tank2d.toml); gravity doubles at t = 0.5.
    let case = Case::load(&common::model_path("tank2d.toml")).unwrap();
    let mut sim = case.build::<2>().unwrap();
    let mass = sim.diagnostics().mass;
    let mean_rho = {
        let p = &sim.sys.particles;
        let f: Vec<usize> = (0..p.len()).filter(|&i| p.body[i] == 0).collect();
        f.iter().map(|&i| p.rho[i]).sum::<f64>() / f.len() as f64
    };
    // (g, averaging window, Σ F/W, Σ floor pressure, samples)
    let mut phases = [
        (9.81, 0.1, 0.5, 0.0, 0.0, 0usize),
        (19.62, 0.6, 1.0, 0.0, 0.0, 0),
    ];
    let dx = 0.02;
    while sim.time < 1.0 {
        if sim.time >= 0.5 && sim.sys.gravity[1] > -15.0 {
            sim.sys.gravity[1] = -19.62;
        }
        sim.step(1.0 - sim.time).unwrap();
        for ph in phases.iter_mut() {
            if sim.time >= ph.1 && sim.time <= ph.2 {
                ph.3 += -sim.sys.bodies[0].force[1] / (mass * ph.0);
                ph.4 += wall_layer_pressure(&sim, -0.5 * dx);
                ph.5 += 1;
            }
        }
    }
    for (g, t0, t1, f, pf, n) in phases {
        let (f, pf) = (f / n as f64, pf / n as f64);
        // the first wall layer lies Δx/2 below the floor: depth H + Δx/2
        let exact = mean_rho * g * (0.5 + 0.5 * dx);
        println!(
            "open tank, g = {g}: t ∈ [{t0}, {t1}] force/weight {f:.4}, floor pressure {pf:.1} (exact {exact:.1}, {:+.2} %)",
            100.0 * (pf / exact - 1.0)
        );
        // measured: force 1.0001 and 1.0039 of the weight; floor pressure +0.92 % and +0.54 %;
        // the issue: 1 % and 2 %
        assert!((f - 1.0).abs() < 0.01, "g = {g}: force/weight {f}");
        assert!(
            (pf / exact - 1.0).abs() < 0.02,
            "g = {g}: floor pressure {pf}"
        );
    }
    let p = &sim.sys.particles;
    assert!((0..p.len())
        .filter(|&i| p.body[i] == 0)
        .all(|i| p.pos[i][0] > 0.0 && p.pos[i][0] < 1.0 && p.pos[i][1] > 0.0));
}

#[test]
fn fluid_momentum_change_and_body_impulse_balance_to_round_off() {
    // Closed tank under gravity, with each integrator: ΔP_fluid + impulse on the box = M g t,
    // because every pair force acts on the fluid and on a wall particle with opposite signs
    // and the integrators weight the body force as they weight the fluid's accelerations.
    let base = closed_tank();
    for integrator in ["leapfrog", "ssp-rk3", "crk-rk2"] {
        let mut case = base.clone();
        case.time.integrator = Some(serde_json::from_str(&format!("{integrator:?}")).unwrap());
        let mut sim = case.build::<2>().unwrap();
        let d0 = sim.diagnostics();
        for _ in 0..300 {
            sim.step(f64::INFINITY).unwrap();
        }
        let d = sim.diagnostics();
        let g_impulse = d.mass * 9.81 * sim.time;
        let imp = sim.sys.bodies[0].impulse;
        let mismatch = ((d.momentum[0] - d0.momentum[0] + imp[0]).powi(2)
            + (d.momentum[1] - d0.momentum[1] + imp[1] + g_impulse).powi(2))
        .sqrt()
            / g_impulse;
        println!(
            "{integrator}: momentum balance over {} steps: {mismatch:.2e} of M g t",
            sim.steps
        );
        // measured: 3.5e-15 (leapfrog), 4.5e-15 (SSP-RK3), 4.3e-15 (CRK-RK2)
        assert!(mismatch < 1e-12, "{integrator}: {mismatch:e}");
    }
}

#[test]
fn sloshing_first_mode_matches_linear_theory() {
    let s = sloshing(&common::model_text("sloshing2d.toml"));
    println!(
        "sloshing: centre-of-mass amplitude {:.4} m, period / linear theory {:.4}, damping rate {:.3} /s",
        s.amplitude, s.period_ratio, s.damping
    );
    // a real oscillation (measured amplitude 6.3 mm), not noise
    assert!(s.amplitude > 0.003, "amplitude {}", s.amplitude);
    // measured +0.05 % (1.0005; Wendland C4 at 1/30 m; the cubic spline's −4.0 % is in
    // tests/kernel_choice.rs): 3× that
    assert!(
        (s.period_ratio - 1.0).abs() < 0.0015,
        "period ratio {}",
        s.period_ratio
    );
    assert!(s.inside, "a particle left the tank");
}

/// What `sloshing` measures.
pub(crate) struct Sloshing {
    /// Fitted period / linear theory's.
    pub period_ratio: f64,
    /// Fitted damping rate (1/s).
    pub damping: f64,
    /// Largest excursion of the centre of mass from its mean (m).
    pub amplitude: f64,
    /// Every fluid particle still in the tank at the end.
    pub inside: bool,
}

/// models/sloshing2d.toml (as `text`): the open tank (L = 1, H = 0.5) is pushed 10 mm sideways
/// and back over 0.6 s, then left alone; linear theory ω² = g k tanh(kH), k = π/L: T =
/// 1.1818 s. Observable: the water's horizontal centre of mass (smooth, unlike a surface height
/// read off particles), resampled every 5 ms over t ∈ [0.8, 3.5] (two free periods).
pub(crate) fn sloshing(text: &str) -> Sloshing {
    let mut sim = Case::parse(text).unwrap().build::<2>().unwrap();
    let com = |sim: &sphfmu::sim::Simulation<2>| {
        let p = &sim.sys.particles;
        let (mut mx, mut m) = (0.0, 0.0);
        for i in (0..p.len()).filter(|&i| p.body[i] == 0) {
            mx += p.mass[i] * p.pos[i][0];
            m += p.mass[i];
        }
        mx / m
    };
    let (t0, dt, t_end) = (0.8, 0.005, 3.5);
    let mut x: Vec<f64> = Vec::new();
    let mut prev = (sim.time, com(&sim));
    while sim.time < t_end {
        sim.step(t_end - sim.time).unwrap();
        let now = (sim.time, com(&sim));
        // linear interpolation onto the uniform grid: the steps are not evenly spaced
        while t0 + dt * x.len() as f64 <= now.0 {
            let ts = t0 + dt * x.len() as f64;
            x.push(prev.1 + (now.1 - prev.1) * (ts - prev.0) / (now.0 - prev.0));
        }
        prev = now;
    }
    let (period, damping) = damped_period(&x, dt, 60);
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    let k = std::f64::consts::PI;
    let exact = 2.0 * std::f64::consts::PI / (9.81 * k * (k * 0.5).tanh()).sqrt();
    let p = &sim.sys.particles;
    Sloshing {
        period_ratio: period / exact,
        damping,
        amplitude: x.iter().map(|v| (v - mean).abs()).fold(0.0, f64::max),
        inside: (0..p.len())
            .filter(|&i| p.body[i] == 0)
            .all(|i| p.pos[i][0] > 0.0 && p.pos[i][0] < 1.0 && p.pos[i][1] > 0.0),
    }
}

/// Period and damping rate of a damped oscillation about a constant from evenly spaced
/// samples (spacing `dt`): the linear prediction x[n+k] = a₁ x[n] + a₂ x[n−k] + c that a
/// signal c + A rⁿ cos(ωn dt + φ) obeys exactly with a₁ = 2 r^k cos(ωk dt), a₂ = −r^{2k},
/// fitted by least squares over every n (lag k about a quarter period).
fn damped_period(x: &[f64], dt: f64, k: usize) -> (f64, f64) {
    use nalgebra::{Matrix3, Vector3};
    let (mut a, mut b) = (Matrix3::<f64>::zeros(), Vector3::<f64>::zeros());
    for n in k..x.len() - k {
        let row = Vector3::new(x[n], x[n - k], 1.0);
        a += row * row.transpose();
        b += row * x[n + k];
    }
    let c = a.lu().solve(&b).expect("regular normal equations");
    let rk = (-c[1]).sqrt();
    let omega = (c[0] / (2.0 * rk)).acos() / (k as f64 * dt);
    (
        2.0 * std::f64::consts::PI / omega,
        -rk.ln() / (k as f64 * dt),
    )
}

/// The open tank to t = 0.5 with δ-SPH density diffusion `delta`: (force/weight and floor
/// pressure / exact, averaged over t ∈ [0.1, 0.5]; r.m.s. fluid speed at the end).
fn open_tank_with_delta(delta: f64) -> (f64, f64, f64) {
    let text = common::model_text("tank2d.toml").replace(
        "density = \"continuity\"",
        &format!("density = \"continuity\"\ndelta = {delta}"),
    );
    let case = Case::parse(&text).unwrap();
    let mut sim = case.build::<2>().unwrap();
    let mass = sim.diagnostics().mass;
    let (mut f, mut pf, mut n) = (0.0, 0.0, 0.0);
    let mean_rho = {
        let p = &sim.sys.particles;
        let f: Vec<usize> = (0..p.len()).filter(|&i| p.body[i] == 0).collect();
        f.iter().map(|&i| p.rho[i]).sum::<f64>() / f.len() as f64
    };
    while sim.time < 0.5 {
        sim.step(0.5 - sim.time).unwrap();
        if sim.time >= 0.1 {
            f += -sim.sys.bodies[0].force[1] / (mass * 9.81);
            pf += wall_layer_pressure(&sim, -0.01);
            n += 1.0;
        }
    }
    let p = &sim.sys.particles;
    let fluid: Vec<usize> = (0..p.len()).filter(|&i| p.body[i] == 0).collect();
    let v_rms =
        (fluid.iter().map(|&i| p.vel[i].norm_squared()).sum::<f64>() / fluid.len() as f64).sqrt();
    (f / n, pf / n / (mean_rho * 9.81 * 0.51), v_rms)
}

#[test]
fn density_diffusion_leaves_the_hydrostatic_tank_alone_and_calms_it() {
    let (f0, p0, v0) = open_tank_with_delta(0.0);
    let (f1, p1, v1) = open_tank_with_delta(0.1);
    println!(
        "open tank to t = 0.5: δ = 0: force/weight {f0:.4}, floor P/exact {p0:.4}, v_rms {v0:.2e}; δ = 0.1: {f1:.4}, {p1:.4}, {v1:.2e}"
    );
    // measured: force/weight 1.0001 both, floor pressure +0.92 % and +0.89 %, v_rms 1.01e-3
    // and 9.44e-4 (the hydrostatic correction keeps the column; the issue: 1 % and 2 %)
    assert!((f1 - 1.0).abs() < 0.01 && (p1 - 1.0).abs() < 0.02);
    assert!(v1 < v0, "density diffusion should calm the settling tank");
}

#[test]
fn a_3d_open_tank_carries_its_water_and_follows_doubled_gravity() {
    // η = 1.3 rather than the cubic spline's 1.2: standard SPH's pressure gradient on a cubic
    // lattice is the exact one times the lattice sum M = −Σ_b V_b x_b ∂W/∂x(x_b) (Rosswog's
    // Q4 in 3D), and the water settles where that gradient balances gravity, so its pressure
    // reads 1/M − 1 high: M = 0.9817 at η = 1.2 (1/M − 1 = +1.87 %, floor +2.04 %:
    // tests/kernel_choice.rs), 0.9935 at η = 1.3.
    let (phases, inside) = open_tank_3d("eta = 1.3", true);
    let excess = 1.0 / cubic_lattice_gradient_moment(1.3) - 1.0;
    for (g, f, pf) in phases {
        println!(
            "3D open tank, g = {g}: force/weight {f:.4}, floor pressure / exact {pf:.4} (1/M − 1 = {:+.2} %)",
            100.0 * excess,
        );
        // measured: force/weight 1.0002 and 1.0055; floor pressure +0.79 % and +0.18 % (1/M − 1 =
        // +0.66 %); the issue: 1 % and 2 %
        assert!((f - 1.0).abs() < 0.01, "g = {g}: force/weight {f}");
        assert!((pf - 1.0).abs() < 0.02, "g = {g}: floor pressure {pf}");
        // settled only: the doubled phase still rings at ±25 %, which moves its mean by ~1 %
        assert!(
            g > 10.0 || (pf - 1.0 - excess).abs() < 0.003,
            "g = {g}: floor pressure {pf} against the lattice moment's {excess}"
        );
    }
    assert!(inside, "a particle left the tank");
}

/// 0.2 m of water in a 0.2 m × 0.2 m open tank, continuity density, Δx = 0.02 (1000 fluid
/// particles), with `kernel` as its `[kernel]` table: per phase (g, force on the tank / weight,
/// floor pressure / ρgH), settled under g to t = 0.3 and, with `double`, after gravity doubles
/// at t = 0.3; and whether every fluid particle is still in the tank.
pub(crate) fn open_tank_3d(kernel: &str, double: bool) -> (Vec<(f64, f64, f64)>, bool) {
    let t_end = if double { 1.2 } else { 0.3 };
    let text = format!(
        r#"gravity = [0.0, 0.0, -9.81]
[case]
name = "tank3d"
dimension = 3
[domain]
min = [-0.1, -0.1, -0.1]
max = [0.3, 0.3, 0.4]
boundary = ["open", "open", "open"]
[eos]
type = "tait"
rho0 = 1000.0
sound_speed = 15.0
gamma = 7.0
[scheme]
name = "standard"
alpha = 0.1
beta = 0.0
density = "continuity"
[kernel]
{kernel}
[time]
t_end = {t_end:?}
[output]
snapshot_every = 0.0
[[region]]
min = [0.0, 0.0, 0.0]
max = [0.2, 0.2, 0.2]
spacing = 0.02
density = 1000.0
pressure = 0.0
hydrostatic = true
[[body]]
name = "tank"
shape = {{ type = "tank", min = [0.0, 0.0, 0.0], max = [0.2, 0.2, 0.3] }}
"#
    );
    let dx = 0.02;
    let case = Case::parse(&text).unwrap();
    let mut sim = case.build::<3>().unwrap();
    let mass = sim.diagnostics().mass;
    let mean_rho = {
        let p = &sim.sys.particles;
        let f: Vec<usize> = (0..p.len()).filter(|&i| p.body[i] == 0).collect();
        f.iter().map(|&i| p.rho[i]).sum::<f64>() / f.len() as f64
    };
    // (g, averaging window, Σ F/W, Σ floor pressure, samples). The column's acoustic period
    // 4H/c is 0.053 s; after the step in g the force rings at ±35 %, weakly damped (α = 0.1),
    // under a slower swing of ±3 % (period ≈ 0.3 s), so the average starts 4 acoustic periods
    // later and spans 0.7 s (over [0.5, 0.9] it read 1.0096)
    let mut phases = vec![(9.81, 0.15, 0.3, 0.0, 0.0, 0usize)];
    if double {
        phases.push((19.62, 0.5, 1.2, 0.0, 0.0, 0));
    }
    while sim.time < t_end {
        if double && sim.time >= 0.3 && sim.sys.gravity[2] > -15.0 {
            sim.sys.gravity[2] = -19.62;
        }
        sim.step(t_end - sim.time).unwrap();
        // first wall layer under the floor
        let p = &sim.sys.particles;
        let v: Vec<f64> = (0..p.len())
            .filter(|&i| {
                p.body[i] == 1
                    && (p.pos[i][2] + 0.5 * dx).abs() < 1e-9
                    && (0..2).all(|k| p.pos[i][k] > 0.0 && p.pos[i][k] < 0.2)
            })
            .map(|i| p.pressure[i])
            .collect();
        for ph in phases.iter_mut() {
            if sim.time >= ph.1 && sim.time <= ph.2 {
                ph.3 += -sim.sys.bodies[0].force[2] / (mass * ph.0);
                ph.4 += v.iter().sum::<f64>() / v.len() as f64;
                ph.5 += 1;
            }
        }
    }
    let p = &sim.sys.particles;
    let inside = (0..p.len())
        .filter(|&i| p.body[i] == 0)
        .all(|i| (0..2).all(|k| p.pos[i][k] > 0.0 && p.pos[i][k] < 0.2) && p.pos[i][2] > 0.0);
    let phases = phases
        .into_iter()
        .map(|(g, _, _, f, pf, n)| {
            // the first wall layer lies Δx/2 under the floor
            let exact = mean_rho * g * (0.2 + 0.5 * dx);
            (g, f / n as f64, pf / n as f64 / exact)
        })
        .collect();
    (phases, inside)
}

/// M = −Σ_b V_b x_b ∂W/∂x(x_b) over a unit cubic lattice for the cubic spline at h = η Δx:
/// the factor standard SPH's gradient of a linear field carries on that lattice (1 in the
/// continuum).
pub(crate) fn cubic_lattice_gradient_moment(eta: f64) -> f64 {
    use sphfmu::kernel::{AnyKernel, DimKernel, KernelName};
    let kernel = DimKernel::<3>::new(AnyKernel::from_name(KernelName::CubicSpline, 0).unwrap());
    let mut m = 0.0;
    for i in -3i32..=3 {
        for j in -3i32..=3 {
            for k in -3i32..=3 {
                let r = ((i * i + j * j + k * k) as f64).sqrt();
                if r > 0.0 {
                    // ∂W/∂x = dW/dr · x/r
                    m -= i as f64 * kernel.dwdr(r, eta) * i as f64 / r;
                }
            }
        }
    }
    m
}

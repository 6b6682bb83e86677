//! Pressure ports (issue 6): openings with particle buffers where an outside model sets the
//! pressure and receives the flow. Poiseuille flow between two ports against the exact flow
//! rate, a tank draining through a bottom port against Torricelli's law, a port pressure step
//! set through the Coupling API, save/restore across particle creation and deletion, and bad
//! input.

use crate::common;
use sphfmu::case::Case;
use sphfmu::coupling::sampling::port_value;
use sphfmu::coupling::{Coupling, CouplingOptions, ParticleKind};

/// Exact plane Poiseuille flow of models/poiseuille-ports2d.toml: Q = ΔP H³ / (12 μ L).
const Q_EXACT: f64 = 0.12 / (12.0 * 0.1 * 2.0);

#[test]
fn poiseuille_between_two_pressure_ports_matches_the_exact_flow_rate() {
    let case = Case::parse(&common::model_text("poiseuille-ports2d.toml")).unwrap();
    let mut sim = case.build::<2>().unwrap();
    let m0 = sim.diagnostics().mass;
    // flow through the two ports (mean of inlet and outlet) every 0.1 s over t ∈ (6, 10],
    // after the start-up (viscous time H²/(π²ν) = 1 s; the inlet pressure ramps up over 1 s)
    let mut samples = vec![];
    for k in 1..=100 {
        let t = 0.1 * k as f64;
        sim.advance_to(t, |_| {}).unwrap();
        let (a, b) = (port_value(&sim.sys, 0), port_value(&sim.sys, 1));
        if k > 60 {
            samples.push(0.5 * (a.volume_flow - b.volume_flow));
        }
        // mass: what the domain holds is what it started with plus what came in minus what
        // went out, to round-off (particles are counted as they cross)
        let d = sim.diagnostics();
        let balance = d.mass - m0 - (a.mass_in + b.mass_in) + (a.mass_out + b.mass_out);
        assert!(
            balance.abs() < 1e-12 * m0,
            "t = {t}: mass balance off by {balance:e}"
        );
        // nothing leaves through a wall: fluid stays in the channel
        let p = &sim.sys.particles;
        for i in 0..p.len() {
            if p.body[i] == 0 && p.port[i] == 0 {
                let x = p.pos[i];
                assert!(
                    (-1e-9..=2.0 + 1e-9).contains(&x[0]) && (0.0..=1.0).contains(&x[1]),
                    "t = {t}: fluid particle outside the channel at {x:?}"
                );
            }
        }
    }
    let mean = samples.iter().sum::<f64>() / samples.len() as f64;
    // measured (30 particles across): mean 0.04995 over (5, 10], Q/Q_exact = 1.001…1.016 in
    // the last 2.5 s; 20 across gives +2…+5 %, 40 across +0.6…+1.5 %
    let err = mean / Q_EXACT - 1.0;
    println!(
        "Poiseuille between ports: Q = {mean:.5}, exact {Q_EXACT:.5} ({:+.2} %)",
        100.0 * err
    );
    // measured +0.61 % (0.05031 against 0.05000): 3× that
    assert!(err.abs() < 0.018, "flow rate {mean} vs exact {Q_EXACT}");
    // steady: each 1 s average within 3 % of the exact value too
    for w in samples.chunks(10) {
        let m = w.iter().sum::<f64>() / w.len() as f64;
        assert!(
            (m / Q_EXACT - 1.0).abs() < 0.03,
            "1-s mean {m} vs {Q_EXACT}"
        );
    }
}

#[test]
fn a_tank_drains_through_a_bottom_port_by_torricellis_law() {
    let case = Case::parse(&common::model_text("drain2d.toml")).unwrap();
    let mut sim = case.build::<2>().unwrap();
    let (rho0, g, area) = (1000.0, 9.81, 0.2);
    let depth = |sim: &sphfmu::sim::Simulation<2>| sim.diagnostics().mass / rho0;
    let mut before = (0.0, depth(&sim));
    let mut cd = vec![];
    for k in 1..=8 {
        let t = 0.1 * k as f64;
        sim.advance_to(t, |_| {}).unwrap();
        let out = port_value(&sim.sys, 0).mass_out;
        let h = depth(&sim);
        // the exact outflow over the window (particles counted as they leave) against
        // Torricelli at the window's mean depth
        let q = (out - before.0) / rho0 / 0.1;
        let torricelli = area * (2.0 * g * 0.5 * (h + before.1)).sqrt();
        before = (out, h);
        println!(
            "t = {t:.1}: depth {h:.4} m, outflow {q:.4} m²/s, Cd = {:.3}",
            q / torricelli
        );
        if k > 1 {
            cd.push(q / torricelli);
        }
        let p = &sim.sys.particles;
        for i in 0..p.len() {
            if p.body[i] == 0 && p.port[i] == 0 && p.pos[i][1] < 0.0 {
                assert!(
                    (p.pos[i][0] - 0.5).abs() <= 0.1 + 1e-9,
                    "t = {t}: fluid below the floor outside the opening at {:?}",
                    p.pos[i]
                );
            }
        }
    }
    // measured: Cd = 0.57…0.64 per window for t ∈ [0.1, 0.8] while the depth falls from 0.48
    // to 0.26 m (Q ∝ √h holds: Cd shows no trend), mean 0.60 — the free-streamline value of
    // a 2D slot in a wide tank is π/(π + 2) = 0.611 (Kirchhoff)
    let mean = cd.iter().sum::<f64>() / cd.len() as f64;
    println!("drain: discharge coefficient Cd = {mean:.3}");
    assert!((0.55..0.67).contains(&mean), "Cd = {mean}");
    for c in &cd {
        assert!(
            (c / mean - 1.0).abs() < 0.1,
            "Cd {c} strays from the mean {mean}"
        );
    }
}

/// The Poiseuille case with the inlet pressure set from outside.
fn external_inlet() -> Case {
    let text = common::model_text("poiseuille-ports2d.toml").replace(
        "{ type = \"ramp\", from = 0.0, to = 0.12, duration = 1.0 }",
        "{ type = \"external\", initial = 0.06 }",
    );
    Case::parse(&text).unwrap()
}

fn mean_flow(c: &mut Coupling, from: f64, to: f64) -> f64 {
    let mut q = vec![];
    let mut t = from;
    while t < to - 1e-9 {
        t += 0.1;
        c.step_to(t).unwrap();
        let p = c.ports();
        q.push(0.5 * (p[0].volume_flow - p[1].volume_flow));
    }
    q.iter().sum::<f64>() / q.len() as f64
}

#[test]
fn a_port_pressure_step_from_outside_doubles_the_flow() {
    let mut c = Coupling::new(&external_inlet(), &CouplingOptions::default()).unwrap();
    c.step_to(4.0).unwrap();
    let q1 = mean_flow(&mut c, 4.0, 5.0);
    let inlet = c.port_index("inlet").unwrap();
    c.set_port_pressure(inlet, 0.12).unwrap();
    assert_eq!(c.ports()[inlet].pressure, 0.12);
    // the flow responds over the viscous time H²/(π²ν) = 1 s
    let early = mean_flow(&mut c, 5.0, 5.5);
    c.step_to(9.0).unwrap();
    let (q2a, q2b) = (mean_flow(&mut c, 9.0, 9.5), mean_flow(&mut c, 9.5, 10.0));
    let q2 = 0.5 * (q2a + q2b);
    // Stokes flow is linear in the pressure drop. Measured: before the step Q is 8 % below
    // exact (the start from rest has settled, but the channel still holds its initial
    // lattice: Q creeps up by ~2 % per 3 s as inflowing fluid replaces it, the same creep
    // the ramped case shows), after it 1 % below; ratio 2.15; the first half second shows 0.28 of the step
    // (exact 0.22); the last two half-second
    // means agree to 0.5 %.
    println!(
        "pressure step 0.06 → 0.12: Q {q1:.5} → {early:.5} (first 0.5 s) → {q2:.5}; {:+.2} % / {:+.2} % from exact",
        100.0 * (2.0 * q1 / Q_EXACT - 1.0),
        100.0 * (q2 / Q_EXACT - 1.0)
    );
    // exact start-up of plane Poiseuille flow: Q(t)/Q∞ = 1 − Σ_{n odd} 96/(π⁴n⁴) e^{−n²π²νt/H²};
    // its mean over the first 0.5 s is the fraction of the step the window should show
    let pi2 = std::f64::consts::PI.powi(2);
    let (nu, w) = (0.1, 0.5);
    let lag: f64 = (1..40)
        .step_by(2)
        .map(|n| {
            let (n2, k) = ((n * n) as f64, (n * n) as f64 * pi2 * nu);
            96.0 / (pi2 * pi2 * n2 * n2) * (1.0 - (-k * w).exp()) / (k * w)
        })
        .sum();
    let frac = (early - q1) / (q2 - q1);
    println!(
        "first 0.5 s: {frac:.3} of the step (exact Stokes start-up {:.3})",
        1.0 - lag
    );
    assert!(
        (frac - (1.0 - lag)).abs() < 0.1,
        "response {frac} vs {}",
        1.0 - lag
    );
    assert!((1.95..2.25).contains(&(q2 / q1)), "ratio {}", q2 / q1);
    assert!((q2 / Q_EXACT - 1.0).abs() < 0.03, "after the step: {q2}");
    assert!(
        (q2a / q2b - 1.0).abs() < 0.02,
        "not settled: {q2a} then {q2b}"
    );
    let d = c.diagnostics();
    assert!(d.fluid_particles > 0 && d.mass.is_finite());
    for s in c.particles(1) {
        assert!(s.position.iter().chain(&s.velocity).all(|x| x.is_finite()));
        if s.kind == ParticleKind::Fluid {
            let x = s.position;
            assert!((-1e-9..=2.0 + 1e-9).contains(&x[0]) && (0.0..=1.0).contains(&x[1]));
        }
    }
}

#[test]
fn bad_port_pressures_from_outside_fail_and_change_nothing() {
    let case = external_inlet();
    let mut c = Coupling::new(&case, &CouplingOptions::default()).unwrap();
    c.step_to(0.05).unwrap();
    let before = c.save().unwrap();
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        let e = c.set_port_pressure(0, bad).unwrap_err();
        assert!(
            e.0.contains("\"inlet\" pressure") && e.0.contains("≥ 0"),
            "{e}"
        );
    }
    let e = c.set_port_pressure(1, 0.1).unwrap_err();
    assert!(e.0.contains("prescribed by the case"), "{e}");
    let e = c.set_port_pressure(2, 0.1).unwrap_err();
    assert!(e.0.contains("out of range"), "{e}");
    assert!(c
        .port_index("nope")
        .unwrap_err()
        .0
        .contains("no port named"));
    assert!(
        c.save().unwrap() == before,
        "a rejected input changed the state"
    );
}

/// What a continued run is judged by, as bit patterns: diagnostics, port values and every
/// particle's state (the saved bytes also hold wall-clock timings).
fn bits(c: &Coupling) -> Vec<u64> {
    let d = c.diagnostics();
    let mut out = vec![
        d.time.to_bits(),
        d.step,
        d.particles as u64,
        d.mass.to_bits(),
    ];
    for p in c.ports() {
        out.extend([p.mean_pressure, p.volume_flow, p.mass_in, p.mass_out].map(f64::to_bits));
    }
    for s in c.particles(1) {
        out.extend(s.position.iter().chain(&s.velocity).map(|x| x.to_bits()));
        out.extend([s.density.to_bits(), s.pressure.to_bits()]);
    }
    out
}

#[test]
fn save_and_restore_across_particle_creation_and_deletion_is_bit_exact() {
    let case = Case::parse(&common::model_text("drain2d.toml")).unwrap();
    let mut a = Coupling::new(&case, &CouplingOptions::default()).unwrap();
    a.step_to(0.05).unwrap();
    let saved = a.save().unwrap();
    a.step_to(0.12).unwrap();
    let n = a.diagnostics();
    assert!(a.ports()[0].mass_out > 0.0, "particles left during the run");
    let mut b = Coupling::new(&case, &CouplingOptions::default()).unwrap();
    b.restore(&saved).unwrap();
    b.step_to(0.12).unwrap();
    assert_eq!(b.diagnostics().particles, n.particles);
    assert!(
        bits(&a) == bits(&b),
        "the restored run departs from the uninterrupted one"
    );
}

#[test]
fn bad_ports_in_a_case_are_named() {
    let base = common::model_text("poiseuille-ports2d.toml");
    let check = |from: &str, to: &str, want: &str| {
        let text = base.replacen(from, to, 1);
        assert_ne!(text, base, "{from:?} not found");
        let e = Case::parse(&text)
            .and_then(|c| c.build::<2>().map(|_| ()))
            .unwrap_err();
        assert!(e.0.contains(want), "{to}: {e}");
    };
    check(
        "center = [0.0, 0.5]",
        "center = [0.3, 0.5]",
        "port[0].center: [0.3, 0.5] is not on the surface",
    );
    check(
        "center = [0.0, 0.5]",
        "center = [0.0, 0.5]\nnormal = [-1.0, 0.0]",
        "port[0].normal",
    );
    check(
        "body = \"channel\"\ncenter = [0.0",
        "body = \"pipe\"\ncenter = [0.0",
        "port[0].body: no body named \"pipe\"",
    );
    check(
        "half_width = 0.5 }",
        "half_width = -0.5 }",
        "port[0].opening.half_width: must be a finite number > 0",
    );
    check(
        "half_width = 0.5 }",
        "half_width = 0.001 }",
        "port[0].opening: holds no wall particle",
    );
    check(
        "{ type = \"segment\", half_width = 0.5 }",
        "{ type = \"disk\", radius = 0.5 }",
        "port[0].opening: a 2D case takes type = \"segment\"",
    );
    check(
        "name = \"outlet\"",
        "name = \"inlet\"",
        "port[1].name: \"inlet\" is used by an earlier port",
    );
    check(
        "type = \"constant\", value = 0.0",
        "type = \"table\", time = [0.0, 0.0], value = [0.0, 1.0]",
        "port[1].pressure.time: must be finite and strictly increasing",
    );
    check(
        "type = \"tait\"\nrho0 = 1.0\nsound_speed = 3.0\ngamma = 7.0",
        "type = \"ideal-gas\"\ngamma = 1.4",
        "port[0]: ports need a liquid EOS",
    );
    check(
        "no_slip = true",
        "no_slip = true\nmotion = { type = \"external\" }",
        "port[0].body: \"channel\" moves",
    );
    // schemes measured unstable next to a port's buffer are refused by the setting that
    // fixes them, and accepted with it
    let scheme = "name = \"standard\"\nalpha = 0.0\nbeta = 0.0\nviscosity = 0.1";
    check(scheme, "name = \"crksph\"", "scheme.limiter: crksph");
    check(
        scheme,
        "name = \"rosswog-f1\"",
        "scheme.triggers: rosswog-f1",
    );
    check(
        scheme,
        "name = \"rosswog-f3\"",
        "scheme.triggers: rosswog-f3",
    );
    for fixed in [
        "name = \"crksph\"\nlimiter = false",
        "name = \"crksph\"\norder = \"zeroth\"",
        "name = \"rosswog-f1\"\ntriggers = false",
        "name = \"rosswog-f4\"",
    ] {
        let text = base.replacen(scheme, fixed, 1);
        assert_ne!(text, base);
        Case::parse(&text)
            .and_then(|c| c.build::<2>().map(|_| ()))
            .unwrap_or_else(|e| panic!("{fixed}: {e}"));
    }
}

/// A closed 3D box of water with a disk port in its floor and a rectangular port in a side
/// wall, each held at the hydrostatic pressure of its centre (ρ0 g × depth below the lid).
/// Continuity density with δ-SPH, as for liquids with a free surface (with summation density
/// the same box moved at up to 0.16 m/s near the openings, against 0.034 m/s without ports:
/// an open point, see the issue note).
fn box3d(floor_pressure: f64, side_pressure: f64) -> String {
    format!(
        r#"gravity = [0.0, 0.0, -9.81]
[case]
name = "ports3d"
dimension = 3
[domain]
min = [-0.2, -0.2, -0.2]
max = [0.6, 0.6, 0.5]
boundary = ["open", "open", "open"]
[eos]
type = "tait"
rho0 = 1000.0
sound_speed = 20.0
gamma = 7.0
[scheme]
name = "standard"
alpha = 0.1
beta = 0.0
density = "continuity"
delta = 0.1
[time]
t_end = 0.3
[[region]]
min = [0.0, 0.0, 0.0]
max = [0.4, 0.4, 0.32]
spacing = 0.04
density = 1000.0
pressure = 0.0
hydrostatic = true
[[body]]
name = "box"
shape = {{ type = "closed-box", min = [0.0, 0.0, 0.0], max = [0.4, 0.4, 0.32] }}
[[port]]
name = "floor"
body = "box"
center = [0.2, 0.2, 0.0]
opening = {{ type = "disk", radius = 0.08 }}
pressure = {{ type = "constant", value = {floor_pressure} }}
[[port]]
name = "side"
body = "box"
center = [0.0, 0.2, 0.16]
opening = {{ type = "rectangle", half_width = 0.08, half_height = 0.06, tangent = [0.0, 1.0, 0.0] }}
pressure = {{ type = "constant", value = {side_pressure} }}
"#
    )
}

#[test]
fn ports_at_the_hydrostatic_pressure_keep_a_3d_box_at_rest() {
    let (rho_g, h) = (1000.0 * 9.81, 0.32);
    let case = Case::parse(&box3d(rho_g * h, rho_g * (h - 0.16))).unwrap();
    let mut sim = case.build::<3>().unwrap();
    let m0 = sim.diagnostics().mass;
    sim.advance_to(0.3, |_| {}).unwrap();
    let (a, b) = (port_value(&sim.sys, 0), port_value(&sim.sys, 1));
    let p = &sim.sys.particles;
    let vmax = (0..p.len())
        .filter(|&i| p.body[i] == 0 && p.port[i] == 0)
        .map(|i| p.vel[i].norm())
        .fold(0.0, f64::max);
    let net = (a.mass_in + b.mass_in - a.mass_out - b.mass_out) / m0;
    println!(
        "3D ports at hydrostatic pressure: max |v| {vmax:.4} m/s (√(gH) = {:.3}), net inflow {net:.2e} of the mass, mean pressure floor {:.1} / side {:.1} Pa (set {:.1} / {:.1})",
        (9.81 * h).sqrt(),
        a.mean_pressure,
        b.mean_pressure,
        rho_g * h,
        rho_g * (h - 0.16)
    );
    // measured: max |v| 0.0082 m/s (0.5 % of √(gH)), no particle crossed; the mean pressure on
    // the openings 3154.7 / 1569.9 Pa against 3139.2 / 1569.6 set
    assert!(vmax < 0.05 * (9.81 * h).sqrt(), "the fluid moves: {vmax}");
    assert!(net.abs() < 0.01, "net inflow {net}");
    let d = sim.diagnostics();
    assert!((d.mass - m0 - net * m0).abs() < 1e-12 * m0);
    // a floor port 20 % below the hydrostatic pressure drives a flow from the side port to
    // the floor port through the full box
    let case = Case::parse(&box3d(0.8 * rho_g * h, rho_g * (h - 0.16))).unwrap();
    let mut sim = case.build::<3>().unwrap();
    sim.advance_to(0.5, |_| {}).unwrap();
    let (a, b) = (port_value(&sim.sys, 0), port_value(&sim.sys, 1));
    println!(
        "floor port 20 % below hydrostatic: {:.3} kg out at the floor, {:.3} kg in at the side in 0.5 s; flows {:.4} / {:.4} m³/s",
        a.mass_out, b.mass_in, a.volume_flow, b.volume_flow
    );
    // measured: 1.031 kg out at the floor, 0.514 kg in at the side by t = 0.5 s (the full box
    // gives up volume only as fast as the liquid decompresses, so out exceeds in)
    assert!(a.mass_out > 0.0 && b.mass_in > 0.0, "no through-flow");
    assert!(a.volume_flow < 0.0 && b.volume_flow > 0.0);
}

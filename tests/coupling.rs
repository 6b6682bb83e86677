//! The Coupling interface (issue 5): inputs, stepping to a time, loads, probes and markers,
//! save / restore bit for bit, and bad inputs that change nothing.

use crate::common;
use sphfmu::case::Case;
use sphfmu::coupling::{BodyKinematics, Coupling, CouplingOptions, PatchValue, ProbeValue};

fn options() -> CouplingOptions {
    CouplingOptions {
        threads: 2,
        ..CouplingOptions::default()
    }
}

/// The fields a continued run is judged by, as bit patterns.
fn fingerprint(c: &Coupling) -> Vec<u64> {
    let d = c.diagnostics();
    let mut out = vec![d.time.to_bits(), d.step, d.total_energy.to_bits()];
    out.extend(d.momentum.iter().map(|x| x.to_bits()));
    for l in c.loads() {
        out.extend(l.force.iter().chain(&l.torque).map(|x| x.to_bits()));
    }
    for p in c.probes() {
        out.extend(
            [p.density, p.pressure, p.velocity[0]]
                .iter()
                .map(|x| x.to_bits()),
        );
    }
    out.extend(c.markers().iter().map(|x| x.to_bits()));
    out
}

/// A 2D periodic box of gas with a pressure bump (sound waves in every direction), small
/// enough for each scheme family in a second.
const WAVE_BOX: &str = r#"
[case]
name = "wave-box"
dimension = 2
[domain]
min = [0.0, 0.0]
max = [1.0, 1.0]
boundary = ["periodic", "periodic"]
[eos]
type = "ideal-gas"
gamma = 1.4
[time]
t_end = 1.0
[output]
snapshot_every = 0.0
[[region]]
spacing = 0.04
density = 1.0
pressure = 1.0
[[region]]
shape = "sphere"
center = [0.5, 0.5]
radius = 0.2
lattice = "cubic"
spacing = 0.04
density = 1.5
pressure = 2.0
[[probe]]
name = "centre"
point = [0.5, 0.5]
"#;

/// Save at t1, run to t2; restore into the same instance and into a fresh one, run to t2
/// again: identical bit for bit.
fn save_restore_is_exact(label: &str, case: &Case, drive: impl Fn(&mut Coupling, f64)) {
    let mut a = Coupling::new(case, &options()).unwrap();
    let t1 = 0.05;
    let t2 = 0.12;
    drive(&mut a, 0.0);
    a.step_to(t1).unwrap();
    let saved = a.save().unwrap();
    let at_t1 = fingerprint(&a);
    drive(&mut a, t1);
    a.step_to(t2).unwrap();
    let reference = fingerprint(&a);
    // rollback in place
    a.restore(&saved).unwrap();
    assert_eq!(
        fingerprint(&a),
        at_t1,
        "{}: restore does not return to t1",
        label
    );
    drive(&mut a, t1);
    a.step_to(t2).unwrap();
    assert_eq!(fingerprint(&a), reference, "{}: rollback diverged", label);
    // into a new instance
    let mut b = Coupling::new(case, &options()).unwrap();
    b.restore(&saved).unwrap();
    drive(&mut b, t1);
    b.step_to(t2).unwrap();
    assert_eq!(
        fingerprint(&b),
        reference,
        "{}: new instance diverged",
        label
    );
    assert!(
        a.diagnostics().step > 5,
        "{label}: too few steps to mean anything"
    );
}

#[test]
fn save_and_restore_continue_bit_for_bit_with_every_scheme_family() {
    let base = Case::parse(WAVE_BOX).unwrap();
    for scheme in [
        "standard",
        "rpsph",
        "rosswog-f1",
        "rosswog-f4",
        "crksph",
        "compsph-cullen",
        "psph",
    ] {
        let case = base.with_scheme(scheme).unwrap();
        save_restore_is_exact(scheme, &case, |_, _| {});
    }
}

#[test]
fn save_and_restore_are_exact_with_bodies_driven_from_outside() {
    let case = Case::parse(&common::model_text("free-piston2d.toml")).unwrap();
    // the master's inputs are a function of time only, as a deterministic master's are
    save_restore_is_exact("free piston", &case, |c, t| {
        let piston = c.body_index("piston").unwrap();
        let v = 0.02 * (1.0 - t);
        c.set_body_kinematics(
            piston,
            &BodyKinematics {
                position: [1.0 + 0.02 * t - 0.01 * t * t, 0.1, 0.0],
                velocity: [v, 0.0, 0.0],
                ..Default::default()
            },
        )
        .unwrap();
        c.set_gravity([0.01 * t, 0.0, 0.0]).unwrap();
    });
}

#[test]
fn save_and_restore_are_exact_in_a_moving_frame_and_with_wall_pair_schemes() {
    // a closed tank in a frame that sways and rocks (every fictitious term), and the same
    // tank with Rosswog F1 (wall–wall pairs kept in its lists)
    let framed = format!(
        "{}\n[frame]\nmotion = {{ type = \"sinusoid\", amplitude = [0.01, 0.0], angle_amplitude = 0.05, frequency = 1.5 }}\nreference = [0.5, 0.25]\n",
        common::model_text("closed-tank2d.toml")
    );
    let case = Case::parse(&framed).unwrap();
    save_restore_is_exact("moving frame", &case, |_, _| {});
    let case = Case::parse(&common::model_text("closed-tank2d.toml"))
        .unwrap()
        .with_scheme("rosswog-f1")
        .unwrap();
    save_restore_is_exact("rosswog-f1 with walls", &case, |_, _| {});
}

#[test]
fn a_free_piston_driven_by_a_master_oscillates_at_the_gas_spring_frequency() {
    // The master integrates M ẍ = F − P0 A with symplectic Euler at the communication step
    // and sends position and velocity back (the FMU demo does the same through FMI).
    let case = Case::parse(&common::model_text("free-piston2d.toml")).unwrap();
    let mut c = Coupling::new(&case, &options()).unwrap();
    let piston = c.body_index("piston").unwrap();
    let (mass, p0a, gamma, len): (f64, f64, f64, f64) = (2.0, 0.2, 1.4, 1.0);
    let omega = (gamma * p0a / (mass * len)).sqrt();
    let period = 2.0 * std::f64::consts::PI / omega;
    let (mut x, mut v, h) = (1.0, 0.02, 0.05);
    let mut crossings = vec![];
    let mut t = 0.0;
    while t < 1.15 * period {
        c.set_body_kinematics(
            piston,
            &BodyKinematics {
                position: [x, 0.1, 0.0],
                velocity: [v, 0.0, 0.0],
                ..Default::default()
            },
        )
        .unwrap();
        c.step_to(t + h).unwrap();
        t += h;
        let f = c.loads()[piston].force[0];
        v += (f - p0a) / mass * h;
        let x_new = x + v * h;
        if (x - 1.0) * (x_new - 1.0) < 0.0 {
            crossings.push(t - h + h * (x - 1.0) / (x - x_new));
        }
        x = x_new;
    }
    // x − L0 crosses zero at T/2 and T
    assert!(crossings.len() >= 2, "crossings {crossings:?}");
    let measured = crossings[1];
    println!(
        "free piston: period {measured:.3} (crossings {crossings:?}), gas-spring value {period:.3}, ratio {:.4}",
        measured / period
    );
    // measured: ratio 1.0131 (the gas mass 0.2 against M = 2 predicts +1.6 %); the issue asks 3 %
    assert!((measured / period - 1.0).abs() < 0.03);
}

#[test]
fn probes_and_markers_read_the_hydrostatic_pressure() {
    let text = common::model_text("closed-tank2d.toml")
        + r#"
[[probe]]
name = "mid"
point = [0.5, 0.25]
[[marker]]
name = "floor"
body = "tank"
point = [0.5, 0.0]
[[marker]]
name = "wall"
body = "tank"
point = [0.0, 0.25]
[[patch]]
name = "lid"
body = "tank"
min = [0.1, 0.5]
max = [0.9, 0.7]
"#;
    let case = Case::parse(&text).unwrap();
    let mut c = Coupling::new(&case, &options()).unwrap();
    // time averages over t ∈ [0.5, 1] as in tests/bodies.rs (the acoustic oscillation of
    // the settling tank averages out)
    let (mut p, mut m, mut n) = (ProbeValue::default(), vec![0.0; 2], 0.0);
    let mut patches = [PatchValue::default(); 2];
    let mut t = 0.5;
    c.step_to(t).unwrap();
    while t < 1.0 + 1e-9 {
        let q = c.probes()[0];
        p.pressure += q.pressure;
        p.coverage += q.coverage;
        p.velocity[1] += q.velocity[1];
        for (s, x) in m.iter_mut().zip(c.markers()) {
            *s += x;
        }
        for (s, x) in patches.iter_mut().zip(c.patches()) {
            s.mean_pressure += x.mean_pressure;
            s.peak_pressure = s.peak_pressure.max(x.peak_pressure);
            s.area = x.area;
            s.force[1] += x.force[1];
        }
        n += 1.0;
        t += 0.025;
        c.step_to(t).unwrap();
    }
    p.pressure /= n;
    p.coverage /= n;
    p.velocity[1] /= n;
    m.iter_mut().for_each(|x| *x /= n);
    for s in patches.iter_mut() {
        s.mean_pressure /= n;
        s.force[1] /= n;
    }
    // Tait water from 2e4 Pa at the top: mean ρ 1030.5 kg/m³ over the column
    let exact = |y: f64| 2e4 + 1030.5 * 9.81 * (0.5 - y);
    println!(
        "probe {p:?} (exact P {:.1}); markers {m:?} (exact {:.1}, {:.1})",
        exact(0.25),
        exact(0.0),
        exact(0.25)
    );
    // measured: probe +0.01 %, coverage 0.9988; floor marker −0.95 %, side-wall marker −2.5 %
    // (the fluid next to a wall reads low, as the closed-tank test's wall layers do)
    assert!((p.pressure / exact(0.25) - 1.0).abs() < 0.005);
    assert!((p.coverage - 1.0).abs() < 0.01 && p.velocity[1].abs() < 0.01);
    assert!((m[0] / exact(0.0) - 1.0).abs() < 0.015);
    assert!((m[1] / exact(0.25) - 1.0).abs() < 0.03);
    // patches: the model's floor and the lid above; 40 surface particles each (0.8 m per metre of depth); the first wall layer
    // lies Δx/2 beyond the floor and the lid
    let [floor, lid] = patches;
    println!("patches: floor {floor:?}, lid {lid:?}");
    assert!((floor.area - 0.8).abs() < 1e-12 && (lid.area - 0.8).abs() < 1e-12);
    let floor_force = -floor.force[1] / (exact(0.0) * 0.8);
    let lid_force = lid.force[1] / (exact(0.5) * 0.8);
    println!(
        "floor patch: mean P / exact {:.4}, force / (P A) {floor_force:.4}; lid: mean P / exact {:.4}, force / (P A) {lid_force:.4}",
        floor.mean_pressure / exact(-0.01),
        lid.mean_pressure / exact(0.51)
    );
    // measured: floor force 0.9997 and lid force 0.9953 of P·A; the floor's wall layer reads
    // −1.6 % (the lid's −2.1 %), as the closed-tank test's wall layers do
    assert!((floor.mean_pressure / exact(-0.01) - 1.0).abs() < 0.02);
    assert!((floor_force - 1.0).abs() < 0.02 && (lid_force - 1.0).abs() < 0.02);
    assert!(floor.peak_pressure >= floor.mean_pressure);
}

#[test]
fn bad_inputs_are_clear_errors_and_change_nothing() {
    let case = Case::parse(&common::model_text("free-piston2d.toml")).unwrap();
    let mut c = Coupling::new(&case, &options()).unwrap();
    c.step_to(0.02).unwrap();
    let before = fingerprint(&c);
    let saved = c.save().unwrap();
    let piston = c.body_index("piston").unwrap();
    let end = c.body_index("end").unwrap();
    let k = |x: f64| BodyKinematics {
        position: [x, 0.1, 0.0],
        ..Default::default()
    };
    let errors = [
        c.set_gravity([f64::NAN, 0.0, 0.0]).unwrap_err().0,
        c.set_gravity([0.0, 0.0, -9.81]).unwrap_err().0,
        c.set_body_kinematics(piston, &k(f64::INFINITY))
            .unwrap_err()
            .0,
        c.set_body_kinematics(end, &k(0.0)).unwrap_err().0,
        c.set_body_kinematics(7, &k(0.0)).unwrap_err().0,
        c.body_index("lid").unwrap_err().0,
        c.step_to(0.01).unwrap_err().0,
        c.step_to(f64::NAN).unwrap_err().0,
        c.restore(&saved[..saved.len() / 2]).unwrap_err().0,
        c.restore(b"hello").unwrap_err().0,
    ];
    let expected = [
        "gravity[0]: must be finite, got NaN",
        "gravity[2]: must be 0 in a 2D case",
        "body \"piston\" position[0]: must be finite",
        "body \"end\": its motion is prescribed by the case",
        "body: index 7 out of range",
        "body: no body named \"lid\"",
        "step_to: target time must be finite and ≥ the current time",
        "step_to: target time must be finite",
        "state: damaged",
        "state: not a saved sphfmu state",
    ];
    for (e, want) in errors.iter().zip(expected) {
        assert!(e.starts_with(want), "{e:?} should start with {want:?}");
    }
    assert_eq!(
        fingerprint(&c),
        before,
        "a rejected input changed the state"
    );
    // a state from another case (other resolution) is refused
    let finer = Coupling::new(
        &case,
        &CouplingOptions {
            resolution: 1.25,
            ..options()
        },
    )
    .unwrap();
    let e = c.restore(&finer.save().unwrap()).unwrap_err().0;
    assert!(e.starts_with("state: saved from another case"), "{e}");
    // options out of range
    for (o, want) in [
        (
            CouplingOptions {
                resolution: 0.0,
                ..options()
            },
            "resolution: must be in [0.1, 10]",
        ),
        (
            CouplingOptions {
                cfl: Some(2.0),
                ..options()
            },
            "cfl: must be in (0, 1]",
        ),
        (
            CouplingOptions {
                scheme: Some("sph2000".into()),
                ..options()
            },
            "scheme: unknown preset",
        ),
    ] {
        let e = Coupling::new(&case, &o).err().unwrap().0;
        assert!(e.starts_with(want), "{e}");
    }
    // a marker off every surface, a probe of the wrong length
    let off = common::model_text("free-piston2d.toml")
        .replace("point = [1.0, 0.1]\n", "point = [0.7, 0.1]\n");
    let e = Case::parse(&off).unwrap_err().0;
    assert!(
        e.contains("marker[0].point") && e.contains("within one wall spacing"),
        "{e}"
    );
    let short =
        common::model_text("free-piston2d.toml").replace("point = [0.5, 0.1]", "point = [0.5]");
    let e = Case::parse(&short).unwrap_err().0;
    assert!(e.starts_with("probe[0].point: must have 2 entries"), "{e}");
}

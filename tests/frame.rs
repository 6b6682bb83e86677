//! The non-inertial frame option (issue 5, `[frame]`): a tank's motion applied as fictitious
//! forces in the tank's frame instead of moving its walls.

use crate::common;
use sphfmu::case::Case;

/// (time, water's centre of mass x relative to the tank, horizontal force on the tank).
fn accelerated_tank(text: &str, t_end: f64) -> Vec<(f64, f64, f64)> {
    let mut sim = Case::parse(text).unwrap().build::<2>().unwrap();
    let mut out = vec![];
    while sim.time < t_end {
        sim.step(t_end - sim.time).unwrap();
        let p = &sim.sys.particles;
        let (mut mx, mut m) = (0.0, 0.0);
        for i in (0..p.len()).filter(|&i| p.body[i] == 0) {
            mx += p.mass[i] * p.pos[i][0];
            m += p.mass[i];
        }
        let tank = &sim.sys.bodies[0];
        out.push((sim.time, mx / m - tank.pose.displacement[0], tank.force[0]));
    }
    out
}

/// Linear interpolation of column `k` of a time series at t.
fn at(series: &[(f64, f64, f64)], t: f64, k: usize) -> f64 {
    let i = series
        .partition_point(|s| s.0 < t)
        .clamp(1, series.len() - 1);
    let (a, b) = (series[i - 1], series[i]);
    let col = |s: (f64, f64, f64)| if k == 1 { s.1 } else { s.2 };
    col(a) + (col(b) - col(a)) * (t - a.0) / (b.0 - a.0)
}

#[test]
fn a_frame_acceleration_equals_moving_the_walls() {
    // The open tank accelerates at 0.1 m/s² for 0.5 s (a velocity ramp to 0.05 m/s), then
    // coasts: the water sloshes. Once with the walls moved through the box, once at rest in
    // the tank's frame with the fictitious force −A.
    let ramp = r#"motion = { type = "ramp", velocity = [0.05, 0.0], ramp_time = 0.5 }"#;
    let shape = r#"shape = { type = "tank", min = [0.0, 0.0], max = [1.0, 0.8] }"#;
    let moving = common::model_text("tank2d.toml").replace(shape, &format!("{shape}\n{ramp}"));
    let framed = format!("{}\n[frame]\n{ramp}\n", common::model_text("tank2d.toml"));
    // to t = 0.8 (0.3 s of free sloshing after the ramp); 1.2 s gave the same figures
    let t_end = 0.8;
    let a = accelerated_tank(&moving, t_end);
    let b = accelerated_tank(&framed, t_end);
    let (mut dx, mut sx, mut df, mut sf) = (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64);
    let x0 = a[0].1;
    for k in 1..=16 {
        let t = 0.05 * k as f64;
        dx = dx.max((at(&a, t, 1) - at(&b, t, 1)).abs());
        sx = sx.max((at(&a, t, 1) - x0).abs());
        df = df.max((at(&a, t, 2) - at(&b, t, 2)).abs());
        sf = sf.max(at(&a, t, 2).abs());
    }
    println!(
        "frame vs moving walls: centre of mass {:.2e} m of a {sx:.2e} m swing ({:.2} %), force {df:.3} N/m of {sf:.3} ({:.2} %)",
        dx,
        100.0 * dx / sx,
        100.0 * df / sf
    );
    // the water does slosh: 0.1 m/s² on 1000 × 0.5 kg/m tilts the surface by 0.6°
    assert!(sx > 5e-4, "swing {sx}");
    // measured: centre of mass 0.09 % of the swing, force 0.85 % of its largest value (the
    // runs differ in where the walls sit in the box — other neighbour lists and round-off —
    // and in how the wall condition gets the acceleration: a_w of the moving walls, the
    // frame force at the resting ones)
    assert!(dx < 0.01 * sx, "centre of mass: {dx} of {sx}");
    assert!(df < 0.02 * sf, "force: {df} of {sf}");
}

#[test]
fn a_spinning_closed_tank_holds_the_centrifugal_pressure() {
    // Water in the closed box, no gravity, in a frame spinning at Ω = 4 rad/s about the box
    // centre from t = 0 (the water co-rotating): at rest in the frame, P = P_c + ½ρΩ²r².
    let omega = 4.0;
    let text = common::model_text("closed-tank2d.toml")
        .replace("gravity = [0.0, -9.81]\n", "")
        .replace("hydrostatic = true\n", "")
        + &format!(
            "\n[frame]\nmotion = {{ type = \"ramp\", velocity = [0.0, 0.0], angular_velocity = {omega}, ramp_time = 0.0 }}\nreference = [0.5, 0.25]\n"
        );
    let mut sim = Case::parse(&text).unwrap().build::<2>().unwrap();
    // mean pressure and mean r² of the particles within r < 0.12 and with r > 0.3
    let rings = |sim: &sphfmu::sim::Simulation<2>| {
        let p = &sim.sys.particles;
        let mut s = [[0.0; 3]; 2];
        for i in (0..p.len()).filter(|&i| p.body[i] == 0) {
            let r2 = (p.pos[i][0] - 0.5).powi(2) + (p.pos[i][1] - 0.25).powi(2);
            let k = if r2 < 0.12 * 0.12 {
                0
            } else if r2 > 0.09 {
                1
            } else {
                continue;
            };
            s[k][0] += p.pressure[i];
            s[k][1] += r2;
            s[k][2] += 1.0;
        }
        let m = |k: usize| (s[k][0] / s[k][2], s[k][1] / s[k][2]);
        (m(0), m(1))
    };
    let (mut dp, mut dp_exact, mut n, mut vmax) = (0.0, 0.0, 0.0, 0.0_f64);
    while sim.time < 0.6 {
        sim.step(0.6 - sim.time).unwrap();
        if sim.time >= 0.3 {
            let ((p0, r0), (p1, r1)) = rings(&sim);
            dp += p1 - p0;
            dp_exact += 0.5 * 1000.0 * omega * omega * (r1 - r0);
            n += 1.0;
            let p = &sim.sys.particles;
            vmax = (0..p.len())
                .filter(|&i| p.body[i] == 0)
                .map(|i| p.vel[i].norm())
                .fold(vmax, f64::max);
        }
    }
    let ratio = dp / dp_exact;
    println!(
        "spinning tank: outer − inner ring pressure {:.1} Pa, ½ρΩ²Δ⟨r²⟩ {:.1} Pa ({:+.2} %), largest speed in the frame {vmax:.2e} m/s",
        dp / n,
        dp_exact / n,
        100.0 * (ratio - 1.0)
    );
    // measured −0.75 % (ρ = 1000 in the exact value; the water is compressed by
    // P/(ρc²) ≈ 3 %, which would raise it: the bound allows that)
    assert!((ratio - 1.0).abs() < 0.04, "ratio {ratio}");
    // the water stays nearly at rest in the rotating frame (Ωr ≈ 2 m/s in the lab): measured
    // 0.081 m/s, the acoustic settling from the uniform start, ΔP/(ρc) ≈ 1300/(1000·25) = 0.05
    assert!(vmax < 0.15, "largest speed {vmax}");
}

#[test]
fn bad_frames_are_clear_errors() {
    let base = common::model_text("tank2d.toml");
    for (frame, msg) in [
        (
            "motion = { type = \"external\" }\norientation = \"matrix\"",
            "frame.orientation: \"matrix\" is for a 3D frame",
        ),
        (
            r#"motion = { type = "table", time = [0.0, 1.0], displacement = [[0.0, 0.0], [0.1, 0.0]] }"#,
            "frame.motion: a table",
        ),
        (
            r#"motion = { type = "ramp", velocity = [0.0, 0.0], angular_velocity = nan, ramp_time = 1.0 }"#,
            "frame.motion.angular_velocity",
        ),
        (
            "motion = { type = \"fixed\" }\naxis = [0.0, 0.0, 1.0]",
            "frame.axis: only in 3D",
        ),
        (
            "motion = { type = \"fixed\" }\nreference = [0.5]",
            "frame.reference",
        ),
    ] {
        let err = Case::parse(&format!("{base}\n[frame]\n{frame}\n"))
            .expect_err("must fail")
            .0;
        assert!(err.contains(msg), "{err}");
    }
}

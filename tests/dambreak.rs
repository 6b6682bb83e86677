//! Dam break (models/dambreak2d.toml): the surge front against Martin & Moyce (1952) and the
//! impact on the block.

use crate::common;
use sphfmu::case::Case;

/// Martin & Moyce (1952), Phil. Trans. R. Soc. A 244, 312–324, Fig. 3, n² = 2: (T, Z) with
/// T = t √(2g/a), Z = x/a, for columns a = 1.125 in and a = 2.25 in, as digitised in PySPH's
/// examples (pysph/examples/db_exp_data.py); the points before the block (Z < 3.8).
const MARTIN_MOYCE: [(f64, f64); 9] = [
    (0.849, 1.245),
    (1.212, 1.443),
    (1.602, 1.884),
    (2.283, 2.689),
    (2.950, 3.728),
    (0.832, 1.217),
    (1.219, 1.474),
    (1.997, 2.292),
    (2.547, 2.995),
];

#[test]
fn the_surge_front_follows_martin_and_moyce_and_hits_the_block() {
    let case = Case::load(&common::model_path("dambreak2d.toml")).unwrap();
    let mut sim = case.build::<2>().unwrap();
    let (a, g): (f64, f64) = (0.2, 9.81);
    let scale = (2.0 * g / a).sqrt();
    let mut points: Vec<(f64, f64)> = MARTIN_MOYCE.to_vec();
    points.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut worst: f64 = 0.0;
    let mut table = String::new();
    let mut late: Vec<(f64, f64, f64)> = vec![];
    for (t_exp, z_exp) in points {
        sim.advance_to(t_exp / scale, |_| {}).unwrap();
        let p = &sim.sys.particles;
        let front = (0..p.len())
            .filter(|&i| p.body[i] == 0)
            .map(|i| p.pos[i][0])
            .fold(f64::NEG_INFINITY, f64::max);
        let z = front / a;
        table.push_str(&format!(" (T {t_exp:.2}: Z {z:.3} vs {z_exp:.3})"));
        worst = worst.max((z / z_exp - 1.0).abs());
        if t_exp > 1.2 {
            late.push((t_exp, z, z_exp));
        }
    }
    // front speed dZ/dT after the first acceleration: least-squares slopes
    let slope = |pick: &dyn Fn(&(f64, f64, f64)) -> f64| {
        let n = late.len() as f64;
        let (st, sz) = late
            .iter()
            .fold((0.0, 0.0), |(a, b), q| (a + q.0, b + pick(q)));
        let (mt, mz) = (st / n, sz / n);
        let num: f64 = late.iter().map(|q| (q.0 - mt) * (pick(q) - mz)).sum();
        let den: f64 = late.iter().map(|q| (q.0 - mt).powi(2)).sum();
        num / den
    };
    let (s_sph, s_exp) = (slope(&|q| q.1), slope(&|q| q.2));
    println!(
        "dam break front:{table}; worst {worst:.3}; front speed dZ/dT for T > 1.2: {s_sph:.3} vs {s_exp:.3}"
    );
    // measured: the front runs ahead of the experiment by 0.12 to 0.33 in Z (worst 16.4 %),
    // at the experiment's speed (slope 1.269 against 1.254, +1.2 %): the lead builds up in the first instants, as
    // in other SPH and VOF solutions of this case, which ascribe it to the release of the
    // experiment's column (not instantaneous); the speed is the physics checked tightly
    assert!(worst < 0.2, "front off by {worst}");
    assert!(
        (s_sph / s_exp - 1.0).abs() < 0.05,
        "front speed {s_sph} vs {s_exp}"
    );
    // the surge reaches the block (x = 0.8) and pushes it downstream
    let mut peak: f64 = 0.0;
    sim.advance_to(0.45, |s| peak = peak.max(s.sys.bodies[1].force[0]))
        .unwrap();
    println!("peak horizontal force on the block up to t = 0.45: {peak:.1} N/m");
    assert!(peak > 100.0, "no impact on the block: {peak}");
    // nothing gets past the first layer of wall particles, Δx/2 = 0.005 behind the surfaces
    // (measured: one particle 0.0026 below the floor in the wake of the block at t = 0.45)
    let p = &sim.sys.particles;
    let out: Vec<_> = (0..p.len())
        .filter(|&i| p.body[i] == 0)
        .filter(|&i| !(p.pos[i][0] > -0.005 && p.pos[i][0] < 1.205 && p.pos[i][1] > -0.005))
        .map(|i| (p.pos[i][0], p.pos[i][1]))
        .collect();
    assert!(out.is_empty(), "particles outside the tank: {out:?}");
}

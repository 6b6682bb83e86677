//! `sphfmu bench`'s table: every size is timed over the same steps of a fresh box, repeated
//! until it reaches the particle-updates asked for, so sizes are compared over the same
//! stretch of the run.

use sphfmu::bench::run_table;

#[test]
fn small_sizes_repeat_the_same_window_instead_of_running_longer() {
    // 400 particles (a 20 × 20 lattice), windows of 3 steps, at least 4,000 updates: 4 repeats
    let rows = run_table(&[400], &[2], (3, 4000), "cubic-spline", None).unwrap();
    let r = &rows[0];
    assert_eq!((r.particles, r.steps, r.repeats), (400, 3, 4));
    let updates = r.particle_updates_per_second * r.seconds;
    assert!((updates - 400.0 * 12.0).abs() < 1e-6 * updates, "{updates}");
    // each repeat times the same three steps of the same run: the force pairs are four times
    // those of one window
    let one = &run_table(&[400], &[2], (3, 0), "cubic-spline", None).unwrap()[0];
    assert_eq!(one.repeats, 1);
    let pairs = |r: &sphfmu::bench::BenchRow| (r.force_pairs_per_second * r.seconds).round();
    assert_eq!(pairs(r), 4.0 * pairs(one));
}

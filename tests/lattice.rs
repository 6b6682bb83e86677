//! Lattices from case files fill the box at the requested density: the summation density
//! on periodic cubic, hexagonal (2D) and close-packed (3D) lattices matches ρ. Masses carry
//! each lattice's kernel-sum factor (`case::ics::lattice_density_factor`); before it, the
//! errors below were 1.76e-3, 1.10e-4, 8.47e-4 and 2.28e-3, the lattices' own discretisation
//! errors.

use sphfmu::case::Case;

fn periodic_box(d: usize, lattice: &str, kernel: &str, eta: f64) -> String {
    let v = |x: f64| format!("[{}]", vec![format!("{x}"); d].join(", "));
    format!(
        r#"
[case]
name = "lattice"
dimension = {d}
[domain]
min = {lo}
max = {hi}
boundary = [{b}]
[eos]
type = "ideal-gas"
gamma = 1.4
[kernel]
name = "{kernel}"
eta = {eta}
[time]
t_end = 1.0
[[region]]
lattice = "{lattice}"
spacing = 0.05
density = 2.5
pressure = 1.0
"#,
        lo = v(0.0),
        hi = v(1.0),
        b = vec!["\"periodic\""; d].join(", ")
    )
}

fn mean_density_error<const D: usize>(text: &str) -> (f64, usize) {
    let sim = Case::parse(text).unwrap().build::<D>().unwrap();
    let p = &sim.sys.particles;
    let err = p.rho.iter().map(|r| (r / 2.5 - 1.0).abs()).sum::<f64>() / p.len() as f64;
    (err, p.len())
}

#[test]
fn lattices_reproduce_the_requested_density() {
    // (dimension, lattice, kernel, η, tolerance from measurement)
    let (e, n) = mean_density_error::<1>(&periodic_box(1, "cubic", "cubic-spline", 1.2));
    assert_eq!(n, 20);
    println!("1D cubic, M4 η=1.2: {e:.3e}");
    // measured 6.1e-8 (the h iteration's tolerance)
    assert!(e < 1e-6, "1D cubic {e}");
    let (e, n) = mean_density_error::<2>(&periodic_box(2, "cubic", "wendland-c6", 2.2));
    assert_eq!(n, 400);
    println!("2D cubic, C6 η=2.2: {e:.3e}");
    // measured 4.8e-12
    assert!(e < 1e-9, "2D cubic {e}");
    let (e, n) = mean_density_error::<2>(&periodic_box(2, "hexagonal", "cubic-spline", 1.2));
    println!("2D hexagonal, M4 η=1.2: mean |ρ/ρ0 − 1| = {e:.3e}, {n} particles");
    // Rosswog (2015) Sec. 3.6; also Sec. 4.2.3: 9.0e-4 for M4, η = 1.2 on a perfect hexagonal
    // lattice (8.47e-4 here before the factor). What is left, measured 3.3e-5, comes from the
    // 20 × 24-row box stretching the rows by < 4 % (the factor is the unstretched lattice's).
    assert!(e < 1e-4, "2D hexagonal {e}");
    let (e, n) = mean_density_error::<3>(&periodic_box(3, "hexagonal", "wendland-c2", 1.6));
    println!("3D close-packed, C2 η=1.6: mean |ρ/ρ0 − 1| = {e:.3e}, {n} particles");
    // measured 7.1e-7 (rows and layers stretched by up to 4 % to tile the box)
    assert!(e < 1e-5, "3D hcp {e}");
}

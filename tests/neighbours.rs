//! The grid neighbour search equals the O(N²) reference on random, clustered and periodic sets.

use crate::common;
use sphfmu::domain::{BoundaryKind, Domain};
use sphfmu::neighbours::{brute_force, CellGrid, NeighbourList};
use sphfmu::particles::Vector;

struct Rng(u64);
impl Rng {
    fn u(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Every row of `list` holds the entries of the brute-force `reference` (in any order);
/// returns the entry count.
fn assert_same_lists(list: &NeighbourList, reference: &[Vec<u32>], label: &str) -> usize {
    let mut total = 0;
    for (a, want) in reference.iter().enumerate() {
        let mut got = list.of(a).to_vec();
        got.sort_unstable();
        assert_eq!(&got, want, "particle {a} {label}");
        total += got.len();
    }
    total
}

/// The simulation's working list equals brute force over its current positions and
/// kernel supports 2h.
fn assert_working_list_exact(sim: &sphfmu::sim::Simulation<2>, label: &str) {
    let p = &sim.sys.particles;
    let reach: Vec<f64> = p.h.iter().map(|&h| 2.0 * h).collect();
    let reference = brute_force(&p.pos, &reach, &sim.sys.domain);
    assert_same_lists(&sim.sys.neighbours, &reference, label);
}

fn check<const D: usize>(pos: &[Vector<D>], reach: &[f64], dom: &Domain<D>) -> usize {
    let grid = CellGrid::build(pos, dom, reach);
    let list = NeighbourList::build(pos, reach, dom, &grid);
    assert_same_lists(&list, &brute_force(pos, reach, dom), "")
}

fn domain<const D: usize>(kind: BoundaryKind) -> Domain<D> {
    Domain {
        lo: [0.0; D],
        hi: [1.0; D],
        kind: [kind; D],
    }
}

#[test]
fn random_sets_with_variable_h_all_boundaries() {
    let mut rng = Rng(0x1234_5678);
    for kind in [
        BoundaryKind::Open,
        BoundaryKind::Periodic,
        BoundaryKind::Reflect,
    ] {
        let pos: Vec<Vector<2>> = (0..1500)
            .map(|_| Vector::<2>::new(rng.u(), rng.u()))
            .collect();
        let reach: Vec<f64> = (0..1500).map(|_| 0.02 + 0.06 * rng.u()).collect();
        let n = check(&pos, &reach, &domain::<2>(kind));
        assert!(
            n > 10_000,
            "{kind:?}: too few pairs ({n}) for a meaningful test"
        );
        let pos3: Vec<Vector<3>> = (0..1500)
            .map(|_| Vector::<3>::new(rng.u(), rng.u(), rng.u()))
            .collect();
        let reach3: Vec<f64> = (0..1500).map(|_| 0.05 + 0.1 * rng.u()).collect();
        check(&pos3, &reach3, &domain::<3>(kind));
        let pos1: Vec<Vector<1>> = (0..500).map(|_| Vector::<1>::new(rng.u())).collect();
        let reach1: Vec<f64> = (0..500).map(|_| 0.005 + 0.02 * rng.u()).collect();
        check(&pos1, &reach1, &domain::<1>(kind));
    }
}

#[test]
fn clustered_sets_with_strongly_varying_h() {
    let mut rng = Rng(99);
    // A dense clump (small h) inside a sparse background (large h): scatter neighbours matter.
    let mut pos = Vec::new();
    let mut reach = Vec::new();
    for _ in 0..1200 {
        pos.push(Vector::<2>::new(
            0.5 + 0.03 * (rng.u() - 0.5),
            0.5 + 0.03 * (rng.u() - 0.5),
        ));
        reach.push(0.004 + 0.004 * rng.u());
    }
    for _ in 0..400 {
        pos.push(Vector::<2>::new(rng.u(), rng.u()));
        reach.push(0.08 + 0.04 * rng.u());
    }
    for kind in [
        BoundaryKind::Open,
        BoundaryKind::Periodic,
        BoundaryKind::Reflect,
    ] {
        check(&pos, &reach, &domain::<2>(kind));
    }
}

#[test]
fn periodic_and_mirror_images_reach_across_faces() {
    // Two particles near opposite faces: periodic sees each other; reflect sees own mirrors.
    let pos = vec![Vector::<2>::new(0.01, 0.5), Vector::<2>::new(0.99, 0.5)];
    let reach = vec![0.05, 0.05];
    let per = domain::<2>(BoundaryKind::Periodic);
    let grid = CellGrid::build(&pos, &per, &reach);
    let l = NeighbourList::build(&pos, &reach, &per, &grid);
    assert_eq!(l.of(0).len(), 1);
    let refl = domain::<2>(BoundaryKind::Reflect);
    let grid = CellGrid::build(&pos, &refl, &reach);
    let l = NeighbourList::build(&pos, &reach, &refl, &grid);
    // each sees only its own mirror image across its nearest face
    assert_eq!(l.of(0).len(), 1);
    let (b, code) = sphfmu::neighbours::unpack(l.of(0)[0]);
    assert_eq!((b, code), (0, 1));
    let d = refl.separation(&pos[0], &pos[0], code);
    assert!((d[0] - 0.02).abs() < 1e-15);
}

/// The reused master list keeps the working list exact while particles move and h changes:
/// after several steps of a flow, the working list equals brute force at radius max(2h_a, 2h_b).
#[test]
fn reused_lists_stay_exact_while_particles_move() {
    let text = r#"
[case]
name = "moving"
dimension = 2
[domain]
min = [0.0, 0.0]
max = [1.0, 1.0]
boundary = ["periodic", "reflect"]
[eos]
type = "ideal-gas"
gamma = 1.4
[time]
t_end = 1.0
[[region]]
spacing = 0.025
density = 1.0
pressure = 1.0
velocity = [0.5, 0.0]
[[region]]
shape = "sphere"
center = [0.5, 0.5]
radius = 0.2
spacing = 0.025
density = 1.0
pressure = 4.0
[perturbation]
amplitude = 0.2
seed = 3
"#;
    let case = sphfmu::case::Case::parse(text).unwrap();
    let mut sim = case.build::<2>().unwrap();
    let builds0 = sim.sys.verlet.builds;
    for _ in 0..12 {
        sim.step(f64::INFINITY).unwrap();
        assert_working_list_exact(&sim, &format!("at step {}", sim.steps));
    }
    // the point of the skin: fewer builds than evaluations
    assert!(
        sim.sys.verlet.builds - builds0 < 12,
        "master list rebuilt every step"
    );
}

/// A gas that moves as a whole keeps its master list: the rebuild test measures each
/// particle's displacement from the common drift, so a uniform flow several smoothing lengths
/// per step fast (the skin would be gone in one step if measured from rest) never rebuilds,
/// and the working list stays exact.
#[test]
fn uniform_drift_keeps_the_master_list() {
    let text = common::header(2, 0.0, 1.0, "periodic", 1.4)
        + "[time]\nt_end = 1.0\n[[region]]\nspacing = 0.025\ndensity = 1.0\npressure = 1.0\nvelocity = [3.0, 2.0]\n";
    let case = sphfmu::case::Case::parse(&text).unwrap();
    let mut sim = case.build::<2>().unwrap();
    sim.step(f64::INFINITY).unwrap();
    let builds0 = sim.sys.verlet.builds;
    let x0 = sim.sys.particles.pos[0];
    let h = sim.sys.particles.h[0];
    let mut moved = 0.0;
    // the first steps are short (dt grows by at most 1.5 per step): go on until the flow has
    // crossed two smoothing lengths, far more than the skin of 0.15·2h
    while moved < 2.0 * h && sim.steps < 200 {
        sim.step(f64::INFINITY).unwrap();
        moved = sim
            .sys
            .domain
            .separation(&sim.sys.particles.pos[0], &x0, 0)
            .norm();
    }
    assert!(moved > 2.0 * h, "the flow moved only {moved} (h = {h})");
    assert_eq!(
        sim.sys.verlet.builds, builds0,
        "master list rebuilt under a uniform drift"
    );
    assert_working_list_exact(&sim, "after the drift");
}

/// The grid search equals brute force on the master lists' own build states of a violent
/// periodic flow integrated with SSP-RK3: positions between drifts may lie just outside the
/// box (one did at step 23 when the search first filed cells by exact periods) and must still
/// find every neighbour through the right image.
#[test]
fn build_matches_brute_force_on_integrator_states() {
    // the conservation tests' violent periodic box, standard SPH
    let text = common::random_box(
        "name = \"standard\"",
        "integrator = \"ssp-rk3\"",
        (0.025, 0.02),
    );
    let case = sphfmu::case::Case::parse(&text).unwrap();
    let mut sim = case.build::<2>().unwrap();
    let mut outside = 0;
    for step in 0..40 {
        sim.step(f64::INFINITY).unwrap();
        let v = &sim.sys.verlet;
        let dom = &sim.sys.domain;
        outside += v
            .pos
            .iter()
            .filter(|x| (0..2).any(|k| x[k] < dom.lo[k] || x[k] >= dom.hi[k]))
            .count();
        let grid = CellGrid::build(&v.pos, dom, &v.reach);
        let l = NeighbourList::build(&v.pos, &v.reach, dom, &grid);
        let reference = brute_force(&v.pos, &v.reach, dom);
        assert_same_lists(&l, &reference, &format!("at step {step}"));
    }
    println!("build states with a particle outside the box: {outside} particle-steps");
    assert!(
        outside > 0,
        "no build state had a particle outside the box: the test would not show what it is for"
    );
}

/// Reordering numbers the particles in the grid's cell order even when the particles were
/// renumbered since the grid was built, and a second reorder without a rebuild in between
/// changes nothing. The grid's cell order was once left in the numbering of its build, so a
/// case that rarely rebuilds (the closed tank: one build in 7,728 steps) applied that stale
/// permutation again every 20 steps and scrambled its particles' order.
#[test]
fn reorder_follows_the_cells_through_renumbering() {
    let text = common::header(2, 0.0, 1.0, "periodic", 1.4)
        + "[time]\nt_end = 1.0\n[[region]]\nspacing = 0.05\ndensity = 1.0\npressure = 1.0\n";
    let case = sphfmu::case::Case::parse(&text).unwrap();
    let mut sim = case.build::<2>().unwrap();
    sim.step(f64::INFINITY).unwrap();
    let n = sim.sys.particles.len();
    assert_eq!(sim.sys.grid.sorted.len(), n, "the first step built a grid");
    // any renumbering: here the reverse order
    let reverse: Vec<u32> = (0..n as u32).rev().collect();
    sim.sys.permute_particles(&reverse);
    sim.reorder();
    // a grid built afresh on the same build positions lists the particles in index order
    let v = &sim.sys.verlet;
    let identity: Vec<u32> = (0..n as u32).collect();
    assert_eq!(
        CellGrid::build(&v.pos, &sim.sys.domain, &v.reach).sorted,
        identity,
        "after a reorder particle i is the i-th in cell order"
    );
    assert_eq!(sim.sys.grid.sorted, identity, "the grid's order renamed");
    let ids: Vec<_> = sim.sys.particles.id.clone();
    sim.reorder();
    assert_eq!(
        sim.sys.particles.id, ids,
        "a second reorder renumbered again"
    );
    // and the lists that came along still match the positions
    sim.step(f64::INFINITY).unwrap();
    assert_working_list_exact(&sim, "after the reorders");
}

//! The distributed run (`sphfmu::parallel`) with ranks as threads: the same case on 1, 2 and
//! 3 ranks gives the same particles, bit for bit, and conserves as a single process does.

use crate::common::random_box;
use sphfmu::case::Case;
use sphfmu::coupling::{Coupling, CouplingOptions};
use sphfmu::parallel::{self, comm::Comm, comm::Reduce, comm::ThreadRanks};
use sphfmu::particles::Particles;
use sphfmu::sim::Diagnostics;
use std::sync::Arc;

/// What a run on several ranks ends with, as rank 0 sees it.
struct Outcome<const D: usize> {
    /// Every rank's particles, by id.
    particles: Particles<D>,
    before: Diagnostics,
    after: Diagnostics,
    /// Each body's force and torque (z) after the last step.
    loads: Vec<Vec<f64>>,
    /// Each port's mass in and out.
    flows: Vec<[f64; 2]>,
}

/// Run `text` on `ranks` thread ranks for `steps` steps; every rank's particles, by id, and
/// the totals before and after.
fn run_on(text: &str, ranks: usize, steps: usize) -> (Particles<2>, Diagnostics, Diagnostics) {
    let o = run_with::<2>(text, ranks, steps, None);
    (o.particles, o.before, o.after)
}

/// [`run_on`] in `D` dimensions with the halo `depth` supports deep (`None`: the scheme's
/// own), with the bodies' loads and the ports' flows.
fn run_with<const D: usize>(
    text: &str,
    ranks: usize,
    steps: usize,
    depth: Option<usize>,
) -> Outcome<D> {
    let case = Case::parse(text).expect("case parses");
    let handles: Vec<_> = ThreadRanks::group(ranks)
        .into_iter()
        .map(|comm| {
            let case = case.clone();
            std::thread::spawn(move || {
                let comm: Arc<dyn Comm> = Arc::new(comm);
                let sys = case.system::<D>().expect("system");
                let scheme = case.scheme.build::<D>();
                let depth = depth.unwrap_or(parallel::halo_depth(&sys, &*scheme));
                let mut sim = parallel::start_with_halo(
                    sys,
                    scheme,
                    case.integrator(),
                    case.step_control(),
                    comm.clone(),
                    depth,
                )
                .expect("distributed start");
                let before = sim.diagnostics();
                for _ in 0..steps {
                    sim.step(f64::INFINITY).expect("step");
                }
                let after = sim.diagnostics();
                let moved = sim.layout.as_ref().map_or(0, |l| l.exchange().1.migrated);
                let moved = Reduce::sum(&*comm, &[moved as f64]).expect("sum")[0];
                if ranks > 1 {
                    // the comparison covers particles changing hands, not only halos
                    assert!(moved > 0.0, "no particle changed ranks in {steps} steps");
                }
                let loads = sim
                    .sys
                    .bodies
                    .iter()
                    .map(|b| b.force.iter().copied().chain([b.torque[2]]).collect())
                    .collect();
                let flows = sim
                    .sys
                    .ports
                    .iter()
                    .map(|p| [p.mass_in, p.mass_out])
                    .collect();
                let particles = parallel::gather_particles(&sim, &*comm).expect("gather");
                Outcome {
                    particles,
                    before,
                    after,
                    loads,
                    flows,
                }
            })
        })
        .collect();
    let mut out: Vec<_> = handles
        .into_iter()
        .map(|h| h.join().expect("rank thread"))
        .collect();
    out.swap_remove(0)
}

/// The first particle (by id) where two runs differ in position, velocity or u, if any.
fn first_difference<const D: usize>(a: &Particles<D>, b: &Particles<D>) -> Option<String> {
    assert_eq!(a.len(), b.len(), "particle counts");
    (0..a.len()).find_map(|i| {
        (a.pos[i] != b.pos[i] || a.vel[i] != b.vel[i] || a.u[i].to_bits() != b.u[i].to_bits()).then(
            || {
                format!(
                    "particle {}: x {:?} vs {:?}, v {:?} vs {:?}, u {:e} vs {:e}",
                    a.id[i], a.pos[i], b.pos[i], a.vel[i], b.vel[i], a.u[i], b.u[i]
                )
            },
        )
    })
}

/// The violent random periodic box (a disc crossing a moving background) after 50 steps on
/// 1, 2 and 3 ranks: equal to the bit. A halo of the skin alone (no kernel support deep)
/// must change them, or the comparison could not fail. (Every Newtonian scheme refreshes its
/// halo's fields between passes, and its halo is one support deep; with the refreshes
/// removed, each scheme tested here gave other particles on 2 or 3 ranks, and CRKSPH's
/// energy drift on 3 ranks grew from 1e-15 to 3e-7.)
fn same_on_1_2_3_ranks(scheme: &str) {
    let text = random_box(scheme, "", (0.04, 0.028));
    let (one, _, _) = run_on(&text, 1, 50);
    for ranks in [2, 3] {
        let (many, _, _) = run_on(&text, ranks, 50);
        if let Some(d) = first_difference(&one, &many) {
            panic!("{scheme}: 1 rank against {ranks}: {d}");
        }
    }
    let thin = run_with::<2>(&text, 2, 50, Some(0));
    assert!(
        first_difference(&one, &thin.particles).is_some(),
        "{scheme}: a halo of the skin alone gave the same particles"
    );
}

#[test]
fn standard_sph_is_bit_identical_on_1_2_3_ranks() {
    same_on_1_2_3_ranks("name = \"standard\"");
}

/// rpSPH runs the standard passes with their halo refreshes (its own force form reads the
/// same neighbour fields).
#[test]
fn rpsph_is_bit_identical_on_1_2_3_ranks() {
    same_on_1_2_3_ranks("name = \"rpsph\"");
}

#[test]
fn standard_sph_with_cullen_dehnen_is_bit_identical_on_1_2_3_ranks() {
    same_on_1_2_3_ranks("name = \"standard\"\ncullen_dehnen = true");
}

#[test]
fn compatible_sph_is_bit_identical_on_1_2_3_ranks() {
    same_on_1_2_3_ranks("name = \"compsph\"");
}

#[test]
fn compatible_sph_with_cullen_dehnen_is_bit_identical_on_1_2_3_ranks() {
    same_on_1_2_3_ranks("name = \"compsph-cullen\"");
}

#[test]
fn psph_is_bit_identical_on_1_2_3_ranks() {
    same_on_1_2_3_ranks("name = \"psph\"");
}

#[test]
fn crksph_is_bit_identical_on_1_2_3_ranks() {
    same_on_1_2_3_ranks("name = \"crksph\"");
}

#[test]
fn rosswog_f1_is_bit_identical_on_1_2_3_ranks() {
    same_on_1_2_3_ranks("name = \"rosswog-f1\"");
}

#[test]
fn rosswog_f2_is_bit_identical_on_1_2_3_ranks() {
    same_on_1_2_3_ranks("name = \"rosswog-f2\"");
}

#[test]
fn rosswog_f3_is_bit_identical_on_1_2_3_ranks() {
    same_on_1_2_3_ranks("name = \"rosswog-f3\"");
}

#[test]
fn rosswog_f4_is_bit_identical_on_1_2_3_ranks() {
    same_on_1_2_3_ranks("name = \"rosswog-f4\"");
}

/// The special-relativistic F1–F4 (c = 1; the box's speeds, 0.36 and 0.41, stay well below it)
/// share the Newtonian loop's halo refreshes; their primitive recovery runs on the halo copies
/// from refreshed N and the carried S and ε, so it gives the owners' bits there too.
#[test]
fn rosswog_sr_f1_to_f4_are_bit_identical_on_1_2_3_ranks() {
    for preset in ["f1", "f2", "f3", "f4"] {
        same_on_1_2_3_ranks(&format!("name = \"rosswog-sr-{preset}\""));
    }
}

/// Conservation on several ranks is as good as on one: CRKSPH's energy (compatible update,
/// round-off) and momentum over 50 steps of the random box, on 1 and 3 ranks. The totals are
/// sums of per-rank sums, so they may differ in the last bits; the drifts must agree to
/// 1e-13 of the total (measured: energy drift -2.2e-15 on 1 rank, 3.7e-15 on 3; momentum
/// 5.0e-15 and 4.2e-16, the summation order alone).
#[test]
fn crksph_conserves_on_3_ranks_as_on_1() {
    let text = random_box("name = \"crksph\"", "", (0.04, 0.028));
    let drift = |ranks| {
        let (_, d0, d1) = run_on(&text, ranks, 50);
        assert_eq!(d0.fluid_particles, d1.fluid_particles);
        let e = (d1.total_energy - d0.total_energy) / d0.total_energy.abs();
        let p = (0..2)
            .map(|k| (d1.momentum[k] - d0.momentum[k]).abs())
            .fold(0.0, f64::max);
        (e, p, d0.fluid_particles)
    };
    let (e1, p1, n1) = drift(1);
    let (e3, p3, n3) = drift(3);
    eprintln!("energy drift 1 rank {e1:e}, 3 ranks {e3:e}; momentum {p1:e} / {p3:e}");
    assert_eq!(n1, n3, "every particle counted once");
    assert!(e1.abs() < 1e-12, "CRKSPH energy drift on one rank {e1:e}");
    assert!(
        (e3 - e1).abs() < 1e-13,
        "energy drift {e3:e} on 3 ranks, {e1:e} on 1"
    );
    assert!(p3 < 1e-12 && p1 < 1e-12, "momentum drift {p1:e} / {p3:e}");
}

/// A case on 1, 2 and 3 ranks, `steps` steps: the particles, the bodies' loads and the
/// ports' flows equal to the bit.
/// A halo of the skin alone must change the particles on 2 ranks, or the comparison could
/// not fail.
fn boundary_case_same_on_1_2_3_ranks<const D: usize>(text: &str, steps: usize) -> Outcome<D> {
    let one = run_with::<D>(text, 1, steps, None);
    let thin = run_with::<D>(text, 2, steps, Some(0));
    assert!(
        thin.particles.len() != one.particles.len()
            || first_difference(&one.particles, &thin.particles).is_some(),
        "a halo of the skin alone gave the same particles"
    );
    for ranks in [2, 3] {
        let many = run_with::<D>(text, ranks, steps, None);
        if let Some(d) = first_difference(&one.particles, &many.particles) {
            panic!("1 rank against {ranks}: {d}");
        }
        // the loads and the port flows are exact sums (`parallel::exact`): the same bits
        assert_eq!(one.loads, many.loads, "body loads on 1 rank and on {ranks}");
        assert_eq!(one.flows, many.flows, "port flows on 1 rank and on {ranks}");
    }
    one
}

/// A channel between two ports in a closed box (a body with no-slip walls), driven hard
/// enough that particles enter and leave through both ports within the run: buffers refill
/// with new particles and drop the ones past their depth on every rank count alike.
#[test]
fn a_body_with_ports_is_bit_identical_on_1_2_3_ranks() {
    let text = crate::common::model_text("channel-ports2d.toml")
        .replace("spacing = 0.05", "spacing = 0.1")
        .replace(
            "type = \"external\", initial = 0.06",
            "type = \"constant\", value = 3.0",
        );
    let one = boundary_case_same_on_1_2_3_ranks::<2>(&text, 300);
    let [inlet, outlet] = [one.flows[0], one.flows[1]];
    eprintln!(
        "inlet in/out {inlet:?}, outlet in/out {outlet:?}, particles {}",
        one.particles.len()
    );
    assert!(inlet[0] > 0.0, "no particle entered through the inlet");
    assert!(outlet[1] > 0.0, "no particle left through the outlet");
    assert!(
        one.loads[0].iter().any(|&f| f != 0.0),
        "the channel felt no load"
    );
}

/// A tank sloshing in its own accelerating frame (`[frame]`): walls and the frame's
/// fictitious forces on 1, 2 and 3 ranks.
#[test]
fn a_tank_in_a_moving_frame_is_bit_identical_on_1_2_3_ranks() {
    let text = format!(
        "{}\n[frame]\nmotion = {{ type = \"ramp\", velocity = [0.5, 0.0], ramp_time = 0.05 }}\n",
        crate::common::model_text("tank2d.toml").replace("spacing = 0.02", "spacing = 0.04")
    );
    boundary_case_same_on_1_2_3_ranks::<2>(&text, 60);
}

/// The same tank, at rest, with Rosswog's F1: walls make the first step repeat its h–ρ–P
/// loop until X settles, and the ranks must agree on the number of passes (each refreshes
/// the halo).
#[test]
fn a_tank_with_rosswog_f1_is_bit_identical_on_1_2_3_ranks() {
    let text = crate::common::model_text("tank2d.toml")
        .replace("spacing = 0.02", "spacing = 0.04")
        .replace(
            "name = \"standard\"\nalpha = 0.1\nbeta = 0.0\ndensity = \"continuity\"",
            "name = \"rosswog-f1\"",
        );
    assert!(text.contains("rosswog-f1"));
    boundary_case_same_on_1_2_3_ranks::<2>(&text, 40);
}

/// The 1D Kidder implosion, whose shell is driven at both ends (`[region.drive]`).
#[test]
fn a_driven_1d_shell_is_bit_identical_on_1_2_3_ranks() {
    let text = crate::common::model_text("verify/kidder.toml");
    boundary_case_same_on_1_2_3_ranks::<1>(&text, 1500);
}

/// What a master reads of the closed tank after each step: the tank's force and torque, the
/// floor patch's mean and peak pressure and force, a probe's pressure and velocity.
fn tank_outputs(c: &Coupling) -> Vec<f64> {
    let l = &c.loads()[0];
    let pa = &c.patches()[0];
    let pr = &c.probes()[0];
    let mut row = vec![l.force[0], l.force[1], l.torque[2]];
    row.extend([pa.mean_pressure, pa.peak_pressure, pa.force[0], pa.force[1]]);
    row.extend([pr.pressure, pr.velocity[0], pr.velocity[1]]);
    row
}

/// How a coupled run on ranks goes: from the case's start or from a saved state, `steps`
/// communication steps of `H` under a swinging gravity (an input every step, so every step
/// re-evaluates and rebuilds the halo), the state saved after step `save_at`.
struct CoupledPlan {
    ranks: usize,
    from: Option<(usize, Vec<u8>)>,
    steps: usize,
    save_at: usize,
    /// Restore the saved state at the end and step again to the end: the rows of the replay.
    replay: bool,
}

const H: f64 = 0.004;

/// Rank 0's rows (one per step), the state saved after step `save_at`, and the replay's rows.
fn coupled_run(text: &str, plan: CoupledPlan) -> (Vec<Vec<f64>>, Vec<u8>, Vec<Vec<f64>>) {
    let case = Case::parse(text).expect("case parses");
    let options = CouplingOptions {
        threads: 1,
        ..Default::default()
    };
    let plan = Arc::new(plan);
    let handles: Vec<_> = ThreadRanks::group(plan.ranks)
        .into_iter()
        .map(|comm| {
            let (case, options, plan) = (case.clone(), options.clone(), plan.clone());
            std::thread::spawn(move || {
                let comm: Arc<dyn Comm> = Arc::new(comm);
                let mut c = Coupling::new_on(&case, &options, Some(comm)).expect("coupling");
                let k0 = plan.from.as_ref().map_or(0, |(k, bytes)| {
                    c.restore(bytes)
                        .expect("a state saved on other ranks restores");
                    *k
                });
                let step = |c: &mut Coupling, k: usize| {
                    let t = (k + 1) as f64 * H;
                    c.set_gravity([2.0 * (12.0 * t).sin(), -9.81, 0.0]).unwrap();
                    c.step_to(t).expect("step");
                    tank_outputs(c)
                };
                let (mut rows, mut saved) = (vec![], vec![]);
                for k in k0..k0 + plan.steps {
                    rows.push(step(&mut c, k));
                    if k == plan.save_at {
                        saved = c.save().expect("save");
                    }
                }
                let mut replay = vec![];
                if plan.replay {
                    c.restore(&saved).expect("restore");
                    for k in plan.save_at + 1..k0 + plan.steps {
                        replay.push(step(&mut c, k));
                    }
                }
                (rows, saved, replay)
            })
        })
        .collect();
    let mut all: Vec<_> = handles
        .into_iter()
        .map(|h| h.join().expect("rank"))
        .collect();
    let first = all.swap_remove(0);
    for (rows, saved, _) in &all {
        assert_eq!(rows, &first.0, "ranks read different outputs");
        assert!(saved == &first.1, "ranks saved different states");
    }
    first
}

fn bits(rows: &[Vec<f64>]) -> Vec<Vec<u64>> {
    rows.iter()
        .map(|r| r.iter().map(|x| x.to_bits()).collect())
        .collect()
}

/// The co-simulation interface on ranks (`Coupling::new_on`, what `mpirun -n R sphfmu serve`
/// runs): a master's inputs every step, and the tank's loads, patch and probe read back are
/// the same bits in one process and on 1, 2 and 3 ranks (exact sums, `parallel::exact`); a state saved on 2
/// ranks restores on 3 and on 1 and continues with the same bits; a rollback on the same
/// ranks replays them.
#[test]
fn a_coupling_on_ranks_reads_the_same_bits_and_restores_on_any_number_of_ranks() {
    let text = crate::common::model_text("closed-tank2d.toml")
        .replace("spacing = 0.02", "spacing = 0.04")
        + "\n[[probe]]\nname = \"middle\"\npoint = [0.5, 0.2]\n";
    let (steps, save_at) = (24, 11);
    let plan = |ranks, replay| CoupledPlan {
        ranks,
        from: None,
        steps,
        save_at,
        replay,
    };
    let (one, _, _) = coupled_run(&text, plan(1, false));
    {
        let case = Case::parse(&text).unwrap();
        let mut alone = Coupling::new(&case, &Default::default()).unwrap();
        let rows: Vec<Vec<f64>> = (0..steps)
            .map(|k| {
                let t = (k + 1) as f64 * H;
                alone
                    .set_gravity([2.0 * (12.0 * t).sin(), -9.81, 0.0])
                    .unwrap();
                alone.step_to(t).unwrap();
                tank_outputs(&alone)
            })
            .collect();
        // canonical neighbour order is every run's (`System::canonical_order`): one
        // process reads what the ranks read
        assert_eq!(bits(&rows), bits(&one), "one process against 1 rank");
    }
    let (two, saved, replay) = coupled_run(&text, plan(2, true));
    let (three, _, _) = coupled_run(&text, plan(3, false));
    assert_eq!(bits(&one), bits(&two), "1 rank against 2");
    assert_eq!(bits(&one), bits(&three), "1 rank against 3");
    assert_eq!(
        bits(&replay),
        bits(&one[save_at + 1..]),
        "the rollback on 2 ranks"
    );
    for ranks in [3, 1] {
        let (resumed, _, _) = coupled_run(
            &text,
            CoupledPlan {
                ranks,
                from: Some((save_at + 1, saved.clone())),
                steps: steps - save_at - 1,
                save_at: usize::MAX,
                replay: false,
            },
        );
        assert_eq!(
            bits(&resumed),
            bits(&one[save_at + 1..]),
            "saved on 2 ranks, resumed on {ranks}"
        );
    }
    // a single process takes the state too (its own summation order from there on)
    let case = Case::parse(&text).unwrap();
    let mut alone = Coupling::new(&case, &Default::default()).unwrap();
    alone
        .restore(&saved)
        .expect("a state saved on ranks restores in one process");
    alone.step_to((save_at + 2) as f64 * H).expect("step");
}

//! The state every scheme works on: particles, box, kernel, EOS, neighbour structures, and
//! the one neighbour loop (`gather`) that all per-pair passes go through.

use crate::domain::{Domain, ImageCode};
use crate::eos::{Eos, EosConfig};
use crate::kernel::DimKernel;
use crate::neighbours::{cut, slack, unpack, CellGrid, NeighbourList};
use crate::parallel::exact::ExactSum;
use crate::particles::{Particles, Vector};
use crate::threads::{LIGHT, MEDIUM};
use rayon::prelude::*;

/// Counters of the latest evaluation (for benchmarks and diagnostics).
#[derive(Debug, Clone, Copy, Default, serde::Serialize, serde::Deserialize)]
pub struct EvalStats {
    /// Pair interactions evaluated in the force pass.
    pub force_pairs: u64,
    /// Pair interactions in all passes (density iterations, gradients, forces).
    pub total_pairs: u64,
    /// Neighbour-list rebuilds caused by growing smoothing lengths.
    pub list_rebuilds: u64,
    /// Mean Newton–Raphson iterations per particle in the latest smoothing-length solve.
    pub h_iterations: f64,
    /// Density evaluations per particle summed over all solves (for run statistics).
    pub h_iterations_total: f64,
    /// Smoothing-length solves (evaluations and refreshes).
    pub h_solves: u64,
    /// Particles whose h hit the cap `h_max`.
    pub h_capped: u64,
    /// Particles whose IA matrix τ was near-singular (kernel-gradient fallback), latest
    /// evaluation and summed over the run.
    pub ia_fallbacks: u64,
    pub ia_fallbacks_total: u64,
    /// Wall-clock seconds spent per phase since the counters were last reset
    /// (neighbour lists, h/density solve, gradients, forces).
    pub seconds_neighbours: f64,
    /// Part of `seconds_neighbours` spent building master lists (the rest: validity checks
    /// and cutting the working list).
    pub seconds_list_builds: f64,
    /// Part of `seconds_neighbours` spent cutting the working list from the master list,
    /// with any pass that rides on the cut (standard SPH's velocity-gradient sums).
    #[serde(default)]
    pub seconds_cut: f64,
    pub seconds_density: f64,
    pub seconds_gradients: f64,
    pub seconds_forces: f64,
    /// Special-relativistic primitive recoveries (Rosswog (2015) Eqs. 97–99) over the run:
    /// particle recoveries, their Newton–Raphson iterations (sum and largest), and the
    /// recoveries that fell back to the cold state (no root with u ≥ 0).
    #[serde(default)]
    pub sr_recoveries: u64,
    #[serde(default)]
    pub sr_recovery_iterations: u64,
    #[serde(default)]
    pub sr_recovery_max_iterations: u64,
    #[serde(default)]
    pub sr_recovery_fallbacks: u64,
    /// Steps whose length the scheme's own limit set ([`crate::scheme::Scheme::step_limit`]:
    /// the SR light-cone margin), not the Courant or force criteria.
    #[serde(default)]
    pub steps_set_by_scheme: u64,
}

/// One neighbour seen from particle a.
#[derive(Debug, Clone, Copy)]
pub struct Pair<const D: usize> {
    pub b: usize,
    pub code: ImageCode,
    /// x_a − image(x_b)
    pub dx: Vector<D>,
    pub r: f64,
    /// Velocity of b's image (normal components reversed for mirror images).
    pub vb: Vector<D>,
    /// Position of this pair in the working list (for per-pair caches).
    pub index: usize,
}

#[derive(Debug, Clone)]
pub struct System<const D: usize> {
    pub particles: Particles<D>,
    pub domain: Domain<D>,
    pub kernel: DimKernel<D>,
    pub eos: EosConfig,
    /// h = η (m/ρ)^{1/D}
    pub eta: f64,
    /// Upper bound on h (isolated particles would otherwise grow without limit).
    pub h_max: f64,
    /// Uniform body force per unit mass.
    pub gravity: Vector<D>,
    pub grid: CellGrid<D>,
    /// Master list with a skin, reused over steps while it stays exact.
    pub verlet: VerletList<D>,
    /// Working list for the current positions and h (no skin).
    pub neighbours: NeighbourList,
    pub stats: EvalStats,
    /// Rigid bodies made of wall particles (`particles.body`), see `boundary::bodies`.
    pub bodies: Vec<crate::boundary::bodies::Body<D>>,
    /// The scheme evolves ρ by the continuity equation (`particles.drhodt`): the integrators
    /// advance it with x, v and u.
    pub evolve_density: bool,
    /// Keep wall–wall pairs in the working list: schemes whose per-particle sums need a wall
    /// particle's full neighbourhood (CRKSPH's volumes and reproducing coefficients, Rosswog's
    /// IA matrices) set it; their force passes skip those pairs (see `wall_pair`).
    pub wall_pairs: bool,
    /// The non-inertial frame the computation runs in (`[frame]`), if any: every particle
    /// then feels its fictitious accelerations besides `gravity` (see `boundary::frame`).
    pub frame: Option<crate::boundary::frame::Frame<D>>,
    /// Pressure ports (openings with particle buffers, `boundary::ports`).
    pub ports: Vec<crate::boundary::ports::Port<D>>,
    /// EOS per material id (`[[material]]`; ids without an entry, and every id when it is
    /// empty, use `eos`): see [`System::eos_of`].
    pub material_eos: Vec<EosConfig>,
    /// Driven regions (`boundary::drive`), indexed by `particles.drive` − 1.
    pub drives: Vec<crate::boundary::drive::Drive<D>>,
    /// Time of the state the next evaluation sees (set by the driver: the end of the step
    /// being taken), for time-dependent boundary values (port pressures).
    pub time: f64,
    /// Set by a special-relativistic scheme (`scheme::rosswog::sr`): where the particles keep
    /// the canonical momentum S and energy ε per baryon that the integrator evolves in place
    /// of v and u, and their Lorentz factors. `None` in Newtonian runs.
    pub relativistic: Option<crate::scheme::rosswog::sr::SrSlots>,
    /// Neighbour rows in the order of the particles' stable ids (not of their indices), so
    /// that every per-particle sum is the same whatever the numbering: a distributed run
    /// (`parallel`) then matches a single process bit for bit on any number of ranks. On by
    /// default (cases build it so): sorting the rows at list builds cost nothing measurable
    /// (`sphfmu run` of noh2d 5.4 s sorted against 6.0 s unsorted, dambreak2d 7.2 s both, 2
    /// threads), and a local FMU then reads the same bits as a node under mpirun.
    pub canonical_order: bool,
    /// The last `halo` particles are copies of other ranks' particles (`parallel::halo`):
    /// evaluated with the rest, but neither stepped for the time step, counted in the totals
    /// nor checked; 0 in a single-process run.
    pub halo: usize,
    /// The other ranks of a distributed run, for the sums outside the scheme's passes that
    /// span them (body loads, probes and port samples); `None` in a single process.
    pub ranks: Option<std::sync::Arc<dyn RankSums>>,
    /// Arrays the passes fill anew every step, kept for the next step (memory, not state).
    pub scratch: crate::scratch::Scratch,
}

/// Sums over the ranks of a distributed run (`parallel`): every rank's exact registers
/// ([`ExactSum`]) merged, so a total is the same bits however the particles are shared among
/// the ranks. Every rank calls it at the same point (a collective). A failed exchange leaves
/// `x` as this rank's own sums and is reported at the step's agreement, so no caller needs
/// an error path.
pub trait RankSums: Send + Sync + std::fmt::Debug {
    fn merge_in_place(&self, x: &mut [ExactSum]);
    /// Element-wise maxima over the ranks (the same rules).
    fn max_in_place(&self, x: &mut [f64]);
    /// The owners' values of some fields for this rank's halo copies, in the halo's order,
    /// `width` numbers per copy; `pack` gives this rank's values for a list of its owned
    /// particles (the copies another rank holds). A collective; a failed exchange gives
    /// `None` (the halo keeps its values) and is reported at the step's agreement.
    fn halo_values(&self, width: usize, pack: &dyn Fn(&[u32]) -> Vec<f64>) -> Option<Vec<f64>>;
}

/// A neighbour list with a skin, the positions and radii it was built for.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct VerletList<const D: usize> {
    pub list: NeighbourList,
    pub pos: Vec<Vector<D>>,
    pub reach: Vec<f64>,
    /// How many times it was built.
    pub builds: u64,
}

impl<const D: usize> Default for VerletList<D> {
    fn default() -> Self {
        Self {
            list: NeighbourList::default(),
            pos: vec![],
            reach: vec![],
            builds: 0,
        }
    }
}

impl<const D: usize> System<D> {
    /// How many particles this process owns (all but the halo copies at the end).
    pub fn owned(&self) -> usize {
        self.particles.len() - self.halo
    }

    /// Make the master (Verlet) list valid for the current positions and return, per
    /// particle, the largest h it can serve exactly.
    ///
    /// The list holds every pair closer than `max(Rb_a, Rb_b)` at build time (Rb = build
    /// reach). Since then particle a moved by d_a. For any fixed vector u,
    /// |d_a − d_b| ≤ |d_a − u| + |d_b − u| ≤ e_a + E with e_a = |d_a − u| and E = max e: a
    /// pair closer than `max(R_a, R_b)` now, say R_a ≥ R_b, was closer than R_a + e_a + E at
    /// the build, so it is listed while `R_a + e_a + E ≤ Rb_a` for all a. u is the centre of
    /// the displacements' bounding box (its components along reflecting axes zero): a flow
    /// that moves as a whole then uses the skin for its relative motion only, where u = 0
    /// would spend it twice on the common drift. Flows moving both ways, like the two
    /// shocks of a periodic Sod tube, keep u near 0 and gain nothing from it, so once that
    /// bound has run out each particle also gets the local bound of [`slack`] (u chosen per
    /// neighbourhood), and the smaller of the two is s_a: listed while `R_a + s_a ≤ Rb_a`.
    /// The list is rebuilt (reach 2h(1+skin)) when `rebuild` is set or no slack is left.
    pub fn prepare_master_list(&mut self, skin: f64, mut rebuild: bool) -> Vec<f64> {
        let t0 = std::time::Instant::now();
        let n = self.particles.len();
        let v = &mut self.verlet;
        if v.pos.len() != n || v.list.offsets.len() != n + 1 {
            rebuild = true;
        }
        // s_a per particle: the bound on |d_a − d_b| over a's partners (0 after a build).
        let mut disp = vec![0.0; n];
        if !rebuild {
            let dom = &self.domain;
            let pos = &self.particles.pos;
            let moved: Vec<Vector<D>> = (0..n)
                .into_par_iter()
                .with_min_len(LIGHT)
                .map(|i| dom.separation(&pos[i], &v.pos[i], 0))
                .collect();
            let inf = Vector::<D>::repeat(f64::INFINITY);
            let (lo, hi) = moved
                .par_iter()
                .with_min_len(LIGHT)
                .map(|d| (*d, *d))
                .reduce(|| (inf, -inf), |(a, b), (c, d)| (a.inf(&c), b.sup(&d)));
            // On a reflecting axis a mirror image moves with the normal component of d_b
            // reversed, so |M d_b − u| = |d_b − u| needs u's normal component to be zero.
            let u = Vector::<D>::from_fn(|k, _| {
                if n > 0 && dom.kind[k] != crate::domain::BoundaryKind::Reflect {
                    0.5 * (lo[k] + hi[k])
                } else {
                    0.0
                }
            });
            disp = moved
                .par_iter()
                .with_min_len(LIGHT)
                .map(|d| (d - u).norm())
                .collect();
            let delta = disp.iter().cloned().fold(0.0, f64::max);
            disp.par_iter_mut()
                .with_min_len(LIGHT)
                .for_each(|e| *e += delta);
            let k = &self.kernel;
            let h = &self.particles.h;
            // Rebuild when some particle's current support already lacks slack.
            let lacks = |disp: &[f64]| {
                (0..n)
                    .into_par_iter()
                    .with_min_len(LIGHT)
                    .any(|i| k.radius(h[i]) + disp[i] > v.reach[i])
            };
            rebuild = lacks(&disp);
            if rebuild {
                // The local bound of `slack` where smaller, only when the global one has run
                // out (the closed tank never gets there, and it costs an O(N) pass a step).
                let reach_max = v.reach.iter().cloned().fold(0.0, f64::max);
                let local = slack::local_bound(pos, &moved, reach_max, dom);
                disp.par_iter_mut()
                    .with_min_len(LIGHT)
                    .zip(local)
                    .for_each(|(e, l)| *e = e.min(l));
                rebuild = lacks(&disp);
            }
        }
        if rebuild {
            let tb = std::time::Instant::now();
            let p = &self.particles;
            v.reach =
                p.h.iter()
                    .map(|&h| self.kernel.radius(h) * (1.0 + skin))
                    .collect();
            self.grid = CellGrid::build(&p.pos, &self.domain, &v.reach);
            let old = std::mem::take(&mut v.list);
            v.list = NeighbourList::build_reusing(&p.pos, &v.reach, &self.domain, &self.grid, old);
            if self.canonical_order {
                v.list.sort_rows_by_id(&p.id);
            }
            v.pos.clone_from(&p.pos);
            v.builds += 1;
            disp.iter_mut().for_each(|d| *d = 0.0);
            self.stats.seconds_list_builds += tb.elapsed().as_secs_f64();
        }
        self.stats.seconds_neighbours += t0.elapsed().as_secs_f64();
        // listed while R_a + s_a ≤ Rb_a, s_a the bound on |d_a − d_b| (see above)
        v.reach
            .iter()
            .zip(&disp)
            .map(|(&r, &d)| (r - d) / crate::kernel::SUPPORT)
            .collect()
    }

    /// The working list: the master list cut to `max(2h_a, 2h_b)` once h is final, without
    /// wall–wall pairs unless the scheme asked for them (`wall_pairs`).
    pub fn compact_neighbours(&mut self) {
        self.compact_neighbours_with(&mut vec![(); self.particles.len()], &cut::NoVisit);
    }

    /// [`Self::compact_neighbours`], with `visitor` run on the kept pairs of each row, in
    /// working-list order, as [`Self::gather`] would afterwards (see [`cut`]).
    pub fn compact_neighbours_with<V: cut::CutVisitor<D>>(
        &mut self,
        out: &mut [V::Acc],
        visitor: &V,
    ) {
        let t0 = std::time::Instant::now();
        let old = std::mem::take(&mut self.neighbours);
        self.neighbours =
            self.with_scratch(|sys, scratch| cut::cut(sys, out, visitor, old, scratch));
        let dt = t0.elapsed().as_secs_f64();
        self.stats.seconds_neighbours += dt;
        self.stats.seconds_cut += dt;
    }

    /// `pass(self, scratch)` with the store of kept arrays ([`crate::scratch`]) lent apart from
    /// the rest of the system, so a pass that reads the system can take and keep its arrays.
    pub fn with_scratch<R>(
        &mut self,
        pass: impl FnOnce(&Self, &mut crate::scratch::Scratch) -> R,
    ) -> R {
        let mut scratch = std::mem::take(&mut self.scratch);
        let r = pass(self, &mut scratch);
        self.scratch = scratch;
        r
    }

    /// Reorder the particles (new index i = old index `perm[i]`) and carry the master list,
    /// its build positions and radii along, so a reorder costs no rebuild.
    pub fn permute_particles(&mut self, perm: &[u32]) {
        self.particles.permute(perm);
        self.grid.permute(perm);
        let v = &mut self.verlet;
        if v.pos.len() == perm.len() && v.list.offsets.len() == perm.len() + 1 {
            v.list = v.list.permuted(perm);
            v.pos = perm.iter().map(|&i| v.pos[i as usize]).collect();
            v.reach = perm.iter().map(|&i| v.reach[i as usize]).collect();
        } else {
            *v = VerletList {
                builds: v.builds,
                ..Default::default()
            };
        }
        self.neighbours = NeighbourList::default();
    }

    /// Forget the neighbour lists (after particles were created or deleted): the next
    /// evaluation builds them anew.
    pub fn reset_neighbours(&mut self) {
        self.verlet = VerletList {
            builds: self.verlet.builds,
            ..Default::default()
        };
        self.neighbours = NeighbourList::default();
        // its cell order is the reorder permutation: stale once the count changed
        self.grid = CellGrid::default();
    }

    /// Scale every h by the expected compression over `dt` (continuity equation,
    /// dh/dt = (h/D) ∇·v) so the h iteration starts close to its answer.
    pub fn predict_h(&mut self, dt: f64) {
        let p = &mut self.particles;
        let d = D as f64;
        p.h.par_iter_mut()
            .zip(p.div_v.par_iter())
            .with_min_len(LIGHT)
            .for_each(|(h, &dv)| {
                let f = (dt * dv / d).clamp(-0.2, 0.2);
                *h *= 1.0 + f;
            });
    }

    /// The uniform body force in the computation's coordinates: g, or in a moving frame
    /// Rᵀ(g − A) (its origin's acceleration removed).
    pub fn uniform_body_force(&self) -> Vector<D> {
        match &self.frame {
            Some(f) => f.uniform(&self.gravity),
            None => self.gravity,
        }
    }

    /// Body force per unit mass on a particle at x moving at v: g, plus the frame's Euler,
    /// Coriolis and centrifugal terms in a rotating frame. `uniform` is
    /// [`Self::uniform_body_force`], computed once per pass.
    #[inline]
    pub fn body_force(&self, uniform: &Vector<D>, x: &Vector<D>, v: &Vector<D>) -> Vector<D> {
        crate::boundary::frame::body_force_in(self.frame.as_ref(), uniform, x, v)
    }

    /// Both particles of the pair belong to bodies: rigid walls exert no force on each other
    /// (their loads are what the fluid exerts), so force passes skip such pairs.
    #[inline(always)]
    pub fn wall_pair(&self, a: usize, b: usize) -> bool {
        let body = &self.particles.body;
        body[a] != 0 && body[b] != 0
    }

    /// The neighbour loop, written once: for every particle a (in parallel), call
    /// `f(a, &mut out[a], &pair)` for each listed neighbour. Self is not visited.
    pub fn gather<T: Send, F>(&self, out: &mut [T], f: F)
    where
        F: Fn(usize, &mut T, &Pair<D>) + Sync,
    {
        let p = &self.particles;
        self.gather_with(|i| (p.pos[i], p.vel[i]), out, f)
    }

    /// [`Self::gather`] reading positions and velocities through `kin` — for passes that pack
    /// what they read of a neighbour into one record per particle (one cache line instead of
    /// one per field array).
    #[inline]
    pub fn gather_with<T: Send, K, F>(&self, kin: K, out: &mut [T], f: F)
    where
        K: Fn(usize) -> (Vector<D>, Vector<D>) + Sync,
        F: Fn(usize, &mut T, &Pair<D>) + Sync,
    {
        let dom = &self.domain;
        let nb = &self.neighbours;
        out.par_iter_mut()
            .enumerate()
            .with_min_len(64)
            .for_each(|(a, acc)| {
                let (xa, _) = kin(a);
                let first = nb.offsets[a];
                for (k, &e) in nb.of(a).iter().enumerate() {
                    let (b, code) = unpack(e);
                    let (xb, vb) = kin(b);
                    let dx = dom.separation(&xa, &xb, code);
                    let pair = Pair {
                        b,
                        code,
                        dx,
                        r: dx.norm(),
                        vb: dom.image_velocity(&vb, code),
                        index: first + k,
                    };
                    f(a, acc, &pair);
                }
            });
    }

    /// [`Self::gather`] with one output slot per listed pair as well (in list order), for
    /// schemes that keep pair forces (the compatible energy update, Frontiere, Raskin & Owen (2017) §3.3; eqs 56–68).
    pub fn gather_pairs<T: Send, Q: Send, F>(&self, out: &mut [T], per_pair: &mut [Q], f: F)
    where
        F: Fn(usize, &mut T, &mut Q, &Pair<D>) + Sync,
    {
        let nb = &self.neighbours;
        let slices = nb.split_rows_mut(per_pair);
        let dom = &self.domain;
        let p = &self.particles;
        out.par_iter_mut()
            .zip(slices.into_par_iter())
            .enumerate()
            .with_min_len(64)
            .for_each(|(a, (acc, slots))| {
                let xa = p.pos[a];
                let first = nb.offsets[a];
                for (k, (&e, slot)) in nb.of(a).iter().zip(slots.iter_mut()).enumerate() {
                    let (b, code) = unpack(e);
                    let dx = dom.separation(&xa, &p.pos[b], code);
                    let pair = Pair {
                        b,
                        code,
                        dx,
                        r: dx.norm(),
                        vb: dom.image_velocity(&p.vel[b], code),
                        index: first + k,
                    };
                    f(a, acc, slot, &pair);
                }
            });
    }

    /// End of a force pass: record its timing and pair count, and write per particle
    /// dv/dt (plus gravity), du/dt and the signal speed (at least c_s) from `derivs(a)`.
    pub fn store_derivatives(
        &mut self,
        started: std::time::Instant,
        derivs: impl Fn(usize) -> (Vector<D>, f64, f64) + Sync,
    ) {
        self.stats.seconds_forces += started.elapsed().as_secs_f64();
        self.stats.force_pairs = self.neighbours.total_pairs() as u64;
        self.stats.total_pairs += self.stats.force_pairs;
        let g = self.uniform_body_force();
        let frame = self.frame.as_ref();
        let p = &mut self.particles;
        let (cs, pos, vel) = (&p.sound_speed, &p.pos, &p.vel);
        p.acc
            .par_iter_mut()
            .zip(p.dudt.par_iter_mut())
            .zip(p.v_sig.par_iter_mut())
            .enumerate()
            .with_min_len(LIGHT)
            .for_each(|(a, ((acc, du), vs))| {
                let (dv, dudt, vsig) = derivs(a);
                *acc = dv + crate::boundary::frame::body_force_in(frame, &g, &pos[a], &vel[a]);
                *du = dudt;
                *vs = vsig.max(cs[a]);
            });
    }

    /// After an evaluation: frozen particles keep still, wall particles record their body's
    /// load and take its rigid motion.
    /// The EOS of material `m`.
    pub fn eos_of(&self, m: u16) -> EosConfig {
        crate::eos::of_material(&self.eos, &self.material_eos, m)
    }

    pub fn hold_constrained(&mut self) {
        self.particles.hold_frozen();
        self.hold_ports();
        self.hold_walls();
    }

    /// P and c_s from the EOS for every particle, then the port condition on buffer particles
    /// and the wall condition on wall particles.
    pub fn update_eos(&mut self) {
        let (eos, table) = (self.eos, &self.material_eos);
        let p = &mut self.particles;
        p.pressure
            .par_iter_mut()
            .zip(p.sound_speed.par_iter_mut())
            .zip(p.rho.par_iter().zip(p.u.par_iter()))
            .zip(p.material.par_iter())
            .with_min_len(MEDIUM)
            .for_each(|(((pr, cs), (&rho, &u)), &m)| {
                let eos = crate::eos::of_material(&eos, table, m);
                *pr = eos.pressure(rho, u);
                *cs = eos.sound_speed(rho, u);
            });
        self.apply_boundary_conditions();
    }

    /// The port condition, then the wall condition (which sees buffer particles as fluid).
    pub fn apply_boundary_conditions(&mut self) {
        self.apply_port_condition(self.time);
        self.apply_wall_condition();
    }

    /// Index of the first own particle with a non-finite evolved or derived field, if any
    /// (halo copies are their owners' to check).
    pub fn first_non_finite(&self) -> Option<(usize, &'static str)> {
        let p = &self.particles;
        // the first such particle by index, whatever the thread count (`find_map_first`)
        (0..self.owned())
            .into_par_iter()
            .with_min_len(LIGHT)
            .find_map_first(|i| {
                if !p.pos[i].iter().all(|x| x.is_finite()) {
                    Some((i, "position"))
                } else if !p.vel[i].iter().all(|x| x.is_finite()) {
                    Some((i, "velocity"))
                } else if !p.u[i].is_finite() {
                    Some((i, "internal energy"))
                } else if !(p.rho[i].is_finite() && p.rho[i] > 0.0) {
                    Some((i, "density"))
                } else if !(p.h[i].is_finite() && p.h[i] > 0.0) {
                    Some((i, "smoothing length"))
                } else {
                    None
                }
            })
    }
}

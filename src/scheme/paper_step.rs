//! Per-particle pair sums shared by the CRKSPH paper's schemes (CRKSPH, compSPH, PSPH) and
//! their time-step rule (Frontiere, Raskin & Owen (2017)): dt = C · min(l/c, l/√(Q_max/ρ), l/approach speed,
//! 1/|∇·v|) with the nodal spacing l = h/η. Writing v_sig = η·max(c, √(Q_max/ρ), approach) and
//! at least h|∇·v| lets the driver's C·h/v_sig apply exactly that rule.

use crate::particles::Vector;
use crate::system::System;

#[derive(Clone, Copy)]
pub(crate) struct PairSums<const D: usize> {
    pub acc: Vector<D>,
    pub dudt: f64,
    /// Largest viscous pressure seen (CRKSPH counts 4Q, compSPH and PSPH 1Q).
    pub q_max: f64,
    /// Largest approach speed max(0, (v_j − v_i)·x̂_ij).
    pub approach: f64,
    /// The part of `dudt` that is an antisymmetric exchange rather than pair work (PSPH's
    /// conduction), kept apart for the compatible update.
    pub exchange: f64,
}

impl<const D: usize> Default for PairSums<D> {
    fn default() -> Self {
        Self {
            acc: Vector::zeros(),
            dudt: 0.0,
            q_max: 0.0,
            approach: 0.0,
            exchange: 0.0,
        }
    }
}

/// One row of a force pass that keeps its pair accelerations (PSPH's and CRKSPH's lane
/// passes): the row's sums and its a_ij slots.
pub(crate) struct PairRow<'s, const D: usize> {
    pub sums: PairSums<D>,
    pub slots: &'s mut [Vector<D>],
}

impl<'s, const D: usize> PairRow<'s, D> {
    /// One row per particle, each with its slice of `slots` (one per listed pair).
    pub fn split(sys: &System<D>, slots: &'s mut [Vector<D>]) -> Vec<Self> {
        sys.neighbours
            .split_rows_mut(slots)
            .into_iter()
            .map(|slots| PairRow {
                sums: PairSums::default(),
                slots,
            })
            .collect()
    }

    /// The rows' sums, in particle order.
    pub fn sums(rows: Vec<Self>) -> Vec<PairSums<D>> {
        rows.into_iter().map(|o| o.sums).collect()
    }
}

/// Store the accelerations and du/dt with the §7.2 signal speeds.
pub(crate) fn store<const D: usize>(
    sys: &mut System<D>,
    started: std::time::Instant,
    out: &[PairSums<D>],
) {
    let eta = sys.eta;
    let p = &sys.particles;
    let vsig: Vec<f64> = out
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let s = p.sound_speed[i]
                .max((o.q_max.max(0.0) / p.rho[i]).sqrt())
                .max(o.approach);
            (eta * s).max(p.h[i] * p.div_v[i].abs())
        })
        .collect();
    sys.store_derivatives(started, |i| (out[i].acc, out[i].dudt, vsig[i]));
}

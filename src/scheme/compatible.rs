//! Compatible energy update with the entropy-weighted pairwise work split (Frontiere, Raskin & Owen (2017) §3.3; eqs 56–68;
//! Frontiere, Raskin & Owen 2017, eqs 56–68; Owen 2014), shared by CRKSPH and compSPH.
//!
//! The final-stage evaluation keeps every pair acceleration a_ij (Σ_j a_ij = a_i exactly, and
//! m_i a_ij = −m_j a_ji). With v^{1/2} = (v⁰ + v¹)/2 the pair work ΔE_ij = m_i (v_j^{1/2} −
//! v_i^{1/2})·a_ij Δt is symmetric (eq 60); i receives f_ij ΔE_ij and j the rest (eq 61), so
//! Σ m(½v² + u) changes only by the work of external forces, to round-off. The entropy weight
//! f_ij (eqs 62–63, 67) heats the lower-entropy side and cools the higher-entropy side first.
//!
//! Decision (Frontiere, Raskin & Owen (2017), a point the paper leaves open (decided here)): s = P/ρ^γ is taken at the start of the step, as Spheral does.

use crate::neighbours::{unpack, NeighbourList};
use crate::particles::Vector;
use crate::system::System;
use rayon::prelude::*;

/// The pairs of the final-stage evaluation and their accelerations a_ij (on i from j,
/// gravity excluded), one per list entry.
#[derive(Debug, Clone, Default)]
pub struct PairWork<const D: usize> {
    pub list: NeighbourList,
    pub acc: Vec<Vector<D>>,
    /// du/dt per particle that is no pair work but an antisymmetric exchange (m_i du_i =
    /// −m_j du_j pair by pair, e.g. PSPH's artificial conductivity, G.10–G.12): added to the
    /// compatible update as it is. Empty when the scheme has none.
    pub exchange: Vec<f64>,
}

impl<const D: usize> PairWork<D> {
    /// Slots for the current working list, zeroed; keep the list they belong to.
    pub fn reset(&mut self, sys: &System<D>) {
        self.list.clone_from(&sys.neighbours);
        self.acc.clear();
        self.acc
            .resize(sys.neighbours.total_pairs(), Vector::<D>::zeros());
        self.exchange.clear();
    }
}

/// Share f_ij of the pair work du_ij = (v_j − v_i)·a_ij given to i (eqs 62–63, 67): the even
/// split when the work or the entropy difference vanishes, else heating goes preferentially
/// to the lower-entropy particle and cooling comes from the higher-entropy one. f_ij + f_ji = 1
/// because du_ij and du_ji = du_ij m_i/m_j have the same sign.
#[inline]
pub fn entropy_weight(du_ij: f64, s_i: Option<f64>, s_j: Option<f64>) -> f64 {
    let (Some(si), Some(sj)) = (s_i, s_j) else {
        return 0.5;
    };
    if du_ij == 0.0 || si == sj {
        return 0.5;
    }
    let (smin, smax) = (si.abs().min(sj.abs()), si.abs().max(sj.abs()));
    let sum = smin + smax;
    if sum.is_nan() || sum <= 0.0 {
        return 0.5;
    }
    let lower_share = if (du_ij >= 0.0) == (si >= sj) {
        smin
    } else {
        smax
    };
    lower_share / sum
}

/// A distributed run's halo after a force pass whose energy comes from the compatible update
/// (`parallel::refresh`): [`thermal_update`] reads the neighbours' v^{1/2} (eq 66), so their
/// accelerations (and du/dt, for the stages) as their owners computed them.
pub fn refresh_halo_accelerations<const D: usize>(sys: &mut System<D>) {
    let (sync, p) = (sys.halo_sync(), &mut sys.particles);
    sync.refresh(vec![
        crate::parallel::rows(&mut p.acc),
        crate::parallel::rows(&mut p.dudt),
    ]);
}

/// u¹ = u⁰ + Σ_j f_ij (v_j^{1/2} − v_i^{1/2})·a_ij Δt (eqs 65–66), plus the exchange term of
/// [`PairWork::exchange`] times Δt, for every particle. `v_half`
/// holds (v⁰ + v¹)/2, `s0` the start-of-step entropy proxies; `frozen` particles keep the u
/// they have.
///
/// A pair with a frozen (or driven) partner still splits its work: the partner's share is
/// the compression work done on the boundary particle itself (eq 78 gives each side
/// ½ V_i V_j P_j v_ij·(G_ij − G_ji)), which its imposed u replaces. Giving the evolved
/// particle the whole pair work instead doubles its heating: tried on Kidder's implosion, the
/// entropy of the points next to the rind rose by ×2.4–2.7 at t = 0.99τ.
pub fn thermal_update<const D: usize>(
    sys: &System<D>,
    work: &PairWork<D>,
    v_half: &[Vector<D>],
    s0: &[Option<f64>],
    u0: &[f64],
    dt: f64,
) -> Vec<f64> {
    let dom = &sys.domain;
    let frozen = &sys.particles.frozen;
    (0..u0.len())
        .into_par_iter()
        .with_min_len(64)
        .map(|i| {
            if frozen[i] {
                // its own u: u⁰ for a frozen layer, the step's end value for a driven one
                return sys.particles.u[i];
            }
            let lo = work.list.offsets[i];
            let mut du = 0.0;
            for (k, &e) in work.list.of(i).iter().enumerate() {
                let (j, code) = unpack(e);
                let vj = dom.image_velocity(&v_half[j], code);
                let du_ij = (vj - v_half[i]).dot(&work.acc[lo + k]);
                du += entropy_weight(du_ij, s0[i], s0[j]) * du_ij;
            }
            if let Some(x) = work.exchange.get(i) {
                du += x;
            }
            u0[i] + du * dt
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::entropy_weight;

    #[test]
    fn weights_of_a_pair_sum_to_one() {
        let cases = [
            (0.3, 1.0, 2.0),
            (-0.3, 1.0, 2.0),
            (0.3, 2.0, 1.0),
            (-0.3, 2.0, 1.0),
            (0.0, 2.0, 1.0),
            (0.5, 1.0, 1.0),
        ];
        for (du, si, sj) in cases {
            let fij = entropy_weight(du, Some(si), Some(sj));
            // seen from j the work has the same sign (du_ji = du_ij m_i/m_j)
            let fji = entropy_weight(du * 3.0, Some(sj), Some(si));
            assert!((fij + fji - 1.0).abs() < 1e-15, "{du} {si} {sj}");
        }
        // heating (du > 0) favours the lower-entropy side
        assert!(entropy_weight(1.0, Some(1.0), Some(3.0)) > 0.5);
        assert!(entropy_weight(1.0, Some(3.0), Some(1.0)) < 0.5);
        // cooling comes from the higher-entropy side
        assert!(entropy_weight(-1.0, Some(3.0), Some(1.0)) > 0.5);
        assert_eq!(entropy_weight(1.0, None, Some(1.0)), 0.5);
    }
}

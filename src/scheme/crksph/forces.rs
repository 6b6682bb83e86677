//! CRKSPH pressure forces (Frontiere, Raskin & Owen (2017) eq 64; eq 38 without Q, eq 64 without Q): the pair acceleration on i from j is
//! a_ij = −(1/(2 m_i)) V_i V_j (P_i + P_j)(G_ij − G_ji), with G_ji the corrected-kernel
//! gradient seen from j (its own coefficients, x_ji = −x_ij, ∇_j W_ji = −∇_i W_ij). Since
//! m_i a_ij = −m_j a_ji, linear momentum is conserved to round-off; the force is not central,
//! so angular momentum only approximately (Frontiere, Raskin & Owen (2017) App C).

use super::pair_kernels::PairKernel;
use super::reproducing::RkCoefficients;
use crate::particles::Vector;
use crate::system::System;

/// m_i a_ij for one pair, given i's and j's coefficients (j's reflected for a mirror image).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn pair_force<const D: usize>(
    ci: &RkCoefficients<D>,
    cj: &RkCoefficients<D>,
    xij: &Vector<D>,
    w: f64,
    gw: &Vector<D>,
    vi: f64,
    vj: f64,
    pi_plus_pj: f64,
) -> Vector<D> {
    let (_, gij) = ci.corrected(xij, w, gw);
    let (_, gji) = cj.corrected(&(-xij), w, &(-gw));
    (gij - gji) * (-0.5 * vi * vj * pi_plus_pj)
}

/// Pressure acceleration of every particle for per-particle pressures `pressure`.
pub fn pressure_acceleration<const D: usize>(
    sys: &System<D>,
    vol: &[f64],
    coef: &[RkCoefficients<D>],
    kern: &[PairKernel],
    pressure: &[f64],
) -> Vec<Vector<D>> {
    let p = &sys.particles;
    let mut acc = vec![Vector::<D>::zeros(); p.len()];
    sys.gather(&mut acc, |i, a, pr| {
        let j = pr.b;
        if sys.wall_pair(i, j) {
            return;
        }
        let pk = kern[pr.index];
        let cj = coef[j].reflected(pr.code);
        *a += pair_force(
            &coef[i],
            &cj,
            &pr.dx,
            pk.w,
            &pk.gradient(&pr.dx),
            vol[i],
            vol[j],
            pressure[i] + pressure[j],
        ) / p.mass[i];
    });
    acc
}

//! Which rank owns which part of space: recursive coordinate bisection weighted by each
//! particle's measured cost, as SWIFT's and Gadget's older decompositions do (Berger &
//! Bokhari 1987). Every rank computes the same regions from the same gathered points, so
//! no region table is ever sent.

use crate::domain::{BoundaryKind, Domain};
use crate::particles::Vector;

/// One box per rank, `[lo, hi)` on every axis; together they tile space. Their outer faces
/// lie at ±∞ on open and reflecting axes and on the domain's faces on periodic ones (where
/// every position lies in the box, and distances wrap).
#[derive(Debug, Clone, PartialEq)]
pub struct Regions<const D: usize> {
    pub lo: Vec<[f64; D]>,
    pub hi: Vec<[f64; D]>,
    /// Length of each periodic axis (`None` elsewhere).
    period: [Option<f64>; D],
}

impl<const D: usize> Regions<D> {
    /// Bisect `points` (position, cost) into `ranks` regions of about equal total cost: the
    /// ranks are split in two halves, the points along the axis of their largest spread at
    /// the cost quantile of the lower half, and each half again.
    pub fn bisect(points: &[(Vector<D>, f64)], ranks: usize, domain: &Domain<D>) -> Self {
        let ranks = ranks.max(1);
        let mut lo = [f64::NEG_INFINITY; D];
        let mut hi = [f64::INFINITY; D];
        let mut period = [None; D];
        for k in 0..D {
            if domain.kind[k] == BoundaryKind::Periodic {
                lo[k] = domain.lo[k];
                hi[k] = domain.hi[k];
                period[k] = Some(domain.length(k));
            }
        }
        let mut out = Self {
            lo: vec![lo; ranks],
            hi: vec![hi; ranks],
            period,
        };
        let mut order: Vec<usize> = (0..points.len()).collect();
        out.split(points, &mut order, 0, ranks, lo, hi);
        out
    }

    fn split(
        &mut self,
        points: &[(Vector<D>, f64)],
        subset: &mut [usize],
        first: usize,
        count: usize,
        lo: [f64; D],
        hi: [f64; D],
    ) {
        if count == 1 {
            self.lo[first] = lo;
            self.hi[first] = hi;
            return;
        }
        let left = count / 2;
        // the axis along which the points spread most (the box may be unbounded)
        let mut axis = 0;
        let mut widest = -1.0;
        for k in 0..D {
            let (a, b) = subset
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &i| {
                    (a.min(points[i].0[k]), b.max(points[i].0[k]))
                });
            let spread = if subset.is_empty() {
                hi[k] - lo[k]
            } else {
                b - a
            };
            if spread.is_finite() && spread > widest {
                widest = spread;
                axis = k;
            }
        }
        subset.sort_unstable_by(|&i, &j| points[i].0[axis].total_cmp(&points[j].0[axis]));
        let total: f64 = subset.iter().map(|&i| points[i].1).sum();
        let target = total * left as f64 / count as f64;
        let mut cut = if subset.is_empty() {
            let (a, b) = (lo[axis], hi[axis]);
            if a.is_finite() && b.is_finite() {
                0.5 * (a + b)
            } else if a.is_finite() {
                a + 1.0
            } else if b.is_finite() {
                b - 1.0
            } else {
                0.0
            }
        } else {
            let mut acc = 0.0;
            let mut at = subset.len();
            for (n, &i) in subset.iter().enumerate() {
                if acc + 0.5 * points[i].1 >= target {
                    at = n;
                    break;
                }
                acc += points[i].1;
            }
            let x = |n: usize| points[subset[n.min(subset.len() - 1)]].0[axis];
            if at == 0 {
                x(0)
            } else if at >= subset.len() {
                // everything on the lower side: cut just above the last point
                let last = x(subset.len() - 1);
                last + last.abs().max(1.0) * 1e-9
            } else {
                0.5 * (x(at - 1) + x(at))
            }
        };
        cut = cut.clamp(lo[axis], hi[axis]);
        let split_at = subset.partition_point(|&i| points[i].0[axis] < cut);
        let (low, high) = subset.split_at_mut(split_at);
        let mut hi_low = hi;
        hi_low[axis] = cut;
        let mut lo_high = lo;
        lo_high[axis] = cut;
        self.split(points, low, first, left, lo, hi_low);
        self.split(points, high, first + left, count - left, lo_high, hi);
    }

    pub fn ranks(&self) -> usize {
        self.lo.len()
    }

    /// The rank whose region holds x.
    pub fn owner(&self, x: &Vector<D>) -> usize {
        (0..self.ranks())
            .find(|&r| (0..D).all(|k| self.lo[r][k] <= x[k] && x[k] < self.hi[r][k]))
            // a position on a periodic axis' upper face (or NaN) belongs to the last region
            .unwrap_or(self.ranks() - 1)
    }

    /// Distance from x to rank r's region, through the periodic images.
    pub fn distance(&self, r: usize, x: &Vector<D>) -> f64 {
        let (lo, hi) = (&self.lo[r], &self.hi[r]);
        let mut sum = 0.0;
        for k in 0..D {
            let gap = |y: f64| (lo[k] - y).max(y - hi[k]).max(0.0);
            let d = match self.period[k] {
                Some(l) => gap(x[k]).min(gap(x[k] - l)).min(gap(x[k] + l)),
                None => gap(x[k]),
            };
            sum += d * d;
        }
        sum.sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::domain::BoundaryKind::{Open, Periodic};

    fn domain(kind: [BoundaryKind; 2]) -> Domain<2> {
        Domain {
            lo: [0.0, 0.0],
            hi: [2.0, 1.0],
            kind,
        }
    }

    /// A 20 × 10 lattice on [0, 2) × [0, 1).
    fn lattice(cost: impl Fn(&Vector<2>) -> f64) -> Vec<(Vector<2>, f64)> {
        (0..200)
            .map(|i| {
                let x =
                    Vector::<2>::new(0.05 + 0.1 * (i % 20) as f64, 0.05 + 0.1 * (i / 20) as f64);
                (x, cost(&x))
            })
            .collect()
    }

    /// Every point has exactly one owner, and the cost is split as evenly as the points allow.
    #[test]
    fn bisection_tiles_space_and_balances_cost() {
        // the left half costs three times the right: the cut moves left of x = 1
        let pts = lattice(|x| if x[0] < 1.0 { 3.0 } else { 1.0 });
        for ranks in [1, 2, 3, 4, 7] {
            let r = Regions::bisect(&pts, ranks, &domain([Open, Open]));
            let mut load = vec![0.0; ranks];
            for (x, c) in &pts {
                let owners: Vec<usize> = (0..ranks)
                    .filter(|&k| (0..2).all(|a| r.lo[k][a] <= x[a] && x[a] < r.hi[k][a]))
                    .collect();
                assert_eq!(
                    owners.len(),
                    1,
                    "{ranks} ranks: point {x:?} owned by {owners:?}"
                );
                assert_eq!(r.owner(x), owners[0]);
                load[owners[0]] += c;
            }
            let mean = load.iter().sum::<f64>() / ranks as f64;
            let worst = load.iter().cloned().fold(0.0, f64::max);
            // one lattice column (10 points of cost ≤ 3) is the granularity of a cut
            assert!(worst <= mean + 30.0, "{ranks} ranks: loads {load:?}");
        }
    }

    /// Distances wrap on periodic axes and not on open ones; inside a region it is zero.
    #[test]
    fn distance_wraps_on_periodic_axes() {
        let pts = lattice(|_| 1.0);
        let periodic = Regions::bisect(&pts, 2, &domain([Periodic, Periodic]));
        let open = Regions::bisect(&pts, 2, &domain([Open, Open]));
        // the cut is at x = 1: rank 0 owns [0, 1), rank 1 [1, 2)
        assert_eq!(periodic.owner(&Vector::<2>::new(0.5, 0.5)), 0);
        assert_eq!(periodic.hi[0][0], 1.0);
        let near_right_face = Vector::<2>::new(1.95, 0.5);
        assert_eq!(periodic.distance(1, &near_right_face), 0.0);
        // across the periodic face at x = 2 it is 0.05 from rank 0's region
        assert!((periodic.distance(0, &near_right_face) - 0.05).abs() < 1e-12);
        // on an open axis the way round does not exist: 0.95 to the cut
        assert!((open.distance(0, &near_right_face) - 0.95).abs() < 1e-12);
    }
}

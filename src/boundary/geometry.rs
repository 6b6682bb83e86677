//! Shapes of boundary bodies and the wall particles that make them (issue 5). Each shape is a
//! signed distance φ(x): negative inside the solid, positive in the fluid's space. Wall particles
//! are the points of the fluid's lattice (cell centres of spacing Δx, aligned with `origin`)
//! with −thickness ≤ φ < 0, so a flat wall gets layers at Δx/2, 3Δx/2, … behind its surface,
//! mirroring the fluid's first rows in front of it; `thickness` covers a full kernel support.

use crate::particles::Vector;
use serde::{Deserialize, Serialize};

/// `shape = { type = ..., ... }` of a `[[body]]` in case files.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Shape {
    /// Open-top tank: the fluid space is the box [min, max]; walls on every face but the top
    /// (the last axis' upper face), rising to the top of the box.
    Tank { min: Vec<f64>, max: Vec<f64> },
    /// Closed box: walls on every face of [min, max] around the fluid inside.
    ClosedBox { min: Vec<f64>, max: Vec<f64> },
    /// Solid block [min, max] (a piston plate, an obstacle); the fluid is outside.
    Block { min: Vec<f64>, max: Vec<f64> },
    /// A wall whose surface passes through `point` with `normal` pointing into the fluid,
    /// `half_width` either side of `point` along the surface.
    Plane {
        point: Vec<f64>,
        normal: Vec<f64>,
        half_width: f64,
    },
    /// Solid disk (2D) or sphere (3D) of `radius` about `center`; the fluid is outside.
    Disk { center: Vec<f64>, radius: f64 },
    /// Solid polygon (2D) with `vertices` in order (either sense); the fluid is outside.
    Polygon { vertices: Vec<[f64; 2]> },
}

fn v<const D: usize>(x: &[f64]) -> Vector<D> {
    Vector::<D>::from_iterator(x.iter().cloned())
}

/// Signed distance to the surface of the box [lo, hi], negative inside.
fn box_distance<const D: usize>(x: &Vector<D>, lo: &Vector<D>, hi: &Vector<D>) -> f64 {
    let mut outside = 0.0;
    let mut inside = f64::NEG_INFINITY;
    for k in 0..D {
        let d = (lo[k] - x[k]).max(x[k] - hi[k]);
        if d > 0.0 {
            outside += d * d;
        }
        inside = inside.max(d);
    }
    if outside > 0.0 {
        outside.sqrt()
    } else {
        inside
    }
}

/// Distance from p to the segment [a, b] (2D).
fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (qx, qy) = (a[0] + t * dx - p[0], a[1] + t * dy - p[1]);
    (qx * qx + qy * qy).sqrt()
}

impl Shape {
    /// Check the shape's entries; `key` names it (e.g. `body[0]`).
    pub fn validate(&self, key: &str, dim: usize) -> Result<(), String> {
        let vec = |k: &str, x: &[f64]| -> Result<(), String> {
            if x.len() != dim {
                return Err(format!(
                    "{key}.{k}: must have {dim} entries (case.dimension), got {}",
                    x.len()
                ));
            }
            if let Some(y) = x.iter().find(|y| !y.is_finite()) {
                return Err(format!("{key}.{k}: entries must be finite, got {y}"));
            }
            Ok(())
        };
        let positive = |k: &str, x: f64| -> Result<(), String> {
            if x.is_finite() && x > 0.0 {
                Ok(())
            } else {
                Err(format!("{key}.{k}: must be a finite number > 0, got {x}"))
            }
        };
        match self {
            Shape::Tank { min, max }
            | Shape::ClosedBox { min, max }
            | Shape::Block { min, max } => {
                vec("min", min)?;
                vec("max", max)?;
                if let Some(k) = (0..dim).find(|&k| max[k] <= min[k]) {
                    return Err(format!(
                        "{key}.max: must exceed min on every axis; axis {k}: {} ≤ {} (no thickness)",
                        max[k], min[k]
                    ));
                }
                Ok(())
            }
            Shape::Plane {
                point,
                normal,
                half_width,
            } => {
                vec("point", point)?;
                vec("normal", normal)?;
                if normal.iter().map(|x| x * x).sum::<f64>() <= 0.0 {
                    return Err(format!("{key}.normal: must not be the zero vector"));
                }
                positive("half_width", *half_width)
            }
            Shape::Disk { center, radius } => {
                vec("center", center)?;
                positive("radius", *radius)
            }
            Shape::Polygon { vertices } => {
                if dim != 2 {
                    return Err(format!("{key}.shape: \"polygon\" needs case.dimension = 2"));
                }
                if vertices.len() < 3 {
                    return Err(format!(
                        "{key}.vertices: a polygon needs at least 3 vertices, got {}",
                        vertices.len()
                    ));
                }
                if let Some(p) = vertices.iter().find(|p| !p.iter().all(|x| x.is_finite())) {
                    return Err(format!("{key}.vertices: entries must be finite, got {p:?}"));
                }
                let area: f64 = (0..vertices.len())
                    .map(|i| {
                        let (a, b) = (vertices[i], vertices[(i + 1) % vertices.len()]);
                        a[0] * b[1] - b[0] * a[1]
                    })
                    .sum();
                if area.abs() <= 0.0 {
                    return Err(format!("{key}.vertices: the polygon has no area"));
                }
                Ok(())
            }
        }
    }

    /// Signed distance φ(x): negative inside the solid.
    pub fn distance<const D: usize>(&self, x: &Vector<D>) -> f64 {
        match self {
            Shape::ClosedBox { min, max } => -box_distance(x, &v::<D>(min), &v::<D>(max)),
            Shape::Tank { min, max } => {
                let (lo, hi) = (v::<D>(min), v::<D>(max));
                let top = D - 1;
                // Above the rim nothing is solid; below it, the solid is outside the box.
                if x[top] > hi[top] {
                    return f64::INFINITY;
                }
                let mut open = hi;
                open[top] = f64::INFINITY;
                -box_distance(x, &lo, &open)
            }
            Shape::Block { min, max } => box_distance(x, &v::<D>(min), &v::<D>(max)),
            Shape::Plane {
                point,
                normal,
                half_width,
            } => {
                let n = v::<D>(normal).normalize();
                let d = x - v::<D>(point);
                let along = (d - n * d.dot(&n)).norm();
                if along > *half_width {
                    f64::INFINITY
                } else {
                    d.dot(&n)
                }
            }
            Shape::Disk { center, radius } => (x - v::<D>(center)).norm() - radius,
            Shape::Polygon { vertices } => {
                let p = [x[0], x[1.min(D - 1)]];
                let n = vertices.len();
                let mut dist = f64::INFINITY;
                let mut inside = false;
                for i in 0..n {
                    let (a, b) = (vertices[i], vertices[(i + 1) % n]);
                    dist = dist.min(segment_distance(p, a, b));
                    // even–odd rule
                    if (a[1] > p[1]) != (b[1] > p[1])
                        && p[0] < a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
                    {
                        inside = !inside;
                    }
                }
                if inside {
                    -dist
                } else {
                    dist
                }
            }
        }
    }

    /// Bounding box of the solid grown by `thickness`.
    fn bounds<const D: usize>(&self, thickness: f64) -> (Vector<D>, Vector<D>) {
        let t = Vector::<D>::repeat(thickness);
        match self {
            Shape::Tank { min, max }
            | Shape::ClosedBox { min, max }
            | Shape::Block { min, max } => (v::<D>(min) - t, v::<D>(max) + t),
            Shape::Plane {
                point, half_width, ..
            } => {
                let r = Vector::<D>::repeat(half_width + thickness);
                (v::<D>(point) - r, v::<D>(point) + r)
            }
            Shape::Disk { center, radius } => {
                let r = Vector::<D>::repeat(*radius);
                (v::<D>(center) - r, v::<D>(center) + r)
            }
            Shape::Polygon { vertices } => {
                let mut lo = Vector::<D>::repeat(f64::INFINITY);
                let mut hi = Vector::<D>::repeat(f64::NEG_INFINITY);
                for p in vertices {
                    for k in 0..D.min(2) {
                        lo[k] = lo[k].min(p[k]);
                        hi[k] = hi[k].max(p[k]);
                    }
                }
                (lo, hi)
            }
        }
    }

    /// The wall lattice of the shape: its spacing per axis and the origin its cell centres
    /// are aligned with (x = origin + (i + ½) spacing). A box-like shape (tank, closed box,
    /// block) aligns with its own faces, its spacing per axis set so that a whole number of
    /// cells spans it (the nearest to `dx`): every face then has its first wall layer half a
    /// spacing behind it, on both sides of the box, whatever the fluid's lattice (with one
    /// spacing and the fluid's origin, a box that is no whole number of spacings long gets a
    /// wider gap on one side than on the other: a lopsided wall push). Other shapes take `dx`
    /// and `origin` as they are.
    pub fn wall_lattice<const D: usize>(
        &self,
        dx: f64,
        origin: &Vector<D>,
    ) -> (Vector<D>, Vector<D>) {
        match self {
            Shape::Tank { min, max }
            | Shape::ClosedBox { min, max }
            | Shape::Block { min, max } => {
                let spacing = Vector::<D>::from_fn(|k, _| {
                    let len = max[k] - min[k];
                    len / (len / dx).round().max(1.0)
                });
                (spacing, v::<D>(min))
            }
            _ => (Vector::<D>::repeat(dx), *origin),
        }
    }

    /// Wall particle positions: lattice points (spacing `dx` per axis, cell centres aligned
    /// with `origin`) with −thickness ≤ φ < 0.
    pub fn wall_points<const D: usize>(
        &self,
        dx: &Vector<D>,
        origin: &Vector<D>,
        thickness: f64,
    ) -> Vec<Vector<D>> {
        let (lo, hi) = self.bounds::<D>(thickness);
        // first and last lattice index per axis: x = origin + (i + ½) dx
        let first: Vec<i64> = (0..D)
            .map(|k| ((lo[k] - origin[k]) / dx[k] - 0.5).floor() as i64)
            .collect();
        let last: Vec<i64> = (0..D)
            .map(|k| ((hi[k] - origin[k]) / dx[k] - 0.5).ceil() as i64)
            .collect();
        let mut out = Vec::new();
        let mut idx = first.clone();
        'outer: loop {
            let x = Vector::<D>::from_fn(|k, _| origin[k] + (idx[k] as f64 + 0.5) * dx[k]);
            let phi = self.distance(&x);
            if phi < 0.0 && phi >= -thickness {
                out.push(x);
            }
            for k in 0..D {
                if idx[k] < last[k] {
                    idx[k] += 1;
                    continue 'outer;
                }
                idx[k] = first[k];
            }
            break;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tank_has_layers_behind_three_walls_and_none_above_the_rim() {
        let tank = Shape::Tank {
            min: vec![0.0, 0.0],
            max: vec![1.0, 0.5],
        };
        let dx = 0.05;
        let pts = tank.wall_points::<2>(&Vector::<2>::repeat(dx), &Vector::<2>::zeros(), 3.0 * dx);
        // floor: 3 layers under [−3dx, 1+3dx] (26 columns); side walls: 3 layers × 10 rows
        // each; less the outermost corner point on each side, 2.5√2 dx > 3dx from the corner
        // (it is beyond every fluid particle's support too)
        assert_eq!(pts.len(), 3 * 26 + 2 * 3 * 10 - 2);
        assert!(pts.iter().all(|p| p[1] < 0.5 && tank.distance(p) < 0.0));
        // the first layer sits half a spacing behind the floor
        let lowest_inner = pts
            .iter()
            .filter(|p| p[0] > 0.0 && p[0] < 1.0)
            .map(|p| p[1])
            .fold(f64::NEG_INFINITY, f64::max);
        assert!((lowest_inner + 0.5 * dx).abs() < 1e-12);
    }

    #[test]
    fn distances_of_simple_shapes() {
        let disk = Shape::Disk {
            center: vec![0.0, 0.0],
            radius: 1.0,
        };
        assert!((disk.distance(&Vector::<2>::new(2.0, 0.0)) - 1.0).abs() < 1e-15);
        let square = Shape::Polygon {
            vertices: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        };
        assert!((square.distance(&Vector::<2>::new(0.5, 0.25)) + 0.25).abs() < 1e-15);
        assert!((square.distance(&Vector::<2>::new(1.5, 0.5)) - 0.5).abs() < 1e-15);
        let block = Shape::Block {
            min: vec![0.0, 0.0],
            max: vec![1.0, 1.0],
        };
        let inner = Vector::<2>::new(0.5, 0.25);
        assert_eq!(block.distance(&inner), square.distance(&inner));
        let plane = Shape::Plane {
            point: vec![0.0, 0.0],
            normal: vec![0.0, 2.0],
            half_width: 1.0,
        };
        assert!((plane.distance(&Vector::<2>::new(0.3, -0.2)) + 0.2).abs() < 1e-15);
        assert!(plane.distance(&Vector::<2>::new(3.0, -0.2)).is_infinite());
    }

    #[test]
    fn shapes_without_thickness_or_with_bad_entries_are_rejected() {
        let cases = [
            (
                Shape::ClosedBox {
                    min: vec![0.0, 0.0],
                    max: vec![1.0, 0.0],
                },
                "body[0].max",
            ),
            (
                Shape::Disk {
                    center: vec![0.0, f64::NAN],
                    radius: 1.0,
                },
                "body[0].center",
            ),
            (
                Shape::Polygon {
                    vertices: vec![[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]],
                },
                "body[0].vertices",
            ),
            (
                Shape::Plane {
                    point: vec![0.0, 0.0],
                    normal: vec![0.0, 0.0],
                    half_width: 1.0,
                },
                "body[0].normal",
            ),
        ];
        for (s, key) in cases {
            let e = s.validate("body[0]", 2).unwrap_err();
            assert!(e.starts_with(key), "{e}");
        }
    }
}

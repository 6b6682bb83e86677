//! `[[port]]`: pressure ports of a case (issue 6) — where the opening sits on which body, and
//! the buffer particles that replace the body's wall layers behind it; see `boundary::ports`
//! for the port condition and the particle exchange.

use super::{Case, CaseError};
use crate::boundary::bodies::Body;
use crate::boundary::kinematics::Motion;
use crate::boundary::ports::{Opening, Port, PortPressure};
use crate::eos::EosConfig;
use crate::particles::{Particles, Vector};
use serde::{Deserialize, Serialize};

/// `opening = { type = ..., ... }` of a `[[port]]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum OpeningConfig {
    /// 2D: a segment of `half_width` either side of the centre.
    Segment { half_width: f64 },
    /// 3D: a disk of `radius`.
    Disk { radius: f64 },
    /// 3D: a rectangle, `half_width` along `tangent` (projected onto the plane) and
    /// `half_height` across it.
    Rectangle {
        half_width: f64,
        half_height: f64,
        tangent: Vec<f64>,
    },
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PortConfig {
    pub name: String,
    /// The body whose wall the opening is cut in (its motion must be fixed).
    pub body: String,
    /// Centre of the opening, on the body's surface.
    pub center: Vec<f64>,
    /// Unit normal into the fluid (default: the body surface's normal at the centre).
    pub normal: Option<Vec<f64>>,
    pub opening: OpeningConfig,
    pub pressure: PortPressure,
}

fn vector<const D: usize>(x: &[f64]) -> Vector<D> {
    Vector::<D>::from_iterator(x.iter().cloned())
}

impl PortConfig {
    pub fn validate(&self, i: usize, case: &Case) -> Result<(), CaseError> {
        let key = format!("port[{i}]");
        let d = case.case.dimension;
        if self.name.trim().is_empty() {
            return Err(CaseError(format!("{key}.name: must not be empty")));
        }
        if case.ports[..i].iter().any(|p| p.name == self.name) {
            return Err(CaseError(format!(
                "{key}.name: {:?} is used by an earlier port",
                self.name
            )));
        }
        let Some(body) = case.bodies.iter().find(|b| b.name == self.body) else {
            return Err(CaseError(format!(
                "{key}.body: no body named {:?} (bodies: {:?})",
                self.body,
                case.bodies.iter().map(|b| &b.name).collect::<Vec<_>>()
            )));
        };
        if body.motion != Motion::Fixed {
            return Err(CaseError(format!(
                "{key}.body: {:?} moves; ports sit on fixed bodies (run a moving tank in its own [frame])",
                self.body
            )));
        }
        if !matches!(
            case.eos,
            EosConfig::Tait { .. } | EosConfig::StiffenedGas { .. }
        ) {
            return Err(CaseError(format!(
                "{key}: ports need a liquid EOS (tait or stiffened-gas): the buffer's density comes from the port pressure"
            )));
        }
        case.vec_len(&format!("{key}.center"), &self.center)?;
        if let Some(n) = &self.normal {
            case.vec_len(&format!("{key}.normal"), n)?;
            if n.iter().all(|x| *x == 0.0) {
                return Err(CaseError(format!("{key}.normal: must not be zero")));
            }
        }
        let positive = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(CaseError(format!(
                    "{key}.opening.{name}: must be a finite number > 0, got {v}"
                )))
            }
        };
        match (&self.opening, d) {
            (OpeningConfig::Segment { half_width }, 2) => positive("half_width", *half_width)?,
            (OpeningConfig::Disk { radius }, 3) => positive("radius", *radius)?,
            (
                OpeningConfig::Rectangle {
                    half_width,
                    half_height,
                    tangent,
                },
                3,
            ) => {
                positive("half_width", *half_width)?;
                positive("half_height", *half_height)?;
                case.vec_len(&format!("{key}.opening.tangent"), tangent)?;
            }
            (_, d) => {
                return Err(CaseError(format!(
                    "{key}.opening: a {d}D case takes {}",
                    if d == 2 {
                        "type = \"segment\""
                    } else if d == 3 {
                        "type = \"disk\" or \"rectangle\""
                    } else {
                        "no ports (2D and 3D only)"
                    }
                )))
            }
        }
        self.pressure
            .validate(&format!("{key}.pressure"))
            .map_err(CaseError)
    }
}

/// Turn the wall particles behind each port's opening into its buffer and return the ports.
/// Errors name the port: its centre off the body's surface, its normal not into the fluid,
/// an opening that holds no wall particle.
pub(super) fn add_ports<const D: usize>(
    case: &Case,
    p: &mut Particles<D>,
    bodies: &[Body<D>],
) -> Result<Vec<Port<D>>, CaseError> {
    let fluid_material = (0..p.len())
        .find(|&i| p.body[i] == 0)
        .map_or(0, |i| p.material[i]);
    let mut out = Vec::new();
    for (k, cfg) in case.ports.iter().enumerate() {
        let key = format!("port[{k}]");
        let bi = case
            .bodies
            .iter()
            .position(|b| b.name == cfg.body)
            .expect("validated: the port's body exists");
        let shape = &case.bodies[bi].shape;
        let dx = bodies[bi].spacing;
        let c = vector::<D>(&cfg.center);
        let phi = shape.distance(&c);
        if phi.abs() > 0.5 * dx {
            return Err(CaseError(format!(
                "{key}.center: {:?} is not on the surface of body {:?} (distance {phi:.4e}, allowed ±Δx/2 = {:.4e})",
                cfg.center,
                cfg.body,
                0.5 * dx
            )));
        }
        let n = match &cfg.normal {
            Some(n) => vector::<D>(n).normalize(),
            // the surface normal: the gradient of the signed distance
            None => {
                let e = 1e-3 * dx;
                let g = Vector::<D>::from_fn(|a, _| {
                    let mut up = c;
                    let mut dn = c;
                    up[a] += e;
                    dn[a] -= e;
                    shape.distance(&up) - shape.distance(&dn)
                });
                if !(g.norm() > 0.0 && g.iter().all(|x| x.is_finite())) {
                    return Err(CaseError(format!(
                        "{key}.normal: the surface of {:?} has no normal at the centre; give one",
                        cfg.body
                    )));
                }
                g.normalize()
            }
        };
        // into the fluid: solid a spacing behind the centre, open a spacing in front
        if !(shape.distance(&(c + n * dx)) > 0.0 && shape.distance(&(c - n * dx)) < 0.0) {
            return Err(CaseError(format!(
                "{key}.normal: {:?} must point from body {:?} into the fluid",
                n.as_slice(),
                cfg.body
            )));
        }
        let opening = match &cfg.opening {
            OpeningConfig::Segment { half_width } => Opening::Segment {
                half_width: *half_width,
            },
            OpeningConfig::Disk { radius } => Opening::Disk { radius: *radius },
            OpeningConfig::Rectangle {
                half_width,
                half_height,
                tangent,
            } => {
                let t = vector::<D>(tangent);
                let e1 = t - n * t.dot(&n);
                if e1.norm() < 1e-9 * t.norm() {
                    return Err(CaseError(format!(
                        "{key}.opening.tangent: must not be parallel to the normal"
                    )));
                }
                let e1 = e1.normalize();
                let e2 = Vector::<D>::from_fn(|a, _| {
                    let (b, c3) = ((a + 1) % 3, (a + 2) % 3);
                    n[b] * e1[c3] - n[c3] * e1[b]
                });
                Opening::Rectangle {
                    e1,
                    e2,
                    a: *half_width,
                    b: *half_height,
                }
            }
        };
        let mut port = Port {
            name: cfg.name.clone(),
            pressure: cfg.pressure.clone(),
            external: match cfg.pressure {
                PortPressure::External { initial } => initial,
                _ => 0.0,
            },
            center: c,
            normal: n,
            opening,
            depth: 0.0,
            particle_volume: bodies[bi].particle_volume,
            samples: Vec::new(),
            mass_in: 0.0,
            mass_out: 0.0,
        };
        let tag = k as u16 + 1;
        let mut deepest: f64 = 0.0;
        for i in 0..p.len() {
            if p.body[i] as usize != bi + 1 {
                continue;
            }
            let (d, t) = port.split(&p.pos[i]);
            if d < 0.0 && port.opening.contains(&t) {
                p.body[i] = 0;
                p.port[i] = tag;
                p.material[i] = fluid_material;
                deepest = deepest.max(-d);
            }
        }
        if deepest == 0.0 {
            return Err(CaseError(format!(
                "{key}.opening: holds no wall particle of body {:?} (spacing {dx}); widen it or move the centre",
                cfg.body
            )));
        }
        // The wall's layers sit at (j + ½)Δx behind the surface, the last within one kernel
        // support; the buffer gets one layer more, so that a fluid particle on the plane keeps
        // a full support while the buffer moves by up to a layer between refills. It is whole
        // layers deep, so a copy placed one depth behind lands on the lattice.
        let layers = (deepest / dx + 0.5).round();
        let last = (0..p.len())
            .filter(|&i| p.port[i] == tag && (-port.split(&p.pos[i]).0 - deepest).abs() < 0.25 * dx)
            .collect::<Vec<_>>();
        for i in last {
            let x = p.pos[i] - n * dx;
            p.push(
                p.mass[i],
                x,
                Vector::zeros(),
                p.u[i],
                p.rho[i],
                p.h[i],
                fluid_material,
            );
            let j = p.len() - 1;
            p.port[j] = tag;
            p.pressure[j] = p.pressure[i];
        }
        port.depth = dx * (layers + 1.0);
        port.samples = opening_samples(&port, dx);
        out.push(port);
    }
    Ok(out)
}

/// Points on the opening, one per lattice cell of spacing dx (cell centres in the plane).
fn opening_samples<const D: usize>(port: &Port<D>, dx: f64) -> Vec<Vector<D>> {
    // an orthonormal basis of the plane
    let n = port.normal;
    let mut basis: Vec<Vector<D>> = Vec::new();
    for a in 0..D {
        let mut e = Vector::<D>::zeros();
        e[a] = 1.0;
        let mut e = e - n * e.dot(&n);
        for b in &basis {
            e -= *b * e.dot(b);
        }
        if e.norm() > 1e-6 {
            basis.push(e.normalize());
        }
        if basis.len() == D - 1 {
            break;
        }
    }
    let reach = port.opening.reach();
    let m = (reach / dx).ceil() as i64;
    let mut out = Vec::new();
    let mut idx = vec![-m; D - 1];
    'outer: loop {
        let t = basis
            .iter()
            .zip(&idx)
            .fold(Vector::<D>::zeros(), |acc, (e, &j)| {
                acc + *e * ((j as f64 + 0.5) * dx)
            });
        if port.opening.contains(&t) {
            out.push(port.center + t);
        }
        for j in idx.iter_mut() {
            if *j < m - 1 {
                *j += 1;
                continue 'outer;
            }
            *j = -m;
        }
        break;
    }
    out
}

//! Rigid bodies made of wall particles (issue 5) and the generalised wall boundary condition of
//! Adami, Hu & Adams (2012, J. Comput. Phys. 231, 7057), their eq. 27:
//!
//!   P_w = [Σ_f P_f W_wf + (g − a_w)·Σ_f ρ_f r_wf W_wf] / Σ_f W_wf,   r_wf = x_w − x_f,
//!
//! summed over the fluid neighbours f of wall particle w, with a_w the wall's acceleration
//! (so a wall accelerating into the fluid pushes harder); ρ_w follows from the EOS at P_w
//! (their eq. 28), u_w is the kernel-weighted fluid u (for gases), and the wall particle's mass
//! becomes ρ_w V_w, so the fluid's summation density sees the wall at the fluid's own density
//! (with a fixed reference mass a pressurised liquid reads a density deficit at every wall,
//! 1.5 % of the pressure in a closed tank at 2e4 Pa). Wall particles take part in
//! the fluid's sums and pair forces like fluid particles; wall–wall pairs are left out of the
//! working list. The force the fluid exerts on a body is Σ_w m_w a_w over its wall particles
//! (gravity removed), the exact reaction of what the fluid receives, since every pair force
//! is antisymmetric. Walls move only with their body's kinematics.

use super::kinematics::{from3, to3, HeldPose, Motion, Pose};
use crate::neighbours::unpack;
use crate::parallel::exact::registers;
use crate::particles::Vector;
use crate::system::System;
use rayon::prelude::*;

/// One rigid body at run time.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Body<const D: usize> {
    pub name: String,
    /// From the case, so not part of a saved state (`coupling::state` puts it back).
    #[serde(skip)]
    pub motion: Motion,
    /// Reference point at t = 0 (kinematics and torque are about it, moved by d(t)).
    pub reference: Vector<D>,
    /// Unit rotation axis (3D; 2D rotates about z).
    pub axis: nalgebra::Vector3<f64>,
    pub pose: Pose<D>,
    /// Force of the fluid on the body, from the latest evaluation.
    pub force: Vector<D>,
    /// Torque about the moved reference point (2D: only z).
    pub torque: [f64; 3],
    /// Volume one wall particle stands for: spacing^D over the wall lattice's kernel-sum
    /// factor when the scheme sums density (`case::ics::lattice_density_factor`), so the
    /// fluid's sum sees the wall at the wall density. Its mass is ρ_w times this.
    pub particle_volume: f64,
    /// Spacing of the wall lattice.
    pub spacing: f64,
    /// Time integral of `force` and `torque` with the integrator's own stage weights, so the
    /// fluid's momentum change plus the impulse on every body is the gravity impulse to
    /// round-off.
    pub impulse: Vector<D>,
    pub angular_impulse: [f64; 3],
    /// Pose set from outside (`Motion::External`), carried on at its velocities.
    pub held: HeldPose<D>,
    /// No-slip wall for the laminar viscosity (else free slip).
    pub no_slip: bool,
}

/// What the wall condition sets on one wall particle: P, ρ, u, c, and the velocity it shows
/// in the laminar viscous term.
type WallState<const D: usize> = (f64, f64, f64, f64, Vector<D>);

impl<const D: usize> Body<D> {
    /// The unit rotation axis of the body's prescribed motion (2D: z).
    pub fn unit_axis(&self) -> nalgebra::Unit<nalgebra::Vector3<f64>> {
        nalgebra::Unit::new_normalize(self.axis)
    }

    /// Position, velocity and acceleration of the body point that was at `rest` at t = 0.
    pub fn point(&self, rest: &Vector<D>) -> (Vector<D>, Vector<D>, Vector<D>) {
        let p = &self.pose;
        let r = p.to_world(&(rest - self.reference));
        let (r3, w, al) = (to3(&r), p.angular_velocity, p.angular_acceleration);
        let x = self.reference + p.displacement + r;
        let v = p.velocity + from3::<D>(&w.cross(&r3));
        let a = p.acceleration + from3::<D>(&(al.cross(&r3) + w.cross(&w.cross(&r3))));
        (x, v, a)
    }

    /// The latest force and torque in the body's own axes (Rᵀ F, Rᵀ T): what a multibody
    /// master applies to a body frame.
    pub fn loads_in_body_frame(&self) -> (Vector<D>, nalgebra::Vector3<f64>) {
        let t = nalgebra::Vector3::from(self.torque);
        (
            self.pose.to_body(&self.force),
            self.pose.rotation.inverse_transform_vector(&t),
        )
    }
}

impl<const D: usize> System<D> {
    /// Move every body to its pose at time t (prescribed motions; external ones keep the pose
    /// the coupling layer set) and place its wall particles there with the rigid velocity.
    pub fn place_bodies(&mut self, t: f64) {
        if let Some(f) = &mut self.frame {
            f.place(t);
        }
        if self.bodies.is_empty() {
            return;
        }
        for b in &mut self.bodies {
            b.pose = match b.motion {
                Motion::External => b.held.at(t),
                _ => b.motion.pose::<D>(t, &b.unit_axis()),
            };
        }
        let bodies = &self.bodies;
        let p = &mut self.particles;
        p.pos
            .par_iter_mut()
            .zip(p.vel.par_iter_mut())
            .zip(p.body.par_iter().zip(p.rest.par_iter()))
            .with_min_len(crate::threads::LIGHT)
            .for_each(|((x, v), (&b, rest))| {
                if b > 0 {
                    let (xn, vn, _) = bodies[b as usize - 1].point(rest);
                    *x = xn;
                    *v = vn;
                }
            });
    }

    /// Adami et al.'s wall pressure (eq. 27), density (eq. 28) and energy for every wall
    /// particle from its fluid neighbours. Called after the EOS of the fluid.
    pub fn apply_wall_condition(&mut self) {
        let n = self.particles.len();
        // before the first neighbour search (a scheme's init seeding from the EOS) the walls
        // keep the state they were generated with
        if self.bodies.is_empty() || self.neighbours.offsets.len() != n + 1 {
            return;
        }
        let g = self.uniform_body_force();
        let eos = self.eos;
        let updates: Vec<Option<WallState<D>>> = {
            let p = &self.particles;
            let k = &self.kernel;
            let dom = &self.domain;
            let nb = &self.neighbours;
            let bodies = &self.bodies;
            (0..n)
                .into_par_iter()
                .with_min_len(64)
                .map(|w| {
                    let b = p.body[w];
                    if b == 0 {
                        return None;
                    }
                    let (_, _, a_w) = bodies[b as usize - 1].point(&p.rest[w]);
                    let g = self.body_force(&g, &p.pos[w], &p.vel[w]);
                    let (mut sw, mut spw, mut suw) = (0.0, 0.0, 0.0);
                    let (mut srw, mut svw) = (Vector::<D>::zeros(), Vector::<D>::zeros());
                    for &e in nb.of(w) {
                        let (f, code) = unpack(e);
                        if p.body[f] != 0 {
                            continue;
                        }
                        let r = dom.separation(&p.pos[w], &p.pos[f], code);
                        let wf = k.w(r.norm(), p.h[w]);
                        sw += wf;
                        spw += p.pressure[f] * wf;
                        suw += p.u[f] * wf;
                        srw += r * (p.rho[f] * wf);
                        svw += p.vel[f] * wf;
                    }
                    if sw <= 0.0 {
                        return None;
                    }
                    let pw = (spw + (g - a_w).dot(&srw)) / sw;
                    let uw = suw / sw;
                    let rho = eos.density_at(pw, uw).unwrap_or(p.rho[w]);
                    // Adami et al. eqs. 22–23: no slip mirrors the fluid velocity through the
                    // wall (relative to the wall's own v_w = p.vel[w]); free slip shows v_w
                    let vw = if bodies[b as usize - 1].no_slip {
                        p.vel[w] * 2.0 - svw / sw
                    } else {
                        p.vel[w]
                    };
                    Some((pw, rho, uw, crate::eos::Eos::sound_speed(&eos, rho, uw), vw))
                })
                .collect()
        };
        let p = &mut self.particles;
        for (w, u) in updates.into_iter().enumerate() {
            if let Some((pw, rho, uw, c, vw)) = u {
                p.vel_wall[w] = vw;
                p.pressure[w] = pw;
                p.rho[w] = rho;
                p.u[w] = uw;
                p.sound_speed[w] = c;
                p.mass[w] = rho * self.bodies[p.body[w] as usize - 1].particle_volume;
            }
        }
    }

    /// Add `weight_dt` × the latest force and torque to each body's impulse (called by the
    /// integrators with their stage weights times dt).
    pub fn accumulate_impulse(&mut self, weight_dt: f64) {
        for b in &mut self.bodies {
            b.impulse += b.force * weight_dt;
            for k in 0..3 {
                b.angular_impulse[k] += b.torque[k] * weight_dt;
            }
        }
    }

    /// After an evaluation: record each body's force and torque from its wall particles'
    /// accelerations (gravity removed), then give the walls their rigid-body acceleration
    /// and no energy change, so the integrator moves them with the body.
    pub fn hold_walls(&mut self) {
        if self.bodies.is_empty() {
            return;
        }
        let g = self.uniform_body_force();
        // per body: D force components, then 3 torque components, each summed exactly, so a
        // load is the same bits whichever rank owns which wall particle, in whatever order
        // (`parallel::exact`); a distributed run's halo copies are their owners' to count
        let width = D + 3;
        let mut loads = registers(self.bodies.len() * width);
        let own = self.owned();
        let p = &mut self.particles;
        for i in 0..p.len() {
            let b = p.body[i] as usize;
            if b == 0 {
                continue;
            }
            let body = &self.bodies[b - 1];
            if i < own {
                let g = super::frame::body_force_in(self.frame.as_ref(), &g, &p.pos[i], &p.vel[i]);
                let f = (p.acc[i] - g) * p.mass[i];
                p.wall_force[i] = f;
                let arm = p.pos[i] - (body.reference + body.pose.displacement);
                let t = to3(&arm).cross(&to3(&f));
                let sums = &mut loads[(b - 1) * width..b * width];
                for (s, x) in sums.iter_mut().zip(f.iter().chain(t.iter())) {
                    s.add(*x);
                }
            }
            let (_, _, a) = body.point(&p.rest[i]);
            p.acc[i] = a;
            p.dudt[i] = 0.0;
            p.drhodt[i] = 0.0;
        }
        if let Some(ranks) = &self.ranks {
            ranks.merge_in_place(&mut loads);
        }
        for (b, l) in self.bodies.iter_mut().zip(loads.chunks_exact(width)) {
            b.force = Vector::from_fn(|k, _| l[k].value());
            b.torque = [0, 1, 2].map(|k| l[D + k].value());
        }
    }
}

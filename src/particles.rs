//! Structure-of-arrays particle storage, generic over the dimension D.

use nalgebra::SVector;

/// A D-vector of f64.
pub type Vector<const D: usize> = SVector<f64, D>;

/// Per-particle state. Evolved fields (x, v, u) and the fields every scheme derives each
/// evaluation; schemes that need more register `extra_scalars` / `extra_vectors` slots, which
/// move with the particles when they are reordered.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct Particles<const D: usize> {
    pub mass: Vec<f64>,
    pub pos: Vec<Vector<D>>,
    pub vel: Vec<Vector<D>>,
    /// Specific internal energy u.
    pub u: Vec<f64>,
    pub rho: Vec<f64>,
    pub pressure: Vec<f64>,
    pub sound_speed: Vec<f64>,
    /// Smoothing length (support is 2h).
    pub h: Vec<f64>,
    /// Material id (multi-material rules, output labelling).
    pub material: Vec<u16>,
    /// Stable particle id (survives reordering).
    pub id: Vec<u32>,
    /// Frozen particles take part in every sum but never move (boundary layers).
    pub frozen: Vec<bool>,
    /// 0 for fluid; b + 1 for a wall particle of body b (moved by the body's kinematics, its
    /// pressure from the wall condition, see `boundary::bodies`).
    pub body: Vec<u16>,
    /// 0 for fluid and walls; k + 1 for a buffer particle of port k (`boundary::ports`): it
    /// takes part in every sum like fluid, but its state is set by the port condition.
    #[serde(default)]
    pub port: Vec<u16>,
    /// 0 for evolved particles; k + 1 for a particle of driven region k (`boundary::drive`):
    /// frozen as well, its position, velocity and u set from the region's expressions.
    #[serde(default)]
    pub drive: Vec<u16>,
    /// Position at t = 0 (wall particles: their place in the body frame).
    pub rest: Vec<Vector<D>>,
    /// dv/dt from the latest evaluation.
    pub acc: Vec<Vector<D>>,
    /// du/dt from the latest evaluation.
    pub dudt: Vec<f64>,
    /// dρ/dt (schemes that evolve the density by the continuity equation).
    pub drhodt: Vec<f64>,
    /// Grad-h correction Ω (1 where a scheme has no grad-h terms).
    pub omega: Vec<f64>,
    /// Velocity divergence and |curl| (for switches and diagnostics).
    pub div_v: Vec<f64>,
    pub curl_v: Vec<f64>,
    /// Largest pairwise signal speed seen by the particle in the latest evaluation.
    pub v_sig: Vec<f64>,
    /// Artificial-viscosity coefficient α (constant or switch-driven).
    pub alpha: Vec<f64>,
    /// The velocity a wall particle shows in the laminar viscous term: 2 v_w − v̂_f for a
    /// no-slip body (Adami, Hu & Adams 2012, eqs. 22–23: the fluid velocity extrapolated
    /// through the wall so that it vanishes relative to the wall on the surface), else v_w.
    /// For a port buffer particle: the velocity the port condition gave it. Unused for fluid
    /// particles.
    pub vel_wall: Vec<Vector<D>>,
    /// Force of the fluid on a wall particle from the latest evaluation, m_w (a_w − g) before
    /// the wall is given its rigid motion (patches sum it). Zero for fluid particles.
    pub wall_force: Vec<Vector<D>>,
    pub extra_scalars: Vec<Vec<f64>>,
    pub extra_vectors: Vec<Vec<Vector<D>>>,
}

impl<const D: usize> Particles<D> {
    pub fn len(&self) -> usize {
        self.mass.len()
    }
    pub fn is_empty(&self) -> bool {
        self.mass.is_empty()
    }

    /// Append one particle with the primary fields; derived fields start at zero.
    #[allow(clippy::too_many_arguments)]
    pub fn push(&mut self, m: f64, x: Vector<D>, v: Vector<D>, u: f64, rho: f64, h: f64, mat: u16) {
        let id = self.mass.len() as u32;
        self.mass.push(m);
        self.pos.push(x);
        self.vel.push(v);
        self.u.push(u);
        self.rho.push(rho);
        self.pressure.push(0.0);
        self.sound_speed.push(0.0);
        self.h.push(h);
        self.material.push(mat);
        self.id.push(id);
        self.frozen.push(false);
        self.body.push(0);
        self.port.push(0);
        self.drive.push(0);
        self.rest.push(x);
        self.acc.push(Vector::zeros());
        self.dudt.push(0.0);
        self.drhodt.push(0.0);
        self.omega.push(1.0);
        self.div_v.push(0.0);
        self.curl_v.push(0.0);
        self.v_sig.push(0.0);
        self.alpha.push(0.0);
        self.vel_wall.push(Vector::zeros());
        self.wall_force.push(Vector::zeros());
        for s in &mut self.extra_scalars {
            s.push(0.0);
        }
        for s in &mut self.extra_vectors {
            s.push(Vector::zeros());
        }
    }

    /// Register a scheme-specific scalar field; returns its slot.
    pub fn add_scalar_field(&mut self, init: f64) -> usize {
        self.extra_scalars.push(vec![init; self.len()]);
        self.extra_scalars.len() - 1
    }

    /// Register a scheme-specific vector field; returns its slot.
    pub fn add_vector_field(&mut self) -> usize {
        self.extra_vectors.push(vec![Vector::zeros(); self.len()]);
        self.extra_vectors.len() - 1
    }

    /// Reorder every per-particle array so that new index i holds old index `perm[i]`. `perm`
    /// may also repeat or leave out indices (the ports create and delete particles this way).
    pub fn permute(&mut self, perm: &[u32]) {
        fn ap<T: Copy>(v: &mut Vec<T>, perm: &[u32]) {
            let out: Vec<T> = perm.iter().map(|&i| v[i as usize]).collect();
            *v = out;
        }
        ap(&mut self.mass, perm);
        ap(&mut self.pos, perm);
        ap(&mut self.vel, perm);
        ap(&mut self.u, perm);
        ap(&mut self.rho, perm);
        ap(&mut self.pressure, perm);
        ap(&mut self.sound_speed, perm);
        ap(&mut self.h, perm);
        ap(&mut self.material, perm);
        ap(&mut self.id, perm);
        ap(&mut self.frozen, perm);
        ap(&mut self.body, perm);
        ap(&mut self.port, perm);
        ap(&mut self.drive, perm);
        ap(&mut self.rest, perm);
        ap(&mut self.acc, perm);
        ap(&mut self.dudt, perm);
        ap(&mut self.drhodt, perm);
        ap(&mut self.omega, perm);
        ap(&mut self.div_v, perm);
        ap(&mut self.curl_v, perm);
        ap(&mut self.v_sig, perm);
        ap(&mut self.alpha, perm);
        ap(&mut self.vel_wall, perm);
        ap(&mut self.wall_force, perm);
        for s in &mut self.extra_scalars {
            ap(s, perm);
        }
        for s in &mut self.extra_vectors {
            ap(s, perm);
        }
    }

    /// Zero the derivatives of frozen particles (after every evaluation), so no integrator
    /// moves them or changes their energy. Driven particles keep the velocity their drive
    /// gave them (the next stage sets their whole state again).
    pub fn hold_frozen(&mut self) {
        for i in 0..self.len() {
            if self.frozen[i] {
                self.acc[i] = Vector::zeros();
                self.dudt[i] = 0.0;
                self.drhodt[i] = 0.0;
                if self.drive[i] == 0 {
                    self.vel[i] = Vector::zeros();
                }
            }
        }
    }
}

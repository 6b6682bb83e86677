//! Structure-of-arrays particle storage, generic over the dimension D.

use nalgebra::SVector;

/// A D-vector of f64.
pub type Vector<const D: usize> = SVector<f64, D>;

/// Apply `op` to every fixed per-particle field, either pairwise (`a` = `&from.field`, `b` =
/// `&mut to.field`) or on one set (`b` = `&mut to.field`): the one list of fields that
/// selection, appending, overwriting and truncation share, so a new field cannot be
/// forgotten in one of them. The extra scheme fields are handled by the callers.
macro_rules! for_each_field {
    ($from:expr, $to:expr, |$a:ident, $b:ident| $op:expr) => {
        for_each_field!(@list (pair $from, $to, $a, $b, $op))
    };
    ($to:expr, |$b:ident| $op:expr) => {
        for_each_field!(@list (one $to, $b, $op))
    };
    (@list $args:tt) => {
        for_each_field!(@each $args; mass pos vel u rho pressure sound_speed h material id
            frozen body port drive rest acc dudt drhodt omega div_v curl_v v_sig alpha vel_wall
            wall_force)
    };
    (@each (pair $from:expr, $to:expr, $a:ident, $b:ident, $op:expr); $($f:ident)*) => {{
        $({
            let $a = &$from.$f;
            let $b = &mut $to.$f;
            $op;
        })*
    }};
    (@each (one $to:expr, $b:ident, $op:expr); $($f:ident)*) => {{
        $({
            let $b = &mut $to.$f;
            $op;
        })*
    }};
}

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
        *self = self.selected(perm);
    }

    /// The particles `pick` names, in that order (repeats allowed), with every field.
    pub fn selected(&self, pick: &[u32]) -> Self {
        fn sel<T: Copy>(v: &[T], pick: &[u32]) -> Vec<T> {
            pick.iter().map(|&i| v[i as usize]).collect()
        }
        let mut out = Self::default();
        for_each_field!(self, out, |a, b| *b = sel(a, pick));
        out.extra_scalars = self.extra_scalars.iter().map(|s| sel(s, pick)).collect();
        out.extra_vectors = self.extra_vectors.iter().map(|s| sel(s, pick)).collect();
        out
    }

    /// Append every particle of `other`, which must carry the same extra fields (or none).
    pub fn append(&mut self, other: &Self) -> Result<(), String> {
        if other.is_empty() {
            return Ok(());
        }
        self.check_same_fields(other)?;
        for_each_field!(other, self, |a, b| b.extend_from_slice(a));
        for (s, o) in self.extra_scalars.iter_mut().zip(&other.extra_scalars) {
            s.extend_from_slice(o);
        }
        for (s, o) in self.extra_vectors.iter_mut().zip(&other.extra_vectors) {
            s.extend_from_slice(o);
        }
        Ok(())
    }

    /// Overwrite particles `start..start + other.len()` with `other`'s, every field.
    pub fn overwrite(&mut self, start: usize, other: &Self) -> Result<(), String> {
        if other.is_empty() {
            return Ok(());
        }
        self.check_same_fields(other)?;
        let end = start + other.len();
        if end > self.len() {
            return Err(format!(
                "overwrite of particles {start}..{end} past the end ({})",
                self.len()
            ));
        }
        for_each_field!(other, self, |a, b| b[start..end].copy_from_slice(a));
        for (s, o) in self.extra_scalars.iter_mut().zip(&other.extra_scalars) {
            s[start..end].copy_from_slice(o);
        }
        for (s, o) in self.extra_vectors.iter_mut().zip(&other.extra_vectors) {
            s[start..end].copy_from_slice(o);
        }
        Ok(())
    }

    /// Keep the first `n` particles.
    pub fn truncate(&mut self, n: usize) {
        for_each_field!(self, |b| b.truncate(n));
        self.extra_scalars.iter_mut().for_each(|s| s.truncate(n));
        self.extra_vectors.iter_mut().for_each(|s| s.truncate(n));
    }

    fn check_same_fields(&self, other: &Self) -> Result<(), String> {
        if self.extra_scalars.len() != other.extra_scalars.len()
            || self.extra_vectors.len() != other.extra_vectors.len()
        {
            return Err(format!(
                "particles with {}/{} extra scalar/vector fields cannot join particles with {}/{}",
                other.extra_scalars.len(),
                other.extra_vectors.len(),
                self.extra_scalars.len(),
                self.extra_vectors.len()
            ));
        }
        Ok(())
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

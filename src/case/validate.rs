//! Range checks of a parsed case: every error names the key and the allowed range.

use super::*;

impl Case {
    /// Range checks of every field.
    pub fn validate(&self) -> Result<(), CaseError> {
        let d = self.case.dimension;
        if !(1..=3).contains(&d) {
            return Err(CaseError(format!(
                "case.dimension: must be 1, 2 or 3, got {d}"
            )));
        }
        self.vec_len("domain.min", &self.domain.min)?;
        self.vec_len("domain.max", &self.domain.max)?;
        if self.domain.boundary.len() != d {
            return Err(CaseError(format!(
                "domain.boundary: must have {d} entries (one per axis: open, periodic, reflect), got {}",
                self.domain.boundary.len()
            )));
        }
        for k in 0..d {
            if self.domain.max[k] <= self.domain.min[k] {
                return Err(CaseError(format!(
                    "domain.max[{k}]: must be greater than domain.min[{k}] = {}, got {}",
                    self.domain.min[k], self.domain.max[k]
                )));
            }
        }
        let fm = self.domain.frozen_margin;
        if !(fm.is_finite() && fm >= 0.0) {
            return Err(CaseError(format!(
                "domain.frozen_margin: must be a finite number ≥ 0, got {fm}"
            )));
        }
        self.eos.validate()?;
        self.validate_materials()?;
        self.limits.validate()?;
        let eta = self.eta()?;
        if !(eta.is_finite() && (0.5..=5.0).contains(&eta)) {
            return Err(CaseError(format!(
                "kernel.eta: must be in [0.5, 5], got {eta}"
            )));
        }
        if let Some(h) = self.kernel.h_max {
            if !(h.is_finite() && h > 0.0) {
                return Err(CaseError(format!(
                    "kernel.h_max: must be a finite number > 0, got {h}"
                )));
            }
        }
        self.scheme.validate()?;
        if matches!(self.scheme, SchemeConfig::Psph(_))
            && !matches!(self.eos, EosConfig::IdealGas { .. })
        {
            return Err(CaseError(
                "scheme.name: \"psph\" sums the pressure from u and needs eos.type = \"ideal-gas\""
                    .into(),
            ));
        }
        if self.scheme.relativistic() {
            self.validate_relativistic()?;
        }
        // rpSPH's force sees pressure differences only (Abel 2011 eq. 4) and is not
        // antisymmetric: the load on a body would miss the ambient pressure and not be the
        // reaction of what the fluid receives (measured: a closed tank read −0.05 of its weight)
        if matches!(self.scheme, SchemeConfig::Rpsph(_)) && !self.bodies.is_empty() {
            return Err(CaseError(
                "scheme.name: \"rpsph\" feels pressure differences only, so it gives no load on a [[body]]; use standard, rosswog-f1…f4, crksph, compsph, compsph-cullen or psph with bodies".into(),
            ));
        }
        if !self.ports.is_empty() {
            if let Some(why) = self.scheme.port_refusal() {
                return Err(CaseError(why));
            }
        }
        let t = &self.time;
        let pos = |key: &str, v: f64| -> Result<(), CaseError> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(CaseError(format!(
                    "{key}: must be a finite number > 0, got {v}"
                )))
            }
        };
        pos("time.t_end", t.t_end)?;
        let cfl = self.cfl();
        if !(cfl > 0.0 && cfl <= 1.0) {
            return Err(CaseError(format!(
                "time.cfl: must be in (0, 1], got {}",
                cfl
            )));
        }
        if !(t.cfl_accel > 0.0 && t.cfl_accel <= 1.0) {
            return Err(CaseError(format!(
                "time.cfl_accel: must be in (0, 1], got {}",
                t.cfl_accel
            )));
        }
        pos("time.dt_min", t.dt_min)?;
        if let Some(m) = t.dt_max {
            pos("time.dt_max", m)?;
        }
        if t.max_steps == 0 {
            return Err(CaseError("time.max_steps: must be ≥ 1, got 0".into()));
        }
        let o = &self.output;
        if !(o.snapshot_every.is_finite() && o.snapshot_every >= 0.0) {
            return Err(CaseError(format!(
                "output.snapshot_every: must be ≥ 0 (0 = initial and final only), got {}",
                o.snapshot_every
            )));
        }
        if o.diagnostics_every == 0 {
            return Err(CaseError(
                "output.diagnostics_every: must be ≥ 1, got 0".into(),
            ));
        }
        if self.regions.is_empty() {
            return Err(CaseError(
                "region: at least one [[region]] is required".into(),
            ));
        }
        for (i, r) in self.regions.iter().enumerate() {
            self.validate_region(i, r)?;
        }
        for (i, f) in self.interfaces.iter().enumerate() {
            if f.axis >= d {
                return Err(CaseError(format!(
                    "interface[{i}].axis: must be in [0, {}], got {}",
                    d - 1,
                    f.axis
                )));
            }
            if !f.position.is_finite() {
                return Err(CaseError(format!(
                    "interface[{i}].position: must be finite"
                )));
            }
            pos(&format!("interface[{i}].width"), f.width)?;
            if f.stretch {
                // the stretch inverts the step's mass integral, which needs ρ constant on
                // either side (interface.rs)
                if let Some(j) = self
                    .regions
                    .iter()
                    .position(|r| r.density_profile.is_some())
                {
                    return Err(CaseError(format!(
                        "interface[{i}].stretch: needs a uniform `density` in every region; region[{j}] has a density_profile"
                    )));
                }
            }
        }
        if let Some(p) = &self.perturbation {
            if !(p.amplitude.is_finite() && (0.0..=0.5).contains(&p.amplitude)) {
                return Err(CaseError(format!(
                    "perturbation.amplitude: must be in [0, 0.5] (fraction of the lattice spacing), got {}",
                    p.amplitude
                )));
            }
        }
        super::fields::validate(&self.fields, d, self.regions.len())?;
        if let Some(g) = &self.gravity {
            self.vec_len("gravity", g)?;
        }
        if let Some(g) = &self.glass {
            g.validate()?;
        }
        if let Some(v) = &self.verify {
            v.validate(self)?;
        }
        if let Some(b) = &self.blast {
            b.validate(self)?;
        }
        for (i, b) in self.bodies.iter().enumerate() {
            b.validate(i, self)?;
        }
        for (i, p) in self.ports.iter().enumerate() {
            p.validate(i, self)?;
        }
        if let Some(f) = &self.frame {
            f.validate(self.dimension()).map_err(CaseError)?;
        }
        self.validate_probes()?;
        Ok(())
    }

    fn validate_region(&self, i: usize, r: &Region) -> Result<(), CaseError> {
        if let Some(deg) = r.lattice_rotation {
            if self.case.dimension != 2
                || !matches!(r.lattice, Lattice::Cubic | Lattice::Hexagonal)
                || r.shape != Shape::Box
                || !deg.is_finite()
            {
                return Err(CaseError(format!(
                    "region[{i}].lattice_rotation: turns a cubic or hexagonal lattice in a 2D box region by a finite number of degrees, got {deg} on a {:?} {:?} region in {}D",
                    r.lattice, r.shape, self.case.dimension
                )));
            }
        }
        let key = |s: &str| format!("region[{i}].{s}");
        if r.hydrostatic && (self.gravity.is_none() || r.pressure.is_none()) {
            return Err(CaseError(format!(
                "{}: needs `gravity` and {} (the pressure at the region's top)",
                key("hydrostatic"),
                key("pressure")
            )));
        }
        let pos = |k: &str, v: f64| -> Result<(), CaseError> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(CaseError(format!(
                    "{}: must be a finite number > 0, got {v}",
                    key(k)
                )))
            }
        };
        match r.shape {
            Shape::Box => {
                if r.center.is_some() || r.radius.is_some() {
                    return Err(CaseError(format!(
                        "{}: only for shape = \"sphere\"",
                        key("center/radius")
                    )));
                }
                if let Some(m) = &r.min {
                    self.vec_len(&key("min"), m)?;
                }
                if let Some(m) = &r.max {
                    self.vec_len(&key("max"), m)?;
                }
                let (lo, hi) = self.region_box(r);
                for k in 0..self.case.dimension {
                    if hi[k] <= lo[k] {
                        return Err(CaseError(format!(
                            "{}: must exceed min[{k}] = {}, got {}",
                            key(&format!("max[{k}]")),
                            lo[k],
                            hi[k]
                        )));
                    }
                }
            }
            Shape::Sphere => {
                let c = r.center.as_ref().ok_or_else(|| {
                    CaseError(format!(
                        "{}: required for shape = \"sphere\"",
                        key("center")
                    ))
                })?;
                self.vec_len(&key("center"), c)?;
                pos(
                    "radius",
                    r.radius.ok_or_else(|| {
                        CaseError(format!(
                            "{}: required for shape = \"sphere\"",
                            key("radius")
                        ))
                    })?,
                )?;
            }
        }
        match (r.spacing, r.particle_mass) {
            (Some(s), None) => pos("spacing", s)?,
            (None, Some(m)) => pos("particle_mass", m)?,
            _ => {
                return Err(CaseError(format!(
                    "{}: give exactly one of spacing and particle_mass",
                    key("spacing")
                )))
            }
        }
        match (r.density, &r.density_profile) {
            (Some(rho), None) => pos("density", rho)?,
            (None, Some(f)) => {
                f.compile(&key("density_profile"), self.case.dimension)?;
            }
            _ => {
                return Err(CaseError(format!(
                    "{}: give exactly one of density and density_profile",
                    key("density")
                )))
            }
        }
        let d = self.case.dimension;
        if let Some(drive) = &r.drive {
            drive.check(&key("drive"), d)?;
        }
        match r.lattice {
            Lattice::Rings if d != 2 || r.shape != Shape::Sphere || r.spacing.is_none() => {
                return Err(CaseError(format!(
                    "{}: \"rings\" is a 2D lattice of a shape = \"sphere\" region with a spacing (Δr)",
                    key("lattice")
                )))
            }
            Lattice::QuasiHexagonal
                if d != 2 || r.shape != Shape::Box || r.particle_mass.is_none() =>
            {
                return Err(CaseError(format!(
                    "{}: \"quasi-hexagonal\" is a 2D lattice of equal masses: a shape = \"box\" region with particle_mass",
                    key("lattice")
                )))
            }
            _ => {}
        }
        match (r.pressure, r.internal_energy) {
            (Some(p), None) => {
                if !(p.is_finite() && p >= 0.0) {
                    return Err(CaseError(format!(
                        "{}: must be a finite number ≥ 0, got {p}",
                        key("pressure")
                    )));
                }
            }
            (None, Some(u)) => {
                if !(u.is_finite() && u >= 0.0) {
                    return Err(CaseError(format!(
                        "{}: must be a finite number ≥ 0, got {u}",
                        key("internal_energy")
                    )));
                }
            }
            _ => {
                return Err(CaseError(format!(
                    "{}: give exactly one of pressure and internal_energy",
                    key("pressure")
                )))
            }
        }
        if let Some(v) = &r.velocity {
            self.vec_len(&key("velocity"), v)?;
        }
        if let Some(v) = r.radial_velocity {
            if !v.is_finite() {
                return Err(CaseError(format!(
                    "{}: must be finite",
                    key("radial_velocity")
                )));
            }
        }
        if let Some(c) = &r.radial_center {
            self.vec_len(&key("radial_center"), c)?;
        }
        if let Some(g) = &r.gresho {
            if self.case.dimension != 2 {
                return Err(CaseError(format!(
                    "{}: only in 2D (case.dimension = 2)",
                    key("gresho")
                )));
            }
            g.validate(&key("gresho"))?;
        }
        Ok(())
    }

    /// The box a region fills (its own corners, else the domain).
    pub(crate) fn region_box(&self, r: &Region) -> (Vec<f64>, Vec<f64>) {
        match r.shape {
            Shape::Box => (
                r.min.clone().unwrap_or_else(|| self.domain.min.clone()),
                r.max.clone().unwrap_or_else(|| self.domain.max.clone()),
            ),
            Shape::Sphere => {
                let c = r.center.clone().unwrap_or_default();
                let rad = r.radius.unwrap_or(0.0);
                (
                    c.iter().map(|x| x - rad).collect(),
                    c.iter().map(|x| x + rad).collect(),
                )
            }
        }
    }
}

impl Case {
    /// `[[material]]`: ids 1–255, each once, a valid EOS; schemes that read one EOS-wide
    /// constant (PSPH's γ, Rosswog's pressure offset for X = P^k) need it shared.
    /// What the special-relativistic presets (c = 1, Rosswog (2015) Sec. 6) can run: an ideal
    /// gas (Eq. 62) in a box, stepped by SSP-RK3, with rest-frame states n > 0, P > 0 and
    /// |v| < 1. Bodies, ports, materials, gravity and moving frames have no SR form here
    /// (driven regions do: `boundary::drive` sets S and ε).
    fn validate_relativistic(&self) -> Result<(), CaseError> {
        let name = "the rosswog-sr presets";
        if !matches!(self.eos, EosConfig::IdealGas { .. }) {
            return Err(CaseError(format!(
                "eos.type: {name} need eos.type = \"ideal-gas\" (P = (Γ − 1) n u, Rosswog (2015) Eq. 62)"
            )));
        }
        let refuse = |what: &str, present: bool| -> Result<(), CaseError> {
            if present {
                Err(CaseError(format!("{what}: {name} have no special-relativistic form of it; remove it or use a Newtonian scheme")))
            } else {
                Ok(())
            }
        };
        refuse("body", !self.bodies.is_empty())?;
        refuse("port", !self.ports.is_empty())?;
        refuse("material", !self.materials.is_empty())?;
        refuse("frame", self.frame.is_some())?;
        refuse(
            "gravity",
            self.gravity
                .as_ref()
                .is_some_and(|g| g.iter().any(|x| *x != 0.0)),
        )?;
        if self.integrator() != crate::integrate::IntegratorKind::SspRk3 {
            return Err(CaseError(format!(
                "time.integrator: {name} evolve S and ε with \"ssp-rk3\" only (Rosswog (2015) Sec. 6.5), got \"{}\"",
                self.integrator().name()
            )));
        }
        for (i, r) in self.regions.iter().enumerate() {
            refuse(&format!("region[{i}].gresho"), r.gresho.is_some())?;
            refuse(&format!("region[{i}].hydrostatic"), r.hydrostatic)?;
            if let Some(v) = &r.velocity {
                let speed = v.iter().map(|x| x * x).sum::<f64>().sqrt();
                if speed.is_nan() || speed >= 1.0 {
                    return Err(CaseError(format!(
                        "region[{i}].velocity: |v| must be < 1 (the speed of light, c = 1) with {name}, got {speed}"
                    )));
                }
            }
            if let Some(vr) = r.radial_velocity {
                if vr.is_nan() || vr.abs() >= 1.0 {
                    return Err(CaseError(format!(
                        "region[{i}].radial_velocity: must be in (−1, 1) (c = 1) with {name}, got {vr}"
                    )));
                }
            }
            match (r.pressure, r.internal_energy) {
                (Some(p), _) if !(p.is_finite() && p > 0.0) => {
                    return Err(CaseError(format!(
                        "region[{i}].pressure: must be a finite number > 0 with {name} (X = P^k and the primitive recovery), got {p}"
                    )))
                }
                (None, Some(u)) if !(u.is_finite() && u > 0.0) => {
                    return Err(CaseError(format!(
                        "region[{i}].internal_energy: must be a finite number > 0 with {name}, got {u}"
                    )))
                }
                (None, None) => {
                    return Err(CaseError(format!(
                        "region[{i}].pressure: {name} need a pressure (> 0) in every region"
                    )))
                }
                _ => {}
            }
        }
        Ok(())
    }

    fn validate_materials(&self) -> Result<(), CaseError> {
        for (k, m) in self.materials.iter().enumerate() {
            if !(1..=255).contains(&m.id) {
                return Err(CaseError(format!(
                    "material[{k}].id: must be in [1, 255] (0 is the case's [eos]), got {}",
                    m.id
                )));
            }
            if self.materials[..k].iter().any(|o| o.id == m.id) {
                return Err(CaseError(format!(
                    "material[{k}].id: {} is given twice",
                    m.id
                )));
            }
            m.eos
                .validate()
                .map_err(|e| CaseError(format!("material[{k}].{e}")))?;
            if matches!(self.scheme, SchemeConfig::Psph(_)) && m.eos != self.eos {
                return Err(CaseError(format!(
                    "material[{k}].eos: \"psph\" sums one pressure-entropy field with one γ; every material needs the case's [eos]"
                )));
            }
            if self.scheme.rosswog().is_some()
                && m.eos.pressure_offset() != self.eos.pressure_offset()
            {
                return Err(CaseError(format!(
                    "material[{k}].eos: Rosswog's X = P^k needs one pressure offset for all materials ({} here, {} for [eos])",
                    m.eos.pressure_offset(),
                    self.eos.pressure_offset()
                )));
            }
        }
        Ok(())
    }
}

//! What the instance keeps beside the solver: the input values the master set (applied at the
//! next doStep) and the FMU state snapshots that carry them with the solver's bytes.

use crate::table::{Binding, Causality, MotionInput, Mover, Start, Table};
use sphfmu::coupling::{orientation, BodyKinematics};

/// The inputs of one externally driven body as the master set them. Its orientation is in
/// one of three forms, fixed by the case (a 2D or 1D body's `angle`; a 3D body's
/// `orientation` quaternion or Modelica `T` matrix); the others keep their start values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BodyInputs {
    pub position: [f64; 3],
    pub velocity: [f64; 3],
    pub angle: f64,
    pub quaternion: [f64; 4],
    pub matrix_t: [f64; 9],
    /// World axes; a 2D body's scalar input is the z entry.
    pub angular_velocity: [f64; 3],
    pub acceleration: [f64; 3],
    /// As `angular_velocity`.
    pub angular_acceleration: [f64; 3],
}

impl Default for BodyInputs {
    fn default() -> Self {
        Self {
            position: [0.0; 3],
            velocity: [0.0; 3],
            angle: 0.0,
            quaternion: orientation::IDENTITY,
            matrix_t: orientation::IDENTITY_T,
            angular_velocity: [0.0; 3],
            acceleration: [0.0; 3],
            angular_acceleration: [0.0; 3],
        }
    }
}

/// Which of a body's orientation inputs the table has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OrientationForm {
    Angle,
    Quaternion,
    Matrix,
}

impl BodyInputs {
    /// The solver's kinematics, or why the orientation is not a rotation (`name` is the
    /// body's name, for the message).
    pub fn kinematics(&self, name: &str, form: OrientationForm) -> Result<BodyKinematics, String> {
        let orientation = match form {
            OrientationForm::Angle => orientation::planar(self.angle),
            OrientationForm::Quaternion => {
                orientation::unit_quaternion(&format!("{name}.orientation"), &self.quaternion)?
            }
            OrientationForm::Matrix => {
                orientation::from_matrix_t(&format!("{name}.T"), &self.matrix_t)?
            }
        };
        Ok(BodyKinematics {
            position: self.position,
            orientation,
            velocity: self.velocity,
            angular_velocity: self.angular_velocity,
            acceleration: self.acceleration,
            angular_acceleration: self.angular_acceleration,
        })
    }

    /// The numbers of one input (a 2D angular input is the z entry: the slice's last).
    pub fn field(&self, f: MotionInput, size: usize) -> &[f64] {
        let all: &[f64] = match f {
            MotionInput::Position => &self.position,
            MotionInput::Angle => std::slice::from_ref(&self.angle),
            MotionInput::Quaternion => &self.quaternion,
            MotionInput::Matrix => &self.matrix_t,
            MotionInput::Velocity => &self.velocity,
            MotionInput::AngularVelocity => &self.angular_velocity,
            MotionInput::Acceleration => &self.acceleration,
            MotionInput::AngularAcceleration => &self.angular_acceleration,
        };
        &all[all.len() - size..]
    }

    /// As [`Self::field`], to set.
    pub fn field_mut(&mut self, f: MotionInput, size: usize) -> &mut [f64] {
        let all: &mut [f64] = match f {
            MotionInput::Position => &mut self.position,
            MotionInput::Angle => std::slice::from_mut(&mut self.angle),
            MotionInput::Quaternion => &mut self.quaternion,
            MotionInput::Matrix => &mut self.matrix_t,
            MotionInput::Velocity => &mut self.velocity,
            MotionInput::AngularVelocity => &mut self.angular_velocity,
            MotionInput::Acceleration => &mut self.acceleration,
            MotionInput::AngularAcceleration => &mut self.angular_acceleration,
        };
        let n = all.len();
        &mut all[n - size..]
    }

    fn numbers(&self) -> impl Iterator<Item = &f64> {
        self.position
            .iter()
            .chain(&self.velocity)
            .chain([&self.angle])
            .chain(&self.quaternion)
            .chain(&self.matrix_t)
            .chain(&self.angular_velocity)
            .chain(&self.acceleration)
            .chain(&self.angular_acceleration)
    }

    fn numbers_mut(&mut self) -> impl Iterator<Item = &mut f64> {
        self.position
            .iter_mut()
            .chain(&mut self.velocity)
            .chain([&mut self.angle])
            .chain(&mut self.quaternion)
            .chain(&mut self.matrix_t)
            .chain(&mut self.angular_velocity)
            .chain(&mut self.acceleration)
            .chain(&mut self.angular_acceleration)
    }
}

/// Numbers per body in a serialized state (3 + 3 + 1 + 4 + 9 + 3 + 3 + 3).
const BODY_NUMBERS: usize = 29;

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Inputs {
    pub gravity: [f64; 3],
    /// Per externally driven body (order of `Table::external_bodies`).
    pub bodies: Vec<BodyInputs>,
    /// The frame's, when it is driven from outside.
    pub frame: Option<BodyInputs>,
    /// Per port with an external pressure (order of `Table::external_ports`).
    pub ports: Vec<f64>,
}

impl Inputs {
    /// The inputs of a body or the frame.
    pub fn mover(&self, table: &Table, m: Mover) -> &BodyInputs {
        match m {
            Mover::Body(b) => &self.bodies[table.external_index(b)],
            Mover::Frame => self.frame.as_ref().expect("the table has frame inputs"),
        }
    }

    pub fn mover_mut(&mut self, table: &Table, m: Mover) -> &mut BodyInputs {
        match m {
            Mover::Body(b) => &mut self.bodies[table.external_index(b)],
            Mover::Frame => self.frame.as_mut().expect("the table has frame inputs"),
        }
    }
}

/// A saved FMU state: the solver's bytes plus what the instance keeps beside them.
pub struct Snapshot {
    pub(crate) inputs: Inputs,
    pub(crate) start_time: f64,
    pub(crate) solver: Vec<u8>,
}

/// The inputs at their start values.
pub(crate) fn start_inputs(table: &Table) -> Inputs {
    let mut inputs = Inputs {
        gravity: [0.0; 3],
        bodies: vec![BodyInputs::default(); table.external_bodies.len()],
        frame: table.frame_form.map(|_| BodyInputs::default()),
        ports: vec![0.0; table.external_ports.len()],
    };
    for v in &table.variables {
        if let (Causality::Input, Start::Float(x)) = (v.causality, &v.start) {
            match v.binding {
                Binding::Gravity => inputs.gravity.copy_from_slice(x),
                Binding::Motion(m, MotionInput::Position) => {
                    inputs.mover_mut(table, m).position.copy_from_slice(x);
                }
                Binding::PortPressure(k) => inputs.ports[table.external_port_index(k)] = x[0],
                _ => {}
            }
        }
    }
    inputs
}

/// The serialized FMU state's envelope (`sphfmu::coupling::state::seal`): magic bytes and
/// format version; the CRC-32 covers the inputs and the solver's own (sealed) bytes alike.
const MAGIC: [u8; 8] = *b"sphfmuFS";
/// 2: a body carries its angle, quaternion, matrix, 3-vector angular velocity and the
/// accelerations (issue 22).
const VERSION: u32 = 2;

impl Snapshot {
    /// Sealed bytes: gravity, start time, the body count and 29 numbers per body, 1 and the frame's 29 numbers or 0, the port
    /// count and one pressure per port (f64 little endian), then the solver's state.
    pub fn serialize(&self) -> Vec<u8> {
        let mut out = Vec::new();
        let mut put = |x: f64| out.extend_from_slice(&x.to_le_bytes());
        self.inputs.gravity.iter().for_each(|x| put(*x));
        put(self.start_time);
        put(self.inputs.bodies.len() as f64);
        for b in &self.inputs.bodies {
            b.numbers().for_each(|x| put(*x));
        }
        put(self.inputs.frame.is_some() as u8 as f64);
        if let Some(b) = &self.inputs.frame {
            b.numbers().for_each(|x| put(*x));
        }
        put(self.inputs.ports.len() as f64);
        self.inputs.ports.iter().for_each(|x| put(*x));
        out.extend_from_slice(&self.solver);
        sphfmu::coupling::state::seal(&MAGIC, VERSION, &out)
    }

    /// The state back from [`Self::serialize`]'s bytes. Empty, truncated, extended, random or
    /// altered bytes are an error naming what is wrong; the solver part is checked again, in
    /// full, when the state is set (`Coupling::restore`).
    pub fn deserialize(bytes: &[u8]) -> Result<Snapshot, String> {
        let bytes = sphfmu::coupling::state::open("serialized FMU state", &MAGIC, VERSION, bytes)?;
        let mut at = 0;
        let mut get = || -> Result<f64, String> {
            let b = bytes
                .get(at..at + 8)
                .ok_or("serialized FMU state: too short")?;
            at += 8;
            Ok(f64::from_le_bytes(b.try_into().expect("8 bytes")))
        };
        let count = |n: f64, what: &str| {
            if (0.0..=65535.0).contains(&n) && n.fract() == 0.0 {
                Ok(n as usize)
            } else {
                Err(format!("serialized FMU state: damaged {what} count"))
            }
        };
        let mut gravity = [0.0; 3];
        for g in &mut gravity {
            *g = get()?;
        }
        let start_time = get()?;
        let n = count(get()?, "body")?;
        let mut bodies = vec![];
        for _ in 0..n {
            let mut k = BodyInputs::default();
            for x in k.numbers_mut() {
                *x = get()?;
            }
            bodies.push(k);
        }
        let framed = count(get()?, "frame")?;
        let mut frame = None;
        if framed > 1 {
            return Err("serialized FMU state: damaged frame count".into());
        }
        if framed == 1 {
            let mut k = BodyInputs::default();
            for x in k.numbers_mut() {
                *x = get()?;
            }
            frame = Some(k);
        }
        let m = count(get()?, "port")?;
        let ports = (0..m).map(|_| get()).collect::<Result<Vec<_>, _>>()?;
        let used = 8 * (7 + BODY_NUMBERS * (n + framed) + m);
        Ok(Snapshot {
            inputs: Inputs {
                gravity,
                bodies,
                frame,
                ports,
            },
            start_time,
            solver: bytes[used..].to_vec(),
        })
    }
}

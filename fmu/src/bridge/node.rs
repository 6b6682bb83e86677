//! The solver as a zenoh service (`sphfmu serve`, binary `sphfmu-serve`): one FMU instance
//! (the same code, state machine and checks as the FMU) driven through queryables, so a
//! master on another machine can step it like a co-simulation slave. Besides these, the
//! instance's bridge publishes outputs, takes live inputs and answers snapshots as in the FMU.
//!
//! Requests and replies are CBOR (see `codec`); an error reply is `{"error": message}`.
//! - `<prefix>/step`  `{"t": target}` or `{"h": step}` → `{"t": time reached}`
//! - `<prefix>/get`   `{"names": [...]}` (none: every output) → `{"t", "values": {name: v}}`
//! - `<prefix>/set`   `{"values": {name: v}}` (all or nothing) → `{"t"}`
//! - `<prefix>/save_state` → the FMU state bytes (as `fmi3SerializeFMUState`)
//! - `<prefix>/restore_state` with those bytes → `{"t"}`
//! - `<prefix>/reset` → `{"t"}`: back to the state at the end of initialisation (bit for bit),
//!   also out of Failed (a step the solver could not take, e.g. under an absurd gravity)
//! - `<prefix>/stop` → `{"t"}`, then the node exits.
//!
//! A request with a bad argument gets an error reply and changes nothing; the node goes on
//! serving. A step cut short by `limits.max_internal_steps` / `limits.max_step_seconds`
//! (`--set`) gets an error reply that says where it stopped, with the node at that time.

use super::codec::{self, field, map, numbers};
use crate::instance::inputs::Snapshot;
use crate::instance::Instance;
use crate::table::{Causality, Kind};
use ciborium::Value;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Op {
    Step,
    Get,
    Set,
    SaveState,
    RestoreState,
    Reset,
    Stop,
}

pub const OPS: [(&str, Op); 7] = [
    ("step", Op::Step),
    ("get", Op::Get),
    ("set", Op::Set),
    ("save_state", Op::SaveState),
    ("restore_state", Op::RestoreState),
    ("reset", Op::Reset),
    ("stop", Op::Stop),
];

fn index(inst: &Instance, name: &str) -> Result<usize, String> {
    inst.table
        .variables
        .iter()
        .position(|v| v.name == name)
        .ok_or_else(|| format!("{name}: no such variable"))
}

fn request(payload: Option<&[u8]>, op: &str) -> Result<Value, String> {
    match payload {
        None => Ok(Value::Map(vec![])),
        Some([]) => Ok(Value::Map(vec![])),
        Some(b) => {
            let v = codec::decode(b).map_err(|e| format!("{op}: request {e}"))?;
            match v {
                Value::Map(_) => Ok(v),
                _ => Err(format!("{op}: the request must be a CBOR map")),
            }
        }
    }
}

fn time_reply(inst: &Instance) -> Vec<u8> {
    codec::encode(&map(vec![("t", Value::Float(inst.time()))]))
}

/// The value of variable `i` as CBOR.
fn value(inst: &mut Instance, i: usize) -> Result<Value, String> {
    let r = match inst.table.variables[i].kind {
        Kind::Float64 => inst.get_f64(i).map(|x| numbers(&x)),
        Kind::Int64 => inst.get_i64(i).map(|n| Value::Integer(n.into())),
        Kind::String => inst.get_string(i).map(Value::Text),
    };
    r.map_err(|e| e.1)
}

/// Set variable `i` from a CBOR value, checked as the FMU checks a set.
fn set(inst: &mut Instance, i: usize, v: &Value) -> Result<(), String> {
    let var = &inst.table.variables[i];
    let (name, size, kind) = (var.name.clone(), var.size, var.kind);
    if !matches!(var.causality, Causality::Parameter | Causality::Input) {
        // (before decoding the value, so the reason is the causality, as in the FMU)
        return Err(format!(
            "{name}: is not a parameter or input (causality {:?}), it cannot be set",
            var.causality
        ));
    }
    let d = inst.table.dimension;
    let r = match (kind, v) {
        (Kind::Float64, _) => {
            let x = codec::values_of(v, &name, size, d)?;
            inst.set_f64(i, 0, &x)
        }
        (Kind::Int64, Value::Integer(n)) => {
            let n = i64::try_from(i128::from(*n))
                .map_err(|_| format!("{name}: integer out of range"))?;
            inst.set_i64(i, n)
        }
        (Kind::String, Value::Text(t)) => inst.set_string(i, t),
        (Kind::Int64, _) => return Err(format!("{name}: expected an integer")),
        (Kind::String, _) => return Err(format!("{name}: expected a text string")),
    };
    r.map_err(|e| e.1)
}

/// Set a variable from command-line text (`--set name=value`): numbers comma separated.
pub fn set_text(inst: &mut Instance, name: &str, text: &str) -> Result<(), String> {
    let i = index(inst, name)?;
    let v = match inst.table.variables[i].kind {
        Kind::String => Value::Text(text.into()),
        Kind::Int64 => Value::Integer(
            text.trim()
                .parse::<i64>()
                .map_err(|_| format!("{name}: expected an integer, got {text:?}"))?
                .into(),
        ),
        Kind::Float64 => {
            let xs = text
                .split(',')
                .map(|s| s.trim().parse::<f64>())
                .collect::<Result<Vec<f64>, _>>()
                .map_err(|_| {
                    format!("{name}: expected numbers separated by commas, got {text:?}")
                })?;
            Value::Array(xs.into_iter().map(Value::Float).collect())
        }
    };
    set(inst, i, &v)
}

/// Answer one request; `initial` is the state at the end of initialisation (for `reset`).
pub fn handle(
    inst: &mut Instance,
    op: Op,
    payload: Option<&[u8]>,
    initial: &Snapshot,
) -> Result<Vec<u8>, String> {
    let name = OPS.iter().find(|o| o.1 == op).expect("listed").0;
    match op {
        Op::Step => {
            let r = request(payload, name)?;
            let now = inst.time();
            let num = |k: &'static str| field(&r, k).map(|v| codec::number(v).ok_or(k));
            let h = match (num("t"), num("h")) {
                (Some(Ok(t)), None) => t - now,
                (None, Some(Ok(h))) => h,
                (Some(Err(k)), _) | (_, Some(Err(k))) => {
                    return Err(format!("step: {k} must be a number"))
                }
                _ => {
                    return Err(format!(
                        "step: give the target time {{\"t\": t}} (> {now}) or the step {{\"h\": h}} (> 0)"
                    ))
                }
            };
            inst.do_step(now, h).map_err(|e| e.1)?;
            Ok(time_reply(inst))
        }
        Op::Get => {
            let r = request(payload, name)?;
            let names: Vec<String> = match field(&r, "names") {
                None => inst
                    .table
                    .variables
                    .iter()
                    .filter(|v| v.causality == Causality::Output)
                    .map(|v| v.name.clone())
                    .collect(),
                Some(Value::Array(a)) => a
                    .iter()
                    .map(|v| match v {
                        Value::Text(t) => Ok(t.clone()),
                        _ => Err("get: names must be text strings".to_string()),
                    })
                    .collect::<Result<_, _>>()?,
                Some(_) => return Err("get: names must be an array of text strings".into()),
            };
            let mut values = vec![];
            for n in names {
                let i = index(inst, &n)?;
                values.push((Value::Text(n), value(inst, i)?));
            }
            let t = Value::Float(inst.time());
            Ok(codec::encode(&map(vec![
                ("t", t),
                ("values", Value::Map(values)),
            ])))
        }
        Op::Set => {
            let r = request(payload, name)?;
            let Some(Value::Map(entries)) = field(&r, "values") else {
                return Err("set: give {\"values\": {name: value, ...}}".into());
            };
            let mut resolved = vec![];
            for (k, v) in entries {
                let Value::Text(n) = k else {
                    return Err("set: names must be text strings".into());
                };
                resolved.push((index(inst, n)?, v.clone()));
            }
            let mut message = String::new();
            let outcome = inst.atomically(|inst| {
                for (i, v) in &resolved {
                    if let Err(e) = set(inst, *i, v) {
                        message = e.clone();
                        return Err((crate::instance::Status::Error, e));
                    }
                }
                Ok(())
            });
            outcome.map_err(|_| message)?;
            Ok(time_reply(inst))
        }
        Op::SaveState => Ok(inst.get_state().map_err(|e| e.1)?.serialize()),
        Op::RestoreState => {
            let bytes = payload.ok_or("restore_state: send the bytes of a saved state")?;
            let s = Snapshot::deserialize(bytes).map_err(|e| format!("restore_state: {e}"))?;
            inst.set_state(&s).map_err(|e| e.1)?;
            Ok(time_reply(inst))
        }
        Op::Reset => {
            inst.set_state(initial).map_err(|e| e.1)?;
            Ok(time_reply(inst))
        }
        Op::Stop => Ok(time_reply(inst)),
    }
}

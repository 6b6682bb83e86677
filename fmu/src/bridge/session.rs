//! Live coupling over zenoh (feature `zenoh`): one zenoh session per instance.
//!
//! - After each communication step the instance publishes every output on
//!   `<prefix>/out/<name>` as `{"t": time, "v": value}` (CBOR, see `codec`).
//! - Inputs arrive on `<prefix>/in/<name>` at any time (a zenoh thread decodes and checks
//!   them and keeps the latest per input); they are applied only at the next communication
//!   point, never inside a step, so a step stays deterministic and an FMU state restore
//!   means what it says.
//! - `<prefix>/snapshot` answers with the particles as of the last communication point
//!   (`?stride=N` keeps every N-th, `?kind=all` adds wall and port-buffer particles).
//!
//! Which value wins (README § Live coupling): a live value overrides the master's value for
//! that input from the communication point after it arrives. Once it is older than
//! `zenoh.staleness` seconds (wall clock: the publisher went quiet), `zenoh.on_stale` decides:
//! hold it (default), go back to the master's value, or fail the step. A fresh value resumes
//! live coupling. The master's own value is kept apart and is what getters return.

use super::codec;
use crate::bridge::settings::{OnStale, ZenohSettings};
use ciborium::Value;
use sphfmu::coupling::{ParticleKind, ParticleState};
use std::collections::{BTreeMap, HashMap};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use zenoh::bytes::Encoding;
use zenoh::config::Config;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::query::{Query, Queryable};
use zenoh::sample::Sample;
use zenoh::{Session, Wait};

/// The latest value of one live input.
#[derive(Debug, Clone)]
struct Live {
    values: Vec<f64>,
    at: Instant,
}

#[derive(Debug, Default)]
struct Inbox {
    latest: BTreeMap<usize, Live>,
    /// Why payloads were refused since the last communication point.
    rejected: Vec<String>,
}

/// The particle states of the last communication point, for `<prefix>/snapshot`.
#[derive(Debug, Default)]
struct Cloud {
    time: f64,
    dimension: usize,
    states: Vec<ParticleState>,
}

/// An input as the master sees it: variable index, name, number of elements.
#[derive(Debug, Clone)]
pub struct InputSpec {
    pub index: usize,
    pub name: String,
    pub size: usize,
}

/// A live value to apply at this communication point.
#[derive(Debug, Clone, PartialEq)]
pub struct LiveValue {
    pub index: usize,
    pub values: Vec<f64>,
}

/// What the instance has to do with the live inputs at a communication point.
#[derive(Debug, Default)]
pub struct Exchange {
    pub apply: Vec<LiveValue>,
    /// Messages to log as warnings (refused payloads, inputs gone stale).
    pub warnings: Vec<String>,
    /// Messages to log as information (live coupling resumed).
    pub notes: Vec<String>,
    /// Set when `on_stale = error` and an input is stale: the step must fail with it.
    pub error: Option<String>,
}

pub struct Bridge {
    session: Session,
    settings: ZenohSettings,
    outputs: Vec<(usize, Publisher<'static>)>,
    inbox: Arc<Mutex<Inbox>>,
    cloud: Arc<Mutex<Cloud>>,
    names: HashMap<usize, String>,
    /// Inputs currently stale (warned once, until a fresh value comes).
    stale: Vec<usize>,
    /// The last live value of each input that the instance accepted.
    accepted: BTreeMap<usize, Vec<f64>>,
    _inputs: Subscriber<()>,
    _snapshot: Queryable<()>,
}

fn zerr(what: &str, e: impl std::fmt::Display) -> String {
    format!("zenoh: {what}: {e}")
}

/// The session configuration of the `zenoh.*` parameters: the JSON5 file if any, then mode,
/// endpoints, and (without a file) multicast scouting and gossip off, so nothing leaves the
/// configured endpoints.
pub fn config(s: &ZenohSettings) -> Result<Config, String> {
    let mut c = if s.config.is_empty() {
        let mut c = Config::default();
        for (k, v) in [
            ("scouting/multicast/enabled", "false"),
            ("scouting/gossip/enabled", "false"),
        ] {
            c.insert_json5(k, v).map_err(|e| zerr(k, e))?;
        }
        c
    } else {
        Config::from_file(&s.config).map_err(|e| format!("zenoh.config: {e}"))?
    };
    // endpoints were checked to be <protocol>/<address>; Debug quotes them as JSON5 strings
    let json = |v: &[String]| format!("{v:?}");
    c.insert_json5("mode", &format!("{:?}", s.mode))
        .map_err(|e| zerr("zenoh.mode", e))?;
    let connect = ZenohSettings::endpoints(&s.connect);
    if !connect.is_empty() {
        c.insert_json5("connect/endpoints", &json(&connect))
            .map_err(|e| format!("zenoh.connect: {e}"))?;
    }
    let listen = ZenohSettings::endpoints(&s.listen);
    if !listen.is_empty() {
        c.insert_json5("listen/endpoints", &json(&listen))
            .map_err(|e| format!("zenoh.listen: {e}"))?;
    }
    Ok(c)
}

impl Bridge {
    /// Open the session and declare the publishers, the input subscriber and the snapshot
    /// queryable. `outputs`: (variable index, name) of every output.
    pub fn open(
        settings: &ZenohSettings,
        prefix: &str,
        inputs: Vec<InputSpec>,
        outputs: Vec<(usize, String)>,
        dimension: usize,
    ) -> Result<Bridge, String> {
        let session = zenoh::open(config(settings)?).wait().map_err(|e| {
            format!("zenoh.listen / zenoh.connect: cannot open a zenoh session ({e})")
        })?;
        let mut publishers = Vec::with_capacity(outputs.len());
        let mut names = HashMap::new();
        for (i, name) in outputs {
            let key = format!("{prefix}/out/{name}");
            let p = session
                .declare_publisher(key.clone())
                .encoding(Encoding::APPLICATION_CBOR)
                .wait()
                .map_err(|e| zerr(&key, e))?;
            publishers.push((i, p));
        }
        for s in &inputs {
            names.insert(s.index, s.name.clone());
        }
        let inbox = Arc::new(Mutex::new(Inbox::default()));
        let by_name: HashMap<String, InputSpec> =
            inputs.into_iter().map(|s| (s.name.clone(), s)).collect();
        let in_prefix = format!("{prefix}/in/");
        let sink = inbox.clone();
        let subscriber = session
            .declare_subscriber(format!("{prefix}/in/**"))
            .callback(move |sample: Sample| {
                let key = sample.key_expr().as_str();
                let name = key.strip_prefix(&in_prefix).unwrap_or(key);
                let result = match by_name.get(name) {
                    None => {
                        let mut known: Vec<&str> = by_name.keys().map(|s| s.as_str()).collect();
                        known.sort();
                        Err(format!(
                            "{key}: no such input (inputs: {})",
                            known.join(", ")
                        ))
                    }
                    Some(spec) => codec::input_values(
                        &sample.payload().to_bytes(),
                        name,
                        spec.size,
                        dimension,
                    )
                    .map(|v| (spec.index, v)),
                };
                let mut inbox = sink.lock().unwrap_or_else(|p| p.into_inner());
                match result {
                    Ok((index, values)) => {
                        inbox.latest.insert(
                            index,
                            Live {
                                values,
                                at: Instant::now(),
                            },
                        );
                    }
                    // keep the first few reasons per step (a flood must not grow memory)
                    Err(e) if inbox.rejected.len() < 16 => inbox.rejected.push(e),
                    Err(_) => {}
                }
            })
            .wait()
            .map_err(|e| zerr("input subscriber", e))?;
        let cloud = Arc::new(Mutex::new(Cloud {
            dimension,
            ..Cloud::default()
        }));
        let source = cloud.clone();
        let snapshot = session
            .declare_queryable(format!("{prefix}/snapshot"))
            .callback(move |q: Query| {
                let reply = {
                    let c = source.lock().unwrap_or_else(|p| p.into_inner());
                    snapshot_reply(&c, &q)
                };
                let sent = match reply {
                    Ok(bytes) => q
                        .reply(q.key_expr().clone(), bytes)
                        .encoding(Encoding::APPLICATION_CBOR)
                        .wait(),
                    Err(msg) => q.reply_err(error_payload(&msg)).wait(),
                };
                // the querier may have gone; nothing else to do then
                drop(sent);
            })
            .wait()
            .map_err(|e| zerr("snapshot queryable", e))?;
        Ok(Bridge {
            session,
            settings: settings.clone(),
            outputs: publishers,
            inbox,
            cloud,
            names,
            stale: vec![],
            accepted: BTreeMap::new(),
            _inputs: subscriber,
            _snapshot: snapshot,
        })
    }

    pub fn session(&self) -> &Session {
        &self.session
    }

    /// The live inputs to apply now, by the precedence rule of the module comment.
    pub fn exchange(&mut self) -> Exchange {
        let mut x = Exchange::default();
        let now = Instant::now();
        let limit = (self.settings.staleness > 0.0)
            .then(|| Duration::from_secs_f64(self.settings.staleness));
        let mut inbox = self.inbox.lock().unwrap_or_else(|p| p.into_inner());
        for e in inbox.rejected.drain(..) {
            x.warnings
                .push(format!("zenoh input refused, nothing changed: {e}"));
        }
        for (&index, live) in &inbox.latest {
            let name = &self.names[&index];
            let age = now.duration_since(live.at);
            let stale = limit.is_some_and(|l| age > l);
            let was_stale = self.stale.contains(&index);
            if stale && !was_stale {
                self.stale.push(index);
                x.warnings.push(format!(
                    "zenoh input {name}: no value for {:.2} s (zenoh.staleness {} s): {}",
                    age.as_secs_f64(),
                    self.settings.staleness,
                    match self.settings.on_stale {
                        OnStale::Hold => "holding the last value",
                        OnStale::Master => "the master's value applies again",
                        OnStale::Error => "failing the step (zenoh.on_stale = error)",
                    }
                ));
            } else if !stale && was_stale {
                self.stale.retain(|&k| k != index);
                x.notes
                    .push(format!("zenoh input {name}: live again, its value applies"));
            }
            match (stale, self.settings.on_stale) {
                (false, _) | (true, OnStale::Hold) => x.apply.push(LiveValue {
                    index,
                    values: live.values.clone(),
                }),
                (true, OnStale::Master) => {}
                (true, OnStale::Error) => {
                    x.error.get_or_insert(format!(
                        "zenoh input {name} is stale (no value for {:.2} s, zenoh.staleness {} s, zenoh.on_stale = error)",
                        age.as_secs_f64(),
                        self.settings.staleness
                    ));
                }
            }
        }
        x
    }

    /// The last live value of input `index` that the instance accepted.
    pub fn accepted(&self, index: usize) -> Option<Vec<f64>> {
        self.accepted.get(&index).cloned()
    }

    /// The instance's verdict on a live value of `exchange`: an accepted value is remembered;
    /// a refused one (out of range for the input) is replaced by the last accepted value, or
    /// dropped if there is none, so it is not retried at every step and the input keeps what
    /// it had.
    pub fn settle(&mut self, value: &LiveValue, accepted: bool) {
        if accepted {
            self.accepted.insert(value.index, value.values.clone());
            return;
        }
        let mut inbox = self.inbox.lock().unwrap_or_else(|p| p.into_inner());
        match self.accepted.get(&value.index) {
            Some(v) => {
                if let Some(live) = inbox.latest.get_mut(&value.index) {
                    live.values = v.clone();
                }
            }
            None => {
                inbox.latest.remove(&value.index);
            }
        }
    }

    /// Publish the outputs (`values(i)` gives output variable i's value) at time `t`, and
    /// keep the particles for the snapshot queryable. The first failed put is returned.
    pub fn publish(
        &self,
        t: f64,
        mut values: impl FnMut(usize) -> Option<Value>,
        particles: Vec<ParticleState>,
    ) -> Result<(), String> {
        {
            let mut c = self.cloud.lock().unwrap_or_else(|p| p.into_inner());
            c.time = t;
            c.states = particles;
        }
        let mut first_error = None;
        for (i, p) in &self.outputs {
            let Some(v) = values(*i) else { continue };
            if let Err(e) = p.put(codec::sample(t, v)).wait() {
                first_error.get_or_insert(zerr(p.key_expr().as_str(), e));
            }
        }
        first_error.map_or(Ok(()), Err)
    }
}

/// A CBOR `{"error": message}` for error replies.
pub fn error_payload(msg: &str) -> Vec<u8> {
    codec::encode(&codec::map(vec![("error", Value::Text(msg.into()))]))
}

/// The snapshot reply: `{"t", "dimension", "count", "stride", "kind", "position", "velocity",
/// "density", "pressure"}`; `kind` is one byte per particle (0 fluid, 1 wall, 2 port buffer),
/// the rest little-endian f64 (position and velocity `dimension` values per particle).
fn snapshot_reply(c: &Cloud, q: &Query) -> Result<Vec<u8>, String> {
    let params = q.parameters();
    let stride = match params.get("stride") {
        None => 1,
        Some(s) => match s.parse::<usize>() {
            Ok(n) if n >= 1 => n,
            _ => return Err(format!("stride: must be a whole number ≥ 1, got {s:?}")),
        },
    };
    let all = match params.get("kind") {
        None | Some("fluid") => false,
        Some("all") => true,
        Some(k) => return Err(format!("kind: must be fluid or all, got {k:?}")),
    };
    let code = |k: ParticleKind| match k {
        ParticleKind::Fluid => 0u8,
        ParticleKind::Wall(_) => 1,
        ParticleKind::Buffer(_) => 2,
    };
    let chosen: Vec<&ParticleState> = c
        .states
        .iter()
        .filter(|p| all || p.kind == ParticleKind::Fluid)
        .step_by(stride)
        .collect();
    let d = c.dimension;
    let v = codec::map(vec![
        ("t", Value::Float(c.time)),
        ("dimension", Value::Integer((d as u64).into())),
        ("count", Value::Integer((chosen.len() as u64).into())),
        ("stride", Value::Integer((stride as u64).into())),
        (
            "kind",
            Value::Bytes(chosen.iter().map(|p| code(p.kind)).collect()),
        ),
        (
            "position",
            codec::f64_bytes(chosen.iter().flat_map(|p| p.position[..d].to_vec())),
        ),
        (
            "velocity",
            codec::f64_bytes(chosen.iter().flat_map(|p| p.velocity[..d].to_vec())),
        ),
        (
            "density",
            codec::f64_bytes(chosen.iter().map(|p| p.density)),
        ),
        (
            "pressure",
            codec::f64_bytes(chosen.iter().map(|p| p.pressure)),
        ),
    ]);
    Ok(codec::encode(&v))
}

//! The FMU as a proxy of a remote solver (issue 23): with the parameter `remote` set to the
//! key prefix of a running `sphfmu serve` node, the instance keeps its variable table, its
//! state machine and its argument checks, and forwards the rest to the node over zenoh
//! (`node.rs` answers): each doStep sends every input (`set`, all or nothing), steps the
//! node (`step`) and reads every output back (`get`); getFMUState and setFMUState carry the
//! node's own state bytes (`save_state`, `restore_state`). The master keeps a small FMU in
//! its process while the solver runs elsewhere (another machine, or under mpirun).
//!
//! A node that does not answer within the time limit, or has gone away, is an error of the
//! call that needed it, logged with the node's prefix; the master's process goes on, and a
//! setFMUState of a saved state to a node started anew resumes the run.

use super::codec::{self, field, map};
use super::settings::ZenohSettings;
use ciborium::Value;
use std::collections::HashMap;
use std::time::{Duration, Instant};
use zenoh::{Session, Wait};

/// How long a request may wait for the node's reply. A step of a large case can take long;
/// a node that died closes its links, which ends the wait at once (measured on loopback).
pub const REPLY_TIMEOUT: Duration = Duration::from_secs(3600);
/// How long opening waits for the node to answer its first request (links come up and
/// declarations propagate in about 0.1–0.5 s on loopback).
pub const FIRST_REPLY_TIMEOUT: Duration = Duration::from_secs(20);

/// How a node's error reply begins when the node is ending while it serves a request (a
/// signal: under mpirun, Open MPI's SIGTERM after another rank of the job stopped). The
/// request did not complete and the node will not answer again.
pub const NODE_ENDING: &str = "the node is ending";

/// How a request to the node failed.
#[derive(Debug, Clone, PartialEq)]
pub enum RemoteError {
    /// The node answered with an error: the message is its own (as the local FMU's).
    Refused(String),
    /// No reply: the node is gone, unreachable or too slow.
    Unreachable(String),
    /// The node answered that it is ending (its message begins with [`NODE_ENDING`] and says
    /// why): gone, as [`RemoteError::Unreachable`], but with the node's own reason.
    Ended(String),
}

impl RemoteError {
    pub fn message(&self) -> &str {
        match self {
            RemoteError::Refused(m) | RemoteError::Unreachable(m) | RemoteError::Ended(m) => m,
        }
    }

    /// The node is gone (no reply, or it said it is ending): a later call needs a node anew.
    pub fn node_gone(&self) -> bool {
        !matches!(self, RemoteError::Refused(_))
    }
}

pub struct RemoteNode {
    session: Session,
    pub prefix: String,
    /// The outputs of the node's current state (the latest `get`), by name.
    outputs: HashMap<String, Vec<f64>>,
    /// The node's time at its latest reply.
    pub time: f64,
    /// The node's time at the end of its initialisation (its `reset`): this instance's
    /// solver time is the node's time less this.
    pub origin: f64,
}

impl RemoteNode {
    /// Open a zenoh session from the `zenoh.*` parameters (mode `off` opens a peer) and wait
    /// for the node at `prefix` to answer.
    pub fn open(settings: &ZenohSettings, prefix: &str) -> Result<RemoteNode, String> {
        let mut s = settings.clone();
        if s.mode == "off" {
            s.mode = "peer".into();
        }
        let session = zenoh::open(super::session::config(&s)?)
            .wait()
            .map_err(|e| format!("remote: cannot open a zenoh session ({e})"))?;
        let mut node = RemoteNode {
            session,
            prefix: prefix.to_string(),
            outputs: HashMap::new(),
            time: 0.0,
            origin: 0.0,
        };
        let start = Instant::now();
        loop {
            match node.request("get", &map(vec![("names", Value::Array(vec![]))]), Duration::from_secs(1)) {
                Ok(_) => return Ok(node),
                Err(RemoteError::Refused(m)) => return Err(format!("remote {prefix:?}: {m}")),
                Err(RemoteError::Unreachable(m)) if start.elapsed() > FIRST_REPLY_TIMEOUT => {
                    return Err(format!(
                        "remote {prefix:?}: no `sphfmu serve` node answered within {} s ({m}); start one with --prefix {prefix} and reach it through zenoh.connect or zenoh.listen",
                        FIRST_REPLY_TIMEOUT.as_secs()
                    ))
                }
                Err(_) => std::thread::sleep(Duration::from_millis(100)),
            }
        }
    }

    /// One request `op` with a CBOR payload (bytes as they are for `restore_state`); the
    /// reply's bytes.
    fn ask(&self, op: &str, payload: Vec<u8>, timeout: Duration) -> Result<Vec<u8>, RemoteError> {
        let key = format!("{}/{op}", self.prefix);
        let gone = |why: String| RemoteError::Unreachable(format!("{key}: {why}"));
        let asked = Instant::now();
        let replies = self
            .session
            .get(&key)
            .payload(payload)
            .timeout(timeout)
            .wait()
            .map_err(|e| gone(format!("request not sent ({e})")))?;
        let reply = replies.recv().map_err(|_| {
            // the wait ends early when no node serves the key any more (it died, or its
            // link is down), else at the time limit
            if asked.elapsed() < timeout {
                gone("no node serves it (it stopped, or cannot be reached)".into())
            } else {
                gone(format!("no reply within {} s", timeout.as_secs_f64()))
            }
        })?;
        match reply.result() {
            Ok(sample) => Ok(sample.payload().to_bytes().to_vec()),
            Err(e) => {
                let bytes = e.payload().to_bytes();
                let msg = codec::decode(&bytes)
                    .ok()
                    .and_then(|v| match field(&v, "error") {
                        Some(Value::Text(t)) => Some(t.clone()),
                        _ => None,
                    })
                    .unwrap_or_else(|| format!("{key}: an error reply without a message"));
                if msg.starts_with(NODE_ENDING) {
                    return Err(RemoteError::Ended(msg));
                }
                Err(RemoteError::Refused(msg))
            }
        }
    }

    /// [`Self::ask`] with a CBOR map, decoding the reply and noting its time.
    fn request(&mut self, op: &str, body: &Value, timeout: Duration) -> Result<Value, RemoteError> {
        let bytes = self.ask(op, codec::encode(body), timeout)?;
        self.reply_value(op, &bytes)
    }

    fn reply_value(&mut self, op: &str, bytes: &[u8]) -> Result<Value, RemoteError> {
        let v = codec::decode(bytes)
            .map_err(|e| RemoteError::Unreachable(format!("{}/{op}: reply {e}", self.prefix)))?;
        if let Some(t) = field(&v, "t").and_then(codec::number) {
            self.time = t;
        }
        Ok(v)
    }

    /// Back to the node's state at the end of its initialisation.
    pub fn reset(&mut self) -> Result<(), RemoteError> {
        self.request("reset", &map(vec![]), REPLY_TIMEOUT)
            .map(|_| ())
    }

    /// Set inputs (all or nothing on the node).
    pub fn set(&mut self, values: Vec<(String, Vec<f64>)>) -> Result<(), RemoteError> {
        let entries = values
            .into_iter()
            .map(|(n, x)| (Value::Text(n), codec::numbers(&x)))
            .collect();
        self.request(
            "set",
            &map(vec![("values", Value::Map(entries))]),
            REPLY_TIMEOUT,
        )
        .map(|_| ())
    }

    /// Step the node by `h`; then read every output.
    pub fn step(&mut self, h: f64) -> Result<(), RemoteError> {
        self.request("step", &map(vec![("h", Value::Float(h))]), REPLY_TIMEOUT)?;
        self.read_outputs()
    }

    /// Read every output of the node's current state.
    pub fn read_outputs(&mut self) -> Result<(), RemoteError> {
        let v = self.request("get", &map(vec![]), REPLY_TIMEOUT)?;
        let bad = |why: &str| RemoteError::Unreachable(format!("{}/get: {why}", self.prefix));
        let Some(Value::Map(entries)) = field(&v, "values") else {
            return Err(bad("the reply has no values"));
        };
        let mut outputs = HashMap::with_capacity(entries.len());
        for (k, x) in entries {
            let (Value::Text(name), Some(xs)) = (k, as_numbers(x)) else {
                return Err(bad("a value that is not a number or an array of numbers"));
            };
            outputs.insert(name.clone(), xs);
        }
        self.outputs = outputs;
        Ok(())
    }

    /// Output `name` of the node's current state.
    pub fn output(&self, name: &str) -> Option<&[f64]> {
        self.outputs.get(name).map(|x| x.as_slice())
    }

    /// The node's state as bytes (its FMU state, serialised).
    pub fn save(&self) -> Result<Vec<u8>, RemoteError> {
        self.ask("save_state", vec![], REPLY_TIMEOUT)
    }

    /// Restore the node to `bytes` from [`Self::save`]; then read every output.
    pub fn restore(&mut self, bytes: &[u8]) -> Result<(), RemoteError> {
        let reply = self.ask("restore_state", bytes.to_vec(), REPLY_TIMEOUT)?;
        self.reply_value("restore_state", &reply)?;
        self.read_outputs()
    }
}

/// A number, or an array of numbers, as a vector.
fn as_numbers(v: &Value) -> Option<Vec<f64>> {
    match v {
        Value::Array(a) => a.iter().map(codec::number).collect(),
        other => codec::number(other).map(|x| vec![x]),
    }
}

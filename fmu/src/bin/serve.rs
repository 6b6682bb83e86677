//! `sphfmu-serve` (also `sphfmu serve`): the solver as a zenoh node. See
//! `sphfmu_fmu::bridge::node` for the protocol and README § Live coupling.
//!
//!   sphfmu serve --case models/slosh2d.toml --prefix lab/tank --listen tcp/127.0.0.1:7447
//!
//! Stepped from outside by default; `--run T --step H` steps itself to T (publishing every H,
//! taking live inputs) and then keeps serving.

use clap::Parser;
use sphfmu_fmu::bridge::error_payload;
use sphfmu_fmu::bridge::node::{handle, set_text, Op, OPS};
use sphfmu_fmu::instance::{Instance, Status};
use std::io::Write;
use std::path::PathBuf;
use std::sync::mpsc;
use zenoh::bytes::Encoding;
use zenoh::query::Query;
use zenoh::Wait;

#[derive(Parser)]
#[command(
    name = "sphfmu serve",
    about = "Serve an sphfmu case over zenoh (step, get, set, save_state, restore_state, reset, stop, snapshot)"
)]
struct Args {
    /// Case file (TOML)
    #[arg(long)]
    case: PathBuf,
    /// Key prefix of every queryable and publication
    #[arg(long, default_value = "sphfmu/node")]
    prefix: String,
    /// zenoh mode: peer (no router needed) or client
    #[arg(long, default_value = "peer")]
    mode: String,
    /// Endpoints to listen on, comma separated (default tcp/127.0.0.1:7447 unless --connect
    /// or --config)
    #[arg(long)]
    listen: Option<String>,
    /// Endpoints to connect to, comma separated
    #[arg(long, default_value = "")]
    connect: String,
    /// zenoh JSON5 configuration file
    #[arg(long, default_value = "")]
    config: String,
    /// Seconds after which a live input is stale (0 = never)
    #[arg(long, default_value_t = 1.0)]
    staleness: f64,
    /// A stale live input: hold, master or error
    #[arg(long, default_value = "hold")]
    on_stale: String,
    /// A parameter or input before initialisation, NAME=VALUE (vectors comma separated);
    /// repeatable, e.g. --set scheme=crksph --set threads=2
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// Start time
    #[arg(long, default_value_t = 0.0)]
    start_time: f64,
    /// Step by itself to this time (with --step), then keep serving
    #[arg(long)]
    run: Option<f64>,
    /// Communication step of --run
    #[arg(long, default_value_t = 0.01)]
    step: f64,
    /// Also log every step (category logSolver)
    #[arg(long)]
    verbose: bool,
}

fn setup(a: &Args) -> Result<Instance, String> {
    let folder = a
        .case
        .parent()
        .map(|p| p.to_path_buf())
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or_else(|| ".".into());
    let file = a
        .case
        .file_name()
        .ok_or("--case: must name a file")?
        .to_string_lossy()
        .to_string();
    let logger = Box::new(|s: Status, cat: &str, msg: &str| {
        eprintln!("sphfmu-serve [{s:?}] {cat}: {msg}");
    });
    let mut inst = Instance::with_case("node", &folder, &file, logger)?;
    // the default listener only when nothing else says where to be reached
    let listen = a.listen.clone().unwrap_or_else(|| {
        if a.connect.is_empty() && a.config.is_empty() {
            "tcp/127.0.0.1:7447".into()
        } else {
            String::new()
        }
    });
    let zenoh = [
        ("zenoh.mode", a.mode.clone()),
        ("zenoh.listen", listen),
        ("zenoh.connect", a.connect.clone()),
        ("zenoh.config", a.config.clone()),
        ("zenoh.prefix", a.prefix.clone()),
        ("zenoh.staleness", a.staleness.to_string()),
        ("zenoh.on_stale", a.on_stale.clone()),
    ];
    for (k, v) in zenoh {
        set_text(&mut inst, k, &v)?;
    }
    if a.mode == "off" {
        return Err("--mode: must be peer or client (a node without zenoh serves nobody)".into());
    }
    for s in &a.sets {
        let (k, v) = s
            .split_once('=')
            .ok_or(format!("--set: expected NAME=VALUE, got {s:?}"))?;
        set_text(&mut inst, k.trim(), v).map_err(|e| format!("--set {e}"))?;
    }
    if let Some(t) = a.run {
        if !(t.is_finite() && t > a.start_time && a.step.is_finite() && a.step > 0.0) {
            return Err(format!(
                "--run/--step: need run > start time {} and step > 0, got {t} and {}",
                a.start_time, a.step
            ));
        }
    }
    inst.enter_initialization(a.start_time).map_err(|e| e.1)?;
    inst.exit_initialization().map_err(|e| e.1)?;
    // logging from here on: a failed start is the one line main prints
    let mut cats = vec!["logEvents", "logStatusWarning", "logStatusError"];
    if a.verbose {
        cats.push("logSolver");
    }
    inst.set_debug_logging(true, cats.into_iter().map(String::from).collect())
        .map_err(|e| e.1)?;
    Ok(inst)
}

fn reply(q: &Query, op: Op, r: Result<Vec<u8>, String>) {
    // a saved state is opaque bytes; every other reply is CBOR
    let encoding = if op == Op::SaveState {
        Encoding::APPLICATION_OCTET_STREAM
    } else {
        Encoding::APPLICATION_CBOR
    };
    let sent = match r {
        Ok(bytes) => q
            .reply(q.key_expr().clone(), bytes)
            .encoding(encoding)
            .wait(),
        Err(msg) => q.reply_err(error_payload(&msg)).wait(),
    };
    if let Err(e) = sent {
        eprintln!("sphfmu-serve: reply to {} not sent: {e}", q.key_expr());
    }
}

fn serve(a: Args) -> Result<(), String> {
    let mut inst = setup(&a)?;
    // what `reset` goes back to
    let initial = inst.get_state().map_err(|e| e.1)?;
    let session = inst.live_session().expect("zenoh mode is on");
    let prefix = inst.live_prefix();
    let (tx, rx) = mpsc::channel::<(Op, Query)>();
    let mut queryables = vec![];
    for (name, op) in OPS {
        let tx = tx.clone();
        let q = session
            .declare_queryable(format!("{prefix}/{name}"))
            .callback(move |q: Query| {
                // the main loop owns the instance; it answers in arrival order
                let _ = tx.send((op, q));
            })
            .wait()
            .map_err(|e| format!("zenoh: queryable {prefix}/{name}: {e}"))?;
        queryables.push(q);
    }
    println!(
        "sphfmu-serve: ready, prefix {prefix}, zenoh id {}",
        session.zid()
    );
    let _ = std::io::stdout().flush();
    let mut run = a.run;
    loop {
        let next = match run {
            Some(end) if inst.time() < end - 1e-12 => match rx.try_recv() {
                Ok(x) => Some(x),
                Err(mpsc::TryRecvError::Empty) => {
                    let now = inst.time();
                    let h = a.step.min(end - now);
                    if let Err(e) = inst.do_step(now, h) {
                        eprintln!("sphfmu-serve: --run stopped at t = {now}: {}", e.1);
                        run = None;
                    }
                    continue;
                }
                Err(mpsc::TryRecvError::Disconnected) => None,
            },
            _ => rx.recv().ok(),
        };
        let Some((op, q)) = next else { break };
        let payload = q.payload().map(|p| p.to_bytes().to_vec());
        let r = handle(&mut inst, op, payload.as_deref(), &initial);
        reply(&q, op, r);
        if op == Op::Stop {
            break;
        }
    }
    drop(queryables);
    Ok(())
}

fn main() {
    let a = Args::parse();
    if let Err(e) = serve(a) {
        eprintln!("sphfmu serve: {e}");
        std::process::exit(1);
    }
}

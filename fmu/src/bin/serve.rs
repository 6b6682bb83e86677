//! `sphfmu-serve` (also `sphfmu serve`): the solver as a zenoh node. See
//! `sphfmu_fmu::bridge::node` for the protocol and README § Live coupling.
//!
//!   sphfmu serve --case models/slosh2d.toml --prefix lab/tank --listen tcp/127.0.0.1:7447
//!
//! Stepped from outside by default; `--run T --step H` steps itself to T (publishing every H,
//! taking live inputs) and then keeps serving.
//!
//!   mpirun -n 4 sphfmu serve --case models/slosh2d.toml --prefix lab/tank
//!
//! serves one case shared among 4 ranks (`sphfmu::parallel`): rank 0 joins zenoh, and hands
//! each request (and each step of `--run`) to the other ranks, which make the same instance
//! calls in the same order, since most of them are collectives; rank 0 replies. Live zenoh
//! inputs are ignored there (only rank 0 hears them; every rank must step with the same).

use clap::Parser;
use sphfmu::parallel::comm::Comm;
use sphfmu_fmu::bridge::error_payload;
use sphfmu_fmu::bridge::node::{handle, set_text, Op, OPS};
use sphfmu_fmu::bridge::proxy::NODE_ENDING;
use sphfmu_fmu::instance::inputs::Snapshot;
use sphfmu_fmu::instance::{Instance, Status};
use std::io::Write;
use std::path::PathBuf;
use std::sync::{mpsc, Arc, Mutex, PoisonError};
use std::time::Duration;
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

/// The ranks of `mpirun -n R sphfmu serve` (None when started alone).
type Ranks = Option<Arc<dyn Comm>>;

fn setup(a: &Args, ranks: &Ranks) -> Result<Instance, String> {
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
    let leader = ranks.as_ref().is_none_or(|c| c.rank() == 0);
    if let Some(comm) = ranks {
        inst.share_among(comm.clone());
        // the cores shared among the ranks on this machine, unless --set threads says
        if let Some(n) = sphfmu::parallel::threads_per_rank() {
            set_text(&mut inst, "threads", &n.to_string())?;
        }
    }
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
    // under mpirun rank 0 alone joins zenoh: it answers, and hands every request to the others
    for (k, v) in zenoh.iter().filter(|_| leader) {
        set_text(&mut inst, k, v)?;
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

/// The request rank 0 is serving (its operation, its query, the node's time when it came),
/// kept where the signal thread of [`answer_on_signal`] can answer it.
type Pending = Arc<Mutex<Option<(Op, Query, f64)>>>;

fn take(pending: &Pending) -> Option<(Op, Query, f64)> {
    pending
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
        .take()
}

/// How long the signal thread leaves zenoh's own threads to send its error reply before the
/// process ends: loopback and LAN replies leave in milliseconds, and Open MPI sends SIGKILL
/// 1 s after SIGTERM (its `odls_base_sigkill_timeout`, default 1, `ompi_info --all`).
const REPLY_FLUSH: Duration = Duration::from_millis(200);

/// On SIGTERM, SIGINT or SIGHUP, answer the request being served with an error that says why
/// ([`NODE_ENDING`], which the proxy FMU reads as a node gone), then end as the signal would.
/// Under mpirun this is how a dead rank reaches the master: Open MPI ends the job by sending
/// SIGTERM to the other ranks, while rank 0 may wait in a collective for the dead rank and
/// could never answer from its main loop (issue 23: "the node replies with an error").
fn answer_on_signal(pending: Pending, ranks: Option<usize>) -> Result<(), String> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGTERM, SIGINT, SIGHUP])
        .map_err(|e| format!("signal handlers: {e}"))?;
    std::thread::spawn(move || {
        let Some(sig) = signals.forever().next() else {
            return;
        };
        if let Some((op, q, t)) = take(&pending) {
            let name = match sig {
                SIGTERM => "SIGTERM",
                SIGINT => "SIGINT",
                _ => "SIGHUP",
            };
            let why = match ranks {
                Some(n) => format!(
                    "; on {n} ranks under mpirun this means that another rank stopped (Open MPI ends the whole job)"
                ),
                None => String::new(),
            };
            let msg = format!(
                "{NODE_ENDING}: {name} arrived while it served `{}` from t = {t}{why}. The request did not complete",
                OPS.iter().find(|o| o.1 == op).map_or("?", |o| o.0)
            );
            eprintln!("sphfmu-serve: {msg}");
            if let Err(e) = q.reply_err(error_payload(&msg)).wait() {
                eprintln!("sphfmu-serve: reply to {} not sent: {e}", q.key_expr());
            }
            drop(q);
            std::thread::sleep(REPLY_FLUSH);
        }
        // the signal's own ending (its exit status, no destructors racing the main thread)
        let _ = signal_hook::low_level::emulate_default_handler(sig);
        std::process::exit(128 + sig);
    });
    Ok(())
}

/// What rank 0 hands to every rank: a request to answer, a step of `--run`, or the end.
enum Command {
    Request(Op, Option<Vec<u8>>),
    SelfStep(f64),
    End,
}

impl Command {
    fn encode(&self) -> Vec<u8> {
        match self {
            Command::Request(op, payload) => {
                let i = OPS.iter().position(|o| o.1 == *op).expect("listed") as u8;
                let mut b = vec![0, i, u8::from(payload.is_some())];
                b.extend(payload.iter().flatten());
                b
            }
            Command::SelfStep(h) => [&[1u8][..], &h.to_le_bytes()].concat(),
            Command::End => vec![2],
        }
    }

    fn decode(b: &[u8]) -> Result<Command, String> {
        match b {
            [0, i, has, rest @ ..] if (*i as usize) < OPS.len() => Ok(Command::Request(
                OPS[*i as usize].1,
                (*has == 1).then(|| rest.to_vec()),
            )),
            [1, h @ ..] if h.len() == 8 => Ok(Command::SelfStep(f64::from_le_bytes(
                h.try_into().expect("8 bytes"),
            ))),
            [2] => Ok(Command::End),
            _ => Err("a command from rank 0 that this build does not know".into()),
        }
    }
}

/// Rank 0's `cmd` on every rank (a collective; the others pass None).
fn share(ranks: &Ranks, cmd: Option<&Command>) -> Result<Option<Command>, String> {
    let Some(comm) = ranks else {
        return Ok(None);
    };
    let mine = cmd.map(Command::encode).unwrap_or_default();
    let all = comm.all_gather(mine).map_err(|e| format!("ranks: {e}"))?;
    Command::decode(&all[0]).map(Some)
}

/// A step of `--run` (every rank takes it); false when it failed and --run ends.
fn self_step(inst: &mut Instance, h: f64) -> bool {
    let now = inst.time();
    match inst.do_step(now, h) {
        Ok(_) => true,
        Err(e) => {
            eprintln!("sphfmu-serve: --run stopped at t = {now}: {}", e.1);
            false
        }
    }
}

/// Ranks 1.. of a node under mpirun: do what rank 0 hands over, until it ends.
fn follow(mut inst: Instance, ranks: &Ranks, initial: &Snapshot) -> Result<(), String> {
    loop {
        match share(ranks, None)?.expect("under mpirun") {
            Command::Request(op, payload) => {
                // the same call as rank 0's, with the same outcome; rank 0 replies
                let _ = handle(&mut inst, op, payload.as_deref(), initial);
                if op == Op::Stop {
                    return Ok(());
                }
            }
            Command::SelfStep(h) => {
                self_step(&mut inst, h);
            }
            Command::End => return Ok(()),
        }
    }
}

fn serve(a: Args, ranks: Ranks) -> Result<(), String> {
    let mut inst = setup(&a, &ranks)?;
    // what `reset` goes back to
    let initial = inst.get_state().map_err(|e| e.1)?;
    if ranks.as_ref().is_some_and(|c| c.rank() != 0) {
        return follow(inst, &ranks, &initial);
    }
    let pending: Pending = Arc::default();
    answer_on_signal(pending.clone(), ranks.as_ref().map(|c| c.size()))?;
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
    let on = ranks
        .as_ref()
        .map_or(String::new(), |c| format!(", on {} ranks", c.size()));
    println!(
        "sphfmu-serve: ready, prefix {prefix}{on}, zenoh id {}",
        session.zid()
    );
    let _ = std::io::stdout().flush();
    let mut run = a.run;
    loop {
        let next = match run {
            Some(end) if inst.time() < end - 1e-12 => match rx.try_recv() {
                Ok(x) => Some(x),
                Err(mpsc::TryRecvError::Empty) => {
                    let h = a.step.min(end - inst.time());
                    share(&ranks, Some(&Command::SelfStep(h)))?;
                    if !self_step(&mut inst, h) {
                        run = None;
                    }
                    continue;
                }
                Err(mpsc::TryRecvError::Disconnected) => None,
            },
            _ => rx.recv().ok(),
        };
        let Some((op, q)) = next else {
            share(&ranks, Some(&Command::End))?;
            break;
        };
        let payload = q.payload().map(|p| p.to_bytes().to_vec());
        *pending.lock().unwrap_or_else(PoisonError::into_inner) = Some((op, q, inst.time()));
        if let Err(e) = share(&ranks, Some(&Command::Request(op, payload.clone()))) {
            if let Some((op, q, _)) = take(&pending) {
                reply(&q, op, Err(format!("{NODE_ENDING}: {e}")));
            }
            return Err(e);
        }
        let r = handle(&mut inst, op, payload.as_deref(), &initial);
        // (none when a signal took it: that thread has answered, and the process is ending)
        if let Some((op, q, _)) = take(&pending) {
            reply(&q, op, r);
        }
        if op == Op::Stop {
            break;
        }
    }
    drop(queryables);
    Ok(())
}

fn main() {
    let a = Args::parse();
    let ranks = match sphfmu::parallel::launched() {
        Ok(r) => r,
        Err(e) => {
            eprintln!("sphfmu serve: {e}");
            std::process::exit(1);
        }
    };
    if let Err(e) = serve(a, ranks) {
        eprintln!("sphfmu serve: {e}");
        std::process::exit(1);
    }
}

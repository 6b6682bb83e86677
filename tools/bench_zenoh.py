"""Live-coupling benchmark (`make bench`): on loopback,

1. the round trip of one coupling exchange with the solver node (`sphfmu serve`): a `get` of
   the tank force (request, reply; no stepping), and a full exchange `set` gravity + `step`
   0.0005 s (about one internal step) + `get` the force — median and 99th percentile;
2. what publishing adds to a step: the slosh2d FMU stepped by fmpy with the bridge off and on
   (a subscriber receiving every output), the median wall time per doStep of each;
3. what a master pays to read every output after a step (fmpy getters, bridge off): the FMU
   sweeps the particles once per kind of output (probes, patches, markers, diagnostics) and
   answers the other outputs of that kind from it until the next change.

    target/venv/bin/python tools/bench_zenoh.py [--json target/bench-zenoh.json] [--n 1000]
"""
import argparse
import json
import pathlib
import subprocess
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "fmpy"))
from fmu_sessions import open_fmu  # noqa: E402
from zenoh_sessions import free_port, peer, query  # noqa: E402

FMU = ROOT / "target" / "fmu" / "slosh2d" / "sphfmu.fmu"


def ask(s, key, request):
    ok, r = query(s, key, request, timeout=30.0)
    if not ok:
        raise RuntimeError(r)
    return r


def stats(samples):
    a = np.array(samples) * 1e3
    return {"median_ms": float(np.median(a)), "p99_ms": float(np.percentile(a, 99)), "n": len(a)}


def node_round_trips(n):
    port, prefix = free_port(), "bench/node"
    node = subprocess.Popen([str(ROOT / "target" / "release" / "sphfmu"), "serve",
                             "--case", str(ROOT / "models" / "slosh2d.toml"), "--prefix", prefix,
                             "--listen", f"tcp/127.0.0.1:{port}", "--set", "threads=1"],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        assert "ready" in node.stdout.readline()
        with peer(port) as s:
            end = time.time() + 20
            while True:
                try:
                    ask(s, f"{prefix}/get", {"names": ["time"]})
                    break
                except RuntimeError:
                    if time.time() > end:
                        raise
                    time.sleep(0.1)
            get, full = [], []
            for k in range(n):
                t0 = time.perf_counter()
                ask(s, f"{prefix}/get", {"names": ["tank.force"]})
                get.append(time.perf_counter() - t0)
            for k in range(n):
                t0 = time.perf_counter()
                ask(s, f"{prefix}/set", {"values": {"gravity": [0.0, -9.81]}})
                ask(s, f"{prefix}/step", {"h": 0.0005})
                ask(s, f"{prefix}/get", {"names": ["tank.force"]})
                full.append(time.perf_counter() - t0)
            ask(s, f"{prefix}/stop", {})
        node.wait(timeout=20)
    finally:
        if node.poll() is None:
            node.kill()
    return stats(get), stats(full)


def step_times(live, steps, h):
    fmu, vr = open_fmu(str(FMU), init=False, log=False)
    fmu.enterInitializationMode(startTime=0.0)
    fmu.setInt64([vr["threads"]], [1])
    port, got = free_port(), [0]
    if live:
        fmu.setString([vr["zenoh.mode"]], ["peer"])
        fmu.setString([vr["zenoh.listen"]], [f"tcp/127.0.0.1:{port}"])
        fmu.setString([vr["zenoh.prefix"]], ["bench/fmu"])
    fmu.exitInitializationMode()
    s = peer(port) if live else None
    if live:
        sub = s.declare_subscriber("bench/fmu/out/**", lambda smp: got.__setitem__(0, got[0] + 1))
        time.sleep(1.0)
    outputs = output_variables()
    times, reads, t = [], [], 0.0
    for k in range(steps):
        t0 = time.perf_counter()
        fmu.doStep(t, h)
        times.append(time.perf_counter() - t0)
        t += h
        if not live:
            t0 = time.perf_counter()
            for vr_k, kind, size in outputs:
                if kind == "Int64":
                    fmu.getInt64([vr_k])
                else:
                    fmu.getFloat64([vr_k], nValues=size)
            reads.append(time.perf_counter() - t0)
    fmu.terminate()
    fmu.freeInstance()
    if live:
        time.sleep(0.5)
        sub.undeclare()
        s.close()
    return stats(times), got[0], len(outputs), stats(reads) if reads else None


def output_variables():
    """(value reference, type, number of values) of every output."""
    from fmpy import read_model_description
    md = read_model_description(str(FMU))
    return [(v.valueReference, v.type, int(v.dimensions[0].start) if v.dimensions else 1)
            for v in md.modelVariables if v.causality == "output"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--json", default="target/bench-zenoh.json")
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--steps", type=int, default=400)
    a = ap.parse_args()
    get, full = node_round_trips(a.n)
    h = 0.0005
    off, _, n_out, reads = step_times(False, a.steps, h)
    on, received, _, _ = step_times(True, a.steps, h)
    res = {
        "node_get_round_trip": get,
        "node_set_step_get_round_trip": full,
        "fmu_doStep_bridge_off": off,
        "fmu_doStep_bridge_on": on,
        "fmu_read_all_outputs_after_doStep": reads,
        "outputs_per_step": n_out,
        "samples_received": received,
        "publish_overhead_ms": on["median_ms"] - off["median_ms"],
        "step": h,
        "case": "models/slosh2d.toml (about 310 fluid and 460 wall particles), 1 solver thread",
    }
    pathlib.Path(a.json).parent.mkdir(parents=True, exist_ok=True)
    pathlib.Path(a.json).write_text(json.dumps(res, indent=2))
    print("| live coupling on loopback (tools/bench_zenoh.py) | median | p99 |")
    print("|---|---|---|")
    print(f"| node: get one output (request/reply) | {get['median_ms']:.3f} ms | {get['p99_ms']:.3f} ms |")
    print(f"| node: set + step {h} s + get | {full['median_ms']:.3f} ms | {full['p99_ms']:.3f} ms |")
    print(f"| FMU doStep {h} s, bridge off | {off['median_ms']:.3f} ms | {off['p99_ms']:.3f} ms |")
    print(f"| FMU doStep {h} s, bridge on ({n_out} outputs published) | {on['median_ms']:.3f} ms | {on['p99_ms']:.3f} ms |")
    print(f"| FMU: read all {n_out} outputs after a doStep (fmpy getters) | {reads['median_ms']:.3f} ms | {reads['p99_ms']:.3f} ms |")
    print(f"publishing adds {res['publish_overhead_ms']:.3f} ms per step (median); "
          f"the subscriber received {received} samples; {a.steps * n_out} were published after it "
          "connected (every output after each step)")


if __name__ == "__main__":
    main()

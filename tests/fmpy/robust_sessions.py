"""Sessions of a hostile master for test_robustness.py (issue 18), each in its own process like
fmu_sessions.py: damaged FMU states, cases too large to build, steps too long to finish, steps
too small to take, and the zenoh node under the same abuse.

    python robust_sessions.py <session> '<json args>'
"""
import json
import os
import random
import signal
import socket
import subprocess
import sys
import time

from fmpy.fmi1 import FMICallException

from fmu_sessions import LOG, ROOT, expect_error, open_fmu


def api(fmu, fmi):
    """The FMU-state calls of either version under one set of names."""
    if fmi == 3:
        return (fmu.getFMUState, fmu.setFMUState, fmu.freeFMUState,
                fmu.serializeFMUState, fmu.deserializeFMUState)
    return (fmu.getFMUstate, fmu.setFMUstate, fmu.freeFMUstate,
            fmu.serializeFMUstate, fmu.deSerializeFMUstate)


def force(fmu, vr, fmi):
    if fmi == 3:
        return fmu.getFloat64([vr["piston.force"]], nValues=3)[0]
    return fmu.getReal([vr["piston.force[1]"]])[0]


def session_state_mutants(fmu_path, fmi, count=200, seed=18):
    """Serialize a state, then feed back `count` copies with one random byte changed, and
    truncated, empty and random ones: every one must be refused with a log line (never
    Fatal, never accepted), and the original must still restore bit for bit."""
    fmu, vr = open_fmu(fmu_path, fmi=fmi)
    get, put, free, ser, de = api(fmu, fmi)
    fmu.doStep(0.0, 0.05)
    s = get()
    blob = bytes(ser(s))
    free(s)
    fmu.doStep(0.05, 0.05)
    reference = force(fmu, vr, fmi).hex()
    rng = random.Random(seed)
    outcomes = {"refused": 0, "accepted": 0, "fatal": 0, "other": []}
    log_before = len(LOG)

    def attempt(data):
        try:
            st = de(data)
        except FMICallException as e:
            key = "fatal" if e.status >= 4 else "refused"
            outcomes[key] += 1
            return
        # deserialized: it must then be byte-identical (never for a mutant)
        outcomes["accepted"] += 1
        try:
            put(st)
            fmu.doStep(0.05, 0.05)
        except FMICallException as e:
            if e.status >= 4:
                outcomes["fatal"] += 1
        free(st)

    for _ in range(count):
        m = bytearray(blob)
        i = rng.randrange(len(m))
        m[i] = (m[i] + rng.randrange(1, 256)) % 256
        attempt(bytes(m))
    mutant_logs = len(LOG) - log_before
    mutants = json.loads(json.dumps(outcomes))
    kinds = {}
    for name, data in [("empty", b""), ("truncated", blob[: len(blob) // 2]),
                       ("one_short", blob[:-1]), ("one_long", blob + b"\0"),
                       ("random", bytes(rng.randrange(256) for _ in range(len(blob))))]:
        before = dict(outcomes)
        n_log = len(LOG)
        attempt(data)
        kinds[name] = {"refused": outcomes["refused"] - before["refused"],
                       "log": [m for (_, _, m) in LOG[n_log:]]}
    # the untouched bytes still restore, bit for bit
    st = de(blob)
    put(st)
    free(st)
    fmu.doStep(0.05, 0.05)
    again = force(fmu, vr, fmi).hex()
    fmu.terminate()
    fmu.freeInstance()
    return {"outcomes": mutants, "mutant_logs": mutant_logs, "kinds": kinds,
            "bit_for_bit": again == reference, "bytes": len(blob),
            "sample_log": [m for (_, _, m) in LOG[log_before:log_before + 3]]}


def session_huge_cases(fmu_path, folder):
    """The closed tank with a region of 1e300 extent, and with 1e8 particles: each refused at
    the end of initialisation with a named error, in milliseconds, with the process's peak
    resident memory staying small."""
    base = (ROOT / "models" / "closed-tank2d.toml").read_text()
    variants = {
        "extent_1e300": base.replace("max = [1.0, 0.5]", "max = [1e300, 0.5]", 1),
        "particles_1e8": base.replace("spacing = 0.02", "spacing = 0.00007", 1),
    }
    out = {}
    for name, text in variants.items():
        assert text != base, name
        path = os.path.join(folder, f"{name}.toml")
        with open(path, "w") as f:
            f.write(text)
        fmu, vr = open_fmu(fmu_path, init=False)
        fmu.enterInitializationMode(startTime=0.0)
        fmu.setString([vr["case"]], [path])
        n_log = len(LOG)
        t0 = time.perf_counter()
        status = expect_error(lambda: fmu.exitInitializationMode())
        ms = (time.perf_counter() - t0) * 1e3
        out[name] = {"status": status, "ms": ms, "log": [m for (_, _, m) in LOG[n_log:]]}
        fmu.freeInstance()
    # VmHWM, the peak resident memory of this process's address space (ru_maxrss would carry
    # the pytest parent's over fork and exec): the whole Python process, numpy and fmpy included
    with open("/proc/self/status") as f:
        hwm = next(line for line in f if line.startswith("VmHWM:"))
    out["peak_rss_mb"] = int(hwm.split()[1]) / 1024
    return out


def session_long_step(fmu_path, fmi, seconds):
    """doStep(0, 1e6) with limits.max_step_seconds set: Discard within the limit plus 10 %,
    a log line saying how far it got, the time reached; then restore and step on."""
    fmu, vr = open_fmu(fmu_path, fmi=fmi, init=False)
    if fmi == 3:
        fmu.enterInitializationMode(startTime=0.0)
        fmu.setFloat64([vr["limits.max_step_seconds"]], [seconds])
        fmu.setInt64([vr["threads"]], [2])
    else:
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.setReal([vr["limits.max_step_seconds"]], [seconds])
        fmu.setInteger([vr["threads"]], [2])
    fmu.exitInitializationMode()
    get, put, free, _, _ = api(fmu, fmi)
    saved = get()
    n_log = len(LOG)
    t0 = time.perf_counter()
    status = expect_error(lambda: fmu.doStep(0.0, 1e6))
    wall = time.perf_counter() - t0
    if fmi == 3:
        reached = fmu.getFloat64([vr["time"]])[0]
    else:
        reached = fmu.getRealStatus(2)
    log = [m for (_, _, m) in LOG[n_log:]]
    # it goes on from where it stopped ...
    fmu.doStep(reached, 0.01)
    # ... and an earlier state comes back
    put(saved)
    free(saved)
    fmu.doStep(0.0, 0.1)
    after = force(fmu, vr, fmi)
    fmu.terminate()
    fmu.freeInstance()
    return {"status": status, "wall": wall, "reached": reached, "log": log, "after": after}


def session_tiny_step(fmu_path, fmi):
    """doStep(0.01 - 5e-12, 1e-12) passes the communication-point tolerance but ends before
    the FMU's time: an Error that leaves the instance usable."""
    fmu, vr = open_fmu(fmu_path, fmi=fmi)
    fmu.doStep(0.0, 0.01)
    n_log = len(LOG)
    status = expect_error(lambda: fmu.doStep(0.01 - 5e-12, 1e-12))
    log = [m for (_, _, m) in LOG[n_log:]]
    fmu.doStep(0.01, 0.01)
    after = force(fmu, vr, fmi)
    fmu.terminate()
    fmu.freeInstance()
    return {"status": status, "log": log, "after": after}


def session_huge_start_time(fmu_path):
    """startTime 1e20: a warning at enterInitializationMode, then a doStep of 0.01 s, which
    1e20 + 0.01 == 1e20 would lose, is an Error that fails nothing."""
    fmu, vr = open_fmu(fmu_path, init=False)
    n_log = len(LOG)
    fmu.enterInitializationMode(startTime=1e20)  # fmpy raises on Error, not on Warning
    fmu.setInt64([vr["threads"]], [2])
    fmu.exitInitializationMode()
    warn = [(st, m) for (st, _, m) in LOG[n_log:]]
    status = expect_error(lambda: fmu.doStep(1e20, 0.01))
    log = [m for (_, _, m) in LOG[n_log:]]
    t = fmu.getFloat64([vr["time"]])[0]
    state = fmu.getFMUState()  # still in step mode
    fmu.freeFMUState(state)
    fmu.terminate()
    fmu.freeInstance()
    return {"warn": warn, "status": status, "log": log, "t": t}


# ---- the zenoh node ---------------------------------------------------------------------------

def start_node(port, prefix, *extra):
    node = subprocess.Popen([str(ROOT / "target" / "release" / "sphfmu"), "serve",
                             "--case", str(ROOT / "models" / "slosh2d.toml"), "--prefix", prefix,
                             "--listen", f"tcp/127.0.0.1:{port}", "--set", "threads=1", *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    line = node.stdout.readline()
    assert "ready" in line, (line, node.stderr.read())
    return node


def session_node_abuse(port, prefix):
    """A bit-flipped restore_state is refused and the node keeps serving; an absurd gravity
    fails the next step, and `reset` brings the node back."""
    from zenoh_sessions import peer, query, wait_for
    node = start_node(port, prefix)
    out = {}
    try:
        with peer(port) as s:
            wait_for(s, f"{prefix}/snapshot")
            ok, r = query(s, f"{prefix}/step", {"h": 0.02})
            ok, blob = query(s, f"{prefix}/save_state", raw=True)
            flipped = bytearray(blob)
            flipped[len(flipped) // 2] ^= 0x10
            out["restore_flipped"] = query(s, f"{prefix}/restore_state", bytes(flipped))
            out["step_after"] = query(s, f"{prefix}/step", {"h": 0.02})
            out["restore_good"] = query(s, f"{prefix}/restore_state", blob)
            out["absurd_gravity"] = query(s, f"{prefix}/set", {"values": {"gravity": [0.0, -1e300]}})
            out["step_absurd"] = query(s, f"{prefix}/step", {"h": 0.02})
            out["step_failed"] = query(s, f"{prefix}/step", {"h": 0.02})
            out["reset"] = query(s, f"{prefix}/reset", {})
            query(s, f"{prefix}/set", {"values": {"gravity": [0.0, -9.81]}})
            out["step_after_reset"] = query(s, f"{prefix}/step", {"h": 0.02})
            query(s, f"{prefix}/stop", {})
        node.wait(timeout=20)
        out["exit"] = node.returncode
        return out
    finally:
        if node.poll() is None:
            node.kill()


def port_free(port):
    with socket.socket() as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind(("127.0.0.1", port))
            return True
        except OSError:
            return False


def session_node_sigterm(port, prefix):
    """kill -TERM on `sphfmu serve`: within 2 s no process holds the port."""
    node = start_node(port, prefix)
    held = not port_free(port)
    node.send_signal(signal.SIGTERM)
    t0 = time.time()
    while time.time() - t0 < 2.0 and not port_free(port):
        time.sleep(0.05)
    freed = port_free(port)
    waited = time.time() - t0
    try:
        node.wait(timeout=5)
    except subprocess.TimeoutExpired:
        node.kill()
    # no sphfmu-serve left over from this node
    left = subprocess.run(["pgrep", "-f", f"sphfmu-serve.*{prefix}"], capture_output=True, text=True)
    return {"held": held, "freed": freed, "seconds": waited, "left": left.stdout.split()}


if __name__ == "__main__":
    name, args = sys.argv[1], json.loads(sys.argv[2]) if len(sys.argv) > 2 else {}
    result = globals()["session_" + name](**args)
    print(json.dumps(result))

"""Live-coupling sessions for test_zenoh.py, each in its own Python process (as fmu_sessions.py):

    python zenoh_sessions.py <session> '<json args>'

prints one JSON line with the results. The FMU (fmpy's FMU3Slave) or the node listens on a
loopback port chosen by the test; this process's zenoh peer connects to it (multicast off)."""
import json
import math
import os
import pathlib
import subprocess
import sys
import time

import cbor2
import numpy as np
import zenoh

from fmu_sessions import LOG, open_fmu

ROOT = pathlib.Path(__file__).resolve().parents[2]
G = 9.81


def free_port():
    """A loopback TCP port nobody listens on now (for one test's zenoh listener)."""
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def peer(*ports):
    """A zenoh peer connected to the listeners on these loopback ports."""
    conf = zenoh.Config()
    conf.insert_json5("mode", '"peer"')
    conf.insert_json5("scouting/multicast/enabled", "false")
    conf.insert_json5("scouting/gossip/enabled", "false")
    conf.insert_json5("connect/endpoints", json.dumps([f"tcp/127.0.0.1:{p}" for p in ports]))
    return zenoh.open(conf)


def wait_for(session, key, timeout=20.0):
    """Query `key` until it answers (the link is up and declarations have propagated)."""
    end = time.time() + timeout
    while time.time() < end:
        for r in session.get(key, timeout=1.0):
            if r.ok is not None:
                time.sleep(0.2)
                return cbor2.loads(r.ok.payload.to_bytes())
        time.sleep(0.1)
    raise RuntimeError(f"{key}: no answer within {timeout} s")


def query(session, key, request=None, timeout=60.0, raw=False):
    """One request to the node: (ok, decoded reply; the bytes with raw)."""
    payload = cbor2.dumps(request) if isinstance(request, dict) else request
    for r in session.get(key, payload=payload, timeout=timeout):
        if r.ok is not None:
            b = r.ok.payload.to_bytes()
            return True, bytes(b) if raw else cbor2.loads(b)
        return False, cbor2.loads(r.err.payload.to_bytes())
    raise RuntimeError(f"{key}: no reply")


def live_fmu(path, port, prefix, staleness=1.0, on_stale="hold", name="t"):
    fmu, vr = open_fmu(path, name=name, init=False)
    fmu.setDebugLogging(True, ["logEvents", "logStatusWarning", "logStatusError"])
    fmu.enterInitializationMode(startTime=0.0)
    fmu.setInt64([vr["threads"]], [2])
    for k, v in [("zenoh.mode", "peer"), ("zenoh.listen", f"tcp/127.0.0.1:{port}"),
                 ("zenoh.prefix", prefix), ("zenoh.on_stale", on_stale)]:
        fmu.setString([vr[k]], [v])
    fmu.setFloat64([vr["zenoh.staleness"]], [staleness])
    fmu.exitInitializationMode()
    return fmu, vr


def session_fmi2_publishes(fmu_path, port, prefix):
    """The same bridge behind the FMI 2.0 face: parameters set with fmi2SetString/SetReal,
    every step's force published with its time, a live gravity taken."""
    fmu, vr = open_fmu(fmu_path, fmi=2, init=False)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setInteger([vr["threads"]], [2])
    for k, v in [("zenoh.mode", "peer"), ("zenoh.listen", f"tcp/127.0.0.1:{port}"),
                 ("zenoh.prefix", prefix)]:
        fmu.setString([vr[k]], [v])
    fmu.setReal([vr["zenoh.staleness"]], [0.0])
    fmu.exitInitializationMode()
    got = []
    with peer(port) as s:
        sub = s.declare_subscriber(f"{prefix}/out/tank.force",
                                   lambda smp: got.append(cbor2.loads(smp.payload.to_bytes())))
        wait_for(s, f"{prefix}/snapshot")
        s.put(f"{prefix}/in/gravity", cbor2.dumps([0.0, -2 * G]))
        time.sleep(0.3)
        t, fy = 0.0, []
        for k in range(30):
            fmu.doStep(t, 0.02)
            t += 0.02
            fy.append(fmu.getReal([vr["tank.force[2]"]])[0])
        deadline = time.time() + 5
        while len(got) < 30 and time.time() < deadline:
            time.sleep(0.05)
        sub.undeclare()
    fmu.terminate()
    fmu.freeInstance()
    return {"received": len(got), "last_t": got[-1]["t"], "ratio": float(-np.mean(fy[-8:]) / (1000 * G * 0.5))}


def excitation(t):
    """Horizontal gravity: one period of a 0.5 m/s² sine near the first sloshing mode."""
    return 0.5 * math.sin(2 * math.pi * t / 1.18) if t < 1.18 else 0.0


def session_publish_and_gravity(fmu_path, port, prefix):
    """Every step's force arrives with its time; a gravity published over zenoh doubles the
    force on the tank while the master's value stays what the master set."""
    fmu, vr = live_fmu(fmu_path, port, prefix)
    got = []
    with peer(port) as s:
        sub = s.declare_subscriber(f"{prefix}/out/tank.force",
                                   lambda smp: got.append(cbor2.loads(smp.payload.to_bytes())))
        wait_for(s, f"{prefix}/snapshot")
        t, h, times, fy = 0.0, 0.02, [], []
        for k in range(40):
            if k == 20:
                s.put(f"{prefix}/in/gravity", cbor2.dumps([0.0, -2 * G]))
                time.sleep(0.3)
            fmu.doStep(t, h)
            t += h
            times.append(t)
            f = list(fmu.getFloat64([vr["tank.force"]], nValues=3))
            fy.append(f[1])
        deadline = time.time() + 5
        while len(got) < 40 and time.time() < deadline:
            time.sleep(0.05)
        master_g = list(fmu.getFloat64([vr["gravity"]], nValues=3))
        snap = query(s, f"{prefix}/snapshot?stride=3")[1]
        bad = query(s, f"{prefix}/snapshot?stride=0")
        sub.undeclare()
    fmu.terminate()
    fmu.freeInstance()
    pos = np.frombuffer(snap["position"], "<f8").reshape(-1, 2)
    return {
        "received": len(got),
        "times": [g["t"] for g in got],
        "expected_times": times,
        "same_force": bool(abs(got[-1]["v"][1] - f[1]) == 0.0),
        "fy": fy,
        "ratio": float(np.mean(fy[30:]) / np.mean(fy[10:20])),
        "master_gravity": master_g,
        "snapshot_count": snap["count"],
        "snapshot_t": snap["t"],
        "snapshot_in_tank": bool(np.all((pos[:, 0] > 0) & (pos[:, 0] < 1) & (pos[:, 1] > 0))),
        "snapshot_rho": float(np.frombuffer(snap["density"], "<f8").mean()),
        "bad_stride": bad,
    }


def node_run(port, prefix, n=130, h=0.02):
    """The sloshing run stepped through the node; the outputs per step."""
    names = ["tank.force", "patch.left.mean_pressure", "probe.left.pressure"]
    node = subprocess.Popen([str(ROOT / "target" / "release" / "sphfmu"), "serve",
                             "--case", str(ROOT / "models" / "slosh2d.toml"), "--prefix", prefix,
                             "--listen", f"tcp/127.0.0.1:{port}", "--set", "threads=2"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = node.stdout.readline()
        assert "ready" in line, (line, node.stderr.read())
        rows, extra = [], {}
        with peer(port) as s:
            wait_for(s, f"{prefix}/snapshot")
            t = 0.0
            for k in range(n):
                ok, r = query(s, f"{prefix}/set", {"values": {"gravity": [excitation(t), -G]}})
                assert ok, r
                ok, r = query(s, f"{prefix}/step", {"h": h})
                assert ok, r
                t = r["t"]
                ok, r = query(s, f"{prefix}/get", {"names": names})
                assert ok, r
                v = r["values"]
                rows.append(list(v["tank.force"]) + [v["patch.left.mean_pressure"], v["probe.left.pressure"]])
                if k == n // 2:
                    ok, saved = query(s, f"{prefix}/save_state", raw=True)
                    assert ok and len(saved) > 0
                    extra["saved_t"] = t
            # requests are checked as FMU calls: a bad one is an error reply and changes nothing
            extra["bad_gravity"] = query(s, f"{prefix}/set", {"values": {"gravity": [0.0, -G, 1.0]}})
            extra["bad_name"] = query(s, f"{prefix}/get", {"names": ["tank.nothing"]})
            extra["bad_step"] = query(s, f"{prefix}/step", {"h": -1.0})
            extra["bad_parameter"] = query(s, f"{prefix}/set", {"values": {"resolution": 2.0}})
            extra["bad_state"] = query(s, f"{prefix}/restore_state", b"not a state")
            ok, r = query(s, f"{prefix}/get", {"names": ["time", "gravity"]})
            extra["after_bad"] = r["values"]
            # back to the middle of the run and on again: the same outputs as the first time
            ok, r = query(s, f"{prefix}/restore_state", saved)
            extra["restored_t"] = r["t"]
            replay = []
            tt = r["t"]
            for k in range(n // 2 + 1, n):
                query(s, f"{prefix}/set", {"values": {"gravity": [excitation(tt), -G]}})
                ok, r = query(s, f"{prefix}/step", {"h": h})
                tt = r["t"]
                ok, r = query(s, f"{prefix}/get", {"names": names})
                v = r["values"]
                replay.append(list(v["tank.force"]) + [v["patch.left.mean_pressure"], v["probe.left.pressure"]])
            extra["replay_same"] = bool(np.array_equal(np.array(replay), np.array(rows[n // 2 + 1:])))
            query(s, f"{prefix}/stop", {})
        node.wait(timeout=20)
        extra["exit"] = node.returncode
        return rows, extra
    finally:
        if node.poll() is None:
            node.kill()


def session_node_runs_by_itself(port, prefix):
    """`sphfmu serve --run 0.4 --step 0.02`: the node steps itself, publishing as it goes,
    then keeps serving requests."""
    node = subprocess.Popen([str(ROOT / "target" / "release" / "sphfmu"), "serve",
                             "--case", str(ROOT / "models" / "slosh2d.toml"), "--prefix", prefix,
                             "--listen", f"tcp/127.0.0.1:{port}", "--run", "0.4", "--step", "0.02",
                             "--set", "threads=1"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert "ready" in node.stdout.readline()
        times = []
        with peer(port) as s:
            sub = s.declare_subscriber(f"{prefix}/out/diag.steps",
                                       lambda smp: times.append(cbor2.loads(smp.payload.to_bytes())["t"]))
            end = time.time() + 60
            t = 0.0
            while t < 0.4 - 1e-9 and time.time() < end:
                ok, r = query(s, f"{prefix}/get", {"names": ["time"]})
                t = r["values"]["time"]
                time.sleep(0.05)
            ok, r = query(s, f"{prefix}/step", {"h": 0.02})
            after = r["t"]
            sub.undeclare()
            query(s, f"{prefix}/stop", {})
        node.wait(timeout=20)
        return {"t": t, "after": after, "samples": len(times),
                "increasing": bool(all(b > a for a, b in zip(times, times[1:]))),
                "exit": node.returncode}
    finally:
        if node.poll() is None:
            node.kill()


def session_node_from_a_config_file(port, prefix, config):
    """`sphfmu serve --config FILE`: the listener comes from a zenoh JSON5 file."""
    pathlib.Path(config).write_text(
        '{ mode: "peer", listen: { endpoints: ["tcp/127.0.0.1:%d"] },'
        ' scouting: { multicast: { enabled: false }, gossip: { enabled: false } } }' % port)
    node = subprocess.Popen([str(ROOT / "target" / "release" / "sphfmu"), "serve",
                             "--case", str(ROOT / "models" / "slosh2d.toml"), "--prefix", prefix,
                             "--config", config, "--set", "threads=1"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert "ready" in node.stdout.readline()
        with peer(port) as s:
            wait_for(s, f"{prefix}/snapshot")
            ok, r = query(s, f"{prefix}/step", {"t": 0.1})
            query(s, f"{prefix}/stop", {})
        node.wait(timeout=20)
        return {"ok": ok, "t": r["t"], "exit": node.returncode}
    finally:
        if node.poll() is None:
            node.kill()


def fmu_run(fmu_path, n=130, h=0.02):
    fmu, vr = open_fmu(fmu_path)
    rows, t = [], 0.0
    for k in range(n):
        fmu.setFloat64([vr["gravity"]], [excitation(t), -G, 0.0])
        fmu.doStep(t, h)
        t += h
        f = list(fmu.getFloat64([vr["tank.force"]], nValues=3))
        rows.append(f + list(fmu.getFloat64([vr["patch.left.mean_pressure"], vr["probe.left.pressure"]])))
    fmu.terminate()
    fmu.freeInstance()
    return rows


def session_node_matches_fmu(fmu_path, port, prefix):
    node_rows, extra = node_run(port, prefix)
    fmu_rows = fmu_run(fmu_path)
    a, b = np.array(node_rows), np.array(fmu_rows)
    fx = b[:, 0]
    # after the excitation (1.18 s), 1.4 s: more than one sloshing period (1.18 s), so a
    # sloshing force crosses its mean at least twice whatever its phase
    late = fx[60:]
    return {
        **extra,
        "max_difference": float(np.abs(a - b).max()),
        "identical": bool(np.array_equal(a, b)),
        "sign_changes_after_excitation": int(np.sum(np.diff(np.sign(late - late.mean())) != 0)),
        "fx_amplitude": float(np.abs(late - late.mean()).max()),
        "weight": float(b[:, 1].mean()),
    }


def session_peer_gone_and_back(fmu_path, port, prefix, on_stale):
    """A live gravity publisher steps in lockstep, disappears for longer than the staleness
    limit, then comes back with another value; malformed payloads on the way are refused."""
    fmu, vr = live_fmu(fmu_path, port, prefix, staleness=0.3, on_stale=on_stale)
    t, h = 0.0, 0.02
    forces, statuses = [], []

    def step():
        nonlocal t
        try:
            fmu.doStep(t, h)
            t += h
            statuses.append("ok")
        except Exception as e:  # noqa: BLE001 - fmpy raises on an error status
            statuses.append(f"error: {e}")
        forces.append(fmu.getFloat64([vr["tank.force"]], nValues=3)[1])

    with peer(port) as s:
        wait_for(s, f"{prefix}/snapshot")
        for k in range(10):
            s.put(f"{prefix}/in/gravity", cbor2.dumps({"v": [0.0, -2 * G]}))
            time.sleep(0.02)
            step()
        # malformed payloads: refused with a logged reason, nothing changes
        s.put(f"{prefix}/in/gravity", b"\xff\xfe")
        s.put(f"{prefix}/in/gravity", cbor2.dumps([0.0, -G, 0.0, 1.0]))
        s.put(f"{prefix}/in/gravity", cbor2.dumps([0.0, float("nan")]))
        s.put(f"{prefix}/in/no.such.input", cbor2.dumps(1.0))
        s.put(f"{prefix}/in/gravity", cbor2.dumps([0.0, -G, 5.0]))  # checked like a master's set
        time.sleep(0.1)
        step()
    # the peer is gone: the FMU keeps stepping
    gone_from = len(forces)
    for k in range(10):
        time.sleep(0.05)
        step()
    gone_to = len(forces)
    with peer(port) as s:
        wait_for(s, f"{prefix}/snapshot")
        for k in range(25):
            s.put(f"{prefix}/in/gravity", cbor2.dumps([0.0, -3 * G]))
            time.sleep(0.02)
            step()
    fmu.terminate()
    fmu.freeInstance()
    return {
        "forces": forces,
        "statuses": statuses,
        "gone": [gone_from, gone_to],
        "log": [(int(s), c, m) for s, c, m in LOG],
    }


def session_two_live_instances(fmu_path, port, prefix):
    """Two FMU instances in one process, each with its own zenoh session, prefix and port: a
    live gravity sent to one reaches that one only, each publishes under its own prefix; a
    third that asks for a port already taken fails its initialisation with a logged reason."""
    port_b = free_port()
    inst = {"a": live_fmu(fmu_path, port, f"{prefix}/a", name="a"),
            "b": live_fmu(fmu_path, port_b, f"{prefix}/b", name="b")}
    got = {"a": [], "b": []}
    fy = {"a": [], "b": []}
    with peer(port, port_b) as s:
        subs = [s.declare_subscriber(f"{prefix}/{k}/out/tank.force",
                                     lambda smp, k=k: got[k].append(cbor2.loads(smp.payload.to_bytes())))
                for k in inst]
        for k in inst:
            wait_for(s, f"{prefix}/{k}/snapshot")
        s.put(f"{prefix}/a/in/gravity", cbor2.dumps([0.0, -2 * G]))
        time.sleep(0.3)
        t, h = 0.0, 0.02
        for _ in range(20):
            for k, (fmu, vr) in inst.items():
                fmu.doStep(t, h)
                fy[k].append(fmu.getFloat64([vr["tank.force"]], nValues=3)[1])
            t += h
        deadline = time.time() + 5
        while min(len(g) for g in got.values()) < 20 and time.time() < deadline:
            time.sleep(0.05)
        for sub in subs:
            sub.undeclare()
    LOG.clear()
    c, vr = open_fmu(fmu_path, name="c", init=False)
    c.setDebugLogging(True, ["logEvents", "logStatusWarning", "logStatusError"])
    c.enterInitializationMode(startTime=0.0)
    for key, v in [("zenoh.mode", "peer"), ("zenoh.listen", f"tcp/127.0.0.1:{port}")]:
        c.setString([vr[key]], [v])
    try:
        c.exitInitializationMode()
        third = "initialised"
    except Exception as e:  # noqa: BLE001 - fmpy raises on an error status
        third = f"error: {e}"
    c.freeInstance()
    for fmu, _ in inst.values():
        fmu.terminate()
        fmu.freeInstance()
    weight = 1000 * G * 0.5
    return {
        "received": {k: len(g) for k, g in got.items()},
        "last_equal": {k: bool(got[k][-1]["v"][1] == fy[k][-1]) for k in inst},
        "ratio": {k: float(-np.mean(fy[k][-8:]) / weight) for k in inst},
        "third": third,
        "log": [m for _, _, m in LOG],
    }


def start_node(port, prefix, case="slosh2d.toml", ranks=None):
    """`sphfmu serve` on a loopback listener (under `mpirun -n ranks` when given); returns
    once it says it is ready."""
    serve = [str(ROOT / "target" / "release" / "sphfmu"), "serve",
             "--case", str(ROOT / "models" / case), "--prefix", prefix,
             "--listen", f"tcp/127.0.0.1:{port}"]
    env = dict(os.environ)
    if ranks:
        # root in CI containers; idle ranks wait for rank 0's next request without spinning
        env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                   OMPI_MCA_mpi_yield_when_idle="1")
        cmd = ["mpirun", "-n", str(ranks), "--oversubscribe"] + serve
    else:
        cmd = serve + ["--set", "threads=2"]
    node = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    line = node.stdout.readline()
    assert "ready" in line, (line, node.stderr.read())
    return node


def stop_node(node):
    """End a node; mpirun passes SIGTERM on to its ranks (SIGKILL would orphan them)."""
    if node.poll() is None:
        node.terminate()
        try:
            node.wait(timeout=30)
        except subprocess.TimeoutExpired:
            node.kill()
            node.wait(timeout=30)


def rank_pid(prefix, rank):
    """The process id of rank `rank` of the node serving `prefix` (from /proc)."""
    for d in pathlib.Path("/proc").iterdir():
        try:
            cmd = (d / "cmdline").read_bytes()
            env = (d / "environ").read_bytes()
        except (OSError, ValueError):
            continue
        if prefix.encode() in cmd and f"OMPI_COMM_WORLD_RANK={rank}".encode() in env.split(b"\0"):
            return int(d.name)
    raise AssertionError(f"no rank {rank} serving {prefix}")


def proxy_fmu(fmu_path, port, prefix):
    """The packaged FMU with `remote` set: a proxy of the node at `prefix`."""
    fmu, vr = open_fmu(fmu_path, init=False)
    fmu.setDebugLogging(True, ["logEvents", "logStatusWarning", "logStatusError"])
    fmu.enterInitializationMode(startTime=0.0)
    fmu.setString([vr["remote"]], [prefix])
    fmu.setString([vr["zenoh.connect"]], [f"tcp/127.0.0.1:{port}"])
    fmu.exitInitializationMode()
    return fmu, vr


def proxy_rows(fmu, vr, t, k0, k1, h=0.02):
    """Steps k0..k1-1 of the sloshing run (as fmu_run) on `fmu` from time t."""
    rows = []
    for k in range(k0, k1):
        fmu.setFloat64([vr["gravity"]], [excitation(t), -G, 0.0])
        fmu.doStep(t, h)
        t += h
        f = list(fmu.getFloat64([vr["tank.force"]], nValues=3))
        rows.append(f + list(fmu.getFloat64([vr["patch.left.mean_pressure"], vr["probe.left.pressure"]])))
    return rows, t


def checkpointed_run(fmu, vr, rows_of, n):
    """Steps 0..n-1 by `rows_of` (as proxy_rows), the FMU state taken after step n/2: the
    rows, the end time, the state, its serialized bytes and its time."""
    rows, t = rows_of(fmu, vr, 0.0, 0, n // 2)
    state = fmu.getFMUState()
    blob = fmu.serializeFMUState(state)
    saved_t = t
    more, t = rows_of(fmu, vr, t, n // 2, n)
    return rows + more, t, state, blob, saved_t


def session_proxy_matches_local(fmu_path, port, prefix, n=60):
    """The FMU as a proxy of a node (issue 23): the same outputs as the local FMU, a rollback
    replayed bit for bit, a node killed mid-run an fmi3Error with a log line (this process
    survives), and a saved state resumed on a node started anew."""
    from fmpy.fmi1 import FMICallException
    local = np.array(fmu_run(fmu_path, n=n))
    node = start_node(port, prefix)
    out = {}
    try:
        fmu, vr = proxy_fmu(fmu_path, port, prefix)
        rows, t, state, blob, saved_t = checkpointed_run(fmu, vr, proxy_rows, n)
        out["max_difference"] = float(np.abs(np.array(rows) - local).max())
        out["identical"] = bool(np.array_equal(np.array(rows), local))
        # rollback: back to the middle, the second half again
        fmu.setFMUState(state)
        out["restored_t"] = float(fmu.getFloat64([vr["time"]])[0])
        replay, _ = proxy_rows(fmu, vr, saved_t, n // 2, n)
        out["replay_same"] = bool(np.array_equal(np.array(replay), local[n // 2:]))
        # a bad input is refused as by the local FMU (at the set), and nothing changes
        try:
            fmu.setFloat64([vr["gravity"]], [0.0, -G, 1.0])
            fmu.doStep(t, 0.02)
            out["bad_input"] = "accepted"
        except FMICallException:
            out["bad_input"] = LOG[-1][2]
        out["after_bad_t"] = float(fmu.getFloat64([vr["time"]])[0])
        fmu.setFloat64([vr["gravity"]], [0.0, -G, 0.0])
        # the node dies mid-run
        node.kill()
        node.wait(timeout=20)
        try:
            fmu.doStep(t, 0.02)
            out["after_kill"] = "accepted"
        except FMICallException:
            out["after_kill"] = LOG[-1][2]
        # a node started anew, the saved state restored into it: the run resumes
        node = start_node(port, prefix)
        s = fmu.deserializeFMUState(blob)
        try:
            fmu.setFMUState(s)
        except FMICallException as e:
            raise AssertionError(f"setFMUState on the new node: {LOG[-1][2]}") from e
        resumed, _ = proxy_rows(fmu, vr, saved_t, n // 2, n)
        out["resumed_same"] = bool(np.array_equal(np.array(resumed), local[n // 2:]))
        fmu.terminate()
        fmu.freeInstance()
    finally:
        if node.poll() is None:
            node.kill()
    return out


def tank_rows(fmu, vr, t, k0, k1, h=0.02):
    """Steps k0..k1-1 of the closed tank's run (constant gravity) on `fmu` from time t: the
    tank's force and torque, the floor patch's mean and peak pressure and force."""
    names = ["tank.force", "tank.torque", "patch.floor.force"]
    rows = []
    for _ in range(k0, k1):
        fmu.doStep(t, h)
        t += h
        row = []
        for n in names:
            row += list(fmu.getFloat64([vr[n]], nValues=3))
        rows.append(row + list(fmu.getFloat64([vr["patch.floor.mean_pressure"],
                                               vr["patch.floor.peak_pressure"]])))
    return rows, t


def session_proxy_on_ranks(fmu_path, port, prefix, n=50):
    """The proxy FMU driving a node under `mpirun -n 2` through the closed tank's run (issue
    23): its outputs against the local FMU's and a node on 1 rank, a rollback replayed, one
    rank killed in the middle of a step, and the run resumed on a node started anew."""
    import threading
    from fmpy.fmi1 import FMICallException
    local_fmu, lvr = open_fmu(fmu_path)
    local, _ = tank_rows(local_fmu, lvr, 0.0, 0, n)
    local_fmu.terminate()
    local_fmu.freeInstance()
    out = {}
    node = start_node(port, prefix + "/one", case="closed-tank2d.toml", ranks=1)
    try:
        fmu, vr = proxy_fmu(fmu_path, port, prefix + "/one")
        one, _ = tank_rows(fmu, vr, 0.0, 0, n)
        fmu.terminate()
        fmu.freeInstance()
    finally:
        stop_node(node)
    node = start_node(port, prefix, case="closed-tank2d.toml", ranks=2)
    try:
        fmu, vr = proxy_fmu(fmu_path, port, prefix)
        rows, t, state, blob, saved_t = checkpointed_run(fmu, vr, tank_rows, n)
        a, b = np.array(rows), np.array(local)
        scale = np.abs(b).max(axis=0)
        scale[scale == 0] = 1.0  # (the 2D z force and x, y torques are 0 in both)
        out["relative_to_local"] = float((np.abs(a - b) / scale).max())
        out["identical_to_local"] = bool(np.array_equal(a, b))
        out["same_as_one_rank"] = bool(np.array_equal(a, np.array(one)))
        fmu.setFMUState(state)
        replay, _ = tank_rows(fmu, vr, saved_t, n // 2, n)
        out["replay_same"] = bool(np.array_equal(np.array(replay), a[n // 2:]))
        # rank 1 killed while the node takes a long step: Open MPI ends the whole job, the
        # step's request is left without a node, and the proxy says so
        killer = threading.Timer(1.0, lambda: os.kill(rank_pid(prefix, 1), 9))
        killer.start()
        try:
            fmu.doStep(t, 2.0)
            out["after_kill"] = "accepted"
        except FMICallException:
            out["after_kill"] = LOG[-1][2]
        killer.join()
        node.wait(timeout=60)
        out["node_exit"] = node.returncode
        # a node started anew on 2 ranks, the saved state restored into it: the run resumes
        node = start_node(port, prefix, case="closed-tank2d.toml", ranks=2)
        fmu.setFMUState(fmu.deserializeFMUState(blob))
        resumed, _ = tank_rows(fmu, vr, saved_t, n // 2, n)
        out["resumed_same"] = bool(np.array_equal(np.array(resumed), a[n // 2:]))
        fmu.terminate()
        fmu.freeInstance()
    finally:
        stop_node(node)
    return out


if __name__ == "__main__":
    name, args = sys.argv[1], json.loads(sys.argv[2])
    print(json.dumps(globals()[f"session_{name}"](**args)))

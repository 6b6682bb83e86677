"""FMU sessions for test_fmu.py, each run in its own Python process (a crash in the FMU then
fails one test instead of killing pytest):

    python fmu_sessions.py <session> '<json args>'

prints one JSON line with the session's results (the last line of stdout).
"""
import json
import math
import pathlib
import sys

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave

ROOT = pathlib.Path(__file__).resolve().parents[2]
LOG = []


def log_message(env, status, category, message):
    LOG.append((status, category.decode() if category else "", message.decode() if message else ""))


def _log2(env, instance, status, category, message):
    LOG.append((status, category.decode() if category else "", message.decode() if message else ""))


def fmi2_callbacks():
    """fmpy's default callbacks with our logger (kept alive at module level)."""
    from fmpy.fmi2 import defaultCallbacks, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
    global _CB2
    _CB2 = fmi2CallbackFunctions()
    _CB2.logger = fmi2CallbackLoggerTYPE(_log2)
    _CB2.allocateMemory = defaultCallbacks.allocateMemory
    _CB2.freeMemory = defaultCallbacks.freeMemory
    return _CB2


def open_fmu(path, name="t", fmi=3, threads=2, init=True, log=True):
    md = read_model_description(path)
    d = extract(path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    if fmi == 3:
        fmu = FMU3Slave(guid=md.guid, unzipDirectory=d, modelIdentifier="sphfmu", instanceName=name)
        fmu.instantiate(loggingOn=log, logMessage=log_message if log else None)
        if init:
            fmu.enterInitializationMode(startTime=0.0)
            fmu.setInt64([vr["threads"]], [threads])
            fmu.exitInitializationMode()
    else:
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier="sphfmu", instanceName=name)
        fmu.instantiate(loggingOn=log, callbacks=fmi2_callbacks() if log else None)
        if init:
            fmu.setupExperiment(startTime=0.0)
            fmu.enterInitializationMode()
            fmu.setInteger([vr["threads"]], [threads])
            fmu.exitInitializationMode()
    return fmu, vr


def outputs3(fmu, vr, names):
    out = []
    for n in names:
        if n.startswith("diag.steps"):
            out += [float(x) for x in fmu.getInt64([vr[n]])]
        else:
            size = 3 if n.endswith(("force", "torque", "velocity", "momentum", "gravity", "position")) else 1
            out += list(fmu.getFloat64([vr[n]], nValues=size))
    return out


PISTON_OUT = ["piston.force", "probe.middle.pressure", "marker.face.pressure", "diag.energy", "diag.steps"]


def session_tank_gravity(fmu_path):
    """simulate_fmu with a gravity input signal: 9.81, doubled at t = 0.6."""
    from fmpy import simulate_fmu
    sig = np.array([(0.0, (0.0, -9.81, 0.0)), (0.6, (0.0, -9.81, 0.0)),
                    (0.6, (0.0, -19.62, 0.0)), (1.4, (0.0, -19.62, 0.0))],
                   dtype=[("time", "f8"), ("gravity", "f8", (3,))])
    res = simulate_fmu(fmu_path, stop_time=1.4, step_size=0.02, output_interval=0.02, input=sig,
                       start_values={"threads": 2}, output=["tank.force", "diag.mass", "diag.particles",
                               "patch.floor.mean_pressure", "patch.floor.area"])
    t = res["time"]
    fy = res["tank.force"][:, 1]
    mass = res["diag.mass"][-1]
    w1 = (t > 0.3) & (t <= 0.6 + 1e-9)
    w2 = (t > 1.0)
    return {
        "ratio1": float(-fy[w1].mean() / (mass * 9.81)),
        "ratio2": float(-fy[w2].mean() / (mass * 19.62)),
        "particles": int(res["diag.particles"][-1]),
        "mass_drift": float(abs(res["diag.mass"][-1] / res["diag.mass"][0] - 1)),
        "finite": bool(np.all(np.isfinite(fy))),
        # floor wall layer Δx/2 under the floor: 2e4 Pa at the lid, mean ρ 1030.5 kg/m³
        "floor_pressure": float(res["patch.floor.mean_pressure"][w1].mean()
                                / (2e4 + 1030.5 * 9.81 * 0.51)),
        "floor_area": float(res["patch.floor.area"][-1]),
    }


def session_step_sizes(fmu_path):
    """The same interval with fixed and with varying communication steps."""
    results = []
    for steps in ([0.1] * 10, [0.05, 0.15, 0.1, 0.2, 0.07, 0.13, 0.3]):
        fmu, vr = open_fmu(fmu_path)
        t = 0.0
        for h in steps:
            fmu.doStep(t, h)
            t += h
        results.append(outputs3(fmu, vr, PISTON_OUT[:4]) + [t])
        fmu.terminate()
        fmu.freeInstance()
    return {"fixed": results[0], "varying": results[1]}


def session_rollback(fmu_path, fmi):
    fmu, vr = open_fmu(fmu_path, fmi=fmi)
    vr2 = {}
    if fmi == 2:
        names = ["piston.force[1]", "probe.middle.pressure", "diag.energy"]
        get = lambda: list(fmu.getReal([vr[n] for n in names]))  # noqa: E731
        set_v = lambda v: fmu.setReal([vr["piston.velocity[1]"]], [v])  # noqa: E731
    else:
        get = lambda: outputs3(fmu, vr, PISTON_OUT)  # noqa: E731
        set_v = lambda v: fmu.setFloat64([vr["piston.velocity"]], [v, 0.0, 0.0])  # noqa: E731
    t = 0.0
    for _ in range(3):
        fmu.doStep(t, 0.1)
        t += 0.1
    state = fmu.getFMUState() if fmi == 3 else fmu.getFMUstate()
    set_v(0.01)
    fmu.doStep(t, 0.1)
    first = get()
    # try something else, then roll back and repeat the first attempt
    set_v(-0.03)
    fmu.doStep(t + 0.1, 0.05)
    if fmi == 3:
        fmu.setFMUState(state)
        blob = fmu.serializeFMUState(state)
        fmu.freeFMUState(state)
    else:
        fmu.setFMUstate(state)
        blob = fmu.serializeFMUstate(state)
        fmu.freeFMUstate(state)
    set_v(0.01)
    fmu.doStep(t, 0.1)
    again = get()
    fmu.terminate()
    fmu.freeInstance()
    # serialized: a new instance continues from the bytes
    fmu, vr = open_fmu(fmu_path, name="second", fmi=fmi)
    if fmi == 3:
        s = fmu.deserializeFMUState(blob)
        fmu.setFMUState(s)
        fmu.freeFMUState(s)
    else:
        s = fmu.deSerializeFMUstate(blob)
        fmu.setFMUstate(s)
        fmu.freeFMUstate(s)
    set_v(0.01)
    fmu.doStep(t, 0.1)
    restored = get()
    fmu.terminate()
    fmu.freeInstance()
    return {"first": [x.hex() for x in first], "again": [x.hex() for x in again],
            "restored": [x.hex() for x in restored], "bytes": len(blob)}


def session_free_piston(fmu_path):
    sys.path.insert(0, str(ROOT / "tools"))
    import free_piston
    r = free_piston.run(fmu_path, mass=2.0, threads=2)
    return {"period": r["period"], "theory": r["theory"], "crossings": r["crossings"]}


def session_two_instances(fmu_path):
    """Instance A alone, then A beside B (other inputs, stepped in between): A is unchanged."""
    def drive(fmu, vr, v, t):
        fmu.setFloat64([vr["piston.velocity"]], [v, 0.0, 0.0])
        fmu.doStep(t, 0.1)

    a, vr = open_fmu(fmu_path, "alone")
    for k in range(4):
        drive(a, vr, 0.01, 0.1 * k)
    alone = outputs3(a, vr, PISTON_OUT)
    a.terminate()
    a.freeInstance()
    a, vr = open_fmu(fmu_path, "a")
    b, _ = open_fmu(fmu_path, "b", threads=1)
    for k in range(4):
        drive(a, vr, 0.01, 0.1 * k)
        drive(b, vr, -0.02, 0.1 * k)
    beside = outputs3(a, vr, PISTON_OUT)
    other = outputs3(b, vr, PISTON_OUT)
    for f in (a, b):
        f.terminate()
        f.freeInstance()
    return {"alone": [x.hex() for x in alone], "beside": [x.hex() for x in beside],
            "other": [x.hex() for x in other]}


def expect_error(fn):
    try:
        fn()
    except FMICallException as e:
        return e.status
    except Exception as e:  # fmpy raises plain exceptions for NULL instances
        return repr(e)
    return "no error"


def session_bad_calls(fmu_path):
    out = {}
    fmu, vr = open_fmu(fmu_path, init=False)
    out["step_before_init"] = expect_error(lambda: fmu.doStep(0.0, 0.1))
    fmu.enterInitializationMode(startTime=0.0)
    fmu.setInt64([vr["threads"]], [2])
    out["threads_out_of_range"] = expect_error(lambda: fmu.setInt64([vr["threads"]], [-3]))
    out["resolution_out_of_range"] = expect_error(lambda: fmu.setFloat64([vr["resolution"]], [50.0]))
    fmu.exitInitializationMode()
    out["nan_gravity"] = expect_error(lambda: fmu.setFloat64([vr["gravity"]], [float("nan"), 0.0, 0.0]))
    out["gravity_z_in_2d"] = expect_error(lambda: fmu.setFloat64([vr["gravity"]], [0.0, 0.0, -9.81]))
    # a 2D body's angular velocity is a scalar about z: a 3-vector with x/y is refused
    out["omega_3d_in_2d"] = expect_error(
        lambda: fmu.setFloat64([vr["piston.angular_velocity"]], [0.5, 0.0, 1.0]))
    out["omega_kept"] = list(fmu.getFloat64([vr["piston.angular_velocity"]]))
    out["inf_position"] = expect_error(
        lambda: fmu.setFloat64([vr["piston.position"]], [float("inf"), 0.1, 0.0]))
    out["set_output"] = expect_error(lambda: fmu.setFloat64([vr["piston.force"]], [0.0, 0.0, 0.0]))
    out["param_in_step_mode"] = expect_error(lambda: fmu.setFloat64([vr["resolution"]], [2.0]))
    out["negative_step"] = expect_error(lambda: fmu.doStep(0.0, -0.1))
    out["wrong_time"] = expect_error(lambda: fmu.doStep(5.0, 0.1))
    out["wrong_nvalues"] = expect_error(lambda: fmu.getFloat64([vr["piston.force"]], nValues=2))
    out["unknown_vr"] = expect_error(lambda: fmu.getFloat64([9999], nValues=1))
    # the instance still works after all that
    fmu.doStep(0.0, 0.1)
    out["after_errors"] = outputs3(fmu, vr, ["piston.force"])[0]
    out["gravity_kept"] = outputs3(fmu, vr, ["gravity"])
    fmu.terminate()
    out["step_after_terminate"] = expect_error(lambda: fmu.doStep(0.1, 0.1))
    fmu.freeInstance()
    # an unknown case: the error comes at the end of initialisation
    fmu, vr = open_fmu(fmu_path, init=False)
    fmu.enterInitializationMode(startTime=0.0)
    fmu.setString([vr["case"]], ["no-such-case.toml"])
    out["unknown_case"] = expect_error(lambda: fmu.exitInitializationMode())
    fmu.freeInstance()
    # a case with other bodies than the packaged one
    fmu, vr = open_fmu(fmu_path, init=False)
    fmu.enterInitializationMode(startTime=0.0)
    fmu.setString([vr["case"]], ["closed-tank2d.toml"])
    out["other_interface"] = expect_error(lambda: fmu.exitInitializationMode())
    fmu.freeInstance()
    # unknown scheme
    fmu, vr = open_fmu(fmu_path, init=False)
    fmu.enterInitializationMode(startTime=0.0)
    fmu.setString([vr["scheme"]], ["sph2000"])
    out["unknown_scheme"] = expect_error(lambda: fmu.exitInitializationMode())
    fmu.freeInstance()
    out["log"] = [m for (s, c, m) in LOG if s >= 3]
    out["alive"] = True
    return out


def session_blowup_and_reset(fmu_path, fmi):
    """A solver blow-up is an error with its cause logged; restoring a saved state makes the
    instance usable again; reset starts over and reproduces a fresh run."""
    fmu, vr = open_fmu(fmu_path, fmi=fmi)
    if fmi == 3:
        get_state, set_state = fmu.getFMUState, fmu.setFMUState
        set_v = lambda v: fmu.setFloat64([vr["piston.velocity"]], [v, 0.0, 0.0])  # noqa: E731
        force = lambda f: f.getFloat64([vr["piston.force"]], nValues=3)[0]  # noqa: E731
    else:
        get_state, set_state = fmu.getFMUstate, fmu.setFMUstate
        set_v = lambda v: fmu.setReal([vr["piston.velocity[1]"]], [v])  # noqa: E731
        force = lambda f: f.getReal([vr["piston.force[1]"]])[0]  # noqa: E731
    fmu.doStep(0.0, 0.1)
    saved = get_state()
    # the piston rams through the gas at 200 m/s (far beyond what the solver can resolve)
    set_v(-200.0)
    out = {"blowup": expect_error(lambda: fmu.doStep(0.1, 0.5))}
    out["step_after_failure"] = expect_error(lambda: fmu.doStep(0.1, 0.1))
    set_state(saved)
    set_v(0.0)
    fmu.doStep(0.1, 0.1)
    out["after_restore"] = force(fmu)
    fmu.reset()
    if fmi == 3:
        fmu.enterInitializationMode(startTime=0.0)
        fmu.setInt64([vr["threads"]], [2])
    else:
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.setInteger([vr["threads"]], [2])
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 0.1)
    out["after_reset"] = force(fmu)
    fmu.terminate()
    fmu.freeInstance()
    fresh, _ = open_fmu(fmu_path, fmi=fmi)
    fresh.doStep(0.0, 0.1)
    out["fresh"] = force(fresh)
    fresh.terminate()
    fresh.freeInstance()
    out["log"] = [m for (s, c, m) in LOG if s >= 3]
    return out


def session_snapshots(fmu_path, out_dir):
    """VTU snapshots from inside the FMU: output_dir and output_interval."""
    import meshio
    md = read_model_description(fmu_path)
    fmu, vr = open_fmu(fmu_path, init=False)
    fmu.enterInitializationMode(startTime=0.0)
    fmu.setInt64([vr["threads"]], [2])
    fmu.setString([vr["output_dir"]], [out_dir])
    fmu.setFloat64([vr["output_interval"]], [0.1])
    fmu.exitInitializationMode()
    t = 0.0
    for _ in range(6):
        fmu.doStep(t, 0.05)
        t += 0.05
    fmu.terminate()
    fmu.freeInstance()
    pvd = (pathlib.Path(out_dir) / "snapshots.pvd").read_text()
    files = sorted(p.name for p in pathlib.Path(out_dir).glob("*.vtu"))
    points = meshio.read(str(pathlib.Path(out_dir) / files[-1])).points.shape[0]
    return {"files": files, "times": pvd.count("<DataSet"), "points": points,
            "variables": len(md.modelVariables)}


def session_port_pressure(fmu_path):
    """A network master drives the channel FMU's inlet pressure through simulate_fmu: 0.06 Pa
    until t = 4, then 0.12; it reads the port flows and the exact mass counters."""
    from fmpy import simulate_fmu
    sig = np.array([(0.0, 0.06), (4.0, 0.06), (4.0, 0.12), (8.0, 0.12)],
                   dtype=[("time", "f8"), ("port.inlet.pressure", "f8")])
    out = ["port.inlet.volume_flow", "port.outlet.volume_flow", "port.inlet.mass_in",
           "port.inlet.mass_out", "port.outlet.mass_in", "port.outlet.mass_out",
           "port.inlet.pressure_set", "diag.mass", "diag.fluid_particles", "diag.particles"]
    res = simulate_fmu(fmu_path, stop_time=8.0, step_size=0.1, output_interval=0.1, input=sig,
                       start_values={"threads": 2}, output=out)
    t = res["time"]
    q = 0.5 * (res["port.inlet.volume_flow"] - res["port.outlet.volume_flow"])
    net = (res["port.inlet.mass_in"] + res["port.outlet.mass_in"]
           - res["port.inlet.mass_out"] - res["port.outlet.mass_out"])
    balance = res["diag.mass"] - res["diag.mass"][0] - net
    return {
        "q1": float(q[(t > 3.0) & (t <= 4.0)].mean()),
        "q2": float(q[t > 7.0].mean()),
        "set_before": float(res["port.inlet.pressure_set"][t <= 3.95].max()),
        "set_after": float(res["port.inlet.pressure_set"][-1]),
        "balance": float(np.abs(balance).max() / res["diag.mass"][0]),
        "moved": float(res["port.outlet.mass_out"][-1]),
        "fluid_changes": int(len(set(res["diag.fluid_particles"].tolist()))),
        "finite": bool(np.all(np.isfinite(q))),
    }


def session_bad_port_pressure(fmu_path, fmi):
    """Negative and NaN port pressures: errors with a log line; the input keeps its value."""
    fmu, vr = open_fmu(fmu_path, fmi=fmi)
    codes = {}
    for name, value in [("negative", -1.0), ("nan", float("nan"))]:
        if fmi == 3:
            codes[name] = expect_error(lambda: fmu.setFloat64([vr["port.inlet.pressure"]], [value]))
        else:
            codes[name] = expect_error(lambda: fmu.setReal([vr["port.inlet.pressure"]], [value]))
    kept = list(fmu.getFloat64([vr["port.inlet.pressure"]])) if fmi == 3 else \
        list(fmu.getReal([vr["port.inlet.pressure"]]))
    fmu.doStep(0.0, 0.1)
    fmu.terminate()
    fmu.freeInstance()
    return {"codes": codes, "kept": kept, "log": [m for _, _, m in LOG]}


if __name__ == "__main__":
    name, args = sys.argv[1], json.loads(sys.argv[2]) if len(sys.argv) > 2 else {}
    result = globals()["session_" + name](**args)
    print(json.dumps(result))

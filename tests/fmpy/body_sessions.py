"""Sessions of a multibody master driving a 3D body through the FMU (issue 22), each run in its
own Python process by test_bodies.py:

    python body_sessions.py <session> '<json args>'

prints one JSON line with the session's results (the last line of stdout).
"""
import json
import sys

import numpy as np
from fmu_sessions import LOG, ROOT, expect_error, open_fmu

sys.path.insert(0, str(ROOT / "tools"))
from strong_coupling import exp_rot, log_rot, quaternion  # noqa: E402


def rot_x(a):
    return exp_rot(np.array([a, 0.0, 0.0]))


def rot_y(a):
    return exp_rot(np.array([0.0, a, 0.0]))


def tilt(t, roll, pitch, ramp):
    """Roll about world x, then pitch about world y, each rising as (1 - cos) over `ramp`."""
    s = 0.5 * (1.0 - np.cos(np.pi * min(t / ramp, 1.0)))
    return rot_y(pitch * s) @ rot_x(roll * s)


def settled_water(r, volume, half=0.1, n=120):
    """Centroid (world) of `volume` of water at rest, level, in the cube [-half, half]^3 turned
    by r about its centre: the lowest `volume` of a fine grid of the cube's interior."""
    g = (np.arange(n) + 0.5) / n * 2.0 * half - half
    x, y, z = np.meshgrid(g, g, g, indexing="ij")
    pts = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1) @ r.T
    keep = int(round(volume / (2.0 * half) ** 3 * len(pts)))
    low = np.argsort(pts[:, 2], kind="stable")[:keep]
    return pts[low].mean(axis=0)


def open_box(fmu_path, resolution):
    """The box FMU (FMI 3.0) in step mode, 2 threads, at `resolution` × the case's spacing."""
    fmu, vr = open_fmu(fmu_path, init=False)
    fmu.enterInitializationMode(startTime=0.0)
    fmu.setInt64([vr["threads"]], [2])
    fmu.setFloat64([vr["resolution"]], [resolution])
    fmu.exitInitializationMode()
    return fmu, vr


def matrix(q):
    """Rotation matrix (body -> world) of quaternion [w, x, y, z]."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def read(fmu, vr, name, n=3):
    return np.array(fmu.getFloat64([vr[name]], nValues=n))


def session_tilted_box(fmu_path, roll, pitch, ramp, t_end, window, dt, resolution):
    """Roll and pitch the box together through box.orientation (with the angular velocity
    that carries each pose to the next), hold, and average the loads over the last `window`
    seconds against the hydrostatic loads of the level water in the tilted box. Once the box
    holds still (ω = 0, so its pose is the quaternion given), the body-axes loads are checked
    against the world loads turned by that quaternion's matrix."""
    fmu, vr = open_box(fmu_path, resolution)
    mass = float(read(fmu, vr, "diag.mass", 1)[0])
    steps = int(round(t_end / dt))
    rows, body_frame_error = [], 0.0
    for k in range(steps):
        t0, t1 = k * dt, (k + 1) * dt
        r0, r1 = tilt(t0, roll, pitch, ramp), tilt(t1, roll, pitch, ramp)
        q = quaternion(r0)
        turning = t0 < ramp
        w = log_rot(r1 @ r0.T) / dt if turning else np.zeros(3)
        fmu.setFloat64([vr["box.orientation"]], q)
        fmu.setFloat64([vr["box.angular_velocity"]], list(w))
        fmu.doStep(t0, dt)
        f, m = read(fmu, vr, "box.force"), read(fmu, vr, "box.torque")
        if not turning:
            fb, mb = read(fmu, vr, "box.force_body"), read(fmu, vr, "box.torque_body")
            r = matrix(q)
            scale = max(np.abs(f).max(), np.abs(m).max())
            body_frame_error = max(body_frame_error, float(max(
                np.abs(r.T @ f - fb).max(), np.abs(r.T @ m - mb).max()) / scale))
        rows.append([t1, *f, *m])
    fmu.terminate()
    fmu.freeInstance()
    rows = np.array(rows)
    late = rows[rows[:, 0] > t_end - window]
    g = 9.81
    r = tilt(t_end, roll, pitch, ramp)
    cm = settled_water(r, volume=0.2 * 0.2 * 0.08)
    weight = np.array([0.0, 0.0, -mass * g])
    return {
        "mass": mass,
        "force": late[:, 1:4].mean(axis=0).tolist(),
        "torque": late[:, 4:7].mean(axis=0).tolist(),
        "torque_spread": late[:, 4:7].std(axis=0).tolist(),
        "expected_force": weight.tolist(),
        "expected_torque": np.cross(cm, weight).tolist(),
        "frozen_torque": np.cross(r @ np.array([0.0, 0.0, -0.06]), weight).tolist(),
        "body_frame_error": body_frame_error,
        "finite": bool(np.all(np.isfinite(rows))),
    }


def session_pitched_tank(fmu_path, amplitude, omega, cycles, free_time, dt):
    """Pitch the tank about y, theta = amplitude sin(omega t) for `cycles` periods (with the
    exact angular velocity and acceleration of that motion each step), then hold it level;
    record the wall marker's pressure and the tank's horizontal force."""
    fmu, vr = open_box(fmu_path, 1.0)
    forced = cycles * 2.0 * np.pi / omega
    steps = int(round((forced + free_time) / dt))
    rows = []
    for k in range(steps):
        t = k * dt
        on = t < forced - 1e-12
        theta = amplitude * np.sin(omega * t) if on else 0.0
        rate = amplitude * omega * np.cos(omega * t) if on else 0.0
        accel = -amplitude * omega ** 2 * np.sin(omega * t) if on else 0.0
        fmu.setFloat64([vr["tank.orientation"]], [np.cos(theta / 2), 0.0, np.sin(theta / 2), 0.0])
        fmu.setFloat64([vr["tank.angular_velocity"]], [0.0, rate, 0.0])
        fmu.setFloat64([vr["tank.angular_acceleration"]], [0.0, accel, 0.0])
        fmu.doStep(t, dt)
        rows.append([t + dt, read(fmu, vr, "marker.wall.pressure", 1)[0],
                     *read(fmu, vr, "tank.force")])
        if k % 50 == 0:
            print(f"t = {t + dt:.3f}", file=sys.stderr, flush=True)
    fmu.terminate()
    fmu.freeInstance()
    return {"forced": forced, "rows": rows}


def turn_and_step(fmu_path, name, value, omega=(0.0, 0.0, 0.0)):
    """Step the box at rest, turn it to `value` (its orientation input `name`), step on; the
    loads' bits."""
    fmu, vr = open_box(fmu_path, 0.5)
    fmu.doStep(0.0, 0.01)
    fmu.setFloat64([vr[name]], list(value))
    fmu.setFloat64([vr["box.angular_velocity"]], list(omega))
    fmu.doStep(0.01, 0.01)
    out = [float(x) for n in ("box.force", "box.torque", "box.force_body", "box.torque_body")
           for x in read(fmu, vr, n)]
    fmu.terminate()
    fmu.freeInstance()
    return out


def session_quaternion_and_matrix(quaternion_fmu, matrix_fmu):
    """One rotation given as a quaternion to one FMU and as Modelica's R.T to the other: 120°
    about the cube's diagonal (exact in both forms), and a generic turn with a spin."""
    q = [0.5, 0.5, 0.5, 0.5]
    t = [0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0]
    diagonal = (turn_and_step(quaternion_fmu, "box.orientation", q),
                turn_and_step(matrix_fmu, "box.T", t))
    r = rot_y(0.07) @ rot_x(-0.05)
    spin = (0.3, -0.2, 0.1)
    generic = (turn_and_step(quaternion_fmu, "box.orientation", quaternion(r), spin),
               turn_and_step(matrix_fmu, "box.T", r.T.ravel(), spin))
    return {
        "diagonal": [[x.hex() for x in side] for side in diagonal],
        "generic": [list(side) for side in generic],
    }


def session_bad_orientations(quaternion_fmu, matrix_fmu):
    """Inputs that are not rotations: an FMI error with a log line each, the input keeps its
    value and the instance steps on as before. FMI 2.0 sets a quaternion element by element,
    so its check comes at doStep: an error there, time and state unchanged."""
    out = {}
    fmu, vr = open_box(quaternion_fmu, 0.5)
    q = vr["box.orientation"]
    fmu.setFloat64([q], [1.0 + 5e-7, 0.0, 0.0, 0.0])
    out["near_unit_taken"] = list(fmu.getFloat64([q], nValues=4))
    fmu.setFloat64([q], [1.0, 0.0, 0.0, 0.0])
    for name, value in [("nan", [float("nan"), 0.0, 0.0, 1.0]), ("zero", [0.0] * 4),
                        ("long", [1.01, 0.0, 0.0, 0.0])]:
        out[name] = expect_error(lambda: fmu.setFloat64([q], value))
    out["kept"] = list(fmu.getFloat64([q], nValues=4))
    fmu.doStep(0.0, 0.01)
    out["time_after"] = float(fmu.getFloat64([vr["time"]])[0])
    fmu.terminate()
    fmu.freeInstance()
    fmu, vr = open_box(matrix_fmu, 0.5)
    m = vr["box.T"]
    skew = [1.0, 1e-3, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    mirror = [-1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    out["skew"] = expect_error(lambda: fmu.setFloat64([m], skew))
    out["mirror"] = expect_error(lambda: fmu.setFloat64([m], mirror))
    out["matrix_kept"] = list(fmu.getFloat64([m], nValues=9))
    fmu.terminate()
    fmu.freeInstance()
    fmu2 = quaternion_fmu.replace("sphfmu.fmu", "sphfmu-fmi2.fmu")
    fmu, vr = open_fmu(fmu2, fmi=2)
    fmu.doStep(0.0, 0.01)
    before = (fmu.getReal([vr["box.force[3]"]])[0], fmu.getInteger([vr["diag.steps"]])[0])
    fmu.setReal([vr["box.orientation[1]"]], [2.0])
    out["fmi2_step"] = expect_error(lambda: fmu.doStep(0.01, 0.01))
    after = (fmu.getReal([vr["box.force[3]"]])[0], fmu.getInteger([vr["diag.steps"]])[0])
    out["fmi2_unchanged"] = after == before
    fmu.setReal([vr["box.orientation[1]"]], [1.0])
    fmu.doStep(0.01, 0.01)
    out["fmi2_steps_on"] = fmu.getInteger([vr["diag.steps"]])[0] > before[1]
    fmu.terminate()
    fmu.freeInstance()
    out["log"] = [msg for (s, c, msg) in LOG if s >= 3]
    return out


if __name__ == "__main__":
    name, args = sys.argv[1], json.loads(sys.argv[2]) if len(sys.argv) > 2 else {}
    print(json.dumps(globals()["session_" + name](**args)))

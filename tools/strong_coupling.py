#!/usr/bin/env python3
"""A free rigid body coupled two ways to the sphfmu FMU (FMI 3.0, through fmpy), explicitly or
strongly (issue 22).

The master integrates the body's own Newton-Euler equations,

    M dv/dt = F_fluid + F_ext,                  dx/dt = v,
    d(I w)/dt = T_fluid + T_ext  (world axes),  dR/dt = [w]x R,   I = R I_body R^T,

with F_ext = F_pre - K (x - x_rest) - C v + M g and T_ext = -K_rot phi - C_rot w (phi the
rotation vector from the rest orientation), by the trapezoidal rule (Newmark, average
acceleration) over each communication step H. The FMU gets the body's pose and velocities at
the start of the step and the constant accelerations that carry them to the end-of-step
velocities u = [v1, w1]: a = (v1 - v0)/H, alpha = (w1 - w0)/H. Under the trapezoidal rule that
motion ends exactly at the body's x1 and v1 (x1 = x0 + H (v0 + v1)/2), so the FMU's wall moves
without the velocity jumps (water hammer, dP = rho c dv) that a constant velocity per step
would send into a liquid. It returns the fluid's force and torque at the end.

* explicit: the body steps with the fluid loads of the start of the step, then the FMU steps
  with the body's motion (serial staggered: one FMU step per communication step).
* implicit (default): per communication step, fixed-point iterations on u. Each iteration
  rolls the FMU back to the start of the step (fmi3GetFMUState / fmi3SetFMUState, bit for
  bit), steps it with u_k, integrates the body with the trapezoidal loads of the start and the
  end of the step, and relaxes u_{k+1} = u_k + w_k r_k, r_k = u(loads_k) - u_k, with Aitken's
  factor w_k = -w_{k-1} r_{k-1}.(r_k - r_{k-1}) / |r_k - r_{k-1}|^2 (Kuettler & Wall 2008,
  Comput. Mech. 43:61), until |r_k| <= tol (|u| + u_scale).

A light body in a liquid (added mass above the body's own) makes explicit coupling unstable
at every step size of interest; the iterations converge (tests/fmpy/test_strong_coupling.py).

    python tools/strong_coupling.py --fmu target/fmu/added-mass2d/sphfmu.fmu --body piston \\
        --mass 2 --stiffness 0 6630 0 --displace 0 0.002 0 --step 0.01 --stop 1.5 --out target/sc

writes strong_coupling.csv (t, x, v, F, iterations) and summary.json and prints the period.
"""
import argparse
import json
import math
import os
import sys

import numpy as np


def skew(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def exp_rot(phi):
    """Rotation matrix of rotation vector phi (Rodrigues)."""
    a = np.linalg.norm(phi)
    if a < 1e-300:
        return np.eye(3)
    k = skew(phi / a)
    return np.eye(3) + math.sin(a) * k + (1.0 - math.cos(a)) * (k @ k)


def log_rot(r):
    """Rotation vector of rotation matrix r (accurate for small and moderate angles)."""
    v = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]]) / 2.0
    s, c = np.linalg.norm(v), (np.trace(r) - 1.0) / 2.0
    a = math.atan2(s, c)
    return v if s < 1e-300 else v * (a / s)


def quaternion(r):
    """[w, x, y, z] of rotation matrix r (body -> world)."""
    phi = log_rot(r)
    a = np.linalg.norm(phi)
    if a == 0.0:
        return [1.0, 0.0, 0.0, 0.0]
    axis = phi / a
    return [math.cos(a / 2.0), *(math.sin(a / 2.0) * axis)]


class Body:
    """A rigid body's state and its own equations (see the module docs)."""

    def __init__(self, mass, inertia, stiffness, damping, rot_stiffness, rot_damping,
                 gravity, preload, x_rest, free):
        self.m = mass
        self.i_body = np.diag(inertia)
        self.k, self.c = np.asarray(stiffness, float), np.asarray(damping, float)
        self.k_rot, self.c_rot = np.asarray(rot_stiffness, float), np.asarray(rot_damping, float)
        self.g, self.pre = np.asarray(gravity, float), np.asarray(preload, float)
        self.x_rest = np.asarray(x_rest, float)
        self.free = np.asarray(free, float)  # 6 entries: 1 free, 0 locked
        self.x, self.v = self.x_rest.copy(), np.zeros(3)
        self.r, self.w = np.eye(3), np.zeros(3)

    def state(self):
        return (self.x.copy(), self.v.copy(), self.r.copy(), self.w.copy())

    def set_state(self, s):
        self.x, self.v, self.r, self.w = (a.copy() for a in s)

    def accelerations(self, x, v, r, w, f, t):
        a = (f + self.pre - self.k * (x - self.x_rest) - self.c * v + self.m * self.g) / self.m
        i_w = r @ self.i_body @ r.T
        torque = t - self.k_rot * log_rot(r) - self.c_rot * w
        alpha = (np.linalg.solve(i_w, torque - np.cross(w, i_w @ w))
                 if np.any(self.free[3:]) else np.zeros(3))
        return a * self.free[:3], alpha * self.free[3:]

    def step(self, h, loads0, loads1):
        """The state after h under fluid loads varying linearly from loads0 to loads1 (the
        trapezoidal rule; its implicit stage solved by fixed-point, which contracts for
        K h^2 / 4M < 1, as asserted)."""
        x0, v0, r0, w0 = self.state()
        a0, al0 = self.accelerations(x0, v0, r0, w0, *loads0)
        a1, al1 = a0, al0
        for _ in range(100):
            v1 = v0 + 0.5 * h * (a0 + a1)
            x1 = x0 + h * v0 + 0.25 * h * h * (a0 + a1)
            w1 = w0 + 0.5 * h * (al0 + al1)
            r1 = exp_rot(h * w0 + 0.25 * h * h * (al0 + al1)) @ r0
            a_new, al_new = self.accelerations(x1, v1, r1, w1, *loads1)
            done = (np.abs(a_new - a1).max() <= 1e-13 * (1.0 + np.abs(a_new).max())
                    and np.abs(al_new - al1).max() <= 1e-13 * (1.0 + np.abs(al_new).max()))
            a1, al1 = a_new, al_new
            if done:
                break
        else:
            raise RuntimeError("body step: the trapezoidal stage does not converge; "
                               "reduce --step (K h^2/4M must be below 1)")
        return x1, v1, r1, w1


class Fmu:
    """The FMU's body: inputs (pose at the step start, mean velocities) and loads."""

    def __init__(self, path, body, threads, resolution):
        from fmpy import extract, read_model_description
        from fmpy.fmi3 import FMU3Slave
        md = read_model_description(path)
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.body = body
        for what in ("position", "velocity", "acceleration", "angular_velocity", "force", "torque"):
            if f"{body}.{what}" not in self.vr:
                sys.exit(f"strong_coupling: {path} has no variable {body}.{what}: the body must "
                         "have motion = { type = \"external\" }")
        self.planar = f"{body}.angle" in self.vr
        self.fmu = FMU3Slave(guid=md.guid, unzipDirectory=extract(path),
                             modelIdentifier=md.coSimulation.modelIdentifier,
                             instanceName="strong_coupling")
        self.fmu.instantiate()
        self.fmu.enterInitializationMode(startTime=0.0)
        self.fmu.setInt64([self.vr["threads"]], [threads])
        self.fmu.setFloat64([self.vr["resolution"]], [resolution])
        self.fmu.exitInitializationMode()

    def get(self, name, n):
        return np.array(self.fmu.getFloat64([self.vr[f"{self.body}.{name}"]], nValues=n))

    def set(self, name, values):
        self.fmu.setFloat64([self.vr[f"{self.body}.{name}"]], [float(x) for x in values])

    def reference(self):
        return self.get("position", 3)

    def loads(self):
        return self.get("force", 3), self.get("torque", 3)

    def step(self, t, h, s0, u):
        """One FMU step from body state s0 = (x, v, R, w) to end-of-step velocities u."""
        x0, v0, r0, w0 = s0
        a, alpha = (u[:3] - v0) / h, (u[3:] - w0) / h
        self.set("position", x0)
        self.set("velocity", v0)
        self.set("acceleration", a)
        if self.planar:
            self.set("angle", [log_rot(r0)[2]])
            self.set("angular_velocity", [w0[2]])
            self.set("angular_acceleration", [alpha[2]])
        else:
            self.set("orientation", quaternion(r0))
            self.set("angular_velocity", w0)
            self.set("angular_acceleration", alpha)
        self.fmu.doStep(t, h)
        return self.loads()


def end_velocities(s):
    return np.concatenate([s[1], s[3]])


def run(fmu_path, body_name, mass, step, stop, mode="implicit", inertia=(1.0, 1.0, 1.0),
        stiffness=(0.0, 0.0, 0.0), damping=(0.0, 0.0, 0.0), rot_stiffness=(0.0, 0.0, 0.0),
        rot_damping=(0.0, 0.0, 0.0), gravity=(0.0, 0.0, 0.0), displace=(0.0, 0.0, 0.0),
        free="xyzXYZ", tol=1e-6, max_iterations=50, threads=0, resolution=1.0,
        diverge_at=None, progress=False):
    """Run the co-simulation. The spring rests where the body starts, preloaded against the
    fluid's loads at t = 0 and the body's weight, so the body starts in equilibrium and then
    is displaced by `displace`. Returns dict(t, x, v, force, iterations, diverged, ...)."""
    fmu = Fmu(fmu_path, body_name, threads, resolution)
    try:
        x_rest = fmu.reference()
        f0, t0 = fmu.loads()
        flags = [1.0 if c in free else 0.0 for c in "xyzXYZ"]
        body = Body(mass, inertia, stiffness, damping, rot_stiffness, rot_damping, gravity,
                    -f0 - mass * np.asarray(gravity, float), x_rest, flags)
        body.x = x_rest + np.asarray(displace, float)
        loads = (f0, t0)
        # the displaced pose from t = 0: the FMU re-evaluates its loads there on the first step
        rec = {"t": [0.0], "x": [body.x.tolist()], "v": [body.v.tolist()],
               "force": [f0.tolist()], "iterations": []}
        n = int(round(stop / step))
        diverged, scale = None, max(1e-12, np.abs(np.asarray(displace)).max() / step)
        for k in range(n):
            t = k * step
            s0 = body.state()
            if mode == "explicit":
                s1 = body.step(step, loads, loads)
                try:
                    loads1 = fmu.step(t, step, s0, end_velocities(s1))
                except Exception as e:  # fmpy's FMICallException: the fluid blew up
                    print(f"strong_coupling: t = {t:.4g}: the FMU failed ({e}): diverged",
                          file=sys.stderr)
                    diverged = t
                    break
                its = 1
            else:
                saved = fmu.fmu.getFMUState()
                # predictor: the body under the loads of the step's start
                u = end_velocities(body.step(step, loads, loads))
                r_prev, w_relax = None, 0.5
                for its in range(1, max_iterations + 1):
                    if its > 1:
                        fmu.fmu.setFMUState(saved)
                    loads1 = fmu.step(t, step, s0, u)
                    body.set_state(s0)
                    s1 = body.step(step, loads, loads1)
                    r = end_velocities(s1) - u
                    if np.abs(r).max() <= tol * (np.abs(u).max() + scale):
                        break
                    if r_prev is not None:
                        dr = r - r_prev
                        w_relax = -w_relax * float(r_prev @ dr) / float(dr @ dr)
                    u, r_prev = u + w_relax * r, r
                else:
                    fmu.fmu.freeFMUState(saved)
                    raise RuntimeError(f"t = {t:.4g}: no convergence in {max_iterations} iterations "
                                       f"(residual {np.abs(r).max():.3e})")
                fmu.fmu.freeFMUState(saved)
            body.set_state(s1)
            loads = loads1
            rec["t"].append(t + step)
            rec["x"].append(body.x.tolist())
            rec["v"].append(body.v.tolist())
            rec["force"].append(loads[0].tolist())
            rec["iterations"].append(its)
            if progress and k % max(1, n // 50) == 0:
                print(f"\r{mode}: t = {t + step:.3f} / {stop}", end="", file=sys.stderr)
            if diverge_at is not None and np.abs(body.x - x_rest).max() > diverge_at:
                diverged = t + step
                break
        if progress:
            print(file=sys.stderr)
        rec["diverged"] = diverged
        return rec
    finally:
        fmu.fmu.terminate()
        fmu.fmu.freeInstance()


def period(t, y):
    """Mean period from the upward zero crossings of y (linear interpolation)."""
    ups = [t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])
           for i in range(len(y) - 1) if y[i] < 0.0 <= y[i + 1]]
    return (ups[-1] - ups[0]) / (len(ups) - 1) if len(ups) > 1 else float("nan")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--fmu", required=True)
    p.add_argument("--body", required=True, help="the FMU body driven from outside")
    p.add_argument("--mass", type=float, required=True)
    p.add_argument("--inertia", type=float, nargs=3, default=[1.0, 1.0, 1.0],
                   help="principal moments in body axes")
    for name in ("stiffness", "damping", "rot-stiffness", "rot-damping", "gravity", "displace"):
        p.add_argument(f"--{name}", type=float, nargs=3, default=[0.0, 0.0, 0.0])
    p.add_argument("--free", default="xyzXYZ",
                   help="free degrees of freedom: x y z translations, X Y Z rotations")
    p.add_argument("--step", type=float, required=True, help="communication step H")
    p.add_argument("--stop", type=float, required=True)
    p.add_argument("--mode", choices=["implicit", "explicit"], default="implicit")
    p.add_argument("--tol", type=float, default=1e-6)
    p.add_argument("--max-iterations", type=int, default=50)
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--resolution", type=float, default=1.0)
    p.add_argument("--out", default="target/strong_coupling")
    a = p.parse_args()
    if not (a.step > 0 and a.stop > a.step and a.mass > 0 and a.tol > 0):
        sys.exit("strong_coupling: --step and --mass must be > 0, --stop > --step, --tol > 0")
    rec = run(a.fmu, a.body, a.mass, a.step, a.stop, a.mode, a.inertia, a.stiffness, a.damping,
              a.rot_stiffness, a.rot_damping, a.gravity, a.displace, a.free, a.tol,
              a.max_iterations, a.threads, a.resolution,
              diverge_at=100.0 * max(1e-9, max(abs(x) for x in a.displace)), progress=True)
    os.makedirs(a.out, exist_ok=True)
    axis = int(np.argmax(np.abs(a.displace)))
    t = np.array(rec["t"])
    y = np.array(rec["x"])[:, axis] - rec["x"][0][axis] + a.displace[axis]
    summary = {"mode": a.mode, "step": a.step, "period": period(t, y), "diverged": rec["diverged"],
               "iterations_mean": float(np.mean(rec["iterations"])),
               "iterations_max": int(np.max(rec["iterations"]))}
    with open(os.path.join(a.out, "strong_coupling.csv"), "w") as f:
        f.write("t,x,y,z,vx,vy,vz,fx,fy,fz,iterations\n")
        for i, ti in enumerate(rec["t"]):
            its = rec["iterations"][i - 1] if i else 0
            f.write(",".join(f"{v:.10g}" for v in [ti, *rec["x"][i], *rec["v"][i], *rec["force"][i]])
                    + f",{its}\n")
    with open(os.path.join(a.out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    print(json.dumps(summary))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""An independent check of inviscid CRKSPH on a periodic 1D line at rest (verification row
crksph-10): NumPy, written from the equations of Frontiere, Raskin & Owen (2017), not from our
Rust code.

The line: N particles, spacing 1/N, uniform density 1 and pressure 1/γ (γ = 1.4, so c_s = 1),
each displaced at random by up to `--amplitude` of the spacing, at rest. The exact answer is
rest. The scheme: volume V_i = 1 / Σ_j W(x_ij, h) (eq 75), the reproducing kernel of zeroth or
linear order (eqs 8–21), density eq 76, momentum eq 64 and thermal energy eq 78 with no
viscosity, h fixed at η·spacing (so no h update can cause what is measured), RK4 steps of
CFL · spacing / c_s. It prints the kinetic energy against time for each order asked for: growth
from the displacement noise means the semi-discrete equations amplify it.

    target/venv/bin/python tools/crksph_line_check.py            # both orders, to t = 4

Compare `sphfmu run models/verify/crksph-line-rest.toml` (the same line in our code, with its
own h update; kinetic energy in diagnostics.csv).
"""

from __future__ import annotations

import argparse

import numpy as np


def cubic_spline(h: float):
    """M4 with support 2h in 1D: W and dW/dr (signed, with respect to the first point)."""
    norm = 2.0 / (3.0 * h)

    def w(r):
        q = np.abs(r) / h
        return norm * np.where(q < 1, 1 - 1.5 * q**2 + 0.75 * q**3, np.where(q < 2, 0.25 * (2 - q) ** 3, 0.0))

    def dw(r):
        q = np.abs(r) / h
        return norm / h * np.sign(r) * np.where(q < 1, -3 * q + 2.25 * q**2, np.where(q < 2, -0.75 * (2 - q) ** 2, 0.0))

    return w, dw


class Line:
    def __init__(self, n: int, eta: float, gamma: float, order: int):
        self.n, self.length, self.gamma, self.order = n, 1.0, gamma, order
        self.w, self.dw = cubic_spline(eta / n)

    def corrected(self, x):
        """V, W^R_ij and G_ij = ∂W^R_ij/∂x_i (eqs 8–9, 12–21; sums include j = i)."""
        d = x[:, None] - x[None, :]
        d -= self.length * np.round(d / self.length)  # x_ij = x_i − x_j, nearest image
        w, g = self.w(d), self.dw(d)
        vol = 1.0 / w.sum(1)
        vj = vol[None, :]
        m0, dm0 = (vj * w).sum(1), (vj * g).sum(1)
        if self.order == 0:
            a, b, da, db = 1.0 / m0, np.zeros(self.n), -dm0 / m0**2, np.zeros(self.n)
        else:
            m1, m2 = (vj * d * w).sum(1), (vj * d * d * w).sum(1)
            dm1, dm2 = (vj * (d * g + w)).sum(1), (vj * (d * d * g + 2 * d * w)).sum(1)
            b = -m1 / m2
            a = 1.0 / (m0 + b * m1)
            da = -a**2 * (dm0 + 2 * b * dm1 + b * b * dm2)
            db = -(dm1 + dm2 * b) / m2
        a, b, da, db = (z[:, None] for z in (a, b, da, db))
        wr = a * (1 + b * d) * w
        grad = a * (1 + b * d) * g + da * (1 + b * d) * w + a * (db * d + b) * w
        return vol, wr, grad

    def rates(self, x, v, u, m):
        vol, wr, grad = self.corrected(x % self.length)
        rho = (m[None, :] * vol[None, :] * wr).sum(1) / (vol[None, :] ** 2 * wr).sum(1)  # eq 76
        p = (self.gamma - 1) * rho * u
        gg = grad - grad.T  # G_ij − G_ji
        vv = vol[:, None] * vol[None, :]
        acc = -(vv * (p[:, None] + p[None, :]) * gg).sum(1) / (2 * m)  # eq 64
        du = (vv * p[None, :] * (v[:, None] - v[None, :]) * gg).sum(1) / (2 * m)  # eq 78
        return np.array([v, acc, du])


def run(order: int, a) -> list[tuple[float, float, float]]:
    rng = np.random.default_rng(a.seed)
    gamma = 1.4
    line = Line(a.n, a.eta, gamma, order)
    dx = 1.0 / a.n
    x = (np.arange(a.n) + 0.5) * dx + a.amplitude * dx * rng.uniform(-1, 1, a.n)
    m = np.full(a.n, dx)
    # P = 1/γ at ρ = 1, so c_s = 1: u = P / ((γ − 1) ρ)
    y = np.array([x, np.zeros(a.n), np.full(a.n, (1 / gamma) / (gamma - 1))])
    t, dt, out = 0.0, a.cfl * dx, []
    f = lambda s: line.rates(s[0], s[1], s[2], m)  # noqa: E731
    while t < a.t_end - 1e-12:
        k1 = f(y)
        k2 = f(y + dt / 2 * k1)
        k3 = f(y + dt / 2 * k2)
        k4 = f(y + dt * k3)
        y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        t += dt
        out.append((t, 0.5 * (m * y[1] ** 2).sum(), (m * y[2]).sum()))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--orders", default="0,1", help="reproducing orders to run (0, 1)")
    ap.add_argument("--n", type=int, default=100, help="particles")
    ap.add_argument("--eta", type=float, default=1.5, help="h / spacing (M4, support 2h)")
    ap.add_argument("--amplitude", type=float, default=0.02, help="random displacement, fraction of the spacing")
    ap.add_argument("--t-end", type=float, default=4.0)
    ap.add_argument("--cfl", type=float, default=0.1)
    ap.add_argument("--seed", type=int, default=7)
    a = ap.parse_args()
    for order in (int(o) for o in a.orders.split(",")):
        out = run(order, a)
        e0 = out[0][1] + out[0][2]
        marks = [out[min(len(out) - 1, round(len(out) * k / 8) - 1)] for k in range(1, 9)]
        print(f"order {order}: kinetic energy " + ", ".join(f"{ke:.2e} (t {t:.1f})" for t, ke, _ in marks)
              + f"; total energy drift {(out[-1][1] + out[-1][2]) / e0 - 1:.1e}", flush=True)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Linear growth rate of the Rayleigh–Taylor instability of a smooth, stratified gas layer.

    python tools/rt_linear.py --profile rosswog [--n 800]

The reference the RT claims of the verification suite are measured against. A compressible,
inviscid gas at rest in hydrostatic equilibrium, ρ0(y) with dP0/dy = −g ρ0 (gravity g in −y),
between walls at y0 and y1 (v_y = 0), is perturbed as f(y) exp(i(kx − ωt)). The linearised
Euler equations (adiabatic index γ) are the eigenvalue problem

    ω ρ1 = −i (ρ0′ v_y + ρ0 (ik v_x + v_y′))
    ω v_x = (k/ρ0) P1
    ω v_y = −i (P1′ + g ρ1)/ρ0
    ω P1  = −i (P0′ v_y + γ P0 (ik v_x + v_y′))

discretised on a staggered grid (ρ1, v_x, P1 at n cell centres, v_y at the n − 1 inner faces;
second order), solved densely with numpy. The growth rate is the largest Im ω. It is checked
against the sharp-interface limit σ = √(A g k) (A the Atwood number) in the tests, and for
convergence in n here (the rate at n/2 is printed too).

Profiles (the papers' set-ups):
  rosswog  Rosswog (2015) §7.7.2: ρ = 2 − 1/(1 + exp(y/Δ)) (2 above y = 0, 1 below), g = 0.5,
           P(0) = 1, γ = 5/3, walls at y = ±0.8 (the frozen layers), k = 8π; Δ by --width.
  abel     Abel (2011) §3.5: ρ = 1 + 1/(1 + exp(−2(y − ½)/0.05)) (2 above, 1 below), g = 0.5,
           P(½) = 10/7, γ = 1.4, walls at y = 0.1, 0.9, k = 8π.
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np


def profile(name: str, width: float | None = None) -> dict:
    """ρ0 as a function of y, g, γ, the pressure at the reference height, walls, k."""
    if name == "rosswog":
        d = width or 0.0142
        return dict(rho=lambda y: 2.0 - 1.0 / (1.0 + np.exp(y / d)), g=0.5, gamma=5 / 3,
                    y_ref=0.0, p_ref=1.0, walls=(-0.8, 0.8), k=8 * np.pi)
    if name == "abel":
        return dict(rho=lambda y: 1.0 + 1.0 / (1.0 + np.exp(-2 * (y - 0.5) / 0.05)), g=0.5, gamma=1.4,
                    y_ref=0.5, p_ref=10 / 7, walls=(0.1, 0.9), k=8 * np.pi)
    raise ValueError(f"unknown profile {name!r}")


def hydrostatic_pressure(rho, y: np.ndarray, g: float, y_ref: float, p_ref: float) -> np.ndarray:
    """P0(y) = p_ref − g ∫_{y_ref}^{y} ρ0 dy′ (trapezoidal on a fine grid through y_ref)."""
    fine = np.linspace(min(y.min(), y_ref), max(y.max(), y_ref), 20001)
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (rho(fine[1:]) + rho(fine[:-1])) * np.diff(fine))])
    at_ref = np.interp(y_ref, fine, cum)
    return p_ref - g * (np.interp(y, fine, cum) - at_ref)


def growth_rate(pr: dict, n: int = 800, k: float | None = None) -> float:
    """The largest Im ω of the staggered second-order discretisation on n cells."""
    y0, y1 = pr["walls"]
    dy = (y1 - y0) / n
    yc = y0 + (np.arange(n) + 0.5) * dy  # centres: ρ1, v_x, P1
    yf = y0 + (np.arange(1, n)) * dy  # inner faces: v_y (zero on the walls)
    g, gam = pr["g"], pr["gamma"]
    kk = k if k is not None else pr["k"]
    rho_c, rho_f = pr["rho"](yc), pr["rho"](yf)
    p_c = hydrostatic_pressure(pr["rho"], yc, g, pr["y_ref"], pr["p_ref"])
    drho_c = (pr["rho"](yc + 1e-6) - pr["rho"](yc - 1e-6)) / 2e-6
    dp_c = -g * rho_c
    m = n - 1
    # face → centre: d/dy (v_y) and the average; centre → face: d/dy (P1) and the average
    dfc = np.zeros((n, m))
    afc = np.zeros((n, m))
    for j in range(n):
        if j < m:
            dfc[j, j] += 1 / dy
            afc[j, j] += 0.5
        if j > 0:
            dfc[j, j - 1] -= 1 / dy
            afc[j, j - 1] += 0.5
    dcf = np.zeros((m, n))
    acf = np.zeros((m, n))
    for j in range(m):
        dcf[j, j], dcf[j, j + 1] = -1 / dy, 1 / dy
        acf[j, j], acf[j, j + 1] = 0.5, 0.5
    z = lambda a, b: np.zeros((a, b))  # noqa: E731
    dg = np.diag
    # unknowns: ρ1 (n), v_x (n), P1 (n), v_y (m)
    rows = [
        [z(n, n), -1j * dg(rho_c) * 1j * kk, z(n, n), -1j * (dg(drho_c) @ afc + dg(rho_c) @ dfc)],
        [z(n, n), z(n, n), dg(kk / rho_c), z(n, m)],
        [z(n, n), -1j * gam * dg(p_c) * 1j * kk, z(n, n), -1j * (dg(dp_c) @ afc + gam * dg(p_c) @ dfc)],
        [-1j * g * dg(1 / rho_f) @ acf, z(m, n), -1j * dg(1 / rho_f) @ dcf, z(m, m)],
    ]
    a = np.block(rows)
    w = np.linalg.eigvals(a)
    return float(np.max(w.imag))


def sharp_interface_rate(g: float, k: float, r_top: float, r_bottom: float) -> float:
    """σ = √(A g k), A = (ρ_top − ρ_bottom)/(ρ_top + ρ_bottom): incompressible, deep layers."""
    return math.sqrt((r_top - r_bottom) / (r_top + r_bottom) * g * k)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--profile", choices=["rosswog", "abel"], required=True)
    ap.add_argument("--n", type=int, default=800, help="cells between the walls")
    ap.add_argument("--width", type=float, default=None, help="Fermi width Δ (rosswog profile)")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    pr = profile(a.profile, a.width)
    s, s_half = growth_rate(pr, a.n), growth_rate(pr, a.n // 2)
    if a.json:
        print(json.dumps({"profile": a.profile, "n": a.n, "growth_rate": s, "growth_rate_half_n": s_half}))
    else:
        print(f"{a.profile}: growth rate σ = {s:.5f} (n = {a.n}); {s_half:.5f} at n = {a.n // 2}; "
              f"sharp-interface √(Agk) = {sharp_interface_rate(pr['g'], pr['k'], 2.0, 1.0):.5f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

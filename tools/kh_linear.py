#!/usr/bin/env python3
"""Linear growth rate of the Kelvin–Helmholtz instability of a smooth, periodic shear flow.

    python tools/kh_linear.py --profile mcnally [--n 256] [--k 12.566]

The reference the KH claims of the verification suite are measured against in their linear
phase. A compressible, inviscid, isobaric background ρ0(y), U(y) (periodic in y, P0 uniform,
adiabatic index γ) is perturbed as f(y) exp(i(kx − ωt)). The linearised Euler equations for
(v_x, v_y, P1) are the eigenvalue problem

    ω v_x = k U v_x − i U′ v_y + (k/ρ0) P1
    ω v_y = k U v_y − (i/ρ0) P1′
    ω P1  = k U P1 + γ P0 k v_x − i γ P0 v_y′

(ρ1 decouples). y-derivatives are Fourier spectral on n points, so the dense 3n × 3n problem is
solved directly (numpy); the growth rate is the largest Im ω. The answer is checked for
convergence in n (the rate at n/2 is printed too) and, in the tests, against the vortex-sheet
limit σ = k |ΔU| √(ρ1ρ2)/(ρ1 + ρ2) for a thin layer at high sound speed.

Profiles (the papers' set-ups):
  mcnally   McNally, Lyra & Passy (2012), the CRKSPH paper's §4.4.3: ρ 1 / 2, U ±0.5, Δ = 0.025,
            P0 = 2.5, γ = 5/3, λ = 1/2.
  robertson Abel (2011) §3.4 (Robertson et al. 2010 ramp): ρ 2 (middle) / 1, U +0.5 / −0.5,
            Δ_y = 0.05, P0 = 3/5, γ = 5/3, λ = 1.
  rosswog   Rosswog (2015) §7.7.1: Fermi steps at y = 0.25, 0.75, ρ 2 (middle) / 1, U ±0.5,
            P0 = 2.5, γ = 5/3, λ = 1, width `--width` (the sum of the two lattices' sphere radii).
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np


def fourier_derivative(n: int) -> np.ndarray:
    """The spectral first-derivative matrix on n equispaced points of a unit period (n even)."""
    h = 2 * np.pi / n
    col = np.zeros(n)
    j = np.arange(1, n)
    col[1:] = 0.5 * (-1.0) ** j / np.tan(j * h / 2)
    mat = np.array([np.roll(col, i) for i in range(n)]).T
    return 2 * np.pi * mat  # d/dy on [0, 1): the unit period is 2π/(2π)


def profile(name: str, y: np.ndarray, width: float | None = None) -> dict:
    """ρ0, U, U′ at y and the case's P0, γ, wavenumber k."""
    if name == "mcnally":
        r1, r2, u1, u2, d = 1.0, 2.0, 0.5, -0.5, 0.025
        rm, um = (r1 - r2) / 2, (u1 - u2) / 2
        rho, u = np.empty_like(y), np.empty_like(y)
        du = np.empty_like(y)
        a = y < 0.25
        b = (y >= 0.25) & (y < 0.5)
        c = (y >= 0.5) & (y < 0.75)
        e = y >= 0.75
        rho[a], u[a], du[a] = r1 - rm * np.exp((y[a] - 0.25) / d), u1 - um * np.exp((y[a] - 0.25) / d), -um / d * np.exp((y[a] - 0.25) / d)
        rho[b], u[b], du[b] = r2 + rm * np.exp((0.25 - y[b]) / d), u2 + um * np.exp((0.25 - y[b]) / d), -um / d * np.exp((0.25 - y[b]) / d)
        rho[c], u[c], du[c] = r2 + rm * np.exp((y[c] - 0.75) / d), u2 + um * np.exp((y[c] - 0.75) / d), um / d * np.exp((y[c] - 0.75) / d)
        rho[e], u[e], du[e] = r1 - rm * np.exp((0.75 - y[e]) / d), u1 - um * np.exp((0.75 - y[e]) / d), um / d * np.exp((0.75 - y[e]) / d)
        return dict(rho=rho, u=u, du=du, p0=2.5, gamma=5 / 3, k=4 * np.pi)
    if name == "robertson":
        d = 0.05
        ramp = 1 / (1 + np.exp(2 * (0.25 - y) / d)) / (1 + np.exp(2 * (y - 0.75) / d))
        dr1 = (2 / d) * np.exp(2 * (0.25 - y) / d) / (1 + np.exp(2 * (0.25 - y) / d)) ** 2 / (1 + np.exp(2 * (y - 0.75) / d))
        dr2 = -(2 / d) * np.exp(2 * (y - 0.75) / d) / (1 + np.exp(2 * (y - 0.75) / d)) ** 2 / (1 + np.exp(2 * (0.25 - y) / d))
        return dict(rho=1 + ramp, u=-0.5 + ramp, du=dr1 + dr2, p0=0.6, gamma=5 / 3, k=2 * np.pi)
    if name == "rosswog":
        d = width or 0.01

        def fermi(a, b, yt):
            return (a - b) / (np.exp((y - yt) / d) + 1) + b

        def dfermi(a, b, yt):
            e = np.exp((y - yt) / d)
            return -(a - b) * e / (d * (e + 1) ** 2)

        rho = fermi(1.0, 2.0, 0.25) + fermi(2.0, 1.0, 0.75) - 2.0
        u = fermi(-0.5, 0.5, 0.25) + fermi(0.5, -0.5, 0.75) - 0.5
        du = dfermi(-0.5, 0.5, 0.25) + dfermi(0.5, -0.5, 0.75)
        return dict(rho=rho, u=u, du=du, p0=2.5, gamma=5 / 3, k=2 * np.pi)
    raise ValueError(f"unknown profile {name!r}")


def growth_rate(prof_name: str, n: int = 256, k: float | None = None, width: float | None = None,
                custom: dict | None = None) -> float:
    """The largest Im ω of the linearised problem on n points (custom: ρ, U, U′ callables of y
    and p0, gamma, k, for tests)."""
    y = np.arange(n) / n
    if custom:
        pr = dict(rho=custom["rho"](y), u=custom["u"](y), du=custom["du"](y), p0=custom["p0"], gamma=custom["gamma"], k=custom["k"])
    else:
        pr = profile(prof_name, y, width)
    kk = k if k is not None else pr["k"]
    dmat = fourier_derivative(n)
    rho, u, du = pr["rho"], pr["u"], pr["du"]
    g_p0 = pr["gamma"] * pr["p0"]
    z = np.zeros((n, n))
    eye = np.eye(n)
    a = np.block(
        [
            [kk * np.diag(u), -1j * np.diag(du), kk * np.diag(1 / rho)],
            [z, kk * np.diag(u), -1j * np.diag(1 / rho) @ dmat],
            [g_p0 * kk * eye, -1j * g_p0 * dmat, kk * np.diag(u)],
        ]
    )
    w = np.linalg.eigvals(a)
    return float(np.max(w.imag))


def vortex_sheet_rate(k: float, du: float, r1: float, r2: float) -> float:
    """Incompressible vortex sheet: σ = k |ΔU| √(ρ1ρ2)/(ρ1 + ρ2)."""
    return k * abs(du) * math.sqrt(r1 * r2) / (r1 + r2)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--profile", choices=["mcnally", "robertson", "rosswog"], required=True)
    ap.add_argument("--n", type=int, default=256, help="collocation points in y (even)")
    ap.add_argument("--k", type=float, default=None, help="wavenumber (default: the set-up's)")
    ap.add_argument("--width", type=float, default=None, help="Fermi width (rosswog profile)")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    s = growth_rate(a.profile, a.n, a.k, a.width)
    s_half = growth_rate(a.profile, a.n // 2, a.k, a.width)
    if a.json:
        print(json.dumps({"profile": a.profile, "n": a.n, "growth_rate": s, "growth_rate_half_n": s_half}))
    else:
        print(f"{a.profile}: growth rate σ = {s:.6f} (n = {a.n}); {s_half:.6f} at n = {a.n // 2}; e-folding time {1 / s:.4f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

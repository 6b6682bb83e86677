"""Figures the verification suite reads from a finished run (tools/verify.py).

A metric is either a dotted key of the run's summary.json (``radial.post_shock_density``,
``shock_tube.l1_density``, ``vortex_l1``, ``wall_seconds``) or one of the functions below,
registered by name. Each takes the run (its directory, summary and case) and the claim's
``metric_args`` and returns one float. The functions read the last CSV snapshot
(``output.formats`` must hold "csv"; the suite sets it) and diagnostics.csv.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

METRICS = {}


def metric(fn):
    METRICS[fn.__name__] = fn
    return fn


def last_snapshot(run_dir: Path) -> dict[str, np.ndarray]:
    """The last snapshot_*.csv as columns named without their units (x, vx, rho, P, cs ...)."""
    files = sorted(run_dir.glob("snapshot_*.csv"))
    if not files:
        raise ValueError(f"{run_dir}: no CSV snapshot (the suite sets output.formats)")
    with open(files[-1]) as f:
        rows = list(csv.reader(f))
    names = [h.split(" [")[0] for h in rows[0]]
    data = np.array(rows[1:], dtype=float)
    return {n: data[:, i] for i, n in enumerate(names)}


def read_csv(path: Path) -> dict[str, np.ndarray]:
    with open(path) as f:
        rows = list(csv.reader(f))
    names = [h.split(" [")[0] for h in rows[0]]
    data = np.array(rows[1:], dtype=float).reshape(len(rows) - 1, len(names))
    return {n: data[:, i] for i, n in enumerate(names)}


def snapshots(run_dir: Path) -> list[tuple[float, Path]]:
    """(time, CSV path) of every snapshot, times from snapshots.csv (the run's index of its
    snapshots: number and time)."""
    index = read_csv(run_dir / "snapshots.csv")
    out = [(float(t), run_dir / f"snapshot_{int(i):05d}.csv") for i, t in zip(index["snapshot"], index["time"])]
    out = [(t, p) for t, p in out if p.exists()]
    if not out:
        raise ValueError(f"{run_dir}: no CSV snapshot listed in snapshots.csv")
    return out


def series(run_dir: Path, fn) -> tuple[np.ndarray, np.ndarray]:
    """fn(snapshot columns) at every snapshot: (times, values)."""
    snaps = snapshots(run_dir)
    return np.array([t for t, _ in snaps]), np.array([fn(read_csv(p)) for _, p in snaps])


def diagnostics(run_dir: Path) -> dict[str, np.ndarray]:
    with open(run_dir / "diagnostics.csv") as f:
        rows = list(csv.reader(f))
    names = [h.split(" [")[0] for h in rows[0]]
    data = np.array(rows[1:], dtype=float)
    return {n: data[:, i] for i, n in enumerate(names)}


def summary_value(summary: dict, key: str) -> float:
    v = summary
    for part in key.split("."):
        if not isinstance(v, dict) or part not in v:
            raise KeyError(f"summary.json has no {key!r}")
        v = v[part]
    if v is None:
        raise KeyError(f"summary.json's {key!r} is empty for this run")
    return float(v)


@metric
def energy_change(run, args) -> float:
    """|E(t_end) − E(0)| / |E(0)| of kinetic + internal (+ potential) energy."""
    e0 = run.summary["initial"]["total_energy"]
    e1 = run.summary["last"]["total_energy"]
    return abs(e1 - e0) / abs(e0)


@metric
def angular_momentum_change(run, args) -> float:
    """|L_z(t_end) − L_z(0)| / |L_z(0)| from diagnostics.csv (2D: L about the origin)."""
    d = diagnostics(run.dir)
    lz = d["Lz"]
    return abs(lz[-1] - lz[0]) / abs(lz[0])


@metric
def transverse_velocity_ratio(run, args) -> float:
    """max(|v_y|, |v_z|) / max |v_x| over the particles (CRKSPH claim 15, planar 3D Sod)."""
    s = last_snapshot(run.dir)
    vt = np.maximum(np.abs(s["vy"]), np.abs(s["vz"])).max()
    return float(vt / np.abs(s["vx"]).max())


@metric
def displacement(run, args) -> float:
    """How far the particles moved from the first snapshot to the last, matched by id, in
    lattice spacings (``spacing``): the ``stat`` ("mean", default, or "max") of |x(t_end) − x(0)|
    with the minimum image over a periodic box of side ``period`` (the hydrostatic square:
    Rosswog §7.3 reads the mean, CRKSPH §4.2 "square preserved", the largest)."""
    snaps = snapshots(run.dir)
    if len(snaps) < 2 or snaps[-1][0] <= snaps[0][0]:
        raise ValueError("needs a snapshot at t = 0 and a later one")
    a, b = read_csv(snaps[0][1]), read_csv(snaps[-1][1])
    ia, ib = np.argsort(a["id"]), np.argsort(b["id"])
    if not np.array_equal(a["id"][ia], b["id"][ib]):
        raise ValueError("the particles of the first and last snapshot differ")
    d2 = np.zeros(len(ia))
    for axis in ("x", "y", "z")[: run.summary["dimension"]]:
        d = b[axis][ib] - a[axis][ia]
        if "period" in args:
            d -= args["period"] * np.round(d / args["period"])
        d2 += d * d
    moved = np.sqrt(d2) / args["spacing"]
    return float(moved.max() if args.get("stat") == "max" else moved.mean())


@metric
def mean_speed_over_sound(run, args) -> float:
    """⟨|v|⟩/c_s over the particles inside ``box`` = [lo, hi] on every axis (the noise box's
    moving particles, Rosswog §8.3)."""
    s = last_snapshot(run.dir)
    lo, hi = args["box"]
    inside = np.ones(len(s["x"]), dtype=bool)
    for axis in ("x", "y", "z")[: run.summary["dimension"]]:
        inside &= (s[axis] > lo) & (s[axis] < hi)
    speed = np.sqrt(s["vx"] ** 2 + s["vy"] ** 2 + s["vz"] ** 2)
    return float(np.mean(speed[inside] / s["cs"][inside]))


@metric
def vortex_peak(run, args) -> float:
    """The Gresho vortex's peak azimuthal velocity: the largest mean v_φ over rings of width
    ``bin`` about ``center`` (CRKSPH claim 10: ≈ 1 at r = 0.2)."""
    s = last_snapshot(run.dir)
    cx, cy = args.get("center", [0.5, 0.5])
    dx, dy = s["x"] - cx, s["y"] - cy
    r = np.hypot(dx, dy)
    vphi = (dx * s["vy"] - dy * s["vx"]) / np.where(r > 0, r, 1.0)
    width = args.get("bin", 0.02)
    k = (r / width).astype(int)
    means = [vphi[k == i].mean() for i in range(int(0.5 / width)) if np.any(k == i)]
    return float(max(means))


@metric
def plateau_ratio(run, args) -> float:
    """Mean density of the particles in the middle half of [x_from, x_to] (a post-shock
    plateau between the contact and the shock) over the exact plateau ``rho``."""
    s = last_snapshot(run.dir)
    a, b = args["x_from"], args["x_to"]
    lo, hi = a + 0.25 * (b - a), a + 0.75 * (b - a)
    sel = (s["x"] > lo) & (s["x"] < hi)
    return float(s["rho"][sel].mean() / args["rho"])


@metric
def contact_pressure_blip(run, args) -> float:
    """max |P − P*|/P* over the particles within ``width`` of the contact at ``x`` (the
    pressure blip of a shock tube's contact discontinuity; rpSPH claim 10)."""
    s = last_snapshot(run.dir)
    sel = np.abs(s["x"] - args["x"]) < args["width"]
    return float(np.abs(s["P"][sel] - args["p_star"]).max() / args["p_star"])


@metric
def kernel_density_error(run, args) -> float:
    """Q1 = ε_ρ of kernel ``kernel`` on the hexagonal lattice, from `sphfmu kernels`."""
    return run.kernel_table[args["kernel"]]["Q1 = ε_ρ"]


@metric
def kernel_gradient_error(run, args) -> float:
    return run.kernel_table[args["kernel"]]["∇x error"]


@metric
def kernel_density_error_curve(run, args) -> float:
    """The geometric mean of ε_ρ of kernel ``kernel`` over the η of `sphfmu kernels --eta-scan`
    from ``eta_from`` to ``eta_to``. A ratio of two such means is the mean vertical distance
    between two curves of Rosswog (2015) Fig. 4 on its log axis; a mean, not one η, since the
    curves dip to zero where the error changes sign."""
    lo, hi = args["eta_from"] - 1e-9, args["eta_to"] + 1e-9
    errs = [row[args["kernel"]] for eta, row in run.kernel_table.items() if lo <= float(eta) <= hi]
    if not errs:
        raise ValueError(f"no η in [{args['eta_from']}, {args['eta_to']}] in the scan")
    return math.exp(sum(math.log(e) for e in errs) / len(errs))


def parse_kernel_table(text: str) -> dict[str, dict[str, float]]:
    lines = [l for l in text.splitlines() if l.startswith("|")]
    head = [c.strip() for c in lines[0].strip("|").split("|")]
    table = {}
    for l in lines[2:]:
        cells = [c.strip() for c in l.strip("|").split("|")]
        row = {}
        for h, c in zip(head[1:], cells[1:]):
            try:
                row[h] = float(c)
            except ValueError:
                row[h] = math.nan
        table[cells[0]] = row
    return table


@metric
def shock_radius_ratio(run, args) -> float:
    """Shock radius over the exact one (Sedov, Noh): 1 is right, above 1 overshoots."""
    r = run.summary["radial"]
    return r["shock_radius"] / r["shock_radius_exact"]


@metric
def peak_density_ratio(run, args) -> float:
    """Peak of the binned radial density over ``rho0`` (a Sedov shock's compression; the
    strong-shock limit is (γ+1)/(γ−1) = 4 for γ = 5/3)."""
    return run.summary["radial"]["peak_density"] / args.get("rho0", 1.0)


@metric
def post_shock_density_ratio(run, args) -> float:
    """Post-shock density (mean over 0.3–0.8 r_s) over the exact one."""
    r = run.summary["radial"]
    return r["post_shock_density"] / r["post_shock_density_exact"]


@metric
def kinetic_energy_lost(run, args) -> float:
    """1 − E_K(t_end)/E_K(0): the fraction of the kinetic energy a steady flow lost (Abel's
    shear flow, 1 − F of his eq. 8)."""
    return 1.0 - run.summary["last"]["kinetic_energy"] / run.summary["initial"]["kinetic_energy"]


def shear_fit(s: dict[str, np.ndarray]) -> tuple[float, np.ndarray]:
    """Least-squares fit of v_x = a cos 2πy + b sin 2πy + c: (amplitude, residuals)."""
    y, vx = s["y"], s["vx"]
    basis = np.stack([np.cos(2 * np.pi * y), np.sin(2 * np.pi * y), np.ones_like(y)], 1)
    coef, *_ = np.linalg.lstsq(basis, vx, rcond=None)
    return float(np.hypot(coef[0], coef[1])), vx - basis @ coef


@metric
def shear_profile_deviation(run, args) -> float:
    """RMS departure of v_x(y) from its best-fitting cosine, over the cosine's amplitude, at
    t_end. A Newtonian viscosity keeps the cosine (it only decays: Abel's eq. 7), so this
    measures how non-Newtonian the scheme's dissipation is (Abel's Fig. A1: flat tops)."""
    amp, res = shear_fit(last_snapshot(run.dir))
    return float(np.sqrt(np.mean(res**2)) / amp)


@metric
def vy_rms(run, args) -> float:
    """sqrt(⟨v_y²⟩) over all particles at t_end (Rosswog Eq. 111; zero in the exact flow of a
    steady shear)."""
    s = last_snapshot(run.dir)
    return float(np.sqrt(np.mean(s["vy"] ** 2)))


def binned(x: np.ndarray, q: np.ndarray, lo: float, hi: float, width: float) -> tuple[np.ndarray, np.ndarray]:
    """(bin centres, mean of q per bin) over [lo, hi] in bins of `width` (NaN where empty)."""
    edges = np.arange(lo, hi + 0.5 * width, width)
    k = np.digitize(x, edges) - 1
    means = np.array([q[k == i].mean() if np.any(k == i) else np.nan for i in range(len(edges) - 1)])
    return 0.5 * (edges[1:] + edges[:-1]), means


@metric
def planar_shock_position_error(run, args) -> float:
    """|y_s − y_exact| / y_exact for a planar shock moving up `axis` from a wall at 0: y_s is the
    highest bin (width `bin`) whose mean density is at least `rho_mid` (midway between the pre-
    and post-shock densities). The shearing Noh problem (CRKSPH §4.4.5): y_exact = t/3."""
    s = last_snapshot(run.dir)
    centres, rho = binned(s[args.get("axis", "y")], s["rho"], 0.0, args["length"], args["bin"])
    behind = np.where(rho >= args["rho_mid"])[0]
    if len(behind) == 0:
        raise ValueError("no post-shock gas found")
    return float(abs(centres[behind.max()] - args["exact"]) / args["exact"])


def mcnally_mode(s: dict[str, np.ndarray], k: float = 4 * np.pi) -> float:
    """The y-velocity mode amplitude of McNally, Lyra & Passy (2012) eqs 10–13 (their λ = ½,
    k = 4π; another wavenumber with `k`): sums over particles with y′ = y below ½ and 1 − y
    above, weights d_i = h_i² (the CRKSPH paper's reading for particles)."""
    y = np.where(s["y"] < 0.5, s["y"], 1.0 - s["y"])
    w = s["h"] ** 2 * np.exp(-k * np.abs(y - 0.25))
    sn = np.sum(s["vy"] * w * np.sin(k * s["x"]))
    cs = np.sum(s["vy"] * w * np.cos(k * s["x"]))
    d = np.sum(w)
    return float(2 * np.hypot(sn / d, cs / d))


def band_mode(s: dict[str, np.ndarray], k: float, y0: float, band: float) -> float:
    """The amplitude of the v_y mode exp(ikx) over the particles within ``band`` of y = y0 (an
    RT interface): 2|Σ v_y e^{ikx}| / N."""
    sel = np.abs(s["y"] - y0) < band
    return float(2 * abs(np.sum(s["vy"][sel] * np.exp(1j * k * s["x"][sel]))) / max(sel.sum(), 1))


def instability_mode(args: dict):
    """The amplitude a KH or RT claim measures: "mcnally" (McNally's eqs 10–13 at wavenumber
    ``k``, default 4π), "vy_rms" (Rosswog eq. 111) or "band" (the exp(ikx) mode of v_y within
    ``band`` of ``y0``)."""
    if args["mode"] == "mcnally":
        k = args.get("k", 4 * np.pi)
        return lambda s: mcnally_mode(s, k)
    if args["mode"] == "vy_rms":
        return lambda s: float(np.sqrt(np.mean(s["vy"] ** 2)))
    if args["mode"] == "band":
        return lambda s: band_mode(s, args["k"], args["y0"], args["band"])
    raise ValueError(f"unknown mode {args['mode']!r}")


def growth_fit(t: np.ndarray, a: np.ndarray, window: tuple[float, float]) -> float:
    """Least-squares slope of ln a(t) over t in [t0, t1]: the exponential growth rate."""
    sel = (t >= window[0]) & (t <= window[1]) & (a > 0)
    if sel.sum() < 3:
        raise ValueError(f"fewer than 3 snapshots in the fit window {window}")
    return float(np.polyfit(t[sel], np.log(a[sel]), 1)[0])


@metric
def growth_rate_ratio(run, args) -> float:
    """The fitted exponential growth rate of an instability's amplitude (``mode``, see
    `instability_mode`) over ``window``, divided by the linear-theory rate ``sigma``
    (tools/kh_linear.py, tools/rt_linear.py)."""
    t, a = series(run.dir, instability_mode(args))
    return growth_fit(t, a, tuple(args["window"])) / args["sigma"]


@metric
def growth_factor(run, args) -> float:
    """The amplitude at t_end over the amplitude at t = 0 (``mode`` as `growth_rate_ratio`):
    above 1 the seed grew, below 1 it was damped or only oscillated."""
    t, a = series(run.dir, instability_mode(args))
    return float(a[-1] / a[0])


def yee_exact(x: np.ndarray, y: np.ndarray, gamma: float = 1.4, beta: float = 5.0):
    """The Yee vortex (steady): ρ, v_x, v_y at the positions (free stream ρ = P = T = 1, at rest)."""
    r2 = x * x + y * y
    t = 1 - (gamma - 1) * beta**2 / (8 * gamma * np.pi**2) * np.exp(1 - r2)
    f = beta / (2 * np.pi) * np.exp((1 - r2) / 2)
    return t ** (1 / (gamma - 1)), -f * y, f * x


@metric
def yee_error(run, args) -> float:
    """The ``norm`` (L1, L2 or Linf) of ``quantity`` (rho, or v: |v − v_exact|) over the
    particles inside r < ``r_max`` (the frozen rings beyond are left out) at t_end, against the
    initial (steady) state (CRKSPH §4.4.2)."""
    s = last_snapshot(run.dir)
    rho, vx, vy = yee_exact(s["x"], s["y"])
    inside = s["x"] ** 2 + s["y"] ** 2 < args.get("r_max", 5.0) ** 2
    err = {"rho": np.abs(s["rho"] - rho), "v": np.hypot(s["vx"] - vx, s["vy"] - vy)}[args["quantity"]][inside]
    return float({"L1": np.mean(err), "L2": np.sqrt(np.mean(err**2)), "Linf": np.max(err)}[args.get("norm", "L1")])


@metric
def pairing_fraction(run, args) -> float:
    """The fraction of particles (inside ``y_range``) whose nearest neighbour is closer than
    ``fraction`` (default ½) of their own spacing √(m/ρ) (2D): particles pairing or clumping
    (Abel 2011 §3.2, §4.1). A lattice or a glass has none."""
    from scipy.spatial import cKDTree

    s = last_snapshot(run.dir)
    lo, hi = args.get("y_range", [-np.inf, np.inf])
    sel = (s["y"] > lo) & (s["y"] < hi)
    box = args.get("period_x")  # a periodic x side: the tree wraps it
    x = np.mod(s["x"], box) if box else s["x"]
    pts = np.stack([x, s["y"] - s["y"].min()], 1)
    tree = cKDTree(pts, boxsize=[box, 1e9] if box else None)
    d, _ = tree.query(pts[sel], k=2)
    spacing = np.sqrt(s["m"][sel] / s["rho"][sel])
    return float(np.mean(d[:, 1] < args.get("fraction", 0.5) * spacing))


@metric
def stable_time(run, args) -> float:
    """The first time the total energy departs from its initial value by more than
    ``tolerance`` (default 5 %), or the last time reached: how long a run stays stable. Read
    from diagnostics.csv, so a run that stopped unstable has a figure too."""
    d = diagnostics(run.dir)
    e = d["total"]
    bad = np.where(np.abs(e - e[0]) > args.get("tolerance", 0.05) * abs(e[0]))[0]
    return float(d["time"][bad[0]] if len(bad) else d["time"][-1])


stable_time.on_failure = True


@metric
def vrms_over_sound(run, args) -> float:
    """sqrt(⟨|v|²⟩) over the mean sound speed at t_end (Abel's v_rms of a gas that should stay
    at rest, §3.1)."""
    s = last_snapshot(run.dir)
    return float(np.sqrt(np.mean(s["vx"] ** 2 + s["vy"] ** 2 + s["vz"] ** 2)) / np.mean(s["cs"]))


@metric
def rms_radius_change(run, args) -> float:
    """r_rms(t_end)/r_rms(0) − 1 about the origin: how far a blob that should stay still has
    spread."""
    snaps = sorted(run.dir.glob("snapshot_*.csv"))
    r = [np.sqrt(np.mean(s["x"] ** 2 + s["y"] ** 2 + s["z"] ** 2)) for s in (read_csv(snaps[0]), read_csv(snaps[-1]))]
    return float(r[1] / r[0] - 1)


@metric
def post_shock_peak_ratio(run, args) -> float:
    """The largest density between ``x_from`` and ``x_to`` (behind a shock, past its contact)
    over the exact post-shock density ``rho``: 1 is the exact jump, above 1 overshoots."""
    s = last_snapshot(run.dir)
    sel = (s["x"] > args["x_from"]) & (s["x"] < args["x_to"])
    return float(s["rho"][sel].max() / args["rho"])


def shock_radius_by_angle(s: dict[str, np.ndarray], bins: int = 180) -> tuple[np.ndarray, np.ndarray]:
    """(bin-centre angles, shock radius per angle bin about the origin): the radius of the
    densest particle in each bin."""
    r = np.hypot(s["x"], s["y"])
    phi = np.arctan2(s["y"], s["x"])
    k = ((phi + np.pi) / (2 * np.pi) * bins).astype(int) % bins
    rs = np.array([r[k == i][np.argmax(s["rho"][k == i])] for i in range(bins)])
    return (np.arange(bins) + 0.5) / bins * 2 * np.pi - np.pi, rs


def velocity_divergence(s: dict[str, np.ndarray]) -> np.ndarray:
    """∇·v at each particle of a 2D snapshot, from the linearly exact gradient
    (∇v)_a = [Σ_b V_b (v_b − v_a) ⊗ ∇W_ab] [Σ_b V_b (x_b − x_a) ⊗ ∇W_ab]⁻¹, the form of Rosswog
    (2015) Eq. 21 that his triggers read, with V_b = m_b/ρ_b and the M4 cubic spline at h_a
    (support 2h_a). It is exact for a linear velocity field whatever the particles' order, and it
    is computed here from the snapshot alone, so the maps of two schemes are measured alike."""
    from scipy.spatial import cKDTree

    x = np.stack([s["x"], s["y"]], 1)
    v = np.stack([s["vx"], s["vy"]], 1)
    h, vol, n = s["h"], s["m"] / s["rho"], len(s["x"])
    near = cKDTree(x).query_ball_point(x, 2.0 * h, return_sorted=False)
    a = np.repeat(np.arange(n), [len(l) for l in near])
    b = np.concatenate([np.asarray(l, dtype=np.int64) for l in near])
    a, b = a[a != b], b[a != b]
    dx, dv = x[b] - x[a], v[b] - v[a]
    r = np.linalg.norm(dx, axis=1)
    q = r / h[a]
    # dW/dr of the 2D M4 spline, W = 10/(7π h²) f(q); the sign cancels between the two sums
    df = np.where(q < 1.0, -3.0 * q + 2.25 * q * q, -0.75 * np.clip(2.0 - q, 0.0, None) ** 2)
    g = (10.0 / (7.0 * np.pi * h[a] ** 3) * df / np.maximum(r, 1e-300))[:, None] * dx
    w = vol[b]

    def summed(u):  # Σ_b V_b u ⊗ g per particle a, as (n, 2, 2)
        return np.stack([np.stack([np.bincount(a, w * u[:, i] * g[:, k], n) for k in range(2)], -1)
                         for i in range(2)], 1)

    grad = summed(dv) @ np.linalg.pinv(summed(dx))
    return grad[:, 0, 0] + grad[:, 1, 1]


@metric
def sixfold_imprint(run, args) -> float:
    """The amplitude of the sixfold harmonic of the shock radius r_s(φ) over its mean,
    2|Σ r_s e^{6iφ}| / Σ r_s: a hexagonal lattice's imprint on a blast wave (Rosswog §7.8.3)."""
    phi, rs = shock_radius_by_angle(last_snapshot(run.dir), args.get("bins", 180))
    return float(2 * abs(np.sum(rs * np.exp(6j * phi))) / np.sum(rs))


@metric
def bubble_vy_rms(run, args) -> float:
    """The r.m.s. transverse velocity v_y at t_end of the gas that started inside the circle
    ``center``, ``radius`` (the bubble of Rosswog's blast–bubble tests, §7.8.1–2): the rolling
    in ("curling") of the shocked bubble's lobes is transverse motion, which a more
    dissipative scheme damps."""
    first = read_csv(snapshots(run.dir)[0][1])
    cx, cy = args["center"]
    inside = (first["x"] - cx) ** 2 + (first["y"] - cy) ** 2 < args["radius"] ** 2
    s = last_snapshot(run.dir)
    mine = np.isin(s["id"], first["id"][inside])
    return float(np.sqrt(np.mean(s["vy"][mine] ** 2)))


@metric
def trigger_level(run, args) -> float:
    """A column of triggers.csv (Rosswog's dissipation triggers after each step: ``column``,
    e.g. "max K_noise1") reduced over time by ``stat``: "max", "first" or "last"."""
    d = read_csv(run.dir / "triggers.csv")
    c = d[args["column"]]
    return float({"max": c.max(), "first": c[0], "last": c[-1]}[args.get("stat", "max")])


@metric
def noh_l1_velocity(run, args) -> float:
    """L1 of the velocity against Noh's solution at t_end, over the particles within ``r_max``
    of ``center``: at rest behind the shock (r < t/3 in 2D and 3D), v = −r̂ ahead of it
    (unit inflow speed)."""
    s = last_snapshot(run.dir)
    t = run.summary["time"]
    c = args.get("center", [0.0, 0.0, 0.0])
    d = run.summary["dimension"]
    x = np.stack([s[a] - c[k] for k, a in enumerate("xyz"[:d])], 1)
    v = np.stack([s[a] for a in ("vx", "vy", "vz")[:d]], 1)
    r = np.linalg.norm(x, axis=1)
    inside = r < args.get("r_max", 0.5)
    exact = np.where((r > t / 3)[:, None], -x / np.where(r > 0, r, 1)[:, None], 0.0)
    return float(np.mean(np.linalg.norm(v - exact, axis=1)[inside]))


def cloud_mass(s: dict[str, np.ndarray], args: dict) -> float:
    """The mass of cloud-like gas: particles with ρ above ``rho_min`` and u below ``u_max``
    (Agertz et al. 2007: ρ > 0.64 ρ_cloud, T < 0.9 T_ambient)."""
    sel = (s["rho"] > args["rho_min"]) & (s["u"] < args["u_max"])
    return float(np.sum(s["m"][sel]))


def cloud_fraction_series(run_dir: Path, args: dict) -> tuple[np.ndarray, np.ndarray]:
    """(t, M(t)/M0), M0 the cloud-like mass at t = 0 (the cloud's smoothed edge is not)."""
    t, m = series(run_dir, lambda s: cloud_mass(s, args))
    return t, m / m[0]


@metric
def cloud_disruption_time(run, args) -> float:
    """The first time, in units of ``t_kh``, at which the cloud fraction falls below
    ``threshold`` (default 0.1); the run's end time if it never does (a lower bound)."""
    t, f = cloud_fraction_series(run.dir, args)
    below = np.where(f < args.get("threshold", 0.1))[0]
    return float((t[below[0]] if len(below) else t[-1]) / args["t_kh"])


def entropy_ratio(run, args) -> tuple[np.ndarray, np.ndarray]:
    """(x0, s/s_exact) at t_end of the particles that started between ``x_from`` and
    ``x_to`` (the evolved points, not a driven rind), with s = P/ρ^γ against ``s``."""
    snaps = snapshots(run.dir)
    first, last = read_csv(snaps[0][1]), read_csv(snaps[-1][1])
    x0 = dict(zip(first["id"].astype(int), first["x"]))
    ids = last["id"].astype(int)
    start = np.array([x0[i] for i in ids])
    sel = (start > args["x_from"]) & (start < args["x_to"])
    ratio = last["P"][sel] / last["rho"][sel] ** args["gamma"] / args["s"]
    order = np.argsort(start[sel])
    return start[sel][order], ratio[order]


@metric
def entropy_spread(run, args) -> float:
    """max − min of s/s_exact over the evolved points at t_end (Frontiere, Raskin & Owen 2017
    §4.0.1: the min-to-max entropy error of the Kidder implosion)."""
    _, ratio = entropy_ratio(run, args)
    return float(ratio.max() - ratio.min())


def riemann_shock(left: tuple, right: tuple) -> tuple[float, float]:
    """(p*, speed) of the right-moving shock of the Riemann problem of two ideal gases at rest with
    different γ, left (ρ, P, γ) at the higher pressure (Toro 2009 §4.2–4.3 with each side's
    own γ: f_L(p*) + f_R(p*) = 0, the left wave a rarefaction, the right a shock)."""
    (rl, pl, gl), (rr, pr, gr) = left, right
    cl = np.sqrt(gl * pl / rl)

    def f_left(p):  # rarefaction (p < pl)
        return 2 * cl / (gl - 1) * ((p / pl) ** ((gl - 1) / (2 * gl)) - 1)

    def f_right(p):  # shock (p > pr)
        a, b = 2 / ((gr + 1) * rr), (gr - 1) / (gr + 1) * pr
        return (p - pr) * np.sqrt(a / (p + b))

    lo, hi = pr, pl
    for _ in range(200):  # bisection: f_L + f_R rises with p from negative to positive
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f_left(mid) + f_right(mid) < 0 else (lo, mid)
    p_star = 0.5 * (lo + hi)
    cr = np.sqrt(gr * pr / rr)
    return p_star, float(cr * np.sqrt((gr + 1) / (2 * gr) * p_star / pr + (gr - 1) / (2 * gr)))


def snapshot_at(run_dir: Path, t: float) -> dict[str, np.ndarray]:
    """The snapshot nearest time t."""
    snaps = snapshots(run_dir)
    return read_csv(min(snaps, key=lambda s: abs(s[0] - t))[1])


@metric
def wall_shock_error(run, args) -> float:
    """The largest relative error of the two shock positions along the bottom and top walls
    at time ``t`` (each the largest x in the band ``band`` = [y_lo, y_hi] where the pressure
    exceeds the mean of the exact pre- and post-shock values) against the exact two-γ Riemann
    shocks of ``left`` into ``bottom`` and ``top`` ((ρ, P, γ) each) from ``x0``."""
    s = snapshot_at(run.dir, args["t"])
    worst = 0.0
    for side in ("bottom", "top"):
        y_lo, y_hi = args[f"{side}_band"]
        rho, p, g = args[side]
        p_star, speed = riemann_shock(tuple(args["left"]), (rho, p, g))
        exact = args["x0"] + speed * args["t"]
        beyond = (s["y"] > y_lo) & (s["y"] < y_hi) & (s["x"] > args["x0"])
        x_shock = s["x"][beyond & (s["P"] > 0.5 * (p + p_star))].max()
        worst = max(worst, abs(x_shock - exact) / (exact - args["x0"]))
    return float(worst)


@metric
def wall_heating(run, args) -> float:
    """The wall-heating excess of a reflection or collision at ``x`` (Rosswog §7.6.2): the
    largest u of the particles within ``width`` of x over the median u of the shocked plateau
    [plateau_from, plateau_to], minus 1 (0 without wall heating)."""
    s = last_snapshot(run.dir)
    u = s["u"]
    near = np.abs(s["x"] - args.get("x", 0.0)) < args["width"]
    plateau = (s["x"] > args["plateau_from"]) & (s["x"] < args["plateau_to"])
    return float(u[near].max() / np.median(u[plateau]) - 1.0)


def advected_pattern(name: str, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The computing-frame density N of Rosswog's advection tests (§7.5) in [-1, 1]² at rest:
    "sin-cos" (Advection II, Eq. 107) or "triangle" (Advection I: N = 1 inside the
    surface-tension triangle, 2 outside)."""
    if name == "sin-cos":
        return 1.0 + 0.5 * np.sin(np.pi * x) * np.cos(np.pi * y)
    if name == "triangle":
        s, t = np.sqrt(3.0) / 4.0, np.sqrt(3.0)
        inside = (y > -s) & (y < t * (x + 0.5) - s) & (y < -t * (x - 0.5) - s)
        return np.where(inside, 1.0, 2.0)
    raise ValueError(f"advected_pattern: no pattern {name!r}")


@metric
def advected_l1(run, args) -> float:
    """L1 of N at t_end against the initial pattern ``pattern`` moved exactly by v_x·t along x
    in the periodic box [-1, 1]² (Rosswog §7.5), over the mean exact N."""
    s = last_snapshot(run.dir)
    t = run.summary["time"]
    x = (s["x"] - args["vx"] * t + 1.0) % 2.0 - 1.0
    exact = advected_pattern(args["pattern"], x, s["y"])
    return float(np.mean(np.abs(s["rho"] - exact)) / np.mean(exact))

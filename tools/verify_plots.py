"""Figures of the verification suite that a claim draws from its own runs (tools/verify.py).

A claim names one with `plot = "<name>"` (and `plot_args`) in its `[claim.run]`; the function
gets the claim, its finished runs as (scheme label, resolution label, run, metric arguments),
and the PNG path to write. The runs' own profile.png (shock tubes, Sedov, Noh, Gresho) needs no
entry here: these are the tests the CLI has no exact-solution check for (growth curves,
profiles against a steady state, maps).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from verify_metrics import diagnostics, instability_mode, last_snapshot, series

PLOTS = {}


def plot(fn):
    PLOTS[fn.__name__] = fn
    return fn


def figure(ncols: int = 1, nrows: int = 1, size=(6.4, 4.2)):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(nrows, ncols, figsize=(size[0] * ncols, size[1] * nrows), squeeze=False)
    return plt, fig, axes.ravel()


def finish(plt, fig, claim: dict, png: Path, caption: str) -> None:
    fig.suptitle(f"{claim['id']}: {caption}", fontsize=9)
    fig.text(0.01, 0.005, "python tools/verify.py --only " + claim["id"], fontsize=6, color="grey")
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)


def first_judge(claim: dict) -> dict:
    """The claim's `[claim.judge]` table, or the first of its `[[claim.judge]]` ({} if none)."""
    j = claim.get("judge", [])
    return j if isinstance(j, dict) else (j or [{}])[0]


def claim_scheme(claim: dict) -> str | None:
    """The scheme (or variant) the claim's first judge reads."""
    j = first_judge(claim)
    return j.get("scheme") or (j.get("schemes") or [None])[0]


def finest(runs: list) -> dict[str, tuple]:
    """Each scheme's last run (the finest resolution): {label: (resolution, run, args)}."""
    out = {}
    for scheme, res, run, args in runs:
        out[scheme] = (res, run, args)
    return out


def styles(runs: list) -> tuple[dict, dict]:
    """A colour per scheme and a line style per resolution, so curves of many runs stay apart."""
    import matplotlib

    cmap = matplotlib.colormaps["tab10"]
    schemes = list(dict.fromkeys(s for s, _, _, _ in runs))
    resolutions = list(dict.fromkeys(r for _, r, _, _ in runs))
    dashes = ["-", "--", ":", "-."]
    return ({s: cmap(i % 10) for i, s in enumerate(schemes)},
            {r: dashes[i % len(dashes)] for i, r in enumerate(resolutions)})


@plot
def shear_flow(claim: dict, runs: list, png: Path) -> None:
    """Abel's shear flow: E_K(t)/E_K(0) per scheme (every resolution), and v_x against y at
    t_end binned in y (the finest resolution) against the initial cosine, which the inviscid
    flow keeps and a Newtonian viscosity only scales."""
    plt, fig, (ax_f, ax_v) = figure(2)
    colour, style = styles(runs)
    for scheme, res, run, _ in runs:
        d = diagnostics(run.dir)
        ax_f.plot(d["time"], d["kinetic"] / d["kinetic"][0], color=colour[scheme], ls=style[res], lw=1,
                  label=f"{scheme} N={res}" if res else scheme)
    ax_f.set_xlabel("t (sound crossings)")
    ax_f.set_ylabel("F = E_K(t) / E_K(0)")
    ax_f.legend(fontsize=6)
    y_bins = np.linspace(0.0, 1.0, 51)
    centres = 0.5 * (y_bins[1:] + y_bins[:-1])
    for scheme, (res, run, _) in finest(runs).items():
        s = last_snapshot(run.dir)
        k = np.clip(np.digitize(s["y"], y_bins) - 1, 0, 49)
        ax_v.plot(centres, [s["vx"][k == i].mean() for i in range(50)], ".-", ms=3, lw=0.8, color=colour[scheme],
                  label=f"{scheme} N={res}" if res else scheme)
    yy = np.linspace(0, 1, 200)
    ax_v.plot(yy, 0.5 * np.cos(2 * np.pi * yy), "k--", lw=0.8, label="t = 0 (inviscid exact)")
    ax_v.set_xlabel("y")
    ax_v.set_ylabel("v_x at t_end, mean per bin of width 0.02")
    ax_v.legend(fontsize=6)
    finish(plt, fig, claim, png, "shear flow: kinetic energy kept, and the profile's shape at t_end")


@plot
def planar_noh(claim: dict, runs: list, png: Path) -> None:
    """ρ, P and u against y for every particle of each scheme (finest resolution), with the
    planar Noh solution: ρ = 4, P = 4/3, u = 1/2 behind the shock at y = t/3 (γ = 5/3, unit
    inflow speed), the cold inflow (ρ = 1) ahead of it."""
    args = claim["run"]["metric_args"]
    ys, length = args["exact"], args["length"]
    plt, fig, axes = figure(3, size=(4.6, 4.0))
    for scheme, (res, run, _) in finest(runs).items():
        s = last_snapshot(run.dir)
        for ax, q in zip(axes, ("rho", "P", "u")):
            ax.plot(s["y"], s[q], ".", ms=1.5, label=scheme)
    y = np.array([0.0, ys, ys, length])
    for ax, q, (behind, ahead), name in zip(
        axes, ("rho", "P", "u"), ((4.0, 1.0), (4.0 / 3.0, 0.0), (0.5, 0.0)), ("density", "pressure", "specific internal energy")
    ):
        ax.plot(y, [behind, behind, ahead, ahead], "k-", lw=1.2, label="exact (planar Noh)")
        ax.set_xlabel("y")
        ax.set_ylabel(name)
        ax.set_xlim(0, min(length, 3 * ys))
    axes[0].legend(fontsize=6, markerscale=4)
    finish(plt, fig, claim, png, "shearing Noh at t = 0.6: every particle against y")


def density_map(ax, s: dict, title: str, quantity: str = "rho") -> None:
    """The particles coloured by a field (a map at the particles' own positions)."""
    sc = ax.scatter(s["x"], s["y"], c=s[quantity], s=max(0.3, 2e4 / len(s["x"])), cmap="viridis", linewidths=0, rasterized=True)
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_title(title, fontsize=8)
    ax.figure.colorbar(sc, ax=ax, shrink=0.8, label=quantity)


def judged_density_map(ax, claim: dict, runs: list) -> None:
    """The density map at t_end of the scheme the claim's first judge reads (finest run)."""
    judged = claim_scheme(claim)
    best = finest(runs).get(judged)
    if best:
        density_map(ax, last_snapshot(best[1].dir), f"{judged}: density at t_end")


@plot
def mode_growth(claim: dict, runs: list, png: Path) -> None:
    """KH or RT: the mode amplitude against t per scheme and resolution (log axis), the linear-theory
    growth e^{σt} through the judged scheme's amplitude at the fit window's start, and the
    density of the judged scheme's finest run at t_end."""
    args = claim["run"]["metric_args"]
    mode = instability_mode(args)
    plt, fig, (ax_a, ax_m) = figure(2, size=(6.4, 5.0))
    colour, style = styles(runs)
    judged = claim_scheme(claim)
    anchor = None
    for scheme, res, run, _ in runs:
        t, a = series(run.dir, mode)
        ax_a.semilogy(t, a, color=colour[scheme], ls=style[res], lw=1, label=f"{scheme} N={res}" if res else scheme)
        if scheme == judged:
            anchor = (t, a)
    t0, t1 = args["window"]
    if anchor is not None:
        t, a = anchor
        a0 = float(np.interp(t0, t, a))
        tt = np.linspace(t0, t[-1], 50)
        ax_a.semilogy(tt, a0 * np.exp(args["sigma"] * (tt - t0)), "k--", lw=1.2, label=f"linear theory σ = {args['sigma']:g}")
    ax_a.axvspan(t0, t1, color="0.9", zorder=0, label="fit window")
    ax_a.set_xlabel("t")
    ax_a.set_ylabel({"mcnally": "mode amplitude (McNally et al. eqs 10–13)", "vy_rms": "v_y,rms (Rosswog eq. 111)",
                     "band": f"v_y mode amplitude within {args.get('band')} of y = {args.get('y0')}"}[args["mode"]])
    ax_a.legend(fontsize=5, ncol=2)
    best = finest([r for r in runs if r[0] == judged]).get(judged)
    if best:
        density_map(ax_m, last_snapshot(best[1].dir), f"{judged} N={best[0]}: density at t_end")
    finish(plt, fig, claim, png, "instability growth against linear theory")


@plot
def yee_profile(claim: dict, runs: list, png: Path) -> None:
    """The Yee vortex at t_end: ρ and v_φ of every particle of the judged scheme's finest run
    against r, with the exact (initial, steady) profiles; and every scheme's errors against
    the ring count."""
    from verify_metrics import yee_exact

    plt, fig, axes = figure(3, size=(4.6, 4.0))
    judged = claim_scheme(claim)
    best = finest([r for r in runs if r[0] == judged]).get(judged)
    rr = np.linspace(0, 5, 400)
    rho_x, _, vy_x = yee_exact(rr, np.zeros_like(rr))
    if best:
        s = last_snapshot(best[1].dir)
        r = np.hypot(s["x"], s["y"])
        vphi = (s["x"] * s["vy"] - s["y"] * s["vx"]) / np.where(r > 0, r, 1)
        axes[0].plot(r, s["rho"], ".", ms=1, label=f"{judged} N_r={best[0]}")
        axes[1].plot(r, vphi, ".", ms=1, label=f"{judged} N_r={best[0]}")
    axes[0].plot(rr, rho_x, "k-", lw=1, label="exact")
    axes[1].plot(rr, vy_x, "k-", lw=1, label="exact")
    for ax, name in zip(axes[:2], ("density", "v_φ")):
        ax.set_xlabel("r")
        ax.set_ylabel(name)
        ax.set_xlim(0, 5)
        ax.legend(fontsize=6, markerscale=5)
    colour, _ = styles(runs)
    metric = claim["run"]["metric"]
    by_scheme: dict[str, list] = {}
    for scheme, res, run, args in runs:
        from verify_metrics import METRICS

        by_scheme.setdefault(scheme, []).append((float(res), METRICS[metric](run, args)))
    for scheme, pts in by_scheme.items():
        pts.sort()
        axes[2].loglog(*zip(*pts), "o-", color=colour[scheme], ms=3, lw=1, label=scheme)
    axes[2].set_xlabel("N_r (rings)")
    axes[2].set_ylabel(f"{metric} ({claim['run']['metric_args'].get('quantity')}, {claim['run']['metric_args'].get('norm', 'L1')})")
    axes[2].legend(fontsize=6)
    finish(plt, fig, claim, png, "Yee vortex at t = 8")


@plot
def maps(claim: dict, runs: list, png: Path) -> None:
    """Density maps at t_end of the schemes the claim names in ``plot_args.schemes`` (default:
    the judged ones), each at its finest resolution, side by side."""
    wanted = claim["run"].get("plot_args", {}).get("schemes")
    if not wanted:
        wanted = []
        for j in (claim["judge"] if isinstance(claim["judge"], list) else [claim["judge"]]):
            for s in [j.get("scheme")] + list(j.get("schemes", [])):
                if s and s not in wanted:
                    wanted.append(s)
    best = finest(runs)
    shown = [s for s in wanted if s in best]
    plt, fig, axes = figure(max(len(shown), 1), size=(4.2, 6.0))
    for ax, scheme in zip(axes, shown):
        res, run, _ = best[scheme]
        density_map(ax, last_snapshot(run.dir), f"{scheme}" + (f" N={res}" if res else "") + ": density at t_end")
    finish(plt, fig, claim, png, "density at t_end")


@plot
def shock_radius_angle(claim: dict, runs: list, png: Path) -> None:
    """A blast wave's shock radius against angle, minus its mean, per scheme (a sixfold ripple
    is the lattice's imprint), the judged scheme's density map, and ∇·v maps of the schemes the
    judge compares (Rosswog 2015 §7.8.3 shows ∇·v for its noise), on one colour scale."""
    from verify_metrics import shock_radius_by_angle, velocity_divergence

    plt, fig, (ax_r, ax_m, *ax_div) = figure(2, 2, size=(6.4, 4.6))
    colour, _ = styles(runs)
    for scheme, (res, run, _) in finest(runs).items():
        phi, rs = shock_radius_by_angle(last_snapshot(run.dir))
        ax_r.plot(np.degrees(phi), rs - rs.mean(), color=colour[scheme], lw=0.9, label=scheme)
    for a in range(-180, 181, 60):
        ax_r.axvline(a, color="0.85", lw=0.6, zorder=0)
    ax_r.set_xlabel("angle φ (degrees; grey: every 60°)")
    ax_r.set_ylabel("shock radius − its mean")
    ax_r.legend(fontsize=6)
    judged_density_map(ax_m, claim, runs)
    j = first_judge(claim)
    best = finest(runs)
    shown = [s for s in (j.get("schemes") or [j.get("scheme")]) if s in best][:2]
    snaps = {s: last_snapshot(best[s][1].dir) for s in shown}
    divs = {s: velocity_divergence(m) for s, m in snaps.items()}
    # the scale of the flow away from the shock (the shock's own ∇·v is far larger): the 90th
    # percentile of |∇·v| over both maps
    lim = float(np.percentile(np.abs(np.concatenate(list(divs.values()))), 90)) if divs else 1.0
    for ax, s in zip(ax_div, shown):
        m = snaps[s]
        sc = ax.scatter(m["x"], m["y"], c=divs[s], s=max(0.3, 2e4 / len(m["x"])), cmap="RdBu_r",
                        vmin=-lim, vmax=lim, linewidths=0, rasterized=True)
        ax.set_aspect("equal")
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        ax.set_title(f"{s}: ∇·v at t_end (linearly exact estimate from the snapshot)", fontsize=8)
        fig.colorbar(sc, ax=ax, shrink=0.8, label="∇·v")
    for ax in ax_div[len(shown):]:
        ax.set_visible(False)
    finish(plt, fig, claim, png, "blast in a box: the lattice's imprint on the shock")


@plot
def cost_accuracy(claim: dict, runs: list, png: Path) -> None:
    """The claim's error against each run's wall time, per scheme over its resolutions (log
    axes): schemes on one line cost the same for the same error."""
    from verify_metrics import METRICS

    plt, fig, (ax,) = figure(1)
    colour, _ = styles(runs)
    metric = claim["run"]["metric"]
    by_scheme: dict[str, list] = {}
    for scheme, res, run, args in runs:
        by_scheme.setdefault(scheme, []).append((run.seconds, METRICS[metric](run, args), res))
    for scheme, pts in by_scheme.items():
        pts.sort()
        ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", color=colour[scheme], ms=4, label=scheme)
        for t, e, res in pts:
            ax.annotate(str(res), (t, e), fontsize=6, xytext=(3, 3), textcoords="offset points")
    ax.set_xlabel("wall time of the run (s, one thread; labels: particles per dimension)")
    ax.set_ylabel(f"{metric}")
    ax.legend(fontsize=7)
    finish(plt, fig, claim, png, "cost against accuracy")


@plot
def cloud_mass(claim: dict, runs: list, png: Path) -> None:
    """The blob test: the cloud fraction M(t)/M0 against t/τ_KH per scheme, and the judged
    scheme's density at t_end."""
    from verify_metrics import cloud_fraction_series

    args = claim["run"]["metric_args"]
    plt, fig, (ax, ax_m) = figure(2, size=(6.4, 4.2))
    colour, style = styles(runs)
    for scheme, res, run, _ in runs:
        t, f = cloud_fraction_series(run.dir, args)
        ax.plot(t / args["t_kh"], f, color=colour[scheme], ls=style[res], label=scheme)
    ax.axhline(args.get("threshold", 0.1), color="0.6", ls=":", lw=0.8, label="disrupted")
    ax.axvline(6.5, color="k", ls="--", lw=0.8, label="paper: CRKSPH 6.5 τ_KH")
    ax.set_xlabel("t / τ_KH")
    ax.set_ylabel("cloud mass fraction M(t)/M0")
    ax.legend(fontsize=6)
    judged_density_map(ax_m, claim, runs)
    finish(plt, fig, claim, png, "blob: cloud mass against time")


@plot
def entropy_profile(claim: dict, runs: list, png: Path) -> None:
    """s/s_exact of the evolved points at t_end against where they started (Frontiere, Raskin
    & Owen 2017 Fig. 1: the Kidder implosion's entropy profile, exactly 1)."""
    from verify_metrics import entropy_ratio

    plt, fig, axes = figure(1, size=(7.0, 4.4))
    colour, _ = styles(runs)
    for scheme, (res, run, args) in finest(runs).items():
        x0, ratio = entropy_ratio(run, args)
        axes[0].plot(x0, ratio, ".-", ms=3, lw=0.8, color=colour[scheme], label=scheme)
    axes[0].axhline(1.0, color="k", lw=1.0, label="exact (isentropic)")
    axes[0].set_xlabel("initial position x0 [m]")
    axes[0].set_ylabel("entropy P/ρ^γ over the exact s [1]")
    axes[0].legend(fontsize=6)
    finish(plt, fig, claim, png, "Kidder implosion at t = 0.99τ: entropy of the evolved points")


@plot
def triple_point(claim: dict, runs: list, png: Path) -> None:
    """log10 ρ at t_end of every scheme (Frontiere, Raskin & Owen 2017 Figs 24–27), two per
    row, the 7 × 3 box each."""
    best = finest(runs)
    rows = (len(best) + 1) // 2
    plt, fig, axes = figure(2, rows, size=(6.4, 3.2))
    for ax, (scheme, (res, run, _)) in zip(axes, best.items()):
        s = last_snapshot(run.dir)
        s["log10 rho"] = np.log10(s["rho"])
        density_map(ax, s, f"{scheme}: log10 density at t_end", quantity="log10 rho")
    for ax in axes[len(best):]:
        ax.set_visible(False)
    finish(plt, fig, claim, png, "triple point at t = 5 (x, y in m; log10 ρ in kg/m²)")


@plot
def blast_bubble(claim: dict, runs: list, png: Path) -> None:
    """Rosswog (2015) Figs. 27–30: the judged scheme's density N at every snapshot of its
    finest run (left column, the paper's times), and every scheme's at t_end at the resolution
    the judge compares (right column)."""
    from verify_metrics import read_csv, snapshots

    best = finest(runs)
    judged = claim_scheme(claim) or next(iter(best))
    times = snapshots(best[judged][1].dir)[1:]
    at = first_judge(claim).get("at")
    compared = best if at is None else {s: (r, run, a) for s, r, run, a in runs if r == str(at)}
    rows = max(len(times), len(compared))
    plt, fig, axes = figure(2, rows, size=(6.4, 2.1))
    n_of = {r: f", N = {r}" if r else "" for _, r, _, _ in runs}
    for k, (t, path) in enumerate(times):
        density_map(axes[2 * k], read_csv(path), f"{judged}{n_of[best[judged][0]]}: N at t = {t:g}")
    for k, (scheme, (res, run, _)) in enumerate(compared.items()):
        density_map(axes[2 * k + 1], last_snapshot(run.dir), f"{scheme}{n_of[res]}: N at t_end")
    for k in range(len(times), rows):
        axes[2 * k].set_visible(False)
    for k in range(len(compared), rows):
        axes[2 * k + 1].set_visible(False)
    finish(plt, fig, claim, png, "relativistic blast–bubble: density N (computing frame)")


@plot
def kernel_density_curves(claim: dict, runs: list, png: Path) -> None:
    """ε_ρ against η for each kernel of the claim (Rosswog (2015) Fig. 4) from its
    `sphfmu kernels --eta-scan` table, with the η range each judged mean covers shaded."""
    plt, fig, (ax,) = figure(1)
    table = runs[0][2].kernel_table
    etas = np.array([float(e) for e in table])
    drawn = set()
    for scheme, _, run, args in runs:
        k = args["kernel"]
        if k in drawn:
            continue
        drawn.add(k)
        ax.semilogy(etas, [table[e][k] for e in table], lw=1, label=k)
    for scheme, _, _, args in runs:
        if args["eta_from"] == args["eta_to"]:
            ax.axvline(args["eta_from"], color="0.5", ls=":", lw=0.8)
    ax.set_xlabel("η = h / V^(1/2) (support 2h)")
    ax.set_ylabel("ε_ρ = ⟨|Σ V_b W_ab − 1|⟩ (hexagonal lattice)")
    ax.legend(fontsize=6, ncol=2)
    finish(plt, fig, claim, png, "density error against η (Fig. 4 of the paper)")

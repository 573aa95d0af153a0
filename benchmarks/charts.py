"""Regenerate the speed-against-accuracy charts in docs/ (one command):

    .venv/bin/python benchmarks/charts.py

1. Work-precision of the rotary pendulum's steady state (paper model, k = 2.5, R = 0.2):
   RK4 over step sizes, DOPRI5 over tolerances, and the closed form. Error: the largest
   relative error of impact interval, amplitude and impact speed against the closed form
   (itself checked against DOPRI5 at rtol 1e-12 in the tests). Time: minimum of repeated
   runs after a warm-up, per steady state, one thread. The RK4 slope is fitted.
2. Loop closure near a special position (T1 lambda2 = 2, type a): relative error of u31
   against 60-digit mpmath, for the factored form and the papers' arccos form.
3. Failure map: RK4 time-marching on the undamped balancer over (r, steps per revolution),
   with RK4's stability edge (H7, docs/models.md §7.2).
4. Work-precision of the balancer's steady state: Fourier over harmonic counts against RK4
   shooting over step counts.
5. Failure map: grazing contacts missed by event detection over (step size, approach speed),
   a step-end sign change against the kernels' detector (benchmarks/failure_maps.py).
6. Failure map: escape misclassified near the separatrix by an integrator alone, over
   (rtol or step, distance to the separatrix).
7. Work-precision of the rigid pendulum on the blade (200 random designs): its flights in
   closed form over tol against DOPRI5 over rtol, in values and in regimes, against DOPRI5
   at rtol 1e-13 (benchmarks/bench_exact_flights.py).
"""

from __future__ import annotations

import math
import platform
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402,F401
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmarks.timing import best_time  # noqa: E402
from kernels import fourbar as fb  # noqa: E402
from kernels import rotary_pendulum as kr  # noqa: E402
from kernels.pendulum import dispatch  # noqa: E402
from kernels.pendulum.cases import CASE_COLUMNS, ROW  # noqa: E402
from kernels.crank_rocker import synthesize_largest_rod  # noqa: E402

MACHINE = f"{platform.node() or 'host'} ({platform.machine()}, 1 thread)"


def _finish(fig, ax, path: Path, xlabel: str, ylabel: str, title: str) -> None:
    """Labels, the machine in the title, grid, legend; save and close."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(f"{title}\nmade on {MACHINE}", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def pendulum_work_precision(path: Path):
    k, xi, r = 2.5, 4.0, 0.2
    design = dict(model=0.0, k=k, xi=xi, kappa=0.8, R=r, tool=0.0, tool_window=0.2,
                  rotor_inertia_ratio=100.0, motor_slope=100.0, idle_speed=1.0)
    batch = 20  # identical cases per call: the time per steady state without call overhead
    cases = np.tile([design[c] for c in CASE_COLUMNS], (batch, 1))
    rows = [ROW.interval, ROW.amplitude, ROW.speed]

    def solve(integrator, rtol=1e-10, dt=0.002):
        method = kr.DECLARATION.method_record(integrator=integrator, rtol=rtol,
                                              atol=rtol * 1e-2, dt=dt)
        return dispatch.solve_cases(cases, method)

    ref = solve("closed_form")[0, rows]

    def error(*args):
        return float(np.max(np.abs(solve(*args)[0, rows] / ref - 1)))

    series = {}
    dts = np.geomspace(0.2, 0.004, 9)
    series["RK4 (dt = 0.2 ... 0.004)"] = [
        (best_time(lambda d=d: solve("rk4", 1e-10, d)) / batch, error("rk4", 1e-10, d))
        for d in dts]
    rtols = 10.0 ** -np.arange(3, 13.5, 1.0)
    series["DOPRI5 (rtol = 1e-3 ... 1e-13)"] = [
        (best_time(lambda q=q: solve("dopri5", q)) / batch, error("dopri5", q))
        for q in rtols]
    t_closed = best_time(lambda: solve("closed_form")) / batch
    rk4_err = np.array([e for _, e in series["RK4 (dt = 0.2 ... 0.004)"]])
    usable = rk4_err > 1e-13
    order = np.polyfit(np.log(dts[usable]), np.log(rk4_err[usable]), 1)[0]

    fig, ax = plt.subplots(figsize=(7.5, 5), constrained_layout=True)
    for (name, pts), marker in zip(series.items(), ("o", "s")):
        t, e = np.array(pts).T
        ax.loglog(t * 1e6, np.maximum(e, 1e-16), marker + "-", label=name)
    ax.loglog([t_closed * 1e6], [1e-15], "k*", ms=14, label="closed form (exact to ~1e-15)")
    _finish(fig, ax, path, "time per steady state [µs]",
            "max relative error of tau1, A, v* [-]",
            f"Rotary pendulum, paper model, k = 2.5, R = 0.2: work-precision; "
            f"RK4 fitted order {order:.2f}")
    return order


def loop_closure_near_node(path: Path):
    import mpmath

    lam0, lam3 = synthesize_largest_rod(2.0, 0.3)
    lam2 = lam0 + lam3 - 1.0

    def reference(phi):
        with mpmath.workdps(60):
            p = mpmath.mpf(phi)
            l0, l2, l3 = (mpmath.mpf(x) for x in (lam0, lam2, lam3))
            d2 = 1 + l0**2 - 2 * l0 * mpmath.cos(p)
            P, Q = (l2 + l3) ** 2 - d2, d2 - (l2 - l3) ** 2
            return float((1 - l0 * mpmath.cos(p)) / d2
                         + l0 * mpmath.sin(p) * (d2 + l2**2 - l3**2) / (d2 * mpmath.sqrt(P * Q)))

    def arccos_form(phi):
        d = math.sqrt(1 + lam0**2 - 2 * lam0 * math.cos(phi))
        theta = math.atan2(math.sin(phi), math.cos(phi) - lam0)
        psi = math.acos(max(-1.0, min(1.0, (lam3**2 + d * d - lam2**2) / (2 * lam3 * d))))
        phi3 = theta - psi
        phi2 = math.atan2(lam3 * math.sin(phi3) - math.sin(phi),
                          lam0 + lam3 * math.cos(phi3) - math.cos(phi))
        return math.sin(phi - phi2) / (lam3 * math.sin(phi3 - phi2))

    dphi = np.geomspace(1e-1, 1e-10, 46)
    stable, naive = [], []
    for d in dphi:
        ref = reference(-d)
        stable.append(abs(fb.transfer_ratio(-d, lam0, 1.0, lam2, lam3, -1.0) / ref - 1))
        naive.append(abs(arccos_form(-d) / ref - 1))
    fig, ax = plt.subplots(figsize=(7.5, 5), constrained_layout=True)
    ax.loglog(dphi, np.maximum(stable, 1e-17), "o-", ms=3, label="factored form (this engine)")
    ax.loglog(dphi, np.maximum(naive, 1e-17), "s-", ms=3, label="arccos form (the papers)")
    ax.invert_xaxis()
    _finish(fig, ax, path, "distance to the special position |dphi1| [rad]",
            "relative error of u31 vs 60-digit reference [-]",
            "Loop closure near a special position (crank-rocker paper, Table 1, lambda2 = 2)")


def balancer_failure_map(path: Path):
    """RK4 time-marching on the undamped balancer (device, f = 1): growth of the response over
    (r, steps per revolution), against RK4's stability edge |h lambda| = 2 sqrt 2 with
    lambda = i sqrt(1 + 1/r^2), i.e. N = pi sqrt(1 + 1/r^2) / sqrt 2."""
    from kernels import balancer as bl

    geom = (3.0, 1.0, 3.5, 2.5)
    a, b, g0 = bl.fourier_coefficients(*geom, 1.0)
    rs = np.geomspace(0.02, 0.5, 22)
    ns = np.unique(np.geomspace(12, 400, 26).astype(int))
    growth = np.empty((len(ns), len(rs)))
    for i, n in enumerate(ns):
        for j, r in enumerate(rs):
            theta, g, _ = bl.march(*geom, 1.0, 1.0, r, 0.0, g0 / 2, True, int(n), 30)
            growth[i, j] = np.log10(max(np.max(np.abs(g)), 1e-300)) if np.all(
                np.isfinite(g)) else 300.0
    fig, ax = plt.subplots(figsize=(7.5, 5), constrained_layout=True)
    mesh = ax.pcolormesh(rs, ns, np.clip(growth, -1, 8), shading="nearest", cmap="magma")
    edge = np.pi * np.sqrt(1 + 1 / rs**2) / np.sqrt(2)
    ax.plot(rs, edge, "c--", lw=2, label="RK4 stability edge N = pi sqrt(1+1/r^2)/sqrt 2")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("stiffness ratio r = omega0/p [-]")
    ax.set_ylabel("RK4 steps per crank revolution [-]")
    bar = fig.colorbar(mesh)
    bar.set_label("log10 max |g| after 30 revolutions [rad] (8 = blown up)")
    ax.set_title(f"Where time-marching RK4 fails: undamped balancer, f = 1\nmade on {MACHINE}",
                 fontsize=9)
    ax.legend(fontsize=8, loc="lower left")
    fig.savefig(path, dpi=110)
    plt.close(fig)


def balancer_work_precision(path: Path):
    """Steady state of the balancer (device, f = 1.1, r = 0.9, eta = 0.02): RK4 shooting over
    step counts and the Fourier solution over harmonic counts. Error: max over a revolution
    of |g'' - reference| / max |reference|, the reference being the Fourier series with all
    harmonics (checked against shooting at 4000 steps to 1e-7 in the tests)."""
    from kernels import balancer as bl

    geom = (3.0, 1.0, 3.5, 2.5)
    a, b, g0 = bl.fourier_coefficients(*geom, 1.0)
    f, r, eta = 1.1, 0.9, 0.02
    k = 1 + 1 / r**2

    def g2_series(theta, m):
        n = np.arange(1, m + 1)
        d, e = k - n**2 * f**2, 2 * eta * n * f
        an = (1 / r**2) * (d * a[1:m + 1] - e * b[1:m + 1]) / (d**2 + e**2)
        bn = (1 / r**2) * (e * a[1:m + 1] + d * b[1:m + 1]) / (d**2 + e**2)
        return -(np.cos(np.outer(theta, n)) @ (n**2 * an) + np.sin(np.outer(theta, n))
                 @ (n**2 * bn))

    full = int(np.nonzero(np.hypot(a, b))[0][-1])
    grid = np.linspace(0, 2 * np.pi, 2048, endpoint=False)
    ref = g2_series(grid, full)
    scale = np.max(np.abs(ref))
    out = np.empty(len(bl.O))
    fourier = []
    for m in (2, 3, 4, 6, 8, 10, 13, 16, 20, 25):
        err = np.max(np.abs(g2_series(grid, m) - ref)) / scale
        fourier.append((best_time(lambda m=m: bl.response(a, b, g0, f, r, eta, 0, 1e-14, 1e-9, m,
                                                     out)), err))
    shooting = []
    for n in (50, 100, 200, 400, 800, 1600, 3200):
        theta, g, g2 = bl.shooting(*geom, 1.0, f, r, eta, g0 / 2, True, n)
        err = np.max(np.abs(g2 - g2_series(theta, full))) / scale
        shooting.append((best_time(lambda n=n: bl.shooting(*geom, 1.0, f, r, eta, g0 / 2, True, n),
                               3), err))
    steps = np.array([50, 100, 200, 400, 800, 1600, 3200])
    errs = np.array([e for _, e in shooting])
    order = -np.polyfit(np.log(steps[errs > 1e-13]), np.log(errs[errs > 1e-13]), 1)[0]
    fig, ax = plt.subplots(figsize=(7.5, 5), constrained_layout=True)
    for name, pts, marker in (("Fourier, 2 ... 25 harmonics (all metrics)", fourier, "o"),
                              ("RK4 shooting, 50 ... 3200 steps/rev", shooting, "s")):
        t, e = np.array(pts).T
        ax.loglog(t * 1e6, np.maximum(e, 1e-16), marker + "-", label=name)
    _finish(fig, ax, path, "time per (f, r, eta) point [µs]",
            "max |g'' - reference| / max |reference| [-]",
            "Spring balancer (device, f = 1.1, r = 0.9, eta = 0.02): work-precision; "
            f"RK4 shooting fitted order {order:.2f}")


def grazing_failure_map(path: Path):
    """Fraction of 8 step phases in which the contact is found, over (step, approach
    speed): step-end sign change on exact states against the kernels' detector (sub-step
    samples and the interpolant's extremum) on RK4 steps."""
    from benchmarks import failure_maps as fm

    steps = np.geomspace(3e-3, 1.0, 21)
    speeds = np.geomspace(1e-5, 0.3, 21)
    phases = np.arange(8) / 8
    found = {name: np.empty((len(speeds), len(steps))) for name in ("naive", "ours")}
    for i, v in enumerate(speeds):
        for j, h in enumerate(steps):
            found["naive"][i, j] = np.mean([fm.naive_found(h, v, p) for p in phases])
            found["ours"][i, j] = np.mean([fm.detector_found(h, v, p) for p in phases])
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.8), constrained_layout=True, sharey=True)
    titles = {"naive": "sign change at step ends (as SciPy's events)",
              "ours": "sub-step samples + extremum check (kernels), RK4"}
    for ax, name in zip(axes, ("naive", "ours")):
        mesh = ax.pcolormesh(steps, speeds, found[name], shading="nearest", cmap="RdYlGn",
                             vmin=0, vmax=1)
        ax.plot(steps, steps * math.sin(fm.APEX) / 2, "k--",
                label="window = step (w = 2 v / sin A)")
        ax.plot(steps, np.sqrt(2 * math.sin(fm.APEX) * steps**4 / 384), "b:",
                label="eps = step^4/384 (interpolation error)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("step [rotor rad]")
        ax.set_title(titles[name], fontsize=9)
        ax.legend(fontsize=8, loc="upper left")
    axes[0].set_ylabel("approach speed at the stop [rad per rotor rad]")
    fig.colorbar(mesh, ax=axes).set_label("fraction of step phases with the contact found")
    fig.suptitle("Grazing contacts missed (H3): rigid pendulum, apex 1 rad, stop just below "
                 f"it\nmade on {MACHINE}", fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def separatrix_failure_map(path: Path):
    """Launches 2 (1 -+ delta) on the rigid pendulum: how many of the two an integrator
    alone classifies right (return / escape), over (rtol or step, delta)."""
    from benchmarks import failure_maps as fm

    deltas = np.geomspace(1e-13, 1e-1, 25)
    axes_spec = (("DOPRI5", "dopri5", np.geomspace(1e-12, 1e-3, 19),
                  "rtol (atol = rtol/100)", lambda a: a, "delta = rtol"),
                 ("RK4", "rk4", np.geomspace(3e-3, 0.5, 15),
                  "step [rotor rad]", lambda a: a**4 / 100, "delta = step^4/100 (fitted)"))
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.8), constrained_layout=True, sharey=True)
    for ax, (name, method, accuracies, label, guide, guide_label) in zip(axes, axes_spec):
        right = np.array([[fm.separatrix_correct(method, a, d) / 2 for a in accuracies]
                          for d in deltas])
        mesh = ax.pcolormesh(accuracies, deltas, right, shading="nearest", cmap="RdYlGn",
                             vmin=0, vmax=1)
        ax.plot(accuracies, guide(accuracies), "k--", label=guide_label)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylim(deltas[0], deltas[-1])
        ax.set_xlabel(label)
        ax.set_title(f"{name} alone: escape if psi reaches -pi", fontsize=9)
        ax.legend(fontsize=8, loc="upper left")
    axes[0].set_ylabel("relative distance delta of the launch speed to the separatrix [-]")
    fig.colorbar(mesh, ax=axes).set_label("fraction of the pair (return, escape) "
                                          "classified right")
    fig.suptitle("Escape misclassified near the separatrix (H1, H2): rigid pendulum; the "
                 "kernels use the closed-form criterion instead\n"
                 f"made on {MACHINE}", fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def blade_work_precision(path: Path):
    from benchmarks.auto_cases import blade_points
    from benchmarks.bench_exact_flights import closed_form, dopri5, measure, references

    params, max_impacts = blade_points("rigid", 200, 7), 1000
    reference = references(params, max_impacts)
    series = {
        "closed-form flights (tol = 1e-2 ... 1e-11)":
            [measure(params, max_impacts, closed_form(t), reference)
             for t in 10.0 ** -np.arange(2, 11.5)],
        "DOPRI5 (rtol = 1e-6 ... 1e-12)":
            [measure(params, max_impacts, dopri5(r), reference)
             for r in 10.0 ** -np.arange(6, 12.5)]}
    n, resolved = params.shape[1], int(reference[1].sum())
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4.6), constrained_layout=True)
    for (name, rows), marker in zip(series.items(), ("o", "s")):
        t = np.array([r["seconds"] for r in rows]) / n * 1e3
        left.loglog(t, [r["largest value error"] for r in rows], marker + "-", label=name)
        right.semilogx(t, [resolved - r["regime as reference (resolved)"] for r in rows],
                       marker + "-", label=name)
    compared = series[next(iter(series))][-1]["values compared"]
    for ax, ylabel, title in (
            (left, "largest relative error of the cycle's values [-]",
             f"values, at the {compared} designs whose reference values are resolved"),
            (right, "designs in another regime [-]",
             f"regimes, at the {resolved} designs whose reference regime is resolved")):
        ax.set_xlabel("time per steady state [ms]")
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=9)
        ticks = [1, 2, 3, 5, 10, 20, 30, 50]
        ax.xaxis.set_major_locator(matplotlib.ticker.FixedLocator(ticks))
        ax.xaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"Rigid pendulum on the blade, {n} random designs: work-precision against "
                 f"DOPRI5 at rtol 1e-13\nmade on {MACHINE}", fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    docs = ROOT / "docs"
    docs.mkdir(exist_ok=True)
    order = pendulum_work_precision(docs / "work_precision_pendulum.png")
    loop_closure_near_node(docs / "loop_closure_near_node.png")
    balancer_failure_map(docs / "failure_map_balancer_rk4.png")
    balancer_work_precision(docs / "work_precision_balancer.png")
    grazing_failure_map(docs / "failure_map_grazing.png")
    separatrix_failure_map(docs / "failure_map_separatrix.png")
    blade_work_precision(docs / "work_precision_blade.png")
    print(f"wrote docs/: work_precision_pendulum.png (RK4 order {order:.2f}), "
          "loop_closure_near_node.png, failure_map_balancer_rk4.png, "
          "work_precision_balancer.png, failure_map_grazing.png, "
          "failure_map_separatrix.png, work_precision_blade.png")


if __name__ == "__main__":
    main()

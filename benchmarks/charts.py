"""Regenerate the speed-against-accuracy charts in docs/ (one command):

    .venv/bin/python benchmarks/charts.py

1. Work-precision of the rotary pendulum's steady state (paper model, k = 2.5, R = 0.2):
   RK4 over step sizes, DOPRI5 over tolerances, and the closed form. Error: the largest
   relative error of impact interval, amplitude and impact speed against the closed form
   (itself checked against DOPRI5 at rtol 1e-12 in the tests). Time: minimum of repeated
   runs after a warm-up, per steady state, one thread. The RK4 slope is fitted.
2. Loop closure near a special position (T1 lambda2 = 2, type a): relative error of u31
   against 60-digit mpmath, for the factored form and the papers' arccos form.
"""

from __future__ import annotations

import math
import platform
import sys
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from kernels import fourbar as fb  # noqa: E402
from kernels import pendulum as pd  # noqa: E402
from kernels.crank_rocker import synthesize_largest_rod  # noqa: E402

MACHINE = f"{platform.node() or 'host'} ({platform.machine()}, 1 thread)"


def timed(fn, repeats=7):
    fn()
    best = math.inf
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def pendulum_work_precision(path: Path):
    k, xi, r = 2.5, 4.0, 0.2
    out = np.empty(11)
    pd.dimensionless(0, k, xi, 0.8, r, pd.INTEGRATOR_CLOSED, 0, 0, 0, 1000, out)
    ref = out[[3, 1, 4]].copy()  # impact interval, amplitude, pre-impact speed

    def error(integrator, rtol, dt):
        pd.dimensionless(0, k, xi, 0.8, r, integrator, rtol, rtol * 1e-2, dt, 1000, out)
        return float(np.max(np.abs(out[[3, 1, 4]] / ref - 1)))

    series = {}
    dts = np.geomspace(0.2, 0.004, 9)
    series["RK4 (dt = 0.2 ... 0.004)"] = [
        (timed(lambda d=d: pd.dimensionless(0, k, xi, 0.8, r, 2, 0, 0, d, 1000, out)),
         error(2, 0.0, d)) for d in dts]
    rtols = 10.0 ** -np.arange(3, 13.5, 1.0)
    series["DOPRI5 (rtol = 1e-3 ... 1e-13)"] = [
        (timed(lambda q=q: pd.dimensionless(0, k, xi, 0.8, r, 3, q, q * 1e-2, 0, 1000, out)),
         error(3, q, 0.0)) for q in rtols]
    t_closed = timed(lambda: pd.dimensionless(0, k, xi, 0.8, r, 1, 0, 0, 0, 1000, out))
    rk4_err = np.array([e for _, e in series["RK4 (dt = 0.2 ... 0.004)"]])
    usable = rk4_err > 1e-13
    order = np.polyfit(np.log(dts[usable]), np.log(rk4_err[usable]), 1)[0]

    fig, ax = plt.subplots(figsize=(7.5, 5), constrained_layout=True)
    for (name, pts), marker in zip(series.items(), ("o", "s")):
        t, e = np.array(pts).T
        ax.loglog(t * 1e6, np.maximum(e, 1e-16), marker + "-", label=name)
    ax.loglog([t_closed * 1e6], [1e-15], "k*", ms=14, label="closed form (exact to ~1e-15)")
    ax.set_xlabel("time per steady state [µs]")
    ax.set_ylabel("max relative error of tau1, A, v* [-]")
    ax.set_title(f"Rotary pendulum, paper model, k = 2.5, R = 0.2: work-precision\n"
                 f"RK4 fitted order {order:.2f}; made on {MACHINE}", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=110)
    plt.close(fig)
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
    ax.set_xlabel("distance to the special position |dphi1| [rad]")
    ax.set_ylabel("relative error of u31 vs 60-digit reference [-]")
    ax.set_title("Loop closure near a special position (seed 000 Table 1, lambda2 = 2)\n"
                 f"made on {MACHINE}", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    docs = ROOT / "docs"
    docs.mkdir(exist_ok=True)
    order = pendulum_work_precision(docs / "work_precision_pendulum.png")
    loop_closure_near_node(docs / "loop_closure_near_node.png")
    print(f"wrote docs/work_precision_pendulum.png (RK4 order {order:.2f}) and "
          "docs/loop_closure_near_node.png")


if __name__ == "__main__":
    main()

"""Rotary pendulum: trajectories to the steady state per second per core, closed form vs
DOPRI5 (numba, rtol 1e-8) vs SciPy solve_ivp (DOP853 with an impact event and a restart
loop, the same tolerance), on the paper model at random (k, R) below R_crit.

Run: .venv/bin/python benchmarks/bench_rotary_pendulum.py   (writes benchmarks/results/*.json)
"""

from __future__ import annotations

import json
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from kernels import pendulum as pd  # noqa: E402
from kernels import rotary_pendulum as kr  # noqa: E402

XI = 4.0


def cases(n, seed=6):
    rng = np.random.default_rng(seed)
    k = rng.uniform(1.0, 2.5, n)
    v_crit = np.array([pd.paper_critical_speed(x, XI) for x in k])
    r_crit = (v_crit - 1 - k) / (v_crit + 1 + k)
    return k, rng.uniform(0.0, 0.8, n) * r_crit


def scipy_steady_state(k, r, rtol, max_impacts=200):
    """The straightforward SciPy route: integrate flight by flight with an event at psi = 0
    (upward), apply the impact law, restart, until the impact speed converges."""
    def rhs(t, y):
        x = k * k + 1 + 2 * k * math.cos(y[0])
        return [y[1], -k * x / (1 + XI * x) * (y[1] ** 2 + XI) * math.sin(y[0])]

    def impact(t, y):
        return y[0]
    impact.terminal, impact.direction = True, 1

    v, tau1 = 0.0, math.nan
    scipy_steady_state.flights = 0
    for _ in range(max_impacts):
        launch = (1 + k) * (1 + r) + r * v
        # start just below the surface so the restart point is not an event (H4)
        sol = solve_ivp(rhs, (0, 100), [-1e-12, -launch], method="DOP853", events=impact,
                        rtol=rtol, atol=rtol * 1e-2)
        scipy_steady_state.flights += 1
        if not sol.t_events[0].size:
            return math.nan, math.nan
        v_new, tau1 = sol.y_events[0][0][1], sol.t_events[0][0]
        if abs(v_new - v) <= 10 * rtol * v_new or r == 0:
            return v_new, tau1
        v = v_new
    return v, tau1


def main():
    ks, rs = cases(400)
    out = np.empty(pd.N_ROW)
    pd.dimensionless(0, 2.0, XI, 0.8, 0.1, 1, 0, 0, 0, 1000, out)
    pd.dimensionless(0, 2.0, XI, 0.8, 0.1, 3, 1e-8, 1e-10, 0, 1000, out)
    result = {"machine": platform.node()}
    n = len(ks)
    cases_arr = np.stack([np.zeros(n), ks, np.full(n, XI), np.full(n, 0.8), rs, np.zeros(n),
                          np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)], axis=1)
    rows = np.empty((n, kr.N_ROW))
    status = np.empty(n, dtype=np.int8)
    for name, integrator, rtol in (("closed_form", 1, 0.0), ("dopri5_rtol_1e-8", 3, 1e-8)):
        kr.pendulum_block(cases_arr[:2], integrator, rtol, rtol * 1e-2, 0.0, 1000, rows,
                          status)
        best = math.inf
        for _ in range(3):  # batched in numba, as the engine runs it; best of three
            t = time.perf_counter()
            kr.pendulum_block(cases_arr, integrator, rtol, rtol * 1e-2, 0.0, 1000, rows,
                              status)
            best = min(best, time.perf_counter() - t)
        result[name] = n / best
        result[name + "_flights_per_state"] = float(np.mean(rows[:, pd.ROW_EVENTS]))
    n_scipy = 20
    worst, best = 0.0, math.inf
    for _ in range(3):  # best of three, as for the numba paths
        t = time.perf_counter()
        for k, r in zip(ks[:n_scipy], rs[:n_scipy]):
            v, tau1 = scipy_steady_state(k, r, 1e-8)
        best = min(best, time.perf_counter() - t)
    flights = 0
    for k, r in zip(ks[:n_scipy], rs[:n_scipy]):
        v, tau1 = scipy_steady_state(k, r, 1e-8)
        flights += scipy_steady_state.flights
        pd.dimensionless(0, k, XI, 0.8, r, 1, 0, 0, 0, 1000, out)
        worst = max(worst, abs(tau1 / out[pd.ROW_INTERVAL] - 1))
    result["scipy_flights_per_state"] = flights / n_scipy
    result["scipy_dop853_rtol_1e-8"] = n_scipy / best
    result["scipy_worst_rel_error_tau1"] = worst
    result["dopri5_over_scipy"] = result["dopri5_rtol_1e-8"] / result["scipy_dop853_rtol_1e-8"]
    # the same ratio per integrated flight: what the numba core alone buys, without the
    # Aitken jump on the impact map (fewer flights per steady state)
    result["dopri5_over_scipy_per_flight"] = result["dopri5_over_scipy"] * (
        result["dopri5_rtol_1e-8_flights_per_state"] / result["scipy_flights_per_state"])
    # the closed form over a whole grid: the per-point cost with omega1 as a free axis
    m = 10000
    columns = dict(model=np.zeros(m), k=np.repeat(ks[:100], 100), xi=np.full(m, XI),
                   kappa=np.full(m, np.nan), R=np.repeat(rs[:100], 100),
                   omega1=np.tile(np.linspace(20, 100, 100), 100), l2=np.full(m, 0.04),
                   tool=np.zeros(m), tool_window=np.full(m, 0.2),
                   rotor_inertia_ratio=np.full(m, 100.0), motor_slope=np.full(m, 100.0),
                   idle_speed=np.ones(m))
    params = np.array([columns[name] for name in kr.P._fields])
    method = kr.DECLARATION.method_record()  # integrator auto: the closed form here
    kr.run(params, method)
    best = math.inf
    for _ in range(5):
        t = time.perf_counter()
        kr.run(params, method)
        best = min(best, time.perf_counter() - t)
    result["closed_form_grid_points_per_s_100_omega1_per_case"] = m / best
    print(f"rotary pendulum, 1 thread, steady states per second: closed form "
          f"{result['closed_form']:,.0f}; DOPRI5 rtol 1e-8 {result['dopri5_rtol_1e-8']:,.0f}; "
          f"SciPy DOP853 + events {result['scipy_dop853_rtol_1e-8']:,.1f} "
          f"(DOPRI5 / SciPy {result['dopri5_over_scipy']:,.0f}x per steady state, "
          f"{result['dopri5_over_scipy_per_flight']:,.0f}x per flight: "
          f"{result['dopri5_rtol_1e-8_flights_per_state']:.1f} against "
          f"{result['scipy_flights_per_state']:.1f} flights); grid points with omega1 "
          f"rescaled: {result['closed_form_grid_points_per_s_100_omega1_per_case']:,.0f}/s")
    Path(__file__).resolve().parent.joinpath("results", "rotary_pendulum.json").write_text(
        json.dumps(result, indent=2))


if __name__ == "__main__":
    main()

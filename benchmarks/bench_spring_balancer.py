"""Spring balancer throughput: grid points per second per core for a sweep over (f, r, eta)
at one geometry and over many geometries; the gain from computing the Fourier coefficients
once per geometry; Fourier steady state against RK4 shooting on the exact rocker motion.

Run: .venv/bin/python benchmarks/bench_spring_balancer.py   (writes benchmarks/results/*.json)
"""

from __future__ import annotations

import json
import platform
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.timing import best_time  # noqa: E402
from kernels import balancer as bl  # noqa: E402


def grid(n, geometries, seed=4):
    rng = np.random.default_rng(seed)
    p = np.empty((len(bl.P), n))
    geo = np.array([[3.0, 3.5, 2.5], [3.0, 3.0, 1.5], [4.0, 3.8, 2.9], [3.5, 3.2, 2.4]])
    lengths = [bl.P.lambda0, bl.P.lambda2, bl.P.lambda3]
    if geometries == 1:
        p[lengths] = geo[0][:, None]
    else:  # every point its own geometry: the coefficients cannot be shared
        p[lengths] = geo[rng.integers(0, 4, n)].T + rng.uniform(0, 1e-3, (3, n))
    p[bl.P.sigma] = 1.0
    p[bl.P.f] = rng.uniform(0.3, 2.0, n)
    p[bl.P.r] = rng.uniform(0.3, 2.0, n)
    p[bl.P.eta] = rng.uniform(0.005, 0.1, n)
    p[bl.P.spring_neutral] = bl.NEUTRAL_HALF_SWING
    return p


def main():
    method = bl.DECLARATION.method_record()  # harmonics "auto", tol 1e-10
    bl.run(grid(10, 1), method)
    n_shared, n_own = 20000, 200
    t_shared = best_time(lambda: bl.run(grid(n_shared, 1), method))
    t_own = best_time(lambda: bl.run(grid(n_own, n_own), method))
    a, b, g0 = bl.fourier_coefficients(3.0, 1.0, 3.5, 2.5, 1.0)
    t_coef = best_time(lambda: bl.fourier_coefficients(3.0, 1.0, 3.5, 2.5, 1.0))
    out = np.empty(len(bl.O))
    t_resp = best_time(lambda: [bl.response(a, b, g0, 1.1, 0.9, 0.02, 0, 1e-10, 1e-9, 0, out)
                           for _ in range(1000)]) / 1000
    bl.shooting(3.0, 1.0, 3.5, 2.5, 1.0, 1.1, 0.9, 0.02, g0 / 2, True, 100)
    t_shoot = best_time(lambda: [bl.shooting(3.0, 1.0, 3.5, 2.5, 1.0, 1.1, 0.9, 0.02, g0 / 2, d,
                                        4000) for d in (False, True)])
    result = {"machine": platform.node(),
              "one_geometry_points_per_s": n_shared / t_shared,
              "own_geometry_points_per_s": n_own / t_own,
              "gain_coefficients_once_per_geometry": (n_shared / t_shared) / (n_own / t_own),
              "fourier_coefficients_s": t_coef, "response_s_per_point": t_resp,
              "shooting_both_systems_4000_steps_s": t_shoot,
              "fourier_over_shooting_speedup": t_shoot / t_resp}
    print(f"balancer, 1 thread: {result['one_geometry_points_per_s']:,.0f} points/s sharing one "
          f"geometry; {result['own_geometry_points_per_s']:,.0f} points/s with a geometry per "
          f"point; gain {result['gain_coefficients_once_per_geometry']:.0f}x")
    print(f"  Fourier coefficients {t_coef * 1e3:.1f} ms per geometry, response "
          f"{t_resp * 1e6:.0f} us per (f, r, eta); shooting (both systems, RK4 4000 steps) "
          f"{t_shoot * 1e3:.1f} ms: Fourier {result['fourier_over_shooting_speedup']:.0f}x cheaper")
    out_path = Path(__file__).resolve().parent / "results" / "spring_balancer.json"
    out_path.write_text(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()

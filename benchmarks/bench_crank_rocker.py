"""Crank-rocker throughput: numba kernel vs numpy-vectorised formulas, and a 10^6-point sweep.

Run: .venv/bin/python benchmarks/bench_crank_rocker.py   (writes benchmarks/results/*.json)

Times are minimums of repeated runs after a warm-up (compile excluded, reported apart),
measured in one process so the ratios hold when the machine's speed drifts.
"""

from __future__ import annotations

import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from kernels import crank_rocker as cr  # noqa: E402
from benchmarks.timing import paired_times  # noqa: E402

N = 1_000_000


def make_points(n, seed=1):
    """Random synthesis points of types a, b, c (b mostly above its real-synthesis bound)."""
    rng = np.random.default_rng(seed)
    p = np.full((len(cr.P), n), np.nan)
    p[cr.P.type] = rng.integers(0, 3, n)
    p[cr.P.R] = rng.uniform(0.05, 0.4, n)
    p[cr.P.largest_link] = np.exp(rng.uniform(np.log(1.5), np.log(40.0), n))
    p[cr.P.base_root] = 0
    p[cr.P.crank_length] = 0.1
    p[cr.P.omega1] = 30.0
    p[cr.P.sigma] = cr.SIGMA_IMPACT
    return p


def numpy_crank_rocker(p, tol):
    """The same closed forms as kernels.crank_rocker, vectorised with numpy (types a, b, c,
    sigma = impact, omega1 > 0): the straightforward baseline."""
    n = p.shape[1]
    out = np.full((len(cr.O), n), np.nan)
    status = np.full(n, cr.S.ok, dtype=np.int8)
    kind, r, big = p[cr.P.type], p[cr.P.R], p[cr.P.largest_link]
    g2 = ((1 + r) / (1 - r)) ** 2
    a, b, c = kind == 0, kind == 1, kind == 2
    lam0, lam2, lam3 = np.empty(n), np.empty(n), np.empty(n)
    lam2[a] = big[a]
    lam0[a] = g2[a] * (big[a] + 1) / (g2[a] + big[a])
    lam3[a] = big[a] * (big[a] + 1) / (g2[a] + big[a])
    lam0[c] = big[c]
    lam2[c] = g2[c] * (big[c] + 1) / (g2[c] + big[c])
    lam3[c] = big[c] * (big[c] + 1) / (g2[c] + big[c])
    bb = 1 + big
    disc = bb * bb - 4 * g2 * big
    disc = np.where(b & (disc < 0) & (disc >= -cr.BOUND_ROUNDING * bb * bb), 0.0, disc)
    with np.errstate(invalid="ignore"):
        larger = 0.5 * (bb + np.sqrt(disc))
    lam3[b] = big[b]
    lam0[b] = (g2 * big / larger)[b]
    lam2[b] = larger[b]
    g_max = (1 + big) / (2 * np.sqrt(big))
    out[cr.O.restitution_kinematic_max] = np.where(b, (g_max - 1) / (g_max + 1), np.nan)
    nrs = b & ~(disc >= 0)
    lam0[nrs] = lam2[nrs] = lam3[nrs] = np.nan
    out[cr.O.lambda0], out[cr.O.lambda2], out[cr.O.lambda3] = lam0, lam2, lam3
    scale = tol * (1 + lam0 + lam2 + lam3)
    ia = np.abs(lam0 + lam3 - 1 - lam2) <= scale
    ib = np.abs(lam0 + lam2 - 1 - lam3) <= scale
    ic = np.abs(lam0 + 1 - lam2 - lam3) <= scale
    count = ia.astype(float) + ib + ic
    out[cr.O.special_position_count] = np.where(nrs, np.nan, count)
    slack = tol * (lam0 + 1 + lam2 + lam3)
    turns = (lam0 + 1 <= lam2 + lam3 + slack) & (np.abs(lam0 - 1) >= np.abs(lam2 - lam3) - slack)
    out[cr.O.crank_turns_fully] = np.where(nrs, np.nan, turns.astype(float))

    def mu(phi):
        sh, ch = np.sin(0.5 * phi), np.cos(0.5 * phi)
        d2 = (lam0 - 1) ** 2 + 4 * lam0 * sh * sh
        pp = (lam2 + lam3 - lam0 - 1) * (lam2 + lam3 + lam0 + 1) + 4 * lam0 * ch * ch
        qq = (lam0 - 1 - lam2 + lam3) * (lam0 - 1 + lam2 - lam3) + 4 * lam0 * sh * sh
        sl = tol * (lam0 + 1 + lam2 + lam3) ** 2
        bad = (pp < -sl) | (qq < -sl)
        m = np.arctan2(np.sqrt(np.maximum(pp, 0) * np.maximum(qq, 0)), lam2**2 + lam3**2 - d2)
        return np.where(bad, np.nan, np.minimum(m, np.pi - m))

    mu0 = np.where(ia | ib, 0.0, mu(0.0))  # a change point's dead centre: mu = 0 exactly
    mupi = np.where(ic, 0.0, mu(np.pi))
    window = np.pi / 6  # the working stroke leaves out 30 degrees either side of the node
    mu_edge = mu(np.where(c, np.pi, 0.0) + window)
    out[cr.O.envelope] = np.where(nrs, np.nan, np.maximum.reduce([np.ones(n), lam0, lam2, lam3])
                                  * p[cr.P.crank_length])
    out[cr.O.crank_length] = p[cr.P.crank_length]
    out[cr.O.omega1] = p[cr.P.omega1]
    out[cr.O.gamma] = np.where(nrs, np.nan, np.sqrt(lam0 * lam2 / lam3))
    phi_star = np.where(c, np.pi, 0.0)
    out[cr.O.special_crank_angle] = np.where(nrs, np.nan, phi_star)
    out[cr.O.transmission_angle_opposite] = np.where(turns, np.where(c, mu0, mupi), np.nan)
    out[cr.O.transmission_angle_working] = np.where(
        turns, np.minimum(mu_edge, out[cr.O.transmission_angle_opposite]), np.nan)
    kappa = np.where(b, -1.0, 1.0)
    den = np.where(c, 1 + lam0, 1 - lam0)
    sigma = -kappa
    gam = out[cr.O.gamma]
    before = (1 - kappa * sigma * gam) / den
    after = (1 + kappa * sigma * gam) / den
    moving = turns & ~nrs
    out[cr.O.assembly_branch] = np.where(moving, sigma, np.nan)
    out[cr.O.transfer_before] = np.where(moving, before, np.nan)
    out[cr.O.transfer_after] = np.where(moving, after, np.nan)
    out[cr.O.restitution_kinematic] = np.where(moving, after / before, np.nan)
    out[cr.O.impact_transfer_ratio] = np.where(moving, np.abs(before), np.nan)
    out[cr.O.impact_speed] = np.where(moving, np.abs(before) * np.abs(p[cr.P.omega1]) * lam3 * p[cr.P.crank_length],
                               np.nan)
    status[~turns] = cr.S.not_assemblable
    status[moving & (count > 1)] = cr.S.second_special_position
    status[nrs] = cr.S.no_real_synthesis
    return out, status


def kernel_vs_numpy():
    p = make_points(N)
    method = cr.DECLARATION.method_record(geometry_tol=1e-9)
    t = time.perf_counter()
    cr.run(p[:, :10], method)
    first_call = time.perf_counter() - t  # cached compilation (or load from cache)
    ref_out, ref_status, _ = cr.run(p, method)
    np_out, np_status = numpy_crank_rocker(p, 1e-9)
    assert np.array_equal(ref_status, np_status), "numpy baseline disagrees on status"
    assert np.allclose(ref_out, np_out, rtol=1e-12, atol=0, equal_nan=True), \
        "numpy baseline disagrees on values"
    t_numba, t_numpy = paired_times(lambda: cr.run(p, method),
                                    lambda: numpy_crank_rocker(p, 1e-9))
    return {"points": N, "first_call_s": first_call,
            "numba_s": t_numba, "numpy_s": t_numpy,
            "numba_points_per_s": N / t_numba, "numpy_points_per_s": N / t_numpy,
            "speedup_numba_over_numpy": t_numpy / t_numba}


SPEC = """
mechanism = "crank_rocker"
[grid]
R = {{start = 0.05, stop = 0.40, num = 1000}}
largest_link = {{start = 1.5, stop = 40.0, num = 1000, scale = "log"}}
[fixed]
type = "a"
[run]
compress_level = {level}
"""


def in_memory(workers):
    """The engine without the netCDF write: grid blocks, kernel, assembly into numpy."""
    import dask

    from sweep import engine, spec

    s = spec.parse(SPEC.format(level=0))
    ds = engine.build(s)
    with dask.config.set(scheduler="threads", num_workers=workers):
        t = time.perf_counter()
        ds.compute()
        wall = time.perf_counter() - t
    return {"points": s.size, "workers": workers, "wall_s": wall}


def end_to_end(workers, level):
    from sweep import runner, spec

    s = spec.parse(SPEC.format(level=level))
    kernel_time = [0.0]
    run = s.kernel

    def timed(params, method):
        t = time.perf_counter()
        result = run(params, method)
        kernel_time[0] += time.perf_counter() - t
        return result

    s.kernel = timed
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.nc"
        t = time.perf_counter()
        runner.run_sweep(s, path, progress=False, workers=workers, history="benchmark")
        wall = time.perf_counter() - t
        size = path.stat().st_size
    return {"points": s.size, "workers": workers, "compress_level": level, "wall_s": wall,
            "kernel_s_summed_over_threads": kernel_time[0],
            "share_outside_kernel": 1 - kernel_time[0] / (wall * workers),
            "atlas_MB": size / 1e6, "outputs": len(s.outputs)}


def main():
    if "--kernel-only" in sys.argv:
        k = kernel_vs_numpy()
        print(f"{k['speedup_numba_over_numpy']:.2f} {k['numba_points_per_s']:.4g} "
              f"{k['numpy_points_per_s']:.4g}")
        return
    result = {"machine": {"node": platform.node(), "cpu_count": os.cpu_count(),
                          "machine": platform.machine(), "python": platform.python_version()},
              "kernel_vs_numpy": kernel_vs_numpy(),
              "end_to_end": [end_to_end(w, lvl) for w, lvl in ((1, 1), (2, 1), (2, 0))],
              "in_memory": [in_memory(w) for w in (1, 2)]}
    k = result["kernel_vs_numpy"]
    print(f"kernel, 1 thread: numba {k['numba_points_per_s'] / 1e6:.1f} M points/s, "
          f"numpy {k['numpy_points_per_s'] / 1e6:.2f} M points/s, "
          f"ratio {k['speedup_numba_over_numpy']:.1f}x (first call {k['first_call_s']:.2f} s)")
    for e in result["end_to_end"]:
        print(f"10^6-point sweep, {e['workers']} thread(s), zlib {e['compress_level']}: "
              f"{e['wall_s']:.2f} s wall, kernel {e['kernel_s_summed_over_threads']:.3f} s, "
              f"outside kernel {100 * e['share_outside_kernel']:.1f} %, "
              f"{e['atlas_MB']:.1f} MB, {e['outputs']} outputs")
    for e in result["in_memory"]:
        share = 1 - k["numba_s"] / (e["wall_s"] * e["workers"])
        print(f"10^6-point sweep into memory (no netCDF), {e['workers']} thread(s): "
              f"{e['wall_s']:.3f} s wall; engine overhead beyond the kernel {100 * share:.0f} %")
    out = Path(__file__).resolve().parent / "results" / "crank_rocker.json"
    out.write_text(json.dumps(result, indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()

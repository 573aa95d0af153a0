"""Kinetostatics throughput: (grid points x crank angles) per second per core, the numba
kernel's profile evaluations (a run with profiles at every angle minus the same run
without) vs the same vector-form formulas vectorised with numpy over the whole (points,
angles) array. A full grid point adds the cycle quadrature and the refinement of five
peaks, about 270 evaluations, also reported.

Run: .venv/bin/python benchmarks/bench_linkage_forces.py   (writes benchmarks/results/*.json)
"""

from __future__ import annotations

import json
import math
import platform
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.timing import paired_times  # noqa: E402
from benchmarks.timing import best_time  # noqa: E402
from kernels import kinetostatics as kt  # noqa: E402
from kernels.extrema import cell_midpoints  # noqa: E402

POINTS, ANGLES = 2000, 360
SNAP = 1e-9


def make_params(n, seed=2):
    rng = np.random.default_rng(seed)
    pr = np.array([[p.encode(p.default)] * n for p in kt.DECLARATION.parameters],
                  dtype=float)
    pr[kt.P.omega1] = rng.uniform(5, 40, n)
    pr[kt.P.tilt] = rng.uniform(0, math.pi / 2, n)
    pr[kt.P.m3] = rng.uniform(2, 12, n)
    pr[kt.P.sigma] = -1.0
    return pr


def numpy_joint_forces(phi1, pr):
    """Vector form of docs/models.md §4.2 for arrays: phi1 (1, M), parameters as (N, 1)."""
    P = {name: pr[i][:, None] for name, i in kt.P._asdict().items()}
    l0, l1, l2, l3, sigma = P["l0"], P["l1"], P["l2"], P["l3"], P["sigma"]
    sh, ch = np.sin(0.5 * phi1), np.cos(0.5 * phi1)
    lim = SNAP * (l0 + l1 + l2 + l3)
    fp = l2 + l3 - l0 - l1
    fq1, fq2 = l0 - l1 - l2 + l3, l0 - l1 + l2 - l3
    fp, fq1, fq2 = (np.where(np.abs(f) <= lim, 0.0, f) for f in (fp, fq1, fq2))
    d2 = (l0 - l1) ** 2 + 4 * l0 * l1 * sh**2
    p = fp * (l2 + l3 + l0 + l1) + 4 * l0 * l1 * ch**2
    q = fq1 * fq2 + 4 * l0 * l1 * sh**2
    root = np.sqrt(p * q)
    s1, c1 = np.sin(phi1), np.cos(phi1)
    phi3 = np.arctan2(l1 * s1, l1 * c1 - l0) + sigma * np.arctan2(root, l3**2 + d2 - l2**2)
    phi2 = np.arctan2(l3 * np.sin(phi3) - l1 * s1, l0 + l3 * np.cos(phi3) - l1 * c1)
    u31 = l1 * (l1 - l0 * c1) / d2 - sigma * l0 * l1 * s1 * (d2 + l2**2 - l3**2) / (d2 * root)
    s32 = np.sin(phi3 - phi2)
    u21 = l1 * np.sin(phi1 - phi3) / (l2 * s32)
    du31 = (l1 * np.cos(phi1 - phi2) + l2 * u21**2 - l3 * u31**2 * np.cos(phi3 - phi2)) / (l3 * s32)
    du21 = (l1 * np.cos(phi1 - phi3) + l2 * u21**2 * np.cos(phi2 - phi3) - l3 * u31**2) / (l2 * s32)
    w1, e1 = P["omega1"], P["epsilon1"]
    w2, w3 = u21 * w1, u31 * w1
    e2, e3 = du21 * w1**2 + u21 * e1, du31 * w1**2 + u31 * e1
    e = [np.exp(1j * a) for a in (phi1, phi2, phi3)]
    rho = [(P[f"s{k + 1}"] * L + 1j * P[f"q{k + 1}"]) * e[k] for k, L in enumerate((l1, l2, l3))]
    B, C = l1 * e[0], l0 + l3 * e[2]
    S = [rho[0], B + rho[1], l0 + rho[2]]
    a = [(1j * e1 - w1**2) * rho[0], (1j * e1 - w1**2) * B + (1j * e2 - w2**2) * rho[1],
         (1j * e3 - w3**2) * rho[2]]
    g = -P["g"] * (np.sin(P["tilt"]) + 1j * np.cos(P["tilt"]))
    W = [P[f"m{k + 1}"] * (g - a[k]) for k in range(3)]
    mom = [-P["J1"] * e1, -P["J2"] * e2, -P["J3"] * e3 + P["external_moment"]]
    F = (P["external_force_normal"] + 1j * P["external_force"]) * e[2]
    Pp = l0 + P["external_force_arm"] * e[2]
    cross = lambda u, v: (np.conj(u) * v).imag  # noqa: E731
    f21t = (cross(S[1] - C, W[1]) + mom[1]) / l2
    f34t = (cross(S[2] - C, W[2]) + cross(Pp - C, F) + mom[2]) / l3
    V = -(f21t * 1j * e[1] + f34t * 1j * e[2] + W[1] + W[2] + F)
    det = cross(e[1], e[2])
    f21 = (cross(V, e[2]) / det) * e[1] + f21t * 1j * e[1]
    f34 = (cross(e[1], V) / det) * e[2] + f34t * 1j * e[2]
    f32 = -(f34 + W[2] + F)
    f14 = f21 - W[0]
    mb = -(cross(B, -f21) + cross(S[0], W[0]) + mom[0])
    return f14, f21, f32, f34, mb


def main():
    pr = make_params(POINTS)
    angles = cell_midpoints(ANGLES, 2 * np.pi)
    method = kt.DECLARATION.method_record(geometry_tol=SNAP, special_window=0.01,
                                          quadrature_points=2, peak_samples=3,
                                          profile_points=ANGLES)
    bare = method._replace(profile_points=0)  # the same run without profiles
    evals = POINTS * ANGLES
    _, _, prof = kt.run(pr, method)
    f14, f21, f32, f34, mb = numpy_joint_forces(angles[None, :], pr)
    assert mb.shape == prof[kt.F.balancing_moment].shape
    # agreement: the profiles' M_b (virtual work) vs numpy's reaction-route M_b
    assert np.allclose(prof[kt.F.balancing_moment], mb, rtol=1e-8,
                       atol=1e-8 * np.nanmax(np.abs(mb)))
    t_full, t_numpy = paired_times(lambda: kt.run(pr, method),
                                   lambda: numpy_joint_forces(angles[None, :], pr), repeats=5)
    t_bare = best_time(lambda: kt.run(pr, bare), 5)
    t_numba = t_full - t_bare
    numpy_evals = POINTS * ANGLES
    result = {"machine": platform.node(), "points": POINTS, "angles": ANGLES,
              "numba_evaluations_per_s": evals / t_numba,
              "numpy_evaluations_per_s": numpy_evals / t_numpy,
              "speedup": (evals / t_numba) / (numpy_evals / t_numpy),
              "grid_points_per_s_without_profiles": POINTS / t_bare}
    print(f"kinetostatics, 1 thread: numba {result['numba_evaluations_per_s'] / 1e6:.2f} M "
          f"(point x angle)/s, numpy {result['numpy_evaluations_per_s'] / 1e6:.2f} M/s, "
          f"ratio {result['speedup']:.1f}x; grid points without profiles (quadrature, "
          f"sampled and refined peaks): {POINTS / t_bare:,.0f}/s")
    out = Path(__file__).resolve().parent / "results" / "linkage_forces.json"
    out.write_text(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()

"""Random rotary-pendulum designs and the accuracy and cost measures of integrator = "auto"
(shared by tests/test_auto.py and benchmarks/bench_auto.py)."""

from __future__ import annotations

import math

import numpy as np

from kernels.pendulum import accuracy
from kernels.pendulum.free_flight import paper_critical_speed
from sweep import registry

KERNEL = registry.get("rotary_pendulum")
MECH = KERNEL.declaration
OUT = MECH.output_index._asdict()
VALUES = ("amplitude", "frequency_ratio", "impact_interval", "impact_speed",
          "acceleration_peak")
EVALS_PER_STEP = {"rk4": 4, "dopri5": 6, "dop853": 12}  # new right-hand sides per step (FSAL)


def points(model, n, seed):
    """Random designs of one model, as parameter columns (omega1 and l2 vary too)."""
    rng = np.random.default_rng(seed)
    cols = {p.name: np.full(n, p.encode(p.default)) if p.default is not None
            else np.full(n, math.nan) for p in MECH.parameters}
    k = rng.uniform(0.9, 2.5, n)
    cols["model"][:] = MECH.parameter("model").encode(model)
    cols["k"] = k
    cols["omega1"] = rng.uniform(20, 100, n)
    cols["l2"] = rng.uniform(0.02, 0.06, n)
    if model == "paper":
        crit = np.array([paper_critical_speed(x, 4.0) for x in k])
        cols["R"] = rng.uniform(0, 0.8, n) * (crit - 1 - k) / (crit + 1 + k)
    else:  # contact outboard of the centre of percussion, so that the pendulum returns
        cols["kappa"] = (1 + k) ** 2 / (4 * k) * rng.uniform(1.1, 1.5, n)
        cols["R"] = rng.uniform(0, 0.02, n)  # v* stays below v_crit for kappa >= 1.1 k*
    if model == "rotor":
        cols["rotor_inertia_ratio"] = rng.uniform(20, 200, n)
        cols["motor_slope"] = rng.uniform(3, 50, n)
    return np.array([cols[p.name] for p in MECH.parameters])


def blade_points(model, n, seed):
    """Random designs of the blade example's family (a contact face outboard of the centre
    of percussion, a reach of 0.1-0.5 rad, half of them plastic)."""
    rng = np.random.default_rng(seed)
    cols = {p.name: np.full(n, p.encode(p.default)) if p.default is not None
            else np.full(n, math.nan) for p in MECH.parameters}
    cols["model"][:] = MECH.parameter("model").encode(model)
    cols["tool"][:] = MECH.parameter("tool").encode("lab_window")
    cols["k"] = rng.uniform(0.8, 1.5, n) if model != "paper" else rng.uniform(2.3, 2.7, n)
    cols["kappa"] = rng.uniform(1.1, 1.4, n)
    cols["R"] = np.where(rng.uniform(size=n) < 0.5, 0.0, rng.uniform(0.0, 0.02, n))
    cols["tool_window"] = rng.uniform(0.1, 0.5, n)
    if model == "rotor":
        cols["rotor_inertia_ratio"] = np.exp(rng.uniform(np.log(20), np.log(300), n))
        cols["motor_slope"] = np.exp(rng.uniform(np.log(3), np.log(100), n))
    return np.array([cols[p.name] for p in MECH.parameters])


def run(params, integrator="auto", tol=1e-8, rtol=1e-10, dt=0.002, atol_per_rtol=1e-2):
    method = MECH.method_record(integrator=integrator, rtol=rtol, atol=rtol * atol_per_rtol,
                                dt=dt, max_impacts=1000, tol=tol)
    out, status, _ = KERNEL.run(params, method)
    return out, status


def one_solve(tol):
    """run's arguments for one DOPRI5 solve from rest at auto's finer rtol for tol (the
    accuracy auto delivers), the solve auto's price is measured against."""
    finer = accuracy.AUTO_COARSE * accuracy.auto_rtol(tol) / accuracy.AUTO_REFINE
    return dict(integrator="dopri5", rtol=finer, atol_per_rtol=accuracy.AUTO_ATOL_PER_RTOL)


def errors(out, ref, blade=False):
    """The largest relative error of the cycle's values, per design (on the blade, flights
    end on the blade: no frequency ratio)."""
    values = [v for v in VALUES if not (blade and v == "frequency_ratio")]
    return np.max([np.abs(out[OUT[v]] / ref[OUT[v]] - 1) for v in values], axis=0)


def cost(out, method):
    """Right-hand-side evaluations of a run (deterministic, unlike wall time)."""
    return np.sum(out[OUT["n_steps"]]) * EVALS_PER_STEP[method]

"""The rotary-pendulum mechanism kernel (atlas.md §3.4): one steady state per distinct case
(model, k, xi, kappa, R, tool, tool window, rotor parameters) of a block, then rescaled by
omega1 and l2 (omega1 is only a time scale, P-O12)."""

import math
from collections import namedtuple

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS
from kernels import pendulum as pd
from kernels.declaration import POSITIVE, Mechanism, Output, Quantity
from kernels.pendulum import (ROW_ACCEL, ROW_AMPLITUDE, ROW_EVENTS, ROW_FREQUENCY,
                              ROW_IMPACTS, ROW_INTERVAL, ROW_METHOD, ROW_RCRIT, ROW_REGIME,
                              ROW_REJECTED, ROW_ROTOR_SPEED, ROW_SPEED, ROW_STEPS)
from kernels.pendulum_lab import lab_steady
from kernels.pendulum_rotor import METHOD_DOPRI5, METHOD_RK4, rotor_steady
from kernels.pendulum_rotor_lab import rotor_lab_steady

MODEL_PAPER, MODEL_RIGID = pd.MODEL_PAPER, pd.MODEL_RIGID
MODEL_ROTOR = 2
TOOL_ROTOR_STOP, TOOL_LAB_WINDOW = 0, 1
USED_CLOSED, USED_RK4, USED_DOPRI5 = pd.USED_CLOSED, pd.USED_RK4, pd.USED_DOPRI5
_ROTOR = {"model": ("rotor",)}


def _rules(given: dict) -> str | None:
    """The closed form exists only for the constant-speed models on the rotor stop."""
    models = given.get("model", {"paper"})
    tools = given.get("tool", {"rotor_stop"})
    if "closed_form" in given.get("method.integrator", ()) and (
            "rotor" in models or "lab_window" in tools):
        return ("method.integrator: \"closed_form\" exists only for the paper and rigid "
                "models on the rotor stop; allowed here: \"auto\", \"rk4\", \"dopri5\"")
    return None


DECLARATION = Mechanism(
    name="rotary_pendulum",
    title="Rotary-pendulum impact mechanism: steady impact regime (seed 004)",
    summary="closed form (auto): first integral of seed 004's equation, amplitude by Newton, "
            "half period by Gauss-Legendre, escape threshold v_crit, rigid pendulum by the "
            "AGM elliptic integral, affine impact map; or DOPRI5/RK4 with event location on "
            "the step interpolant (sign samples, extremum check) and Newton polishing on "
            "exact partial steps; the rotor model by the generalised Newton impact; the lab "
            "blade by a gap function on the striker's polar angle, a slide after plastic or "
            "accumulated (Zeno) contact; computed once per distinct case and rescaled by "
            "omega1 and l2",
    references="V. E. Erem'yants, N. N. Kynatbekova, Analysis of the kinematics of a "
               "rotary-pendulum impact mechanism (in Russian), Institute of Machine Science "
               "and Automation, National Academy of Sciences of the Kyrgyz Republic; the copy "
               "received gives no year",
    parameters=(
        Quantity("model", "1", "pendulum model: seed 004's equation (paper), the physically "
                 "derived rigid pendulum at constant rotor speed (rigid), a rotor of finite "
                 "inertia with a linear motor law (rotor)", default="paper",
                 choices={"paper": MODEL_PAPER, "rigid": MODEL_RIGID, "rotor": MODEL_ROTOR}),
        Quantity("k", "1", "length ratio l1/l2 (k)", "k", default=2.5, **POSITIVE),
        Quantity("xi", "1", "inertia ratio m l2^2/J_c (xi)", "ξ", default=4.0, **POSITIVE),
        Quantity("kappa", "1", "rigid and rotor models: contact radius over the "
                 "centre-of-percussion radius (kappa); default xi/(1 + xi), contact at the "
                 "striker's centre", "κ", used_when={"model": ("rigid", "rotor")},
                 **POSITIVE),
        Quantity("R", "1", "restitution coefficient of the striker on the tool (R)", "R",
                 default=0.0, minimum=0.0, maximum=1.0, max_inclusive=False),
        Quantity("omega1", "rad s-1", "rotor angular speed (omega1)", "ω1", default=20.0,
                 **POSITIVE),
        Quantity("l2", "m", "pendulum length to the striker (l2)", "l2", default=0.04,
                 **POSITIVE),
        Quantity("tool", "1", "impact condition: a stop on the rotor at psi = 0 "
                 "(rotor_stop, the paper's), or a blade fixed in the frame hit by the "
                 "striker when it reaches it with |psi| <= tool_window (lab_window)",
                 default="rotor_stop",
                 choices={"rotor_stop": TOOL_ROTOR_STOP, "lab_window": TOOL_LAB_WINDOW}),
        Quantity("tool_window", "rad", "lab_window: reach of the blade as the largest |psi| "
                 "at which the striker meets it (the blade's inner edge is at the striker "
                 "radius there)", default=0.2, minimum=0.0, maximum=math.pi / 2,
                 min_inclusive=False, used_when={"tool": ("lab_window",)}),
        Quantity("rotor_inertia_ratio", "1", "rotor model: rotor inertia over the striker's "
                 "centroidal inertia (J1/J_c)", "J1/J_c", default=100.0, minimum=0.0,
                 used_when=_ROTOR),
        Quantity("motor_slope", "1", "rotor model: slope of the motor law tau_m = s_m "
                 "(Omega_idle - phi1') in J_c omega1 (s_m/(J_c omega1))", "s_m",
                 default=100.0, minimum=0.0, used_when=_ROTOR),
        Quantity("idle_speed", "1", "rotor model: the motor's no-load speed over omega1 "
                 "(Omega_idle/omega1); the rotor starts at it", "Ω_idle/ω1", default=1.0,
                 used_when=_ROTOR, **POSITIVE),
    ),
    outputs=(
        Output("regime", "1", "steady regime of the impact motion",
               flags={name: code for code, name in enumerate(pd.REGIMES)}
               | {"undetermined": -1}, undetermined="undetermined"),
        Output("amplitude", "rad", "amplitude of the relative swing (A)", "A"),
        Output("frequency_ratio", "1", "frequency coefficient n (psi ~ A sin(n omega1 t)), "
               "pi over the flight time; NaN on the lab blade, where flights end on the "
               "blade", "n"),
        Output("period", "s", "period of the free relative oscillation T = 2 pi/(n omega1)",
               "T"),
        Output("impact_speed", "m s-1", "normal speed of the striker at impact in steady "
               "state (V* = 2 (1+k) omega1 l2/(1-R) on the rotor stop at constant speed)",
               "V*"),
        Output("impact_interval", "rad", "rotor angle between impacts in steady state "
               "(tau1; on the blade, between the impacts opening each contact)", "τ1"),
        Output("impacts_to_converge", "1", "impacts from rest to the steady state (to "
               "1e-12 by the closed form, to 10 rtol when integrated), or until escape"),
        Output("acceleration_peak", "rad s-2", "peak relative angular acceleration of the "
               "pendulum in steady state", "|ψ''|max"),
        Output("restitution_critical", "1", "largest R with a periodic impact regime "
               "(R_crit, closed-form models on the rotor stop); NaN if none exists or none "
               "is known", "R_crit"),
        Output("rotor_speed_ratio", "1", "mean rotor speed over the steady cycle over "
               "omega1 (1 at constant rotor speed)"),
        Output("n_steps", "1", "integration steps, accepted and rejected (0: closed form)"),
        Output("n_rejected", "1", "rejected integration steps among n_steps"),
        Output("n_events", "1", "impact events located by the integrator"),
        Output("method_used", "1", "method that produced the values",
               flags={"closed_form": USED_CLOSED, "rk4": USED_RK4, "dopri5": USED_DOPRI5}),
    ),
    status=("ok", "escape", "max_steps", "step_underflow", "degenerate", "nonfinite"),
    usable=("escape",),
    method=(
        Quantity("integrator", "1", "auto (the closed form where the model has one, else "
                 "DOPRI5 at a tolerance calibrated for tol), closed_form, rk4 or dopri5",
                 default="auto",
                 choices={"auto": pd.INTEGRATOR_AUTO, "closed_form": pd.INTEGRATOR_CLOSED,
                          "rk4": pd.INTEGRATOR_RK4, "dopri5": pd.INTEGRATOR_DOPRI5}),
        Quantity("rtol", "1", "dopri5 relative tolerance", default=1e-10, minimum=1e-14,
                 maximum=1e-2, used_when={"integrator": ("dopri5",)}),
        Quantity("atol", "1", "dopri5 absolute tolerance (rad, rad per rotor radian)",
                 default=1e-12, minimum=1e-16, maximum=1e-2,
                 used_when={"integrator": ("dopri5",)}),
        Quantity("dt", "1", "rk4 step in rotor radians", default=0.002, minimum=1e-6,
                 maximum=0.5, used_when={"integrator": ("rk4",)}),
        Quantity("max_impacts", "1", "impacts simulated at most", default=1000, minimum=1,
                 maximum=10**6, integer=True),
        Quantity("tol", "1", "auto: relative accuracy requested of the outputs",
                 default=1e-8, minimum=1e-11, maximum=1e-2, used_when={"integrator": ("auto",)}),
    ),
    rules=_rules,
    whole_axes=("omega1", "l2"),
)
P = DECLARATION.parameter_index
O = DECLARATION.output_index
S = DECLARATION.status_codes

#: auto without a closed form: DOPRI5 at atol = rtol (psi and psi' are O(1), so the absolute
#: error is set on that scale, H5) and rtol = tol x a factor calibrated on 360 random rotor
#: designs (seeds 0-29 of tests/test_auto.py's sampler) against a 1e-13 reference: the
#: largest factor whose worst output error stayed below tol with a margin of 1.5-2.
#: Tolerance proportionality fails at loose tolerances (rtol = tol/10 gave 2.9 tol at
#: tol = 1e-3), hence the smaller factors there. DOPRI5 beat fixed-step RK4 at every
#: accuracy measured. Factors by log10(tol), linear in between.
AUTO_RTOL_FACTOR = ((-3.0, 0.01), (-4.0, 0.08), (-5.0, 0.1), (-6.0, 0.2), (-8.0, 0.3))
AUTO_ATOL_PER_RTOL = 1.0
LAB_HORIZON = 200.0 * math.pi  # rotor radians without a contact: regime no_impact
N_ROW = pd.N_ROW
_REGIME_CODES = np.arange(len(pd.REGIMES), dtype=np.float64)  # unused by the drivers
#: the status of each return code of the steady-state drivers
_STATUS = (S.ok, S.escape, S.max_steps, S.step_underflow, S.degenerate)


def auto_rtol(tol):
    """DOPRI5's rtol for a requested output accuracy tol (AUTO_RTOL_FACTOR)."""
    x, f = np.array(AUTO_RTOL_FACTOR).T
    return tol * float(np.interp(math.log10(tol), x[::-1], f[::-1]))


#: the columns of a case: what a steady state depends on (omega1 and l2 only rescale it)
CASE_COLUMNS = ("model", "k", "xi", "kappa", "R", "tool", "tool_window",
                "rotor_inertia_ratio", "motor_slope", "idle_speed")
C = namedtuple("CaseColumns", CASE_COLUMNS)(*range(len(CASE_COLUMNS)))


@njit(**KERNEL_OPTIONS)
def steady_case(case, integrator, rtol, atol, dt, max_impacts, row):
    """Steady state of one case (columns C) in omega1 units into row (slots ROW_*);
    returns the kernel status code."""
    for j in range(row.shape[0]):
        row[j] = math.nan
    model, k, xi, kappa, r = int(case[C.model]), case[C.k], case[C.xi], case[C.kappa], case[C.R]
    tool, window = int(case[C.tool]), case[C.tool_window]
    j1, slope, idle = case[C.rotor_inertia_ratio], case[C.motor_slope], case[C.idle_speed]
    if model != MODEL_ROTOR and tool == TOOL_ROTOR_STOP:
        code = pd.steady_state(model, k, xi, kappa, r, integrator, rtol, atol, dt,
                               max_impacts, row)
        row[ROW_SPEED] = 1.0 + k + row[ROW_SPEED]  # pre-impact psi' -> striker normal speed
        row[ROW_ROTOR_SPEED] = 1.0
        return code
    method = METHOD_RK4 if integrator == pd.INTEGRATOR_RK4 else METHOD_DOPRI5
    row[ROW_METHOD] = pd.USED_RK4 if method == METHOD_RK4 else pd.USED_DOPRI5
    if model == MODEL_ROTOR and tool == TOOL_LAB_WINDOW:
        log = np.empty((1, 2))
        code = rotor_lab_steady(k, xi, kappa, r, window, j1, slope, idle, method, rtol, atol,
                                dt, int(max_impacts), LAB_HORIZON, _REGIME_CODES, row, log)
    elif model == MODEL_ROTOR:
        code = rotor_steady(k, xi, kappa, r, j1, slope, idle, method, rtol, atol, dt,
                            int(max_impacts), _REGIME_CODES, row)
    else:
        log = np.empty((1, 2))
        code = lab_steady(model, k, xi, kappa, r, window, method, rtol, atol, dt,
                          int(max_impacts), LAB_HORIZON, _REGIME_CODES, row, log)
    return _STATUS[code]


@njit(**KERNEL_OPTIONS)
def pendulum_block(cases, integrator, rtol, atol, dt, max_impacts, rows, status):
    row = np.empty(N_ROW)
    for c in range(cases.shape[0]):
        status[c] = steady_case(cases[c], integrator, rtol, atol, dt, max_impacts, row)
        for j in range(N_ROW):
            rows[c, j] = row[j]


@njit(**KERNEL_OPTIONS)
def row_hashes(keys):
    """A 64-bit hash of each row's bit patterns (FNV-1a over the words, splitmix64 finish);
    -0.0 counts as 0.0."""
    out = np.empty(keys.shape[0], dtype=np.uint64)
    for i in range(keys.shape[0]):
        h = np.uint64(14695981039346656037)
        for j in range(keys.shape[1]):
            word = np.array([keys[i, j] + 0.0]).view(np.uint64)[0]
            h = (h ^ word) * np.uint64(1099511628211)
        h ^= h >> np.uint64(30)
        h *= np.uint64(0xBF58476D1CE4E5B9)
        h ^= h >> np.uint64(27)
        h *= np.uint64(0x94D049BB133111EB)
        h ^= h >> np.uint64(31)
        out[i] = h
    return out


def distinct_rows(keys):
    """(distinct rows, index of each row's distinct row): a 1-D unique on row hashes, checked
    row by row (np.unique(axis=0) sorts structured rows and cost 85 % of a closed-form
    block); a hash collision falls back to the exact sort."""
    _, first, inverse = np.unique(row_hashes(keys), return_index=True, return_inverse=True)
    cases = keys[first]
    same = (cases[inverse] == keys) | (np.isnan(cases[inverse]) & np.isnan(keys))
    if not same.all():
        cases, inverse = np.unique(keys, axis=0, return_inverse=True)
    return cases, inverse.ravel()


def run(params, method):
    """Entry point: solve once per distinct case in the block, then rescale by omega1 and
    l2. Parameters a case does not use are blanked, so they do not split it."""
    p = {name: params[i] for name, i in P._asdict().items()}
    model, tool = p["model"], p["tool"]
    p["kappa"] = np.where(np.isnan(p["kappa"]), p["xi"] / (1.0 + p["xi"]), p["kappa"])
    rotor = model == MODEL_ROTOR
    lab = tool == TOOL_LAB_WINDOW
    used = {"tool_window": lab, "rotor_inertia_ratio": rotor, "motor_slope": rotor,
            "idle_speed": rotor}
    keys = np.stack([np.where(used[name], p[name], 0.0) if name in used else p[name]
                     for name in CASE_COLUMNS], axis=1)
    cases, index = distinct_rows(keys)
    rows = np.empty((cases.shape[0], N_ROW))
    case_status = np.empty(cases.shape[0], dtype=np.int8)
    integrator, rtol, atol = method.integrator, method.rtol, method.atol
    if integrator == pd.INTEGRATOR_AUTO:  # closed form where it exists, else this DOPRI5
        rtol = auto_rtol(method.tol)
        atol = rtol * AUTO_ATOL_PER_RTOL
    pendulum_block(np.ascontiguousarray(cases), integrator, rtol, atol, method.dt,
                   method.max_impacts, rows, case_status)
    d = rows[index].T
    w, l2 = p["omega1"], p["l2"]
    out = np.empty((len(O), params.shape[1]))
    out[O.regime] = d[ROW_REGIME]
    out[O.amplitude] = d[ROW_AMPLITUDE]
    out[O.frequency_ratio] = d[ROW_FREQUENCY]
    # the full relative oscillation period (Table 1's T)
    out[O.period] = 2.0 * np.pi / (d[ROW_FREQUENCY] * w)
    out[O.impact_speed] = w * l2 * d[ROW_SPEED]
    out[O.impact_interval] = d[ROW_INTERVAL]
    out[O.impacts_to_converge] = d[ROW_IMPACTS]
    out[O.acceleration_peak] = d[ROW_ACCEL] * w * w
    out[O.restitution_critical] = d[ROW_RCRIT]
    out[O.rotor_speed_ratio] = d[ROW_ROTOR_SPEED]
    out[O.n_steps] = d[ROW_STEPS]
    out[O.n_rejected] = d[ROW_REJECTED]
    out[O.n_events] = d[ROW_EVENTS]
    out[O.method_used] = d[ROW_METHOD]
    status = case_status[index]
    # a steady cycle whose values did not come out finite is not a design value
    cycle = np.isin(out[O.regime], (pd.REGIME_PERIOD_1, pd.REGIME_PERIOD_N,
                                    pd.REGIME_CHATTER))
    values = out[[O.amplitude, O.impact_speed, O.impact_interval, O.acceleration_peak]]
    status[(status == S.ok) & cycle & ~np.all(np.isfinite(values), axis=0)] = S.nonfinite
    return out, status, np.empty((0, params.shape[1], 0))

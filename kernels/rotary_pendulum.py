"""The rotary-pendulum impact mechanism ([RP]): its declaration and entry point.

One steady state per distinct case (model, k, xi, kappa, R, tool, tool window, rotor
parameters) of a block, then rescaled by omega1 and l2 (omega1 is only a time scale, P-O12).
A case is solved in closed form where its model has one (the paper and rigid models on the
rotor stop: kernels/pendulum/models.py), else by the integration core (kernels/impact) on its
system (kernels/pendulum/systems.py), compiled only for the systems a block has.
"""

import math

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS
from kernels.declaration import POSITIVE, Boundary, Mechanism, Output, Quantity
from kernels.impact.impact_map import radical_inverse
from kernels.impact.outcomes import (SEQUENCE_CYCLE, SEQUENCE_DEGENERATE, SEQUENCE_ESCAPE,
                                     SEQUENCE_MAX_STEPS, SEQUENCE_NO_IMPACT,
                                     SEQUENCE_NONFINITE, SEQUENCE_NOT_PERIODIC,
                                     SEQUENCE_SEPARATRIX, SEQUENCE_UNDERFLOW)
from kernels.impact.runge_kutta import METHOD_DOPRI5, METHOD_EXACT, METHOD_RK4
from kernels.pendulum.cases import CASE_COLUMNS, N_ROW, ROW, C
from kernels.pendulum.models import (MODEL_PAPER, MODEL_RIGID, MODEL_ROTOR, closed_flight,
                                     impacts_to_converge, paper_critical, rigid_critical,
                                     steady_state_speed)

TOOL_ROTOR_STOP, TOOL_LAB_WINDOW = 0, 1
INTEGRATOR_AUTO, INTEGRATOR_CLOSED, INTEGRATOR_RK4, INTEGRATOR_DOPRI5 = 0, 1, 2, 3
USED_CLOSED, USED_RK4, USED_DOPRI5 = 0, 1, 2
#: meanings of the codes of the ``regime`` output (CF flag_meanings, in this order)
REGIMES = ("period_1", "period_n", "quasi_periodic", "escape", "chatter", "no_impact",
           "separatrix")
R_ = {name: code for code, name in enumerate(REGIMES)}
#: a launch speed within this (relative) of the escape threshold is on the separatrix: the
#: flight's time diverges like its logarithm, beyond what any method resolves (H1, H2)
SEPARATRIX = 64 * 2.220446049250313e-16
_ROTOR = {"model": ("rotor",)}


def _rules(given: dict) -> str | None:
    """The closed form exists for the constant-speed models on the rotor stop and for the
    rigid model's flights on the blade; the energy per blow needs the striker's mass."""
    if "blow_energy" in given.get("outputs", ()) and "striker_mass" not in given:
        return "striker_mass: required for the output blow_energy"
    models = given.get("model", {"paper"})
    tools = given.get("tool", {"rotor_stop"})
    if "closed_form" in given.get("method.integrator", ()) and (
            "rotor" in models or "paper" in models and "lab_window" in tools):
        return ("method.integrator: \"closed_form\" exists only for the paper and rigid "
                "models on the rotor stop and the rigid model on the blade; allowed here: "
                "\"auto\", \"rk4\", \"dopri5\"")
    if max(given.get("method.starts", {1})) > 1 and not given.get("outputs", set()) & set(
            ATTRACTOR_OUTPUTS):
        return ("method.starts: more than one start is used only with the outputs "
                "attractor_count or basin_fraction; add one to outputs, or omit starts")
    if "edge_margin" in given.get("outputs", ()) and "lab_window" not in tools:
        return ("outputs: edge_margin exists only with tool = \"lab_window\" (the rotor "
                "stop has no edge)")
    return None


#: outputs that need the tangent of the steady cycle, and the ones that need several starts
STABILITY_OUTPUTS = ("multiplier_modulus", "multiplier_angle", "stability_margin")
ATTRACTOR_OUTPUTS = ("attractor_count", "basin_fraction")
MARGIN_OUTPUTS = ("impact_speed_min_ratio", "edge_margin")


DECLARATION = Mechanism(
    name="rotary_pendulum",
    title="Rotary-pendulum impact mechanism: steady impact regime",
    summary="closed form (auto): first integral of the paper's equation, amplitude by Newton, "
            "half period by Gauss-Legendre, escape threshold v_crit, rigid pendulum by the "
            "AGM elliptic integral, affine impact map; or DOPRI5/RK4 with event location on "
            "the step interpolant (sign samples, extremum check) and Newton polishing on "
            "exact partial steps; the rotor model by the generalised Newton impact, its "
            "transient on the stop cut short by the affine map's fixed point and Broyden's "
            "steps; the lab "
            "blade by a gap function on the striker's polar angle, a slide after plastic or "
            "accumulated (Zeno) contact, and at constant rotor speed the whole free swings "
            "that cannot meet the blade skipped in closed form, and the rigid pendulum's "
            "flights stepped exactly by Jacobi's elliptic functions (closed form, auto); "
            "computed once per distinct "
            "case and rescaled by omega1 and l2",
    references="V. E. Erem'yants, N. N. Kynatbekova, Analysis of the kinematics of a "
               "rotary-pendulum impact mechanism (in Russian), Institute of Machine Science "
               "and Automation, National Academy of Sciences of the Kyrgyz Republic; the copy "
               "received gives no year",
    parameters=(
        Quantity("model", "1", "pendulum model: the paper's equation (paper), the physically "
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
        Quantity("striker_mass", "kg", "the striker's mass reduced to its contact point, for "
                 "the energy per blow", "m_s", **POSITIVE),
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
               flags={name: code for code, name in enumerate(REGIMES)}
               | {"undetermined": -1}, undetermined="undetermined", everywhere=True),
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
               "(tau1; on the blade, between the impacts opening each contact)", "τ1",
               chart_units=("turn", 1.0 / (2.0 * math.pi))),
        Output("impacts_to_converge", "1", "impacts from rest to the steady state (to "
               "1e-12 by the closed form, to 10 rtol when integrated; the rotor model on "
               "its stop: estimated past its extrapolated transient, within 3 impacts or "
               "35 %), or until escape", diagnostic=True, count=True),
        Output("acceleration_peak", "rad s-2", "peak relative angular acceleration of the "
               "pendulum in steady state", "|ψ''|max"),
        Output("restitution_critical", "1", "largest R with a periodic impact regime "
               "(R_crit, closed-form models on the rotor stop); NaN if none exists or none "
               "is known", "R_crit", everywhere=True),
        Output("rotor_speed_ratio", "1", "mean rotor speed over the steady cycle over "
               "omega1 (1 at constant rotor speed)"),
        Output("n_steps", "1", "integration steps, accepted and rejected (0: closed form on "
               "the rotor stop; the rigid model's closed-form flights on the blade count "
               "their exact steps)",
               diagnostic=True, count=True),
        Output("n_rejected", "1", "rejected integration steps among n_steps",
               diagnostic=True, count=True),
        Output("n_events", "1", "impact events located by the integrator", diagnostic=True,
               count=True),
        Output("method_used", "1", "method that produced the values",
               flags={"closed_form": USED_CLOSED, "rk4": USED_RK4, "dopri5": USED_DOPRI5},
               everywhere=True),
        Output("multiplier_modulus", "1", "largest modulus |mu| of the multipliers of the "
               "steady cycle's impact map (of its n-fold map for period_n; exact symmetries "
               "removed): below 1 the pattern is stable; R on the rotor stop at constant rotor "
               "speed; by the variational equations, the event-time saltation and Newton's "
               "law differentiated, through slides and accumulated chatter; NaN without a "
               "cycle", "|μ|",
               on_request=True),
        Output("multiplier_angle", "rad", "argument of the leading multiplier in [0, pi]: "
               "near 0 as |mu| -> 1 a fold (the pattern vanishes), pi a period doubling, "
               "between a complex pair (quasi-periodic motion)", "arg μ", on_request=True),
        Output("stability_margin", "1", "1 - multiplier_modulus: how far the blow pattern is "
               "from losing stability (negative: unstable)", on_request=True),
        Output("impact_speed_min_ratio", "1", "slowest impact of the steady cycle over its "
               "fastest (striker normal speeds, all contacts of the cycle): near 0 the "
               "pattern is one small change from chatter or grazing", on_request=True),
        Output("edge_margin", "rad", "lab_window: the smallest distance window - |psi| of a "
               "steady-cycle impact from the blade's edge: near 0 a border collision (the "
               "impact slips past the edge)", on_request=True),
        Output("attractor_count", "1", "distinct steady states reached from method.starts "
               "starting states (rest, then a Halton sequence of arrival states): regime, "
               "period and section state equal to 1e-6; each non-periodic outcome counts "
               "as one", on_request=True, count=True, everywhere=True),
        Output("basin_fraction", "1", "share of the starts that reach the steady state "
               "reported (the one reached from rest, the machine's start-up)",
               on_request=True, everywhere=True),
        Output("error_estimate", "1", "auto: estimated relative error of the steady cycle's "
               "values (the largest over amplitude, frequency ratio, period, impact speed "
               "and interval, acceleration peak, rotor speed ratio, and where asked for the "
               "leading multiplier, impact_speed_min_ratio and edge_margin), from two "
               "DOPRI5 solves 8 times apart in rtol; 0 by the rotor stop's closed form "
               "(exact to round-off); on the blade's exact flights (auto, closed_form) the "
               "tolerance the cycle's section states repeat to (1e-9 at tol >= 1e-9); inf "
               "where the two solves reach different regimes; NaN with a fixed integrator "
               "or without a cycle",
               diagnostic=True),
        Output("blow_energy", "J", "energy per blow: striker_mass times the steady impact "
               "speed squared, over 2", "E_blow", on_request=True),
        Output("blow_rate", "min-1", "blows per minute in steady state: 60 times the mean "
               "rotor speed over the rotor angle between impacts", on_request=True),
    ),
    status=("ok", "escape", "no_impact", "not_periodic", "separatrix", "max_steps",
            "step_underflow", "degenerate", "nonfinite"),
    method=(
        Quantity("integrator", "1", "auto (the closed form where the model has one: the "
                 "paper and rigid models on the rotor stop, the rigid model's flights on the "
                 "blade; else DOPRI5 twice, 8 times apart in rtol, the finer solve reported "
                 "with its error_estimate and refined where that exceeds tol/10), "
                 "closed_form (only where there is one), rk4 or dopri5",
                 default="auto",
                 choices={"auto": INTEGRATOR_AUTO, "closed_form": INTEGRATOR_CLOSED,
                          "rk4": INTEGRATOR_RK4, "dopri5": INTEGRATOR_DOPRI5}),
        Quantity("rtol", "1", "dopri5 relative tolerance", default=1e-10, minimum=1e-14,
                 maximum=1e-2, used_when={"integrator": ("dopri5",)}),
        Quantity("atol", "1", "dopri5 absolute tolerance (rad, rad per rotor radian)",
                 default=1e-12, minimum=1e-16, maximum=1e-2,
                 used_when={"integrator": ("dopri5",)}),
        Quantity("dt", "1", "rk4 step in rotor radians", default=0.002, minimum=1e-6,
                 maximum=0.5, used_when={"integrator": ("rk4",)}),
        Quantity("max_impacts", "1", "impacts simulated at most", default=1000, minimum=1,
                 maximum=10**6, integer=True),
        Quantity("tol", "1", "auto, and closed_form on the blade: relative accuracy "
                 "requested of the outputs", default=1e-8, minimum=1e-11, maximum=1e-2,
                 used_when={"integrator": ("auto", "closed_form")}),
        Quantity("starts", "1", "starting states per design for attractor_count and "
                 "basin_fraction (1: from rest only; each start costs a steady state)",
                 default=1, minimum=1, maximum=1000, integer=True),
    ),
    rules=_rules,
    whole_axes=("omega1", "l2"),
    boundaries=tuple(
        Boundary(frozenset((cycle, "escape")), "the steady impact speed reaches the escape "
                 "threshold v_crit: R = R_crit = (v_crit - (1+k))/(v_crit + (1+k))",
                 indicator="restitution_critical") for cycle in ("ok", "period_1")),
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


def auto_rtol(tol):
    """DOPRI5's rtol for a requested output accuracy tol (AUTO_RTOL_FACTOR)."""
    x, f = np.array(AUTO_RTOL_FACTOR).T
    return tol * float(np.interp(math.log10(tol), x[::-1], f[::-1]))


@njit(**KERNEL_OPTIONS)
def driven_stop_preamble(case, tol, row):
    """What the closed form says of a driven case on the rotor stop, before any flight:
    R_crit, the impacts the affine map needs from rest to tol (or to escape), and the
    steady launch speed v*. Returns (v*, v_crit, escapes, on the separatrix)."""
    model, k, r = int(case[C.model]), case[C.k], case[C.R]
    p = (k, case[C.xi]) if model == MODEL_PAPER else (k, case[C.kappa])
    v_crit = paper_critical(p) if model == MODEL_PAPER else rigid_critical(p)
    r_crit = (v_crit - (1.0 + k)) / (v_crit + (1.0 + k))
    row[ROW.restitution_critical] = r_crit if r_crit > 0.0 else math.nan
    count, escapes = impacts_to_converge(k, r, v_crit, tol)
    row[ROW.impacts] = count
    v = steady_state_speed(k, r)
    return v, v_crit, escapes, abs(v - v_crit) <= SEPARATRIX * v_crit


@njit(**KERNEL_OPTIONS)
def closed_form_block(cases, rows):
    """Driven cases on the rotor stop in closed form: the affine impact map's fixed point
    v* (P-O6) and the flight from it (first integral, amplitude by Newton, half period by
    Gauss-Legendre; the rigid pendulum by the AGM elliptic integral)."""
    for c in range(cases.shape[0]):
        case, row = cases[c], rows[c]
        for j in range(row.shape[0]):
            row[j] = math.nan
        row[ROW.steps] = row[ROW.rejected] = row[ROW.events] = 0.0
        v, v_crit, escapes, separatrix = driven_stop_preamble(case, 1e-12, row)
        if escapes or separatrix:
            row[ROW.outcome] = SEQUENCE_SEPARATRIX if separatrix else SEQUENCE_ESCAPE
            continue
        model, k = int(case[C.model]), case[C.k]
        p = (k, case[C.xi]) if model == MODEL_PAPER else (k, case[C.kappa])
        amplitude, tau1, peak = closed_flight(model, v, p)
        row[ROW.outcome] = SEQUENCE_CYCLE
        row[ROW.period], row[ROW.chatter] = 1.0, 0.0
        row[ROW.amplitude], row[ROW.frequency] = amplitude, math.pi / tau1
        row[ROW.interval], row[ROW.speed] = tau1, 1.0 + k + v
        row[ROW.acceleration], row[ROW.rotor_speed] = peak, 1.0


@njit(**KERNEL_OPTIONS)
def row_hashes(words):
    """A 64-bit hash of each row of a uint64 matrix (FNV-1a over the words, splitmix64
    finish)."""
    out = np.empty(words.shape[0], dtype=np.uint64)
    for i in range(words.shape[0]):
        h = np.uint64(14695981039346656037)
        for j in range(words.shape[1]):
            h = (h ^ words[i, j]) * np.uint64(1099511628211)
        h ^= h >> np.uint64(30)
        h *= np.uint64(0xBF58476D1CE4E5B9)
        h ^= h >> np.uint64(27)
        h *= np.uint64(0x94D049BB133111EB)
        h ^= h >> np.uint64(31)
        out[i] = h
    return out


@njit(**KERNEL_OPTIONS)
def rows_repeat(words, first, inverse):
    """Is every row of the uint64 matrix bit for bit the row first[inverse[i]]?"""
    for i in range(words.shape[0]):
        j = first[inverse[i]]
        for c in range(words.shape[1]):
            if words[i, c] != words[j, c]:
                return False
    return True


def distinct_rows(keys):
    """(distinct rows, index of each row's distinct row): a 1-D unique on row hashes of the
    bit patterns (-0.0 counts as 0.0), checked row by row, bit for bit (np.unique(axis=0)
    sorts structured rows and cost most of a closed-form block; the same check in numpy,
    with its temporaries, doubled this function's time); a hash
    collision, or NaNs with other bits, falls back to the exact sort."""
    words = np.ascontiguousarray(keys + 0.0).view(np.uint64)
    _, first, inverse = np.unique(row_hashes(words), return_index=True, return_inverse=True)
    if rows_repeat(words, first, inverse.ravel()):
        return keys[first], inverse.ravel()
    cases, inverse = np.unique(keys, axis=0, return_inverse=True)
    return cases, inverse.ravel()


#: the values whose relative error auto estimates (and bounds by tol)
ESTIMATED = (ROW.amplitude, ROW.frequency, ROW.interval, ROW.speed, ROW.acceleration,
             ROW.rotor_speed)
#: auto without a closed form: each case is solved at AUTO_COARSE times the calibrated rtol
#: and AUTO_REFINE times finer; the finer solve is reported, with its error estimated as
#: |coarse - fine| / (AUTO_REFINE - 1) (DOPRI5's global error proportional to rtol); a case
#: whose estimate exceeds AUTO_ACCEPT tol (a safety factor on that proportionality) is
#: solved again AUTO_REFINE times finer, at most AUTO_ROUNDS times
AUTO_ACCEPT = 0.1
AUTO_COARSE = 2.0
AUTO_REFINE = 8.0
AUTO_ROUNDS = 3


def solve_system(block, sub, method_code, rtol, atol, dt, max_impacts, starts=1):
    """The rows of the cases of one system, by one integrator at one tolerance."""
    out = np.empty((sub.shape[0], N_ROW))
    block(sub, method_code, rtol, atol, dt, max_impacts, starts, out, np.empty((1, 2)))
    return out


def estimated_error(coarse, fine, margins=False):
    """Relative difference of the cycle's values of two solves over the finer one's error
    ratio: the estimated relative error of the finer solve; inf where the two disagree on
    the outcome, the period or the chatter; NaN where neither has a cycle. The leading
    multiplier (where asked for) counts on the unit circle's scale, |dmu|/max(1, |mu|): it
    may be 0, and a sensitive blade design's multiplier was 1.3e-5 off at tol 1e-8 while
    the other values met it. With ``margins`` (asked for) the slowest-over-fastest impact
    ratio and the edge distance count too, on the scale of 1 (a ratio; radians): an edge
    distance was 1.6e-7 off at tol 1e-8 after a flight of ten rotor turns, where the values
    above met tol."""
    values = [np.abs(coarse[:, j] - fine[:, j]) / np.abs(fine[:, j]) for j in ESTIMATED]
    mu = [rows[:, ROW.modulus] * np.exp(1j * rows[:, ROW.angle]) for rows in (coarse, fine)]
    values.append(np.abs(mu[0] - mu[1]) / np.maximum(1.0, np.abs(mu[1])))
    if margins:
        for j in (ROW.speed_ratio, ROW.edge):
            values.append(np.abs(coarse[:, j] - fine[:, j])
                          / np.maximum(1.0, np.abs(fine[:, j])))
    with np.errstate(invalid="ignore"):
        diff = np.nanmax(np.where(np.isnan(values), -np.inf, values), axis=0)
    error = diff / (AUTO_REFINE - 1.0)
    same = ((coarse[:, ROW.outcome] == fine[:, ROW.outcome])
            & (np.nan_to_num(coarse[:, ROW.period]) == np.nan_to_num(fine[:, ROW.period]))
            & (np.nan_to_num(coarse[:, ROW.chatter]) == np.nan_to_num(fine[:, ROW.chatter])))
    error = np.where(same, np.maximum(error, 0.0), np.inf)
    return np.where(same & (fine[:, ROW.outcome] != SEQUENCE_CYCLE), np.nan, error)


def solve_auto(block, sub, tol, max_impacts, starts=1, margins=False):
    """auto on a system without a closed form: DOPRI5 at AUTO_COARSE times the calibrated
    rtol and AUTO_REFINE times finer, refined further where the estimate exceeds
    AUTO_ACCEPT tol (``margins``: the cycle's margins asked for count in it). Counters add
    up every solve."""
    rtol = AUTO_COARSE * auto_rtol(tol)
    coarse = solve_system(block, sub, METHOD_DOPRI5, rtol, rtol * AUTO_ATOL_PER_RTOL, 0.0,
                          max_impacts, starts)
    rows = coarse.copy()
    pending = np.arange(sub.shape[0])
    for _ in range(AUTO_ROUNDS):
        rtol /= AUTO_REFINE
        fine = solve_system(block, sub[pending], METHOD_DOPRI5, max(rtol, 1e-14),
                            max(rtol, 1e-14) * AUTO_ATOL_PER_RTOL, 0.0, max_impacts, starts)
        error = estimated_error(coarse, fine, margins)
        counters = [ROW.steps, ROW.rejected, ROW.events]
        fine[:, counters] += rows[np.ix_(pending, counters)]
        fine[:, ROW.error] = error
        rows[pending] = fine
        more = (error > AUTO_ACCEPT * tol) & (rtol > 1e-14)
        coarse, pending = fine[more], pending[more]
        if not pending.size:
            break
    return rows


#: the systems whose free flight is known in closed form, stepped exactly (runge_kutta's
#: METHOD_EXACT): the rigid model on the blade (models.rigid_exact)
EXACT_FLIGHTS = ((MODEL_RIGID, TOOL_LAB_WINDOW),)


#: the closed-form flight's longest step, in the pendulum's own time (at tol above 4e-6)
EXACT_STEP_MAX = 0.2
#: its section states repeat to 10 x this rtol (at most 1e-9), whatever tol: the flights are
#: exact, so a tighter test costs a few sections (1-3 % of the steps), and a looser one
#: takes a slowly drifting quasi-periodic sequence for a cycle (at rtol = tol/10 and tol
#: 1e-6, 45 of the blade example's 306 designs, quasi-periodic at DOPRI5 rtol 1e-12,
#: came out period_n)
EXACT_SECTION_RTOL = 1e-10


def exact_step_length(tol):
    """The closed-form flight's step, in the pendulum's own time, for an accuracy tol: the
    flow is exact, but the events are searched on a step's cubic Hermite interpolant
    (kernels/impact/events.py), whose error is about L^4/384 of the motion's scale; L =
    (384 tol)^(1/4) keeps it within tol, so that a contact is missed or invented only
    within tol of grazing (docs/impact_core.md). At most EXACT_STEP_MAX: on 200 random
    blade designs, steps of 0.5 (tol 1e-3) ended 6 more designs in another regime than
    DOPRI5 at rtol 1e-13 than steps of 0.1-0.3 did."""
    return min((384.0 * tol) ** 0.25, EXACT_STEP_MAX)


def exact_settings(tol):
    """(rtol, atol, step) of the closed-form flight for an accuracy tol: steps of
    exact_step_length(tol), section states repeating to 10 x min(tol/10,
    EXACT_SECTION_RTOL), and the tangent's and slides' flights, where integrated, by
    DOPRI5 at that rtol."""
    rtol = min(tol / 10.0, EXACT_SECTION_RTOL)
    return rtol, rtol * AUTO_ATOL_PER_RTOL, exact_step_length(tol)


def solve_exact(block, sub, tol, max_impacts, starts=1):
    """A system with a closed-form flight, for an accuracy tol (exact_settings): the
    flights exact to round-off, events polished to round-off."""
    return solve_system(block, sub, METHOD_EXACT, *exact_settings(tol), max_impacts, starts)


def closed_form_estimate(rows, integrator, repeat=0.0):
    """The error_estimate of rows solved in closed form: where there is a cycle, the
    relative error the solve allows: 0 for the rotor stop's closed form (its values are
    exact to round-off), the section repeat tolerance ``repeat`` for exact flights (their
    cycle is accepted when its section states repeat to it, the values' only error left);
    NaN elsewhere and with a fixed integrator."""
    cycle = rows[:, ROW.outcome] == SEQUENCE_CYCLE
    return np.where(cycle, repeat if integrator in (INTEGRATOR_AUTO, INTEGRATOR_CLOSED)
                    else np.nan, np.nan)


def driven_stop_margins(cases, rows, starts):
    """The margins of the constant-speed models on the rotor stop in closed form: one impact
    a cycle (speed ratio 1), the affine map's multiplier R (P-O6); from start j, arriving at
    u_j = 2 (1 + k) x_j (the tool's ``first``), the first launch (1 + k)(1 + R) + R u_j
    escapes iff it reaches v_crit, else the map contracts to v* (the one attractor)."""
    cycle = rows[:, ROW.outcome] == SEQUENCE_CYCLE
    k, r = cases[:, C.k], cases[:, C.R]
    rows[:, ROW.speed_ratio] = np.where(cycle, 1.0, np.nan)
    rows[:, ROW.modulus] = np.where(cycle, r, np.nan)
    rows[:, ROW.angle] = np.where(cycle, 0.0, np.nan)
    rows[:, ROW.attractors], rows[:, ROW.basin] = 1.0, 1.0
    if starts > 1:
        r_crit = rows[:, ROW.restitution_critical]
        v_crit = (1.0 + k) * (1.0 + r_crit) / (1.0 - r_crit)
        arrival = np.array([2.0 * radical_inverse(j, 2) for j in range(1, starts)])
        launch = ((1.0 + k) * (1.0 + r))[:, None] + r[:, None] * (1.0 + k)[:, None] * arrival
        escaping = (launch >= v_crit[:, None]).sum(axis=1)
        rows[:, ROW.attractors] = np.where(cycle & (escaping > 0), 2.0, 1.0)
        rows[:, ROW.basin] = np.where(cycle, (starts - escaping) / starts, 1.0)


def solve_cases(cases, method, stability=False, starts=1):
    """The result row (cases.ROW) of every case, in omega1 units: closed form where the
    model has one and the method allows it, else the integration core on the case's
    system (imported, and compiled, only when a block has a case of it; with
    ``stability`` the system's block that carries the tangent, where one is needed).
    ``starts``: starting states per case for the attractor count."""
    rows = np.empty((cases.shape[0], N_ROW))
    model, tool = cases[:, C.model], cases[:, C.tool]
    driven_stop = (model != MODEL_ROTOR) & (tool == TOOL_ROTOR_STOP)
    closed = driven_stop & (method.integrator <= INTEGRATOR_CLOSED)
    if closed.any():
        rows_closed = np.empty((int(closed.sum()), N_ROW))
        sub = np.ascontiguousarray(cases[closed])
        closed_form_block(sub, rows_closed)
        rows_closed[:, ROW.method] = USED_CLOSED
        rows_closed[:, ROW.error] = closed_form_estimate(rows_closed, method.integrator)
        driven_stop_margins(sub, rows_closed, starts)
        rows[closed] = rows_closed
    integrated = ~closed
    if integrated.any():
        from kernels.pendulum.systems import SYSTEMS, TANGENT_SYSTEMS, section_repeat_tol

        rk4 = method.integrator == INTEGRATOR_RK4
        for (m, t), block in SYSTEMS.items():
            chosen = integrated & (model == m) & (tool == t)
            if not chosen.any():
                continue
            if stability:
                block = TANGENT_SYSTEMS.get((m, t), block)
            sub = np.ascontiguousarray(cases[chosen])
            # auto keeps two DOPRI5 solves where the multipliers are asked for: the tangent
            # is integrated, and its error needs their estimate (estimated_error)
            exact = (m, t) in EXACT_FLIGHTS and (
                method.integrator == INTEGRATOR_CLOSED
                or method.integrator == INTEGRATOR_AUTO and not stability)
            if exact:
                out = solve_exact(block, sub, method.tol, method.max_impacts, starts)
                out[:, ROW.error] = closed_form_estimate(
                    out, method.integrator,
                    section_repeat_tol(METHOD_EXACT, exact_settings(method.tol)[0]))
            elif method.integrator == INTEGRATOR_AUTO:
                out = solve_auto(block, sub, method.tol, method.max_impacts, starts,
                                 bool(set(method.outputs) & set(MARGIN_OUTPUTS)))
            else:
                out = solve_system(block, sub, METHOD_RK4 if rk4 else METHOD_DOPRI5,
                                   method.rtol, method.atol, method.dt, method.max_impacts,
                                   starts)
                out[:, ROW.error] = np.nan
            out[:, ROW.method] = USED_CLOSED if exact else USED_RK4 if rk4 else USED_DOPRI5
            if t == TOOL_ROTOR_STOP and m != MODEL_ROTOR:
                tol = 1e-9 if rk4 else max(10.0 * method.rtol, 1e-12)
                for j in range(sub.shape[0]):
                    v, v_crit, escapes, separatrix = driven_stop_preamble(sub[j], tol, out[j])
                    if separatrix:
                        out[j, ROW.outcome] = SEQUENCE_SEPARATRIX
                cycle = out[:, ROW.outcome] == SEQUENCE_CYCLE
                out[:, ROW.modulus] = np.where(cycle, sub[:, C.R], np.nan)  # the affine map
                out[:, ROW.angle] = np.where(cycle, 0.0, np.nan)
            rows[chosen] = out
    return rows


#: the status and regime of each way a sequence ends (kernels/impact/outcomes.py)
_OUTCOMES = {SEQUENCE_CYCLE: (S.ok, -1), SEQUENCE_ESCAPE: (S.escape, R_["escape"]),
             SEQUENCE_NO_IMPACT: (S.no_impact, R_["no_impact"]),
             SEQUENCE_NOT_PERIODIC: (S.not_periodic, R_["quasi_periodic"]),
             SEQUENCE_MAX_STEPS: (S.max_steps, -1),
             SEQUENCE_UNDERFLOW: (S.step_underflow, -1),
             SEQUENCE_DEGENERATE: (S.degenerate, -1),
             SEQUENCE_SEPARATRIX: (S.separatrix, R_["separatrix"]),
             SEQUENCE_NONFINITE: (S.nonfinite, -1)}
_STATUS_OF = np.array([_OUTCOMES[k][0] for k in range(len(_OUTCOMES))], np.int8)
_REGIME_OF = np.array([_OUTCOMES[k][1] for k in range(len(_OUTCOMES))], np.float64)


def run(params, method):
    """Entry point: solve once per distinct case in the block, then rescale by omega1 and
    l2. Parameters a case does not use are blanked, so they do not split it."""
    p = {name: params[i] for name, i in P._asdict().items()}
    p["kappa"] = np.where(np.isnan(p["kappa"]), p["xi"] / (1.0 + p["xi"]), p["kappa"])
    rotor = p["model"] == MODEL_ROTOR
    lab = p["tool"] == TOOL_LAB_WINDOW
    used = {"tool_window": lab, "rotor_inertia_ratio": rotor, "motor_slope": rotor,
            "idle_speed": rotor}
    keys = np.stack([np.where(used[name], p[name], 0.0) if name in used else p[name]
                     for name in CASE_COLUMNS], axis=1)
    cases, index = distinct_rows(keys)
    asked = set(method.outputs)
    starts = method.starts if asked & set(ATTRACTOR_OUTPUTS) else 1
    d = solve_cases(cases, method, bool(asked & set(STABILITY_OUTPUTS)), starts)[index].T
    outcome = d[ROW.outcome].astype(np.int64)
    status = _STATUS_OF[outcome]
    cycle = outcome == SEQUENCE_CYCLE
    regime = np.where(cycle, np.where(d[ROW.chatter] > 0, R_["chatter"],
                                      np.where(d[ROW.period] == 1, R_["period_1"],
                                               R_["period_n"])), _REGIME_OF[outcome])
    w, l2 = p["omega1"], p["l2"]
    out = np.empty((len(O), params.shape[1]))
    out[O.regime] = np.where(regime >= 0, regime, np.nan)
    out[O.amplitude] = d[ROW.amplitude]
    out[O.frequency_ratio] = d[ROW.frequency]
    # the full relative oscillation period (Table 1's T)
    out[O.period] = 2.0 * np.pi / (d[ROW.frequency] * w)
    out[O.impact_speed] = w * l2 * d[ROW.speed]
    out[O.impact_interval] = d[ROW.interval]
    out[O.impacts_to_converge] = d[ROW.impacts]
    out[O.acceleration_peak] = d[ROW.acceleration] * w * w
    out[O.restitution_critical] = d[ROW.restitution_critical]
    out[O.rotor_speed_ratio] = d[ROW.rotor_speed]
    out[O.n_steps] = d[ROW.steps]
    out[O.n_rejected] = d[ROW.rejected]
    out[O.n_events] = d[ROW.events]
    out[O.method_used] = d[ROW.method]
    out[O.error_estimate] = d[ROW.error]
    out[O.multiplier_modulus] = d[ROW.modulus]
    out[O.multiplier_angle] = d[ROW.angle]
    out[O.stability_margin] = 1.0 - d[ROW.modulus]
    out[O.impact_speed_min_ratio] = d[ROW.speed_ratio]
    out[O.edge_margin] = d[ROW.edge]
    out[O.attractor_count] = d[ROW.attractors]
    out[O.basin_fraction] = d[ROW.basin]
    # the machine's view, only where asked for: the blow's energy and how often it comes
    out[O.blow_energy] = (0.5 * p["striker_mass"] * out[O.impact_speed] ** 2
                          if "blow_energy" in asked else np.nan)
    out[O.blow_rate] = (60.0 * out[O.rotor_speed_ratio] * np.abs(w) / out[O.impact_interval]
                        if "blow_rate" in asked else np.nan)
    # values of a steady cycle exist only where there is one: an integrated run launched on
    # the separatrix comes back with finite numbers of a cycle whose period is infinite
    cycle_values = [O.amplitude, O.frequency_ratio, O.period, O.impact_speed, O.impact_interval,
                    O.acceleration_peak, O.rotor_speed_ratio, O.error_estimate,
                    O.multiplier_modulus, O.multiplier_angle, O.stability_margin,
                    O.impact_speed_min_ratio, O.edge_margin, O.blow_energy, O.blow_rate]
    out[np.ix_(cycle_values, ~cycle)] = np.nan
    # a steady cycle whose values did not come out finite is not a design value
    values = out[[O.amplitude, O.impact_speed, O.impact_interval, O.acceleration_peak]]
    broken = cycle & ~np.all(np.isfinite(values), axis=0)
    status[broken] = S.nonfinite
    out[O.regime, broken] = np.nan  # nor is its regime known
    return out, status, np.empty((0, params.shape[1], 0))

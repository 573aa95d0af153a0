"""The rotary-pendulum impact mechanism ([RP]): its declaration and entry point.

One steady state per distinct case (model, k, xi, kappa, R, tool, tool window, rotor
parameters) of a block, then rescaled by omega1 and l2 (omega1 is only a time scale, P-O12).
Which system a case is on, and what each supports, is declared once in
kernels/pendulum/table.py; kernels/pendulum/dispatch.py picks the method of each case (the
closed form, closed_form.py, or the integration core on its system, systems.py, by the
accuracy policy, accuracy.py).
"""

import math

import numpy as np

from kernels.declaration import POSITIVE, Boundary, Mechanism, Output, Quantity, profile_points
from kernels.extrema import cell_midpoints
from kernels.impact.outcomes import (SEQUENCE_CYCLE, SEQUENCE_DEGENERATE, SEQUENCE_ESCAPE,
                                     SEQUENCE_MAX_STEPS, SEQUENCE_NO_IMPACT,
                                     SEQUENCE_NONFINITE, SEQUENCE_NOT_PERIODIC,
                                     SEQUENCE_SEPARATRIX, SEQUENCE_UNDERFLOW)
from kernels.pendulum import dispatch
from kernels.pendulum.cases import CASE_COLUMNS, ROW, C
from kernels.pendulum.dispatch import (ATTRACTOR_OUTPUTS, INTEGRATOR_AUTO, INTEGRATOR_CLOSED,
                                       INTEGRATOR_DOP853, INTEGRATOR_DOPRI5, INTEGRATOR_RK4,
                                       USED_CLOSED, USED_DOP853, USED_DOPRI5, USED_RK4)
from kernels.pendulum.distinct import distinct_rows
from kernels.pendulum.free_flight import steady_state_speed
from kernels.pendulum.histories import (ACCELERATION, CYCLE_ANGLE, CYCLE_TIME, CYCLE_WORK,
                                       DRIVE_TORQUE, HINGE_ACROSS, HINGE_ALONG, HINGE_IMPULSE,
                                       IMPACT_LOSS, MEAN_TORQUE, N_HISTORY, N_LOADS,
                                       PEAK_HINGE, PEAK_TORQUE, RATE, ROTOR_ANGLE, SWING, TIME,
                                       driven_cycle, striker_geometry)
from kernels.pendulum.models import MODEL_PAPER, MODEL_ROTOR
from kernels.pendulum.table import (MODELS, SYSTEMS, TOOL_LAB_WINDOW, TOOL_ROTOR_STOP, TOOLS,
                                   with_closed_form)

#: meanings of the codes of the ``regime`` output (CF flag_meanings, in this order)
REGIMES = ("period_1", "period_n", "quasi_periodic", "escape", "chatter", "no_impact",
           "separatrix")
R_ = {name: code for code, name in enumerate(REGIMES)}
_ROTOR = {"model": ("rotor",)}


def _rules(given: dict) -> str | None:
    """The closed form exists for the constant-speed models on the rotor stop and for the
    rigid model's flights on the blade; the energy per blow needs the striker's mass."""
    needing_mass = next((name for name in given.get("outputs", ())
                         if name in ("blow_energy",) + LOAD_OUTPUTS), None)
    if needing_mass and "striker_mass" not in given:
        return f"striker_mass: required for the output {needing_mass}"
    models = given.get("model", {"paper"})
    tools = given.get("tool", {"rotor_stop"})
    if "closed_form" in given.get("method.integrator", ()) and not with_closed_form(models,
                                                                                  tools):
        having = ", ".join(f"{s.model} on {s.tool}" for s in SYSTEMS
                           if s.closed_form or s.exact_flow)
        return (f"method.integrator: \"closed_form\" exists only for {having}; allowed "
                "here: \"auto\", \"rk4\", \"dopri5\", \"dop853\"")
    if max(given.get("method.starts", {1})) > 1 and not given.get("outputs", set()) & set(
            ATTRACTOR_OUTPUTS):
        return ("method.starts: more than one start is used only with the outputs "
                "attractor_count or basin_fraction; add one to outputs, or omit starts")
    if "edge_margin" in given.get("outputs", ()) and "lab_window" not in tools:
        return ("outputs: edge_margin exists only with tool = \"lab_window\" (the rotor "
                "stop has no edge)")
    return None


#: the outputs of the steady cycle's loads (kernels/pendulum/histories.py): they need the
#: striker's mass
LOAD_OUTPUTS = ("hinge_force_peak", "hinge_impulse", "drive_torque_peak", "drive_torque_mean",
                "drive_power_mean", "energy_balance_error")


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
                 choices=MODELS, compiles_apart=True, label="model"),
        Quantity("k", "1", "length ratio l1/l2 (k)", "k", default=2.5, **POSITIVE,
                 label="length ratio $k$"),
        Quantity("xi", "1", "inertia ratio m l2^2/J_c (xi)", "ξ", default=4.0, **POSITIVE,
                 label=r"inertia ratio $\xi$"),
        Quantity("kappa", "1", "rigid and rotor models: contact radius over the "
                 "centre-of-percussion radius (kappa); default xi/(1 + xi), contact at the "
                 "striker's centre", "κ", used_when={"model": ("rigid", "rotor")},
                 **POSITIVE, label=r"contact radius $\kappa$"),
        Quantity("R", "1", "restitution coefficient of the striker on the tool (R)", "R",
                 default=0.0, minimum=0.0, maximum=1.0, max_inclusive=False,
                 label="restitution $R$"),
        Quantity("omega1", "rad s-1", "rotor angular speed (omega1)", "ω1", default=20.0,
                 **POSITIVE, label=r"rotor speed $\omega_1$"),
        Quantity("l2", "m", "pendulum length to the striker (l2)", "l2", default=0.04,
                 **POSITIVE, label="pendulum $l_2$"),
        Quantity("striker_mass", "kg", "the striker's mass (a body with its centre at l2 "
                 "where kappa is its default, at l2 xi/(kappa (1 + xi)) otherwise, and "
                 "centroidal inertia from xi), for the energy per blow and the loads",
                 "m_s", **POSITIVE, label="striker mass $m_s$"),
        Quantity("tool", "1", "impact condition: a stop on the rotor at psi = 0 "
                 "(rotor_stop, the paper's), or a blade fixed in the frame hit by the "
                 "striker when it reaches it with |psi| <= tool_window (lab_window)",
                 default="rotor_stop",
                 choices=TOOLS, compiles_apart=True, label="tool"),
        Quantity("tool_window", "rad", "lab_window: reach of the blade as the largest |psi| "
                 "at which the striker meets it (the blade's inner edge is at the striker "
                 "radius there)", default=0.2, minimum=0.0, maximum=math.pi / 2,
                 min_inclusive=False, used_when={"tool": ("lab_window",)}, label="blade reach"),
        Quantity("rotor_inertia_ratio", "1", "rotor model: rotor inertia over the striker's "
                 "centroidal inertia (J1/J_c)", "J1/J_c", default=100.0, minimum=0.0,
                 used_when=_ROTOR, label="rotor inertia $J_1/J_c$"),
        Quantity("motor_slope", "1", "rotor model: slope of the motor law tau_m = s_m "
                 "(Omega_idle - phi1') in J_c omega1 (s_m/(J_c omega1))", "s_m",
                 default=100.0, minimum=0.0, used_when=_ROTOR, label="motor slope $s_m$"),
        Quantity("idle_speed", "1", "rotor model: the motor's no-load speed over omega1 "
                 "(Omega_idle/omega1); the rotor starts at it", "Ω_idle/ω1", default=1.0,
                 used_when=_ROTOR, **POSITIVE, label=r"idle speed $\Omega/\omega_1$"),
    ),
    outputs=(
        Output("regime", "1", "steady regime of the impact motion",
               flags={name: code for code, name in enumerate(REGIMES)}
               | {"undetermined": -1}, undetermined="undetermined", everywhere=True,
               label="regime"),
        Output("amplitude", "rad", "amplitude of the relative swing (A)", "A",
               label="amplitude $A$"),
        Output("frequency_ratio", "1", "frequency coefficient n (psi ~ A sin(n omega1 t)), "
               "pi over the flight time; NaN on the lab blade, where flights end on the "
               "blade", "n", label="frequency ratio $n$"),
        Output("period", "s", "period of the free relative oscillation T = 2 pi/(n omega1)",
               "T", label="period $T$"),
        Output("impact_speed", "m s-1", "normal speed of the striker at impact in steady "
               "state (V* = 2 (1+k) omega1 l2/(1-R) on the rotor stop at constant speed)",
               "V*", label="impact speed $V^*$"),
        Output("impact_interval", "rad", "rotor angle between impacts in steady state "
               "(tau1; on the blade, between the impacts opening each contact)", "τ1",
               chart_units=("turn", 1.0 / (2.0 * math.pi)), label=r"impact interval $\tau_1$"),
        Output("impacts_to_converge", "1", "impacts from rest to the steady state (to "
               "1e-12 by the closed form, to 10 rtol when integrated; the rotor model on "
               "its stop: estimated past its extrapolated transient, within 3 impacts or "
               "35 %), or until escape", diagnostic=True, count=True, label="impacts to converge"),
        Output("acceleration_peak", "rad s-2", "peak relative angular acceleration of the "
               "pendulum in steady state", "|ψ''|max", label=r"peak $|\psi''|$"),
        Output("restitution_critical", "1", "largest R with a periodic impact regime "
               "(R_crit, closed-form models on the rotor stop); NaN if none exists or none "
               "is known", "R_crit", everywhere=True, label=r"critical $R_\mathrm{crit}$"),
        Output("rotor_speed_ratio", "1", "mean rotor speed over the steady cycle over "
               "omega1 (1 at constant rotor speed)", label="rotor speed ratio"),
        Output("n_steps", "1", "integration steps, accepted and rejected (0: closed form on "
               "the rotor stop; the rigid model's closed-form flights on the blade count "
               "their exact steps)",
               diagnostic=True, count=True, label="steps"),
        Output("n_rejected", "1", "rejected integration steps among n_steps",
               diagnostic=True, count=True, label="rejected steps"),
        Output("n_events", "1", "impact events located by the integrator", diagnostic=True,
               count=True, label="events"),
        Output("method_used", "1", "method that produced the values",
               flags={"closed_form": USED_CLOSED, "rk4": USED_RK4, "dopri5": USED_DOPRI5,
                      "dop853": USED_DOP853},
               everywhere=True, label="method"),
        Output("multiplier_modulus", "1", "largest modulus |mu| of the multipliers of the "
               "steady cycle's impact map (of its n-fold map for period_n; exact symmetries "
               "removed): below 1 the pattern is stable; R on the rotor stop at constant rotor "
               "speed; by the variational equations, the event-time saltation and Newton's "
               "law differentiated, through slides and accumulated chatter; NaN without a "
               "cycle", "|μ|",
               on_request=True, label=r"multiplier $|\mu|$"),
        Output("multiplier_angle", "rad", "argument of the leading multiplier in [0, pi]: "
               "near 0 as |mu| -> 1 a fold (the pattern vanishes), pi a period doubling, "
               "between a complex pair (quasi-periodic motion)", "arg μ", on_request=True,
               label=r"multiplier angle $\arg\mu$"),
        Output("stability_margin", "1", "1 - multiplier_modulus: how far the blow pattern is "
               "from losing stability (negative: unstable)", on_request=True,
               label=r"stability margin $1-|\mu|$"),
        Output("impact_speed_min_ratio", "1", "slowest impact of the steady cycle over its "
               "fastest (striker normal speeds, all contacts of the cycle): near 0 the "
               "pattern is one small change from chatter or grazing", on_request=True,
               label="slowest/fastest impact"),
        Output("edge_margin", "rad", "lab_window: the smallest distance window - |psi| of a "
               "steady-cycle impact from the blade's edge: near 0 a border collision (the "
               "impact slips past the edge)", on_request=True, label="edge margin"),
        Output("attractor_count", "1", "distinct steady states reached from method.starts "
               "starting states (rest, then a Halton sequence of arrival states): regime, "
               "period and section state equal to 1e-6; each non-periodic outcome counts "
               "as one", on_request=True, count=True, everywhere=True, label="attractors"),
        Output("basin_fraction", "1", "share of the starts that reach the steady state "
               "reported (the one reached from rest, the machine's start-up)",
               on_request=True, everywhere=True, label="basin fraction"),
        Output("error_estimate", "1", "auto: estimated relative error of the steady cycle's "
               "values (the largest over amplitude, frequency ratio, period, impact speed "
               "and interval, acceleration peak, rotor speed ratio, and where asked for the "
               "leading multiplier, impact_speed_min_ratio and edge_margin), from two "
               "DOPRI5 solves 8 times apart in rtol (the finer one going on from the "
               "other's cycle); 0 by the rotor stop's closed form "
               "(exact to round-off); on the blade's exact flights (auto, closed_form) the "
               "tolerance the cycle's section states repeat to (1e-9 at tol >= 1e-9); inf "
               "where the two solves reach different regimes; NaN with a fixed integrator "
               "or without a cycle",
               diagnostic=True, label="error estimate"),
        Output("blow_energy", "J", "energy per blow: striker_mass times the steady impact "
               "speed squared, over 2", "E_blow", on_request=True, label="blow energy $E$"),
        Output("blow_rate", "min-1", "blows per minute in steady state: 60 times the mean "
               "rotor speed over the rotor angle between impacts", on_request=True,
               label="blow rate"),
        Output("hinge_force_peak", "N", "peak force of the pendulum's hinge on the rotor over "
               "the steady cycle, the impacts' impulses apart (NaN on a cycle that "
               "slides along the blade or chatters)", "|Q|max", on_request=True,
               label=r"peak hinge force $|Q|_\max$"),
        Output("hinge_impulse", "N s", "largest impulse through the hinge on the rotor "
               "at an impact of the steady cycle: on the rotor stop zero where the "
               "contact is at the centre of percussion (kappa = 1), the paper's premise "
               "for a constant rotor speed",
               "S_Q", on_request=True, label="hinge impulse $S_Q$"),
        Output("drive_torque_peak", "N m", "peak |torque| of the rotor's drive over the "
               "steady cycle: at constant rotor speed the torque that holds it (dH_O/dt of "
               "the pendulum), its impulses at the impacts apart; the rotor model's motor "
               "torque", "|M_d|max", on_request=True, label=r"peak drive torque $|M_d|_\max$"),
        Output("drive_torque_mean", "N m", "mean torque of the rotor's drive over the steady "
               "cycle, the impacts' angular impulses included", "M̄_d", on_request=True,
               label=r"mean drive torque $\bar M_d$"),
        Output("drive_power_mean", "W", "mean power of the rotor's drive over the steady "
               "cycle: its work per cycle over the cycle's time", "P̄_d", on_request=True,
               label=r"mean drive power $\bar P_d$"),
        Output("energy_balance_error", "1", "the drive's work per steady cycle (its "
               "torque integrated along the cycle's history, with its angular impulses at "
               "the impacts at constant rotor speed) less the impacts' losses "
               "(1 - R^2) v_n^2/(2 J M^-1 J^T), over that loss: the history's own error",
               diagnostic=True, on_request=True, label="energy balance error"),
    ),
    profiles=(
        Output("time", "s", "time since the impact that opens the steady cycle", "t",
               label="time $t$"),
        Output("rotor_angle", "rad", "rotor angle turned since that impact (omega1 t)", "φ1",
               label=r"rotor angle $\varphi_1$"),
        Output("swing_angle", "rad", "relative angle of the pendulum (psi), 0 at the stop",
               "ψ", label=r"swing $\psi$"),
        Output("swing_rate", "rad s-1", "relative angular velocity of the pendulum (psi')",
               "ψ′", label=r"swing rate $\psi'$"),
        Output("swing_acceleration", "rad s-2", "relative angular acceleration of the "
               "pendulum (psi'')", "ψ″", label=r"swing acceleration $\psi''$"),
        Output("hinge_force_along", "N", "force of the pendulum's hinge on the rotor along "
               "the pendulum, positive outward from the hinge (needs striker_mass)", "Q_n",
               label="hinge force along $Q_n$"),
        Output("hinge_force_across", "N", "force of the pendulum's hinge on the rotor across "
               "the pendulum, positive towards increasing psi (needs striker_mass)", "Q_t",
               label="hinge force across $Q_t$"),
        Output("hinge_force", "N", "magnitude of the hinge's force on the rotor (needs "
               "striker_mass)", "|Q|", label="hinge force $|Q|$"),
        Output("drive_torque", "N m", "torque of the rotor's drive: at constant rotor speed "
               "the torque that holds it, for the rotor model its motor's (needs "
               "striker_mass)", "M_d", label="drive torque $M_d$"),
    ),
    profile_dim=Quantity("cycle_phase", "1", "phase of the steady cycle: 0 at an impact, 1 "
                         "at the next", "s", label="cycle phase $s$"),
    profile_coordinate=lambda method: cell_midpoints(method.profile_points, 1.0),
    status=("ok", "escape", "no_impact", "not_periodic", "separatrix", "max_steps",
            "step_underflow", "degenerate", "nonfinite"),
    method=(
        Quantity("integrator", "1", "auto (the closed form where the model has one: the "
                 "paper and rigid models on the rotor stop, the rigid model's flights on the "
                 "blade; else DOPRI5 to the cycle, and on from it 8 times finer in rtol, "
                 "the finer solve reported with its error_estimate and refined where that exceeds tol/10), "
                 "closed_form (only where there is one), rk4, dopri5 or dop853 (Dormand-Prince "
                 "8(5,3), for tight rtol)",
                 default="auto",
                 choices={"auto": INTEGRATOR_AUTO, "closed_form": INTEGRATOR_CLOSED,
                          "rk4": INTEGRATOR_RK4, "dopri5": INTEGRATOR_DOPRI5,
                          "dop853": INTEGRATOR_DOP853}),
        Quantity("rtol", "1", "dopri5 and dop853 relative tolerance", default=1e-10,
                 minimum=1e-14, maximum=1e-2, used_when={"integrator": ("dopri5", "dop853")}),
        Quantity("atol", "1", "dopri5 and dop853 absolute tolerance (rad, rad per rotor "
                 "radian)",
                 default=1e-12, minimum=1e-16, maximum=1e-2,
                 used_when={"integrator": ("dopri5", "dop853")}),
        Quantity("dt", "1", "rk4 step in rotor radians", default=0.002, minimum=1e-6,
                 maximum=0.5, used_when={"integrator": ("rk4",)}),
        Quantity("max_impacts", "1", "impacts simulated at most", default=1000, minimum=1,
                 maximum=10**6, integer=True),
        Quantity("tol", "1", "auto, and closed_form on the blade: relative accuracy "
                 "requested of the outputs", default=1e-8, minimum=1e-11, maximum=1e-2,
                 used_when={"integrator": ("auto", "closed_form")}),
        profile_points("phases of the steady cycle's time histories and loads ([RP] "
                       "Fig. 3; 0: none): every model on either tool, any period (NaN on a "
                       "cycle that slides along the blade or chatters)"),
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
    rows = dispatch.solve_cases(cases, method)
    d = rows[index].T
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
    prof, loads = histories(cases, rows, index, status, p, method)
    if set(asked) & set(LOAD_OUTPUTS):
        out[O.hinge_force_peak] = loads[PEAK_HINGE]
        out[O.hinge_impulse] = loads[HINGE_IMPULSE]
        out[O.drive_torque_peak] = loads[PEAK_TORQUE]
        out[O.drive_torque_mean] = loads[MEAN_TORQUE]
        out[O.drive_power_mean] = loads[CYCLE_WORK] / loads[CYCLE_TIME]
        out[O.energy_balance_error] = (loads[CYCLE_WORK] - loads[IMPACT_LOSS]) / loads[IMPACT_LOSS]
    else:
        out[[getattr(O, name) for name in LOAD_OUTPUTS]] = np.nan
    return out, status, prof


#: the profiles' rows
H = DECLARATION.profile_index


def histories(cases, rows, index, status, p, method):
    """The steady cycle's time histories (profiles[rows, n, phases]) and loads
    (loads[histories.N_LOADS, n], SI) where they are asked for (profile points, a load
    output) and exist: a steady cycle without a chatter, the constant-speed models' on the
    rotor stop from the closed form's v* (kernels/pendulum/histories.py), the others from
    their row's section state, slides included (kernels/pendulum/cycle_walk.py), solved
    once per case in omega1, l2 and striker-mass units and rescaled. NaN elsewhere, and the
    forces without striker_mass."""
    phases = DECLARATION.profile_coordinate(method)
    prof = np.full((len(DECLARATION.profiles), index.shape[0], phases.shape[0]), np.nan)
    loads = np.full((N_LOADS, index.shape[0]), np.nan)
    if phases.shape[0] == 0 and not set(method.outputs) & set(LOAD_OUTPUTS):
        return prof, loads
    each = np.full((cases.shape[0], N_HISTORY, phases.shape[0]), np.nan)
    each_loads = np.full((cases.shape[0], N_LOADS), np.nan)
    cycle = (rows[:, ROW.outcome] == SEQUENCE_CYCLE) & (rows[:, ROW.chatter] == 0)
    closed = ((cases[:, C.tool] == TOOL_ROTOR_STOP) & (cases[:, C.model] != MODEL_ROTOR)
              & (rows[:, ROW.period] == 1))
    for c in np.flatnonzero(cycle & closed):
        case, row = cases[c], rows[c]
        model, k, r = int(case[C.model]), case[C.k], case[C.R]
        second = case[C.xi] if model == MODEL_PAPER else case[C.kappa]
        driven_cycle(model, k, second, r, striker_geometry(k, case[C.xi], case[C.kappa]),
                     steady_state_speed(k, r), row[ROW.interval], phases, each[c],
                     each_loads[c])
    integrated = np.flatnonzero(cycle & ~closed)
    if integrated.size:
        from kernels.impact.runge_kutta import METHOD_DOPRI5
        from kernels.pendulum.cycle_walk import CYCLE_WALKS, HISTORY_TOL
        from kernels.pendulum.systems import settings_for
        from kernels.pendulum.table import BY_CODES
        settings = {s: settings_for(s, METHOD_DOPRI5, HISTORY_TOL, HISTORY_TOL, 1e-3,
                                    method.max_impacts) for s in SYSTEMS}
    for c in integrated:
        case, row = cases[c], rows[c]
        system = BY_CODES[int(case[C.model]), int(case[C.tool])]
        key = (row[ROW.section_0], row[ROW.section_1], row[ROW.section_2])
        CYCLE_WALKS[system,](case, key, int(row[ROW.period]), case[C.R], settings[system],
                            striker_geometry(case[C.k], case[C.xi], case[C.kappa]), phases,
                            each[c], each_loads[c])
    w, l2, mass = np.abs(p["omega1"]), p["l2"], p["striker_mass"]
    force, torque = mass * l2 * w * w, mass * l2 * l2 * w * w
    usable = status == S.ok
    history = np.where(usable[:, None, None], each[index], np.nan)
    for name, row, scale in (("swing_angle", SWING, 1.0), ("swing_rate", RATE, w),
                             ("swing_acceleration", ACCELERATION, w * w),
                             ("time", TIME, 1.0 / w), ("rotor_angle", ROTOR_ANGLE, 1.0),
                             ("hinge_force_along", HINGE_ALONG, force),
                             ("hinge_force_across", HINGE_ACROSS, force),
                             ("drive_torque", DRIVE_TORQUE, torque)):
        prof[getattr(H, name)] = history[:, row] * np.broadcast_to(scale, w.shape)[:, None]
    prof[H.hinge_force] = np.hypot(prof[H.hinge_force_along], prof[H.hinge_force_across])
    summary = np.where(usable[:, None], each_loads[index], np.nan).T
    for slot, scale in ((PEAK_HINGE, force), (PEAK_TORQUE, torque),
                        (HINGE_IMPULSE, mass * l2 * w), (MEAN_TORQUE, torque),
                        (CYCLE_WORK, torque), (IMPACT_LOSS, torque), (CYCLE_TIME, 1.0 / w)):
        loads[slot] = summary[slot] * scale
    loads[CYCLE_ANGLE] = summary[CYCLE_ANGLE]
    return prof, loads

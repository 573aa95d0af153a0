"""The crank-driven impact machine (``impact_machine``): the impact four-bar of [CR] driven by
a motor through a crank with a flywheel, the crank's own dynamics between blows and the
blow at the special position (docs/machine.md, derived: no paper gives it).

One degree of freedom, the crank angle phi1, between blows: the reduced inertia J(phi1) of
the crank, flywheel, coupler and rocker, a motor law M(omega1), gravity and a conservative
load on the rocker as generalised forces Q(phi1). The machine cycle is the open interval
(phi1*, phi1* + 2 pi) on the impact branch, where every kinematic quantity is smooth and has
one-sided limits at both ends; the one-sided rocker ratio u31 is evaluated in a
desingularised closed form that is regular at both ends (the vanishing factor of P or Q set
to zero, sin phi1 / sqrt(PQ) cancelled analytically), its derivative by a complex step.

Between blows the revolution is integrated on the integration core
(kernels/impact/flight.py) with the crank angle as the independent variable and the
kinetic energy T = J omega1^2 / 2 as the state: dT/dphi1 = M(omega1) + Q(phi1), with the
time and the works of the motor, gravity and the load as quadratures. The blow is the end of
the interval; a stall (T reaching 0) and the speed extrema (d omega1/dphi1 = 0) are events.
At the blow the generalised Newton impact (law G): the tool's impulse with Newton's law on
the rocker, then a plastic capture onto the departure branch with the one-sided inertias;
it never gains energy. The kinematic law (law S: the rocker reverses with -R and the crank
follows the departure branch) is there for comparison; it can create energy.

The periodic steady state is the fixed point of the section map after the blow, found by
the secant method from the constant-speed guess (a running machine), or from rest by plain
revolutions first (the run-up; a motor that cannot start the machine stalls).
"""

import cmath
import math
from collections import namedtuple
from dataclasses import replace

import numpy as np
from numba import njit

from kernels import INLINE_OPTIONS, INNER_OPTIONS, KERNEL_OPTIONS
from kernels import kinetostatics as _ks
from kernels.crank_rocker import DECLARATION as _CR
from kernels.crank_rocker import _TYPES, ROOT_LARGER_BASE, ROOT_SMALLER_BASE, TYPE_GENERAL
from kernels.crank_rocker import S as LINKAGE
from kernels.crank_rocker import _point as linkage_point
from kernels.declaration import POSITIVE, Mechanism, Output, Quantity, geometry_tol
from kernels.extrema import CLUSTER, cell_midpoints, clustered_points, peak_search
from kernels.fourbar import CHANGE_POINT_C, closure_vectors
from kernels.impact import System
from kernels.impact.flight import make_flight, make_timed_flight
from kernels.impact.outcomes import (FLIGHT_EVENT, FLIGHT_MAX_STEPS, FLIGHT_UNDERFLOW,
                                     Settings)
from kernels.impact.runge_kutta import METHOD_DOPRI5
from kernels.impact.tuples import relative_scales

LAW_GENERALIZED, LAW_KINEMATIC = 0, 1
MOTOR_LINEAR, MOTOR_CONSTANT = 0, 1
START_RUNNING, START_REST = 0, 1
MATERIAL = -1.0  # design_restitution = "material": the synthesis makes Rk = -R
FOR_DELTA = -1.0  # flywheel_inertia = "for_delta_target": sized for method.delta_target

# defaults: the test machine (docs/machine.md §3): [CR] Table 1 at lambda2 = 2.5, type a,
# R = 0.3, crank 0.1 m, tilt 25 degrees, the kinetostatic test mechanism's links
_NONNEG = dict(minimum=0.0)
LINK_MASSES = ("m1", "m2", "m3", "s1", "s2", "s3", "q1", "q2", "q3", "J1", "J2", "J3")
_LINEAR = {"motor_law": ("linear",)}
_WINDOWED = ("outside |phi1 - phi1*| < special_window (the rigid model's reactions grow "
             "like 1/dphi1 at the node); sampled at peak_samples crank angles, the largest "
             "refined by golden section")

FLYWHEEL_OUTPUTS = ("flywheel_for_delta", "flywheel_for_delta_classical")


def _rules(given: dict) -> str | None:
    """The geometry's inputs per type; the flywheel outputs need the generalised law (the
    kinematic law fixes the crank's speed ratio at the blow at -R/Rk: no flywheel smooths
    it)."""
    types = given.get("type", {"a"})
    ratios = [name for name in ("lambda0", "lambda2", "lambda3") if name in given]
    if "general" in types and len(ratios) < 3:
        missing = [n for n in ("lambda0", "lambda2", "lambda3") if n not in ratios]
        return f"{missing[0]}: required for type general (lambda0, lambda2 and lambda3)"
    if (given.get("outputs", set()) & set(FLYWHEEL_OUTPUTS)
            or "for_delta_target" in given.get("flywheel_inertia", ())) and "kinematic" in \
            given.get("impact_law", ()):
        return ("outputs: the flywheel outputs need impact_law = \"generalized\"; the "
                "kinematic law fixes the crank's speed ratio at the blow (-R/Rk), so no "
                "flywheel holds a speed fluctuation")
    return None


DECLARATION = Mechanism(
    name="impact_machine",
    title="Crank-driven impact machine: energy per blow, motor, flywheel",
    summary="one degree of freedom between blows (reduced inertia J(phi1), motor law, "
            "gravity and a conservative rocker load), integrated by DOPRI5 on the crank "
            "angle with the kinetic energy as state; the blow by the generalised Newton "
            "impact at the node (tool impulse with Newton's law, plastic capture onto the "
            "departure branch with the one-sided inertias); the periodic steady state by "
            "the secant method on the section after the blow",
    references="derived (docs/machine.md) on the crank-rocker impact four-bars of "
               "'Crank-rocker impact mechanisms with the largest connecting rod and the "
               "largest base' (in Russian), Institute of Machine Science, National Academy "
               "of Sciences of the Kyrgyz Republic",
    parameters=(
        # the linkage is crank_rocker's: its type and largest link, declared there once
        _CR.parameter("type"),
        replace(_CR.parameter("largest_link"), default=2.5),
        Quantity("base_root", "1", "type b: which root of the synthesis quadratic is the "
                 "base", default="smaller",
                 choices={"smaller": ROOT_SMALLER_BASE, "larger": ROOT_LARGER_BASE},
                 used_when={"type": ("b",)}),
        Quantity("lambda0", "1", "base ratio l0/l1 (type general)", "λ0",
                 used_when={"type": ("general",)}, **POSITIVE),
        Quantity("lambda2", "1", "coupler ratio l2/l1 (type general)", "λ2",
                 used_when={"type": ("general",)}, **POSITIVE),
        Quantity("lambda3", "1", "rocker ratio l3/l1 (type general)", "λ3",
                 used_when={"type": ("general",)}, **POSITIVE),
        Quantity("design_restitution", "1", "restitution the linkage is synthesised for "
                 "(Rk = -design_restitution); \"material\": the worked material's R",
                 "R_d", default="material", minimum=0.0, maximum=1.0, min_inclusive=False,
                 max_inclusive=False, aliases={"material": MATERIAL},
                 used_when={"type": _TYPES}),
        Quantity("R", "1", "restitution coefficient of the worked material (R): Newton's "
                 "law at the tool", "R", default=0.3, minimum=0.0, maximum=1.0),
        Quantity("crank_length", "m", "crank length (l1)", "l1", default=0.1, **POSITIVE),
        # the link masses, centroids and inertias are linkage_forces', declared there once
        *(_ks.DECLARATION.parameter(name) for name in LINK_MASSES),
        Quantity("flywheel_inertia", "kg m2", "flywheel on the crank shaft (J_f); "
                 "\"for_delta_target\": the flywheel that holds the speed fluctuation at "
                 "method.delta_target (its exact root)", "J_f", default=5.0,
                 aliases={"for_delta_target": FOR_DELTA}, **_NONNEG),
        Quantity("motor_law", "1", "motor torque-speed law: linear M0 (1 - omega1/"
                 "omega_idle), or constant M0", default="linear",
                 choices={"linear": MOTOR_LINEAR, "constant": MOTOR_CONSTANT}),
        Quantity("stall_torque", "N m", "motor torque at zero speed (M0)", "M0",
                 default=1200.0, **POSITIVE),
        Quantity("idle_speed", "rad s-1", "motor speed at zero torque (omega_idle)", "ω_idle",
                 default=32.0, used_when=_LINEAR, **POSITIVE),
        Quantity("tilt", "rad", "inclination of the base AD to the horizontal", "θ",
                 default=math.radians(25.0), minimum=-math.pi, maximum=math.pi),
        Quantity("g", "m s-2", "gravitational acceleration", "g", default=9.81, **_NONNEG),
        Quantity("load_force_x", "N", "load on the rocker, along the base A->D (fixed in "
                 "the base frame: conservative)", default=0.0),
        Quantity("load_force_y", "N", "load on the rocker, across the base", default=0.0),
        Quantity("load_arm", "m", "load point on the rocker: distance from D along D->C",
                 default=0.0),
        Quantity("load_offset", "m", "load point on the rocker: offset across the rocker",
                 default=0.0),
        Quantity("load_moment", "N m", "couple on the rocker (counter-clockwise)",
                 default=0.0),
        Quantity("impact_law", "1", "the blow: generalised Newton impact (energy-"
                 "consistent), or the kinematic law (comparison only: it can create "
                 "energy)", default="generalized",
                 choices={"generalized": LAW_GENERALIZED, "kinematic": LAW_KINEMATIC}),
    ),
    outputs=(
        Output("flywheel_inertia", "kg m2", "the flywheel, given or sized for "
               "method.delta_target", "J_f", echoes="flywheel_inertia"),
        Output("mean_crank_speed", "rad s-1", "time-mean crank speed over the steady "
               "cycle (2 pi / T_c)", "ω_mean"),
        Output("speed_fluctuation", "1", "coefficient of speed fluctuation (omega_max - "
               "omega_min)/omega_mean, the one-sided speeds at the blow included", "δ"),
        Output("crank_speed_before_blow", "rad s-1", "crank speed just before the blow",
               "ω1⁻"),
        Output("crank_speed_after_blow", "rad s-1", "crank speed just after the blow",
               "ω1⁺"),
        Output("crank_speed_jump", "rad s-1", "crank speed change at the blow", "Δω1"),
        Output("tool_impulse", "N m s", "angular impulse of the tool on the rocker about D",
               "Π"),
        Output("crank_impulse", "N m s", "angular impulse into the crank and flywheel at "
               "the blow (J_A Delta omega1): the blow's load on the drive", "H_crank"),
        Output("motor_torque_peak", "N m", "largest |motor torque| over the cycle",
               "M_peak"),
        Output("motor_torque_rms", "N m", "RMS motor torque over the cycle", "M_rms"),
        Output("motor_power_mean", "W", "mean motor power (motor work per cycle / T_c)",
               "P_mean"),
        Output("blow_energy", "J", "energy per blow: the striker's (rocker's) kinetic "
               "energy just before it", "E_striker"),
        Output("blow_loss", "J", "kinetic energy lost at the blow", "ΔE"),
        Output("energy_to_material", "J", "energy delivered to the worked material "
               "((1 - R^2) m_r omega3^2 / 2)", "ΔE_tool"),
        Output("capture_loss", "J", "parasitic loss in the linkage at the blow (the "
               "plastic capture onto the departure branch)", "ΔE_capture"),
        Output("blow_rate", "min-1", "blows per minute (60 / T_c)"),
        Output("blow_efficiency", "1", "share of the motor's work per cycle that reaches "
               "the worked material", "η_blow"),
        Output("cycle_period", "s", "time between blows in the steady cycle", "T_c"),
        Output("impact_speed", "m s-1", "rocker tip speed at the blow (|u31- omega1-| l3)"),
        Output("restitution_kinematic", "1", "kinematic restitution of the linkage "
               "(u31 after / u31 before the node)", "Rk"),
        Output("restitution_mismatch", "1", "Rk + R: zero where the linkage is matched to "
               "the material", "Rk + R"),
        Output("reduced_inertia_before", "kg m2", "reduced inertia about the crank just "
               "before the blow", "J⁻"),
        Output("reduced_inertia_after", "kg m2", "reduced inertia about the crank just "
               "after the blow", "J⁺"),
        Output("energy_balance_residual", "1", "(motor work + gravity + load - blow "
               "loss) / blow loss over the steady cycle", diagnostic=True),
        Output("revolutions", "1", "revolutions flown to find the steady state",
               diagnostic=True, count=True),
        Output("n_steps", "1", "integration steps, accepted and rejected", diagnostic=True,
               count=True),
        Output("dynamic_force_peak_A", "N", "peak |F14| at the crank pivot A over the "
               "steady cycle, at the actual crank speed and acceleration", "|F14|max",
               _WINDOWED, on_request=True),
        Output("dynamic_force_peak_B", "N", "peak |F21| at the crank pin B over the "
               "steady cycle, at the actual crank speed and acceleration", "|F21|max",
               _WINDOWED, on_request=True),
        Output("dynamic_force_peak_C", "N", "peak |F32| at the coupler-rocker joint C "
               "over the steady cycle, at the actual crank speed and acceleration",
               "|F32|max", _WINDOWED, on_request=True),
        Output("dynamic_force_peak_D", "N", "peak |F34| at the rocker pivot D over the "
               "steady cycle, at the actual crank speed and acceleration", "|F34|max",
               _WINDOWED, on_request=True),
        Output("flywheel_for_delta", "kg m2", "flywheel that holds the speed fluctuation "
               "at method.delta_target (the exact root of delta(J_f) = target)", "J_f(δ)",
               on_request=True),
        Output("flywheel_for_delta_classical", "kg m2", "the same by the classical energy "
               "method at constant mean speed", "J_f(δ) classical", on_request=True),
    ),
    profiles=(
        Output("crank_speed", "rad s-1", "crank speed over the steady cycle", "ω1"),
        Output("crank_acceleration", "rad s-2", "crank angular acceleration over the "
               "steady cycle", "ε1"),
        Output("motor_torque", "N m", "motor torque over the steady cycle", "M"),
        Output("shaft_torque", "N m", "torque the crank shaft delivers to the linkage, "
               "motor torque - J_A epsilon1 (the kinetostatic balancing moment of the "
               "linkage at the actual speed and acceleration)", "M - J_A ε1"),
    ),
    profile_dim=Quantity("angle_after_blow", "rad", "crank angle after the blow "
                         "(phi1 - phi1*), over the open cycle", "φ1 - φ1*"),
    profile_coordinate=lambda method: cell_midpoints(method.profile_points, 2.0 * np.pi),
    status=("ok", "not_assemblable", "no_real_synthesis", "degenerate", "no_impact",
            "stalls", "reverses", "singular_inertia", "too_slow", "no_convergence",
            "max_steps", "step_underflow", "nonfinite"),
    rules=_rules,
    method=(
        Quantity("tol", "1", "relative tolerance of the revolution's integration (DOPRI5 "
                 "rtol = atol on the scaled state)", default=1e-10, minimum=1e-14,
                 maximum=1e-4),
        Quantity("start", "1", "the machine running (the steady state from the constant-"
                 "speed guess), or started from rest (a run-up first: a motor that cannot "
                 "start it stalls)", default="running",
                 choices={"running": START_RUNNING, "rest": START_REST}),
        Quantity("max_revolutions", "1", "revolutions flown at most to find the steady "
                 "state", default=80, minimum=4, maximum=100000, integer=True),
        Quantity("delta_target", "1", "speed fluctuation the flywheel outputs size for",
                 "δ_target", default=0.02, minimum=1e-6, maximum=1.0,
                 min_inclusive=False, max_inclusive=False),
        Quantity("special_window", "rad", "half-width of the window around the node "
                 "excluded from the dynamic force peaks", "δ", default=0.01, minimum=0.0,
                 maximum=0.5, min_inclusive=False),
        Quantity("peak_samples", "1", "crank angles sampled to find each dynamic force "
                 "peak, then refined", default=361, minimum=3, maximum=10**6, integer=True),
        Quantity("profile_points", "1", "crank angles of the profiles over the steady "
                 "cycle (0: no profiles)", default=0, minimum=0, maximum=100000,
                 integer=True),
        geometry_tol("the synthesis's change point"),
    ),
)
P = DECLARATION.parameter_index
O = DECLARATION.output_index
F = DECLARATION.profile_index
S = DECLARATION.status_codes

#: the steady state: the section map's residual |Phi(w) - w| <= FIXED_POINT_TOL w
FIXED_POINT_TOL = 1e-11
#: a stall: the scaled kinetic energy falling through this (T = 0 itself has no crossing)
STALL_LEVEL = 1e-13
#: complex-step width for u31' (no cancellation: any small step is exact to round-off)
COMPLEX_STEP = 1e-30
#: the first crank angle of a start from rest, flown in closed form [rad]
RESTART_ANGLE = 1e-10
#: run-up revolutions from rest before the secant takes over
RUNUP_REVOLUTIONS = 12
#: a revolution longer than this many reference periods is too slow to be a machine
TOO_SLOW = 1e6

# ---------------------------------------------------------------------------------------
# the machine's data, as one flat tuple ``m`` (indices below)
(M_L0, M_L1, M_L2, M_L3, M_SIGMA, M_KIND, M_START, M_JA, M_M2L1, M_P2, M_Q2, M_JB2, M_JD3,
 M_M1, M_P1, M_Q1, M_M2, M_M3, M_P3, M_Q3, M_GX, M_GY, M_FX, M_FY, M_ARM, M_OFFSET,
 M_MOMENT, M_MOTOR, M_M0, M_IDLE, M_SNAP, M_TREF, M_WREF) = range(33)
NO_DATA = (math.nan,) * 33  # the data of a design that has no machine


@njit(**INNER_OPTIONS)
def u31_on_cycle(sh, ch, m):
    """The rocker ratio u31 on the closed cycle, regular at both ends (docs/machine.md
    §1.1): the stable closed form with the vanishing factor of P or Q exactly 0 and
    sin phi1 / sqrt(PQ) cancelled: s cos(phi1/2)/(sqrt(P) sqrt(l0 l1)) for types a, b
    (s = +1 on (0, 2 pi)), s sin(phi1/2)/(sqrt(Q) sqrt(l0 l1)) for c (s = -1 on (pi, 3 pi)).
    sh, ch: sin and cos of phi1/2 as complex numbers (a complex step gives u31')."""
    l0, l1, l2, l3 = m[M_L0], m[M_L1], m[M_L2], m[M_L3]
    four = 4.0 * l0 * l1
    d2 = (l0 - l1) * (l0 - l1) + four * sh * sh
    c1 = (ch - sh) * (ch + sh)
    root = math.sqrt(l0 * l1)
    if m[M_KIND] == CHANGE_POINT_C:
        q = _factor_q(m) + four * sh * sh
        ratio = -sh / (cmath.sqrt(q) * root)
    else:
        p = _factor_p(m) + four * ch * ch
        ratio = ch / (cmath.sqrt(p) * root)
    return (l1 * (l1 - l0 * c1) / d2
            - m[M_SIGMA] * l0 * l1 * (d2 + l2 * l2 - l3 * l3) / d2 * ratio)


@njit(**INLINE_OPTIONS)
def _factor_p(m):
    """The constant part of P, exactly 0 for type c: (l2 + l3 - l0 - l1)(l0 + l1 + l2 + l3)."""
    if m[M_KIND] == CHANGE_POINT_C:
        return 0.0
    l0, l1, l2, l3 = m[M_L0], m[M_L1], m[M_L2], m[M_L3]
    return (l2 + l3 - l0 - l1) * (l2 + l3 + l0 + l1)


@njit(**INLINE_OPTIONS)
def _factor_q(m):
    """The constant part of Q, exactly 0 for types a and b."""
    if m[M_KIND] != CHANGE_POINT_C:
        return 0.0
    l0, l1, l2, l3 = m[M_L0], m[M_L1], m[M_L2], m[M_L3]
    return (l0 - l1 - l2 + l3) * (l0 - l1 + l2 - l3)


@njit(**INNER_OPTIONS)
def kinematics(phi, m):
    """The linkage on the closed cycle at crank angle phi: (c1, s1, c2, s2, c3, s3, u21,
    u31, u21', u31'), regular at both ends (docs/machine.md §1.1): u31 desingularised, u31'
    by a complex step, u21 and u21' from the loop's real part (no division by
    sin(phi3 - phi2))."""
    l1, l2, l3 = m[M_L1], m[M_L2], m[M_L3]
    sh, ch = math.sin(0.5 * phi), math.cos(0.5 * phi)
    c1, s1, c2, s2, c3, s3, d2, root = closure_vectors(sh, ch, m[M_L0], l1, l2, l3,
                                                       m[M_SIGMA], m[M_SNAP])
    # one complex evaluation gives both: f(x + ih) = f(x) + ih f'(x) + O(h^2)
    z = complex(0.5 * phi, 0.5 * COMPLEX_STEP)
    value = u31_on_cycle(cmath.sin(z), cmath.cos(z), m)
    u31, du31 = value.real, value.imag / COMPLEX_STEP
    c32, s32 = c3 * c2 + s3 * s2, s3 * c2 - c3 * s2  # cos, sin of phi3 - phi2
    c12, s12 = c1 * c2 + s1 * s2, s1 * c2 - c1 * s2  # cos, sin of phi1 - phi2
    u21 = (l3 * u31 * c32 - l1 * c12) / l2
    du21 = (l3 * du31 * c32 - l3 * u31 * s32 * (u31 - u21) + l1 * s12 * (1.0 - u21)) / l2
    return c1, s1, c2, s2, c3, s3, u21, u31, du21, du31


@njit(**INNER_OPTIONS)
def reduced(phi, m):
    """(J, J', Q, u31) at crank angle phi: the reduced inertia about the crank and its
    derivative, the generalised force of gravity and the load (docs/machine.md §1.1-1.2)."""
    c1, s1, c2, s2, c3, s3, u21, u31, du21, du31 = kinematics(phi, m)
    l1 = m[M_L1]
    c12, s12 = c1 * c2 + s1 * s2, s1 * c2 - c1 * s2
    p2, q2 = m[M_P2], m[M_Q2]
    c21 = p2 * c12 + q2 * s12  # (AB . rho2) / l1
    dc21 = (p2 * s12 - q2 * c12) * (u21 - 1.0)
    jb2, jd3, m2l1 = m[M_JB2], m[M_JD3], m[M_M2L1]
    j = (m[M_JA] + m2l1 * l1 + 2.0 * m2l1 * c21 * u21 + jb2 * u21 * u21
         + jd3 * u31 * u31)
    dj = (2.0 * m2l1 * (dc21 * u21 + c21 * du21) + 2.0 * jb2 * u21 * du21
          + 2.0 * jd3 * u31 * du31)
    return j, dj, generalized_force(c1, s1, c2, s2, c3, s3, u21, u31, m), u31


@njit(**INNER_OPTIONS)
def generalized_force(c1, s1, c2, s2, c3, s3, u21, u31, m):
    """Q = Q_g + Q_ext: sum of m_i g . dr_Si/dphi1 and u31 (F . k x rho_P + M_ext)."""
    gx, gy = m[M_GX], m[M_GY]
    p1, q1, p2, q2, p3, q3 = m[M_P1], m[M_Q1], m[M_P2], m[M_Q2], m[M_P3], m[M_Q3]
    l1 = m[M_L1]
    r1x, r1y = p1 * c1 - q1 * s1, p1 * s1 + q1 * c1
    r2x, r2y = p2 * c2 - q2 * s2, p2 * s2 + q2 * c2
    r3x, r3y = p3 * c3 - q3 * s3, p3 * s3 + q3 * c3
    d2x, d2y = -l1 * s1 - u21 * r2y, l1 * c1 + u21 * r2x
    qg = (m[M_M1] * (-gx * r1y + gy * r1x) + m[M_M2] * (gx * d2x + gy * d2y)
          + m[M_M3] * u31 * (-gx * r3y + gy * r3x))
    arm, off = m[M_ARM], m[M_OFFSET]
    rpx, rpy = arm * c3 - off * s3, arm * s3 + off * c3
    qe = u31 * (-m[M_FX] * rpy + m[M_FY] * rpx + m[M_MOMENT])
    return qg + qe


@njit(**INLINE_OPTIONS)
def motor_torque(w, m):
    if m[M_MOTOR] == MOTOR_CONSTANT:
        return m[M_M0]
    return m[M_M0] * (1.0 - w / m[M_IDLE])


# ---------------------------------------------------------------------------------------
# the revolution between blows on the integration core: independent variable phi1,
# state y = (phi1, T, t, W_motor, int M^2 dt, W_Q) scaled by T_ref and 1/omega_ref

@njit(**INLINE_OPTIONS)
def _speed(y, j, m):
    """omega1 from the scaled kinetic energy (0 at or below rest)."""
    return math.sqrt(max(2.0 * y[1] * m[M_TREF] / j, 0.0))


@njit(**INNER_OPTIONS)
def revolution_rhs(y, m):
    j, dj, q, u31 = reduced(y[0], m)
    w = _speed(y, j, m)
    torque = motor_torque(w, m)
    tref, wref = m[M_TREF], m[M_WREF]
    inv_w = 1.0 / w if w > 0.0 else math.inf
    return (1.0, (torque + q) / tref, wref * inv_w, torque / tref,
            torque * torque * inv_w / (tref * wref), q / tref)


@njit(**INLINE_OPTIONS)
def _speed_slope(y, m):
    """d omega1/dphi1 up to the positive factor 1/(J omega1): M + Q - J' omega1^2 / 2."""
    j, dj, q, u31 = reduced(y[0], m)
    w = _speed(y, j, m)
    return motor_torque(w, m) + q - 0.5 * dj * w * w


@njit(**INLINE_OPTIONS)
def revolution_values(t, y, data):
    """Events: 0 the blow (phi1 reaches the end of the cycle), 1 a stall (T falls to 0),
    2 the next speed extremum: d omega1/dphi1 through 0, its sign in data flipped at each
    (so that the extremum just passed is not found again at the restart)."""
    end, m, w_min, w_max, sign = data
    return t - end, y[1] - STALL_LEVEL, sign * _speed_slope(y, m)


@njit(**INLINE_OPTIONS)
def revolution_rates(t, y, dy, data):
    return 1.0, dy[1], math.nan


@njit(**INLINE_OPTIONS)
def revolution_on_event(e, t, y, f, data, p):
    """The blow and a stall end the revolution; a speed extremum is kept and passed."""
    if e <= 1:
        return True, data
    end, m, w_min, w_max, sign = data
    w = _speed(y, reduced(y[0], m)[0], m)
    return False, (end, m, min(w_min, w), max(w_max, w), -sign)


@njit(**INLINE_OPTIONS)
def revolution_start(t, y, f, data, p):
    return 0.0, 0.0


@njit(**INLINE_OPTIONS)
def revolution_monitor(t, y, f):
    return 0.0, 0.0, 0.0


@njit(**INLINE_OPTIONS)
def revolution_scales(y0, y1, rtol, atol):
    return relative_scales(y0, y1, rtol, atol)


REVOLUTION = System(revolution_rhs, revolution_scales, revolution_values, revolution_rates,
                    (1, -1, -1), revolution_on_event, revolution_start,
                    revolution_monitor)
fly_revolution, _ = make_flight(REVOLUTION)
timed_revolution = make_timed_flight(revolution_rhs, revolution_scales)


# ---------------------------------------------------------------------------------------
# the blow at the node (docs/machine.md §2)

@njit(**INNER_OPTIONS)
def node(m):
    """The node's inertias: the one-sided tangents T- = (1, u21-, u31-) at the cycle's end
    and T+ at its start, J- = T-' M3 T-, J+ = T+' M3 T+, the cross inertia J+- = T+' M3 T-,
    and in the velocity coordinates (omega1, omega3) of the node's two-dimensional space the
    form's entries M11, M13, M33 and m_r = M33 - M13^2/M11 (the rocker's inertia about D
    with the crank free). Returns (J-, J+, J+-, m_r, u31-, u31+, u21-, u21+, M11, M13, M33,
    c21)."""
    start = m[M_START]
    cb, sb, c2b, s2b, c3b, s3b, u21m, u31m, _, _ = kinematics(start + 2.0 * math.pi, m)
    ca, sa, c2a, s2a, c3a, s3a, u21p, u31p, _, _ = kinematics(start, m)
    l1, ja, m2l1, jb2, jd3 = m[M_L1], m[M_JA], m[M_M2L1], m[M_JB2], m[M_JD3]
    c12, s12 = ca * c2a + sa * s2a, sa * c2a - ca * s2a
    c21 = m[M_P2] * c12 + m[M_Q2] * s12
    a11, a12 = ja + m2l1 * l1, m2l1 * c21  # M3 = [[a11, a12, 0], [a12, jb2, 0], [0, 0, jd3]]

    def form(x1, x2, x3, y1, y2, y3):
        return a11 * x1 * y1 + a12 * (x1 * y2 + x2 * y1) + jb2 * x2 * y2 + jd3 * x3 * y3

    jm = form(1.0, u21m, u31m, 1.0, u21m, u31m)
    jp = form(1.0, u21p, u31p, 1.0, u21p, u31p)
    jpm = form(1.0, u21p, u31p, 1.0, u21m, u31m)
    b = (u21p - u21m) / (u31p - u31m)  # omega2 = a omega1 + b omega3 on the node's plane
    a = u21m - b * u31m
    m11 = form(1.0, a, 0.0, 1.0, a, 0.0)
    m13 = form(1.0, a, 0.0, 0.0, b, 1.0)
    m33 = form(0.0, b, 1.0, 0.0, b, 1.0)
    mr = m33 - m13 * m13 / m11 if m11 > 0.0 else m33
    return jm, jp, jpm, mr, u31m, u31p, u21m, u21p, m11, m13, m33, c21


@njit(**INNER_OPTIONS)
def blow(w_minus, r, law, nd, m):
    """The blow at crank speed w_minus: (w_plus, tool impulse Pi, loss dE, energy to the
    material dE_tool, capture loss dE_capture). Law G: Pi = -(1 + R) m_r omega3- from
    Newton's law on the rocker, then J+ omega1+ = J+- omega1- + u31+ Pi (the departure
    tangent's momentum kept); law S: omega1+ = (-R/Rk) omega1-, Pi from the same balance."""
    jm, jp, jpm, mr, u31m, u31p, u21m, u21p, m11, m13, m33, c21 = nd
    w3 = u31m * w_minus
    tool = 0.5 * (1.0 - r * r) * mr * w3 * w3
    if law == LAW_KINEMATIC:
        w_plus = -r * u31m / u31p * w_minus
        impulse = (jp * w_plus - jpm * w_minus) / u31p
        loss = 0.5 * jm * w_minus * w_minus - 0.5 * jp * w_plus * w_plus
        return w_plus, impulse, loss, tool, loss - tool
    impulse = -(1.0 + r) * mr * w3
    w_plus = (jpm * w_minus + u31p * impulse) / jp
    # the capture's Carnot loss as a quadratic form of the velocity it removes: the loss
    # as a difference of kinetic energies cancels where the flywheel is heavy
    capture = capture_loss(w_minus, r, w_plus, nd, m)
    return w_plus, impulse, tool + capture, tool, capture


@njit(**INNER_OPTIONS)
def capture_loss(w_minus, r, w_plus, nd, m):
    """Law G's capture loss |qdot_m - omega1+ T+|^2_M3 / 2: the velocity just after the
    tool's impulse (in the node's plane, omega2 = a omega1 + b omega3) against the
    departure motion omega1+ T+ it is captured onto (docs/machine.md §2)."""
    jm, jp, jpm, mr, u31m, u31p, u21m, u21p, m11, m13, m33, c21 = nd
    l1, ja, m2l1, jb2, jd3 = m[M_L1], m[M_JA], m[M_M2L1], m[M_JB2], m[M_JD3]
    b = (u21p - u21m) / (u31p - u31m)
    a = u21m - b * u31m
    w3 = u31m * w_minus
    d3 = -(1.0 + r) * w3
    d1 = -m13 / m11 * d3
    w1m, w3m = w_minus + d1, w3 + d3
    e1 = w1m - w_plus
    e2 = a * w1m + b * w3m - w_plus * u21p
    e3 = w3m - w_plus * u31p
    return 0.5 * ((ja + m2l1 * l1) * e1 * e1 + 2.0 * m2l1 * c21 * e1 * e2 + jb2 * e2 * e2
                  + jd3 * e3 * e3)


# ---------------------------------------------------------------------------------------
# revolutions and the periodic steady state (docs/machine.md §3)

#: how a revolution ends
REV_BLOW, REV_STALL, REV_MAX_STEPS, REV_UNDERFLOW, REV_NONFINITE, REV_TOO_SLOW = range(6)
#: a revolution: how it ended, the speed before the blow, the slowest and fastest speed
#: (one-sided ends included), its time, the motor's work, the integral of M^2 dt, the work
#: of gravity and the load, the integration steps it took, and the crank angle where it
#: ended (the blow's, or a stall's)
Revolution = namedtuple("Revolution", ["end", "w_minus", "w_min", "w_max", "period",
                                       "motor_work", "torque_squared", "load_work",
                                       "steps", "angle"])


@njit(**INNER_OPTIONS)
def revolution(w_plus, nd, m, settings):
    """One revolution from the blow's exit at crank speed w_plus to the next blow."""
    start, tref, wref = m[M_START], m[M_TREF], m[M_WREF]
    jp, jm = nd[1], nd[0]
    energy = 0.5 * jp * w_plus * w_plus / tref
    nan = math.nan
    y0 = (start, energy, 0.0, 0.0, 0.0, 0.0)
    if energy <= STALL_LEVEL:
        # at rest the machine moves only where the drive's torque beats the load there;
        # it then leaves as T = (M0 + Q) dphi, its time sqrt(2 J dphi/(M0 + Q)): a first
        # RESTART_ANGLE in closed form, where dt/dphi = 1/omega is singular
        j, dj, q, u31 = reduced(start, m)
        torque = motor_torque(0.0, m)
        if not torque + q > 0.0:
            return Revolution(REV_STALL, nan, nan, nan, nan, nan, nan, nan, 0, start)
        a = RESTART_ANGLE
        time = math.sqrt(2.0 * j * a / (torque + q))
        y0 = (start + a, (torque + q) * a / tref, time * wref, torque * a / tref,
              torque * torque * time / (tref * wref), q * a / tref)
    rising = 1.0 if _speed_slope(y0, m) > 0.0 else -1.0  # the next extremum: a maximum
    fl = fly_revolution(y0[0], y0, m, (start + 2.0 * math.pi, m, w_plus, w_plus, rising),
                        settings, bool(False))
    steps = fl.cost.steps + fl.cost.rejected
    if fl.outcome == FLIGHT_EVENT and fl.event == 0:
        y = fl.y
        w_minus = math.sqrt(max(2.0 * y[1] * tref / jm, 0.0))
        _, _, w_min, w_max, _ = fl.data
        period = y[2] / wref
        if not (period * wref < TOO_SLOW * 2.0 * math.pi):
            return Revolution(REV_TOO_SLOW, nan, nan, nan, nan, nan, nan, nan, steps, y[0])
        return Revolution(REV_BLOW, w_minus, min(w_min, w_minus), max(w_max, w_minus),
                          period, y[3] * tref, y[4] * tref * wref, y[5] * tref, steps, y[0])
    end = (REV_STALL if fl.outcome == FLIGHT_EVENT else
           REV_MAX_STEPS if fl.outcome == FLIGHT_MAX_STEPS else
           REV_UNDERFLOW if fl.outcome == FLIGHT_UNDERFLOW else REV_NONFINITE)
    return Revolution(end, nan, nan, nan, nan, nan, nan, nan, steps, fl.y[0])


#: the steady cycle: its status (S codes), the speed after the blow and the revolution
#: from there, the blow at its end (speed after it, impulse, loss, energy to the material,
#: capture loss), revolutions flown and integration steps
Cycle = namedtuple("Cycle", ["status", "w_plus", "rev", "w_next", "impulse", "loss", "tool",
                             "capture", "revolutions", "steps"])


@njit(**INNER_OPTIONS)
def constant_speed_guess(nd, r, law, m):
    """The crank speed at which the motor's work per turn pays the blow's loss at constant
    speed, 2 pi M(omega) = dE(omega) (gravity and the load do no net work): the secant's
    start. NaN where there is none (a blow that gains energy)."""
    c = blow(1.0, r, law, nd, m)[2]  # the loss is quadratic in the speed
    if not c > 0.0:
        return math.nan
    if m[M_MOTOR] == MOTOR_CONSTANT:
        return math.sqrt(2.0 * math.pi * m[M_M0] / c)
    a, b = c / (2.0 * math.pi), m[M_M0] / m[M_IDLE]
    return 2.0 * m[M_M0] / (b + math.sqrt(b * b + 4.0 * a * m[M_M0]))


@njit(**INNER_OPTIONS)
def _status_of(end):
    if end == REV_STALL:
        return S.stalls
    if end == REV_MAX_STEPS:
        return S.max_steps
    if end == REV_UNDERFLOW:
        return S.step_underflow
    if end == REV_TOO_SLOW:
        return S.too_slow
    return S.nonfinite


@njit(**INNER_OPTIONS)
def steady(nd, r, law, m, settings, max_revolutions, start_mode):
    """The periodic steady state: the fixed point of the section map omega1+ -> omega1+
    (a revolution, then the blow), |Phi(w) - w| <= FIXED_POINT_TOL w, by the secant method
    from the constant-speed guess; from rest (start_mode START_REST) by plain revolutions
    first, the run-up. m carries the reference speed of the scaled state."""
    nan = math.nan
    revolutions = steps = 0
    w0 = m[M_WREF] if start_mode == START_RUNNING else 0.0
    w_prev = f_prev = nan
    plain = RUNUP_REVOLUTIONS if start_mode == START_REST else 1
    w = w0
    while revolutions < max_revolutions:
        rev = revolution(w, nd, m, settings)
        revolutions += 1
        steps += rev.steps
        if rev.end != REV_BLOW:
            return Cycle(_status_of(rev.end), w, rev, nan, nan, nan, nan, nan, revolutions,
                         steps)
        w_next, impulse, loss, tool, capture = blow(rev.w_minus, r, law, nd, m)
        if not w_next > 0.0:
            return Cycle(S.reverses, w, rev, w_next, impulse, loss, tool, capture,
                         revolutions, steps)
        f = w_next - w
        # the cycle repeats: its speed to FIXED_POINT_TOL, and the kinetic energy it would
        # carry into the next cycle to FIXED_POINT_TOL of the blow's loss (the energy
        # balance of the cycle; with a heavy flywheel the second is the tighter)
        if abs(f) <= FIXED_POINT_TOL * min(w, loss / (nd[1] * w)):
            return Cycle(S.ok, w, rev, w_next, impulse, loss, tool, capture, revolutions,
                         steps)
        if revolutions <= plain or not (f != f_prev):
            w_new = w_next
        else:
            w_new = w - f * (w - w_prev) / (f - f_prev)
            if not (w_new > 0.0 and math.isfinite(w_new)):
                w_new = w_next  # a secant step out of range: a plain revolution instead
        w_prev, f_prev = w, f
        w = w_new
    return Cycle(S.no_convergence, w, Revolution(REV_BLOW, nan, nan, nan, nan, nan, nan, nan,
                                                 0, nan),
                 nan, nan, nan, nan, nan, revolutions, steps)


# ---------------------------------------------------------------------------------------
# one design

@njit(**INNER_OPTIONS)
def machine_data(pr, lam0, lam2, lam3, sigma, start, snap, flywheel, tref, wref):
    """The machine's flat data tuple (M_* indices) from one design's parameters (rows P),
    its synthesised ratios, branch and node angle; the flywheel J_f and the reference
    energy and speed of the scaled state given apart (the flywheel is sized by solving
    again)."""
    l1 = pr[P.crank_length]
    l0, l2, l3 = lam0 * l1, lam2 * l1, lam3 * l1
    p1, q1 = pr[P.s1] * l1, pr[P.q1]
    p2, q2 = pr[P.s2] * l2, pr[P.q2]
    p3, q3 = pr[P.s3] * l3, pr[P.q3]
    m1, m2, m3 = pr[P.m1], pr[P.m2], pr[P.m3]
    ja = pr[P.J1] + m1 * (p1 * p1 + q1 * q1) + flywheel
    jb2 = pr[P.J2] + m2 * (p2 * p2 + q2 * q2)
    jd3 = pr[P.J3] + m3 * (p3 * p3 + q3 * q3)
    kind = float(CHANGE_POINT_C) if start != 0.0 else 0.0
    g, tilt = pr[P.g], pr[P.tilt]
    return (l0, l1, l2, l3, sigma, kind, start, ja, m2 * l1, p2, q2, jb2, jd3, m1, p1, q1,
            m2, m3, p3, q3, -g * math.sin(tilt), -g * math.cos(tilt), pr[P.load_force_x],
            pr[P.load_force_y], pr[P.load_arm], pr[P.load_offset], pr[P.load_moment],
            pr[P.motor_law], pr[P.stall_torque], pr[P.idle_speed], snap, tref, wref)


@njit(**INNER_OPTIONS)
def with_flywheel(m, flywheel, crank_own, tref, wref):
    """The data tuple with another flywheel and reference scales."""
    return (m[0], m[1], m[2], m[3], m[4], m[5], m[6], crank_own + flywheel, m[8], m[9],
            m[10], m[11], m[12], m[13], m[14], m[15], m[16], m[17], m[18], m[19], m[20],
            m[21], m[22], m[23], m[24], m[25], m[26], m[27], m[28], m[29], m[30], tref, wref)


@njit(**INNER_OPTIONS)
def solve(m, crank_own, flywheel, r, law, settings, max_revolutions, start_mode):
    """The steady cycle of the machine with flywheel J_f: (status, cycle, node, data)."""
    m = with_flywheel(m, flywheel, crank_own, 1.0, 1.0)
    nd = node(m)
    wref = constant_speed_guess(nd, r, law, m)
    if not math.isfinite(wref):
        if m[M_MOTOR] == MOTOR_CONSTANT:
            return S.no_convergence, Cycle(S.no_convergence, math.nan, Revolution(
                REV_BLOW, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan,
                math.nan, 0, math.nan), math.nan, math.nan, math.nan, math.nan, math.nan, 0,
                0), nd, m
        wref = m[M_IDLE]
    m = with_flywheel(m, flywheel, crank_own, 0.5 * nd[1] * wref * wref, wref)
    cycle = steady(nd, r, law, m, settings, max_revolutions, start_mode)
    return cycle.status, cycle, nd, m


@njit(**INNER_OPTIONS)
def speed_fluctuation(cycle):
    """delta = (omega_max - omega_min) / omega_mean of a steady cycle, the one-sided speeds
    at the blow included."""
    rev = cycle.rev
    w_max = max(rev.w_max, cycle.w_plus, rev.w_minus)
    w_min = min(rev.w_min, cycle.w_plus, rev.w_minus)
    return (w_max - w_min) * rev.period / (2.0 * math.pi)


@njit(**INNER_OPTIONS)
def inertia_is_singular(m):
    """Whether J(phi1) vanishes on the cycle. J >= J_A, so only without any inertia on the
    crank's side; then at the rocker's dead centres (u31 = 0, bisected from a sample) J is
    the coupler's alone and vanishes with it (a massless coupler)."""
    if m[M_JA] > 0.0:
        return False
    start, top, bottom = m[M_START], 0.0, math.inf
    n = 720
    previous = reduced(start, m)
    for k in range(1, n + 1):
        phi = start + 2.0 * math.pi * k / n
        here = reduced(phi, m)
        top, bottom = max(top, here[0]), min(bottom, here[0])
        if (previous[3] > 0.0) != (here[3] > 0.0):  # a dead centre of the rocker
            lo, hi = phi - 2.0 * math.pi / n, phi
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                if (reduced(mid, m)[3] > 0.0) == (previous[3] > 0.0):
                    lo = mid
                else:
                    hi = mid
            bottom = min(bottom, reduced(0.5 * (lo + hi), m)[0])
        previous = here
    return not bottom > 1e-9 * top


#: samples of the cycle for the classical flywheel estimate: each interval integrated by
#: five-point Gauss-Legendre, the extrema refined by a parabola through three samples
CLASSICAL_SAMPLES = 2048
_GL5_X = (-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
          0.9061798459386640)
_GL5_W = (0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
          0.2369268850561891)


@njit(**INNER_OPTIONS)
def classical_flywheel(nd, r, m, crank_own, delta, w):
    """The flywheel for speed fluctuation delta by the classical energy method at the
    constant mean speed w of the running machine (docs/machine.md §3): the loss of law G
    at J_f -> infinity at w, the mean torque that pays it, the energy the flywheel must
    store and give back over the cycle (the cumulative work of that torque and Q against
    the linkage's own kinetic energy), J_A = (its range)/(delta w^2), less the crank's own
    inertia. 0 where the crank alone holds delta."""
    jm, jp, jpm, mr, u31m, u31p, u21m, u21p, m11, m13, m33, c21 = nd
    ja = m[M_JA]
    c = 0.5 * (jm - jp) - (jpm - jp) + (1.0 + r) * m33 * u31p * u31m
    if not c > 0.0:
        return math.nan
    torque = c * w * w / (2.0 * math.pi)
    start, h = m[M_START], 2.0 * math.pi / CLASSICAL_SAMPLES
    j_start = jp - ja
    work = 0.0
    values = np.empty(CLASSICAL_SAMPLES + 1)
    values[0] = 0.0
    for k in range(CLASSICAL_SAMPLES):
        left = start + h * k
        for i in range(5):
            work += 0.5 * h * _GL5_W[i] * (torque + reduced(left + 0.5 * h * (1.0 + _GL5_X[i]),
                                                            m)[2])
        j = (jm if k == CLASSICAL_SAMPLES - 1 else reduced(left + h, m)[0]) - ja
        values[k + 1] = work - 0.5 * (j - j_start) * w * w
    top = _refined_extreme(values, 1.0)
    bottom = -_refined_extreme(values, -1.0)
    return max(0.0, (top - bottom) / (delta * w * w) - crank_own)


@njit(**INNER_OPTIONS)
def _refined_extreme(values, sign):
    """The largest of sign * values, refined by the parabola through the largest sample and
    its neighbours (the ends as they are)."""
    k = 0
    for i in range(values.shape[0]):
        if sign * values[i] > sign * values[k]:
            k = i
    best = sign * values[k]
    if 0 < k < values.shape[0] - 1:
        a, b, c = sign * values[k - 1], best, sign * values[k + 1]
        curvature = a - 2.0 * b + c
        if curvature < 0.0:
            best = b - 0.125 * (c - a) * (c - a) / curvature
    return best


@njit(**INNER_OPTIONS)
def exact_flywheel(m, crank_own, r, law, settings, max_revolutions, start_mode, delta, guess):
    """The flywheel J_f with delta(J_f) = delta: the secant method in (log J_f, log delta)
    from the classical estimate; 0 where the crank alone holds delta, NaN where a steady
    state is not found."""
    def log_delta(flywheel):
        status, cycle, nd, mm = solve(m, crank_own, flywheel, r, law, settings,
                                      max_revolutions, start_mode)
        if status != S.ok:
            return math.nan
        return math.log(speed_fluctuation(cycle) / delta)

    if not log_delta(0.0) > 0.0:
        return 0.0
    x0 = math.log(max(guess, 1e-3 * max(crank_own, 1e-9)))
    f0 = log_delta(math.exp(x0))
    x1 = x0 + 0.1
    for _ in range(40):
        f1 = log_delta(math.exp(x1))
        if not (math.isfinite(f0) and math.isfinite(f1)):
            return math.nan
        if abs(x1 - x0) <= 1e-10 or f1 == 0.0:
            return math.exp(x1)
        x0, x1, f0 = x1, x1 - f1 * (x1 - x0) / (f1 - f0), f1
    return math.nan


@njit(**INNER_OPTIONS)
def design_data(pr, snap):
    """A design's linkage: (status, the machine's data tuple, the crank's own inertia about
    A): the synthesis of crank_rocker for Rk = -design_restitution (or the given ratios),
    on the impact branch of a positive crank speed; a status other than ok where the
    linkage is not an impact four-bar with one node, or its inertia vanishes."""
    nan = math.nan
    none = NO_DATA
    r_design = pr[P.design_restitution]
    if r_design == MATERIAL:
        r_design = pr[P.R]
    if int(pr[P.type]) != TYPE_GENERAL:
        if r_design <= 0.0:  # gamma = 1, lambda0 = 1: B on D at the node
            return S.degenerate, none, nan
        if not r_design < 1.0:  # gamma = infinity: no linkage
            return S.no_real_synthesis, none, nan
    (status, lam0, lam2, lam3, gamma, rk, before, after, ratio, speed, turns, mu_min,
     mu_opp, sigma, start, count, rk_max, size, l1, w) = linkage_point(
        int(pr[P.type]), r_design, pr[P.largest_link], pr[P.lambda0], pr[P.lambda2],
        pr[P.lambda3], int(pr[P.base_root]), pr[P.crank_length], 1.0, 0.0, snap, nan, nan,
        0.0)
    if status == LINKAGE.second_special_position:  # a second node inside the cycle: the
        return S.degenerate, none, nan  # one-node model does not hold
    if status == LINKAGE.no_impact or status == LINKAGE.no_special_position:
        return S.no_impact, none, nan  # gamma <= 1, or no change point at all
    if status == LINKAGE.not_assemblable:
        return S.not_assemblable, none, nan
    if status == LINKAGE.no_real_synthesis:
        return S.no_real_synthesis, none, nan
    if status == LINKAGE.degenerate:
        return S.degenerate, none, nan
    if status != LINKAGE.ok:
        return S.nonfinite, none, nan
    crank_own = pr[P.J1] + pr[P.m1] * ((pr[P.s1] * pr[P.crank_length]) ** 2 + pr[P.q1] ** 2)
    # a flywheel still to be sized (FOR_DELTA) is none for the singularity test
    m = machine_data(pr, lam0, lam2, lam3, sigma, start, snap,
                     max(pr[P.flywheel_inertia], 0.0), 1.0, 1.0)
    if inertia_is_singular(m):
        return S.singular_inertia, m, crank_own
    return S.ok, m, crank_own


@njit(**INNER_OPTIONS)
def sized_flywheel(m, crank_own, r, law, settings, max_revolutions, start_mode, delta):
    """The flywheel whose steady state has speed fluctuation delta (the inverted input of
    flywheel_inertia = "for_delta_target"): the classical estimate at the mean speed of a
    first solve with a unit flywheel, then the exact root; NaN where none is found."""
    status, cycle, nd, mm = solve(m, crank_own, 1.0, r, law, settings, max_revolutions,
                                  start_mode)
    if status != S.ok:
        return math.nan
    guess = classical_flywheel(nd, r, mm, crank_own, delta, 2.0 * math.pi / cycle.rev.period)
    if not math.isfinite(guess):
        return math.nan
    return exact_flywheel(m, crank_own, r, law, settings, max_revolutions, start_mode, delta,
                          guess)


@njit(**INNER_OPTIONS)
def design(pr, snap, tol, max_revolutions, start_mode, delta, flywheels, peaks, window,
           n_samples, angles, out, prof):
    """One design: its status, its outputs written into out and its profiles at
    ``angles`` after the blow into prof (NaN where none)."""
    for k in range(out.shape[0]):
        out[k] = math.nan
    r = pr[P.R]
    law = int(pr[P.impact_law])
    status, m, crank_own = design_data(pr, snap)
    if status != S.ok:
        return status
    settings = Settings(method=METHOD_DOPRI5, rtol=tol, atol=tol, dt=0.0, max_steps=10 ** 6,
                        horizon=2.0 * math.pi + 1.0)
    flywheel = pr[P.flywheel_inertia]
    if flywheel == FOR_DELTA:  # the flywheel a delta target asks for: sized first
        flywheel = sized_flywheel(m, crank_own, r, law, settings, max_revolutions,
                                  start_mode, delta)
        if not math.isfinite(flywheel):
            return S.no_convergence
    out[O.flywheel_inertia] = flywheel
    status, cycle, nd, m = solve(m, crank_own, flywheel, r, law, settings, max_revolutions,
                                 start_mode)
    out[O.revolutions], out[O.n_steps] = cycle.revolutions, cycle.steps
    if status != S.ok:
        return status
    jm, jp, jpm, mr, u31m, u31p, u21m, u21p, m11, m13, m33, c21 = nd
    rev = cycle.rev
    w_plus, w_minus, w_next = cycle.w_plus, rev.w_minus, cycle.w_next
    period = rev.period
    out[O.mean_crank_speed] = 2.0 * math.pi / period
    out[O.speed_fluctuation] = speed_fluctuation(cycle)
    out[O.crank_speed_before_blow] = w_minus
    out[O.crank_speed_after_blow] = w_next
    out[O.crank_speed_jump] = w_next - w_minus
    out[O.tool_impulse] = cycle.impulse
    out[O.crank_impulse] = m[M_JA] * (w_next - w_minus)
    w_low, w_high = min(rev.w_min, w_plus), max(rev.w_max, w_plus)
    out[O.motor_torque_peak] = max(abs(motor_torque(w_low, m)), abs(motor_torque(w_high, m)))
    out[O.motor_torque_rms] = math.sqrt(rev.torque_squared / period)
    out[O.motor_power_mean] = rev.motor_work / period
    out[O.blow_energy] = 0.5 * m[M_JD3] * (u31m * w_minus) ** 2
    out[O.blow_loss] = cycle.loss
    out[O.energy_to_material] = cycle.tool
    out[O.capture_loss] = cycle.capture
    out[O.blow_rate] = 60.0 / period
    out[O.blow_efficiency] = cycle.tool / rev.motor_work
    out[O.cycle_period] = period
    out[O.impact_speed] = abs(u31m * w_minus) * m[M_L3]
    out[O.restitution_kinematic] = u31p / u31m
    out[O.restitution_mismatch] = u31p / u31m + r
    out[O.reduced_inertia_before], out[O.reduced_inertia_after] = jm, jp
    out[O.energy_balance_residual] = (rev.motor_work + rev.load_work - cycle.loss) / cycle.loss
    if angles.shape[0]:
        cycle_profiles(w_plus, nd, m, settings, angles, prof)
    if peaks:
        dynamic_force_peaks(pr, w_plus, nd, m, settings, window, n_samples, out)
    if flywheels:
        guess = classical_flywheel(nd, r, m, crank_own, delta, 2.0 * math.pi / period)
        out[O.flywheel_for_delta_classical] = guess if law == LAW_GENERALIZED else math.nan
        if law == LAW_GENERALIZED and math.isfinite(guess):
            out[O.flywheel_for_delta] = exact_flywheel(m, crank_own, r, law, settings,
                                                       max_revolutions, start_mode, delta,
                                                       guess)
    for k in range(out.shape[0]):
        if math.isinf(out[k]):
            return S.nonfinite
    return S.ok


@njit(**INNER_OPTIONS)
def cycle_profiles(w_plus, nd, m, settings, angles, prof):
    """The steady cycle from the blow's exit at w_plus, sampled at ``angles`` after the blow
    (ascending, inside the open cycle): crank speed, acceleration, motor and shaft torque
    into prof[k, j], each sample reached by the revolution's steps cut to land on it."""
    start, tref, wref = m[M_START], m[M_TREF], m[M_WREF]
    y = (start, 0.5 * nd[1] * w_plus * w_plus / tref, 0.0, 0.0, 0.0, 0.0)
    for j in range(angles.shape[0]):
        reached, y = timed_revolution(y[0], y, start + angles[j], m, settings)
        if not reached:
            return
        big_j, dj, q, u31 = reduced(y[0], m)
        w = _speed(y, big_j, m)
        torque = motor_torque(w, m)
        eps = (torque + q - 0.5 * dj * w * w) / big_j
        prof[F.crank_speed, j], prof[F.crank_acceleration, j] = w, eps
        prof[F.motor_torque, j], prof[F.shaft_torque, j] = torque, torque - m[M_JA] * eps


@njit(**KERNEL_OPTIONS)
def machine_block(params, snap, tol, max_revolutions, start_mode, delta, flywheels, peaks,
                  window, n_samples, angles, out, status, prof):
    pr = np.empty(params.shape[0])
    out_i = np.empty(out.shape[0])
    prof_i = np.empty((prof.shape[0], prof.shape[2]))
    for i in range(params.shape[1]):
        for k in range(params.shape[0]):
            pr[k] = params[k, i]
        prof_i[:] = math.nan
        status[i] = design(pr, snap, tol, int(max_revolutions), int(start_mode), delta,
                           bool(flywheels), bool(peaks), window, int(n_samples), angles,
                           out_i, prof_i)
        for k in range(out.shape[0]):
            out[k, i] = out_i[k]
        for k in range(prof.shape[0]):
            for j in range(prof.shape[2]):
                prof[k, i, j] = prof_i[k, j]


def run(params, method):
    """Entry point: (outputs, status, profiles[n_profiles, n, n_angles])."""
    n = params.shape[1]
    angles = cell_midpoints(method.profile_points, 2.0 * np.pi)
    out = np.empty((len(O), n))
    status = np.empty(n, dtype=np.int8)
    prof = np.empty((len(F), n, angles.shape[0]))
    flywheels = ("flywheel_for_delta" in method.outputs
                 or "flywheel_for_delta_classical" in method.outputs)
    peaks = any(name.startswith("dynamic_force_peak") for name in method.outputs)
    machine_block(np.ascontiguousarray(params), method.geometry_tol, method.tol,
                  method.max_revolutions, method.start, method.delta_target, flywheels,
                  peaks, method.special_window, method.peak_samples, angles, out, status,
                  prof)
    return out, status, prof


# ---------------------------------------------------------------------------------------
# joint reactions over the dynamic cycle: the kinetostatics of linkage_forces
# (kernels/kinetostatics.py) at the actual crank speed and acceleration of each angle

LP = _ks.P
#: the quantities whose dynamic peaks are outputs, in the order of kinetostatics' peaks
DYNAMIC_PEAK_ROWS = (O.dynamic_force_peak_A, O.dynamic_force_peak_B, O.dynamic_force_peak_C,
                     O.dynamic_force_peak_D)
#: golden section brackets a peak's crank angle to this [rad]
PEAK_LOCATION = 1e-9


@njit(**INNER_OPTIONS)
def linkage_forces_parameters(pr, m):
    """The linkage_forces parameter vector of the machine's linkage (rows of
    kinetostatics.P); speed, acceleration and the load's rocker-frame components are set per
    crank angle (``_reactions``)."""
    lf = np.zeros(len(LP))
    lf[LP.l0], lf[LP.l1], lf[LP.l2], lf[LP.l3] = m[M_L0], m[M_L1], m[M_L2], m[M_L3]
    lf[LP.m1], lf[LP.m2], lf[LP.m3] = pr[P.m1], pr[P.m2], pr[P.m3]
    lf[LP.s1], lf[LP.s2], lf[LP.s3] = pr[P.s1], pr[P.s2], pr[P.s3]
    lf[LP.q1], lf[LP.q2], lf[LP.q3] = pr[P.q1], pr[P.q2], pr[P.q3]
    lf[LP.J1], lf[LP.J2], lf[LP.J3] = pr[P.J1], pr[P.J2], pr[P.J3]
    lf[LP.tilt], lf[LP.g] = pr[P.tilt], pr[P.g]
    lf[LP.external_force_arm] = pr[P.load_arm]
    lf[LP.base_motion] = _ks.BASE_FIXED
    return lf


@njit(**INNER_OPTIONS)
def _state_at(x, data):
    """The cycle's state at crank angle x (after the blow), from the nearest sample before
    it; (reached, y)."""
    q, xs, states, m, settings, lf, res = data
    k = np.searchsorted(xs, x, side="right") - 1
    k = min(max(k, 0), xs.shape[0] - 1)
    y = (states[k, 0], states[k, 1], states[k, 2], states[k, 3], states[k, 4], states[k, 5])
    return timed_revolution(y[0], y, m[M_START] + x, m, settings)


@njit(**INNER_OPTIONS)
def _reactions(y, m, lf, res):
    """The joint reactions at state y (kinetostatics' result vector in res), with the
    crank's actual speed and acceleration and the base-frame load turned into the rocker
    frame; False where they do not exist."""
    big_j, dj, q, u31 = reduced(y[0], m)
    w = _speed(y, big_j, m)
    eps = (motor_torque(w, m) + q - 0.5 * dj * w * w) / big_j
    c1, s1, c2, s2, c3, s3, u21, u31, du21, du31 = kinematics(y[0], m)
    fx, fy = m[M_FX], m[M_FY]
    lf[LP.omega1], lf[LP.epsilon1] = w, eps
    lf[LP.external_force_normal] = fx * c3 + fy * s3
    lf[LP.external_force] = -fx * s3 + fy * c3
    # the load point's offset across the rocker: the force there is the force on the axis
    # plus the couple offset n3 x F
    lf[LP.external_moment] = m[M_MOMENT] + m[M_OFFSET] * (-s3 * fy - c3 * fx)
    return _ks._joint_forces(y[0], lf, m[M_SIGMA], res, m[M_SNAP], m[M_GX], m[M_GY], 0.0,
                             0.0)


@njit(**INNER_OPTIONS)
def _dynamic_quantity(x, data):
    q, xs, states, m, settings, lf, res = data
    reached, y = _state_at(x, data)
    if not (reached and _reactions(y, m, lf, res)):
        return math.nan
    return _ks._peak_quantity(q, res)


_, _refine_dynamic_peak = peak_search(_dynamic_quantity)


@njit(**INNER_OPTIONS)
def dynamic_force_peaks(pr, w_plus, nd, m, settings, window, n_samples, out):
    """The peaks of |F14|, |F21|, |F32|, |F34| over the steady cycle outside the window
    around the node, into out (rows DYNAMIC_PEAK_ROWS): a clustered sample of the cycle,
    each state reached by the revolution's steps, every sampled local maximum refined by
    golden section (kernels/extrema.py)."""
    start, tref = m[M_START], m[M_TREF]
    xs = clustered_points(window, 2.0 * math.pi - window, n_samples, int(CLUSTER))
    states = np.empty((xs.shape[0], 6))
    values = np.empty((4, xs.shape[0]))
    lf = linkage_forces_parameters(pr, m)
    res = np.empty(_ks.N_RESULT)
    y = (start, 0.5 * nd[1] * w_plus * w_plus / tref, 0.0, 0.0, 0.0, 0.0)
    for j in range(xs.shape[0]):
        reached, y = timed_revolution(y[0], y, start + xs[j], m, settings)
        if not (reached and _reactions(y, m, lf, res)):
            return
        for i in range(6):
            states[j, i] = y[i]
        for q in range(4):
            values[q, j] = _ks._peak_quantity(q, res)
    for q in range(4):
        out[DYNAMIC_PEAK_ROWS[q]] = _refine_dynamic_peak((q, xs, states, m, settings, lf,
                                                          res), xs, values[q],
                                                         PEAK_LOCATION)

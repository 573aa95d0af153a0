"""The impact machine's declaration (``impact_machine``): its parameters, outputs,
profiles, statuses and method keys, and the codes of its categorical inputs, which the
lower files of the package read by name (docs/machine.md)."""

import math
from dataclasses import replace

import numpy as np

from kernels import kinetostatics
from kernels.crank_rocker import DECLARATION as CRANK_ROCKER
from kernels.crank_rocker import ROOT_LARGER_BASE, ROOT_SMALLER_BASE, TYPES
from kernels.declaration import POSITIVE, Mechanism, Output, Quantity, geometry_tol
from kernels.extrema import cell_midpoints

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
        CRANK_ROCKER.parameter("type"),
        replace(CRANK_ROCKER.parameter("largest_link"), default=2.5),
        Quantity("base_root", "1", "type b: which root of the synthesis quadratic is the "
                 "base", default="smaller",
                 choices={"smaller": ROOT_SMALLER_BASE, "larger": ROOT_LARGER_BASE},
                 used_when={"type": ("b",)}, label="base root"),
        Quantity("lambda0", "1", "base ratio l0/l1 (type general)", "λ0",
                 used_when={"type": ("general",)}, **POSITIVE, label=r"base ratio $\lambda_0$"),
        Quantity("lambda2", "1", "coupler ratio l2/l1 (type general)", "λ2",
                 used_when={"type": ("general",)}, **POSITIVE, label=r"rod ratio $\lambda_2$"),
        Quantity("lambda3", "1", "rocker ratio l3/l1 (type general)", "λ3",
                 used_when={"type": ("general",)}, **POSITIVE, label=r"rocker ratio $\lambda_3$"),
        Quantity("design_restitution", "1", "restitution the linkage is synthesised for "
                 "(Rk = -design_restitution); \"material\": the worked material's R",
                 "R_d", default="material", minimum=0.0, maximum=1.0, min_inclusive=False,
                 max_inclusive=False, aliases={"material": MATERIAL},
                 used_when={"type": TYPES}, label="design restitution $R_d$"),
        Quantity("R", "1", "restitution coefficient of the worked material (R): Newton's "
                 "law at the tool", "R", default=0.3, minimum=0.0, maximum=1.0,
                 label="material restitution $R$"),
        Quantity("crank_length", "m", "crank length (l1)", "l1", default=0.1, **POSITIVE,
                 label="crank $l_1$"),
        # the link masses, centroids and inertias are linkage_forces', declared there once
        *(kinetostatics.DECLARATION.parameter(name) for name in LINK_MASSES),
        Quantity("flywheel_inertia", "kg m2", "flywheel on the crank shaft (J_f); "
                 "\"for_delta_target\": the flywheel that holds the speed fluctuation at "
                 "method.delta_target (its exact root)", "J_f", default=5.0,
                 aliases={"for_delta_target": FOR_DELTA}, **_NONNEG, label="flywheel $J_f$"),
        Quantity("motor_law", "1", "motor torque-speed law: linear M0 (1 - omega1/"
                 "omega_idle), or constant M0", default="linear",
                 choices={"linear": MOTOR_LINEAR, "constant": MOTOR_CONSTANT}, label="motor law"),
        Quantity("stall_torque", "N m", "motor torque at zero speed (M0)", "M0",
                 default=1200.0, **POSITIVE, label="stall torque $M_0$"),
        Quantity("idle_speed", "rad s-1", "motor speed at zero torque (omega_idle)", "ω_idle",
                 default=32.0, used_when=_LINEAR, **POSITIVE,
                 label=r"idle speed $\omega_\mathrm{idle}$"),
        Quantity("omega1", "rad s-1", "the steady mean crank speed to hold; given, the "
                 "motor's idle speed follows from it (its exact root; linear motor law)",
                 "ω1", used_when=_LINEAR, replaces="idle_speed", **POSITIVE,
                 label=r"mean crank speed $\omega_1$"),
        Quantity("tilt", "rad", "inclination of the base AD to the horizontal", "θ",
                 default=math.radians(25.0), minimum=-math.pi, maximum=math.pi,
                 label=r"tilt $\theta$"),
        Quantity("g", "m s-2", "gravitational acceleration", "g", default=9.81, **_NONNEG,
                 label="gravity $g$"),
        Quantity("load_force_x", "N", "load on the rocker, along the base A->D (fixed in "
                 "the base frame: conservative)", default=0.0, label="load along base"),
        Quantity("load_force_y", "N", "load on the rocker, across the base", default=0.0,
                 label="load across base"),
        Quantity("load_arm", "m", "load point on the rocker: distance from D along D->C",
                 default=0.0, label="load arm"),
        Quantity("load_offset", "m", "load point on the rocker: offset across the rocker",
                 default=0.0, label="load offset"),
        Quantity("load_moment", "N m", "couple on the rocker (counter-clockwise)",
                 default=0.0, label="load couple"),
        Quantity("impact_law", "1", "the blow: generalised Newton impact (energy-"
                 "consistent), or the kinematic law (comparison only: it can create "
                 "energy)", default="generalized",
                 choices={"generalized": LAW_GENERALIZED, "kinematic": LAW_KINEMATIC},
                 label="impact law"),
    ),
    outputs=(
        Output("flywheel_inertia", "kg m2", "the flywheel, given or sized for "
               "method.delta_target", "J_f", echoes="flywheel_inertia", label="flywheel $J_f$"),
        Output("mean_crank_speed", "rad s-1", "time-mean crank speed over the steady "
               "cycle (2 pi / T_c)", "ω_mean", label=r"mean crank speed $\bar\omega_1$"),
        Output("speed_fluctuation", "1", "coefficient of speed fluctuation (omega_max - "
               "omega_min)/omega_mean, the one-sided speeds at the blow included", "δ",
               label=r"speed fluctuation $\delta$"),
        Output("crank_speed_before_blow", "rad s-1", "crank speed just before the blow",
               "ω1⁻", label=r"$\omega_1^-$ before blow"),
        Output("crank_speed_after_blow", "rad s-1", "crank speed just after the blow",
               "ω1⁺", label=r"$\omega_1^+$ after blow"),
        Output("crank_speed_jump", "rad s-1", "crank speed change at the blow", "Δω1",
               label=r"speed jump $\Delta\omega_1$"),
        Output("tool_impulse", "N m s", "angular impulse of the tool on the rocker about D",
               "Π", label=r"tool impulse $\Pi$"),
        Output("crank_impulse", "N m s", "angular impulse into the crank and flywheel at "
               "the blow (J_A Delta omega1): the blow's load on the drive", "H_crank",
               label="crank impulse $H$"),
        Output("motor_torque_peak", "N m", "largest |motor torque| over the cycle",
               "M_peak", label=r"peak torque $M_\max$"),
        Output("motor_torque_rms", "N m", "RMS motor torque over the cycle", "M_rms",
               label=r"RMS torque $M_\mathrm{rms}$"),
        Output("motor_power_mean", "W", "mean motor power (motor work per cycle / T_c)",
               "P_mean", label=r"mean power $\bar P$"),
        Output("blow_energy", "J", "energy per blow: the striker's (rocker's) kinetic "
               "energy just before it", "E_striker", label="blow energy $E$"),
        Output("blow_loss", "J", "kinetic energy lost at the blow", "ΔE",
               label=r"blow loss $\Delta E$"),
        Output("energy_to_material", "J", "energy delivered to the worked material "
               "((1 - R^2) m_r omega3^2 / 2; generalised law only: the kinematic law does "
               "not split its loss, NaN)", "ΔE_tool",
               label=r"to material $\Delta E_\mathrm{tool}$"),
        Output("capture_loss", "J", "parasitic loss in the linkage at the blow (the "
               "plastic capture onto the departure branch; generalised law only, NaN under "
               "the kinematic law)", "ΔE_capture", label=r"capture loss $\Delta E_\mathrm{cap}$"),
        Output("blow_rate", "min-1", "blows per minute (60 / T_c)", label="blow rate"),
        Output("blow_efficiency", "1", "share of the motor's work per cycle that reaches "
               "the worked material (generalised law only, NaN under the kinematic law)",
               "η_blow", label=r"blow efficiency $\eta$"),
        Output("cycle_period", "s", "time between blows in the steady cycle", "T_c",
               label="cycle period $T_c$"),
        Output("impact_speed", "m s-1", "rocker tip speed at the blow (|u31- omega1-| l3)",
               label="impact speed $v$"),
        Output("restitution_kinematic", "1", "kinematic restitution of the linkage "
               "(u31 after / u31 before the node)", "Rk", label="kinematic restitution $R_k$"),
        Output("restitution_mismatch", "1", "Rk + R: zero where the linkage is matched to "
               "the material", "Rk + R", label="mismatch $R_k + R$"),
        Output("reduced_inertia_before", "kg m2", "reduced inertia about the crank just "
               "before the blow", "J⁻", label="$J^-$ before blow"),
        Output("reduced_inertia_after", "kg m2", "reduced inertia about the crank just "
               "after the blow", "J⁺", label="$J^+$ after blow"),
        Output("energy_balance_residual", "1", "(motor work - blow loss) / blow loss over "
               "the steady cycle: gravity and the load are conservative and do no work over "
               "a closed cycle, so this is the integration's and the fixed point's error in "
               "the cycle's energy balance", diagnostic=True, label="energy residual"),
        Output("idle_speed", "rad s-1", "the motor's idle speed, given or solved for the "
               "mean crank speed omega1", "ω_idle", echoes="idle_speed",
               label=r"idle speed $\omega_\mathrm{idle}$"),
        Output("flywheel_sizing", "1", "how the flywheel came about: given; sized for "
               "method.delta_target; or not needed (the crank alone holds the speed "
               "fluctuation under the target, and the flywheel is 0)",
               flags={"undetermined": -1, "given": 0, "sized": 1, "not_needed": 2},
               undetermined="undetermined", label="flywheel sizing"),
        Output("revolutions", "1", "revolutions flown to find the steady state",
               diagnostic=True, count=True, label="revolutions"),
        Output("n_steps", "1", "integration steps, accepted and rejected", diagnostic=True,
               count=True, label="steps"),
        Output("dynamic_force_peak_A", "N", "peak |F14| at the crank pivot A over the "
               "steady cycle, at the actual crank speed and acceleration", "|F14|max",
               _WINDOWED, on_request=True, label="peak $|F_{14}|$ at A"),
        Output("dynamic_force_peak_B", "N", "peak |F21| at the crank pin B over the "
               "steady cycle, at the actual crank speed and acceleration", "|F21|max",
               _WINDOWED, on_request=True, label="peak $|F_{21}|$ at B"),
        Output("dynamic_force_peak_C", "N", "peak |F32| at the coupler-rocker joint C "
               "over the steady cycle, at the actual crank speed and acceleration",
               "|F32|max", _WINDOWED, on_request=True, label="peak $|F_{32}|$ at C"),
        Output("dynamic_force_peak_D", "N", "peak |F34| at the rocker pivot D over the "
               "steady cycle, at the actual crank speed and acceleration", "|F34|max",
               _WINDOWED, on_request=True, label="peak $|F_{34}|$ at D"),
        Output("flywheel_for_delta", "kg m2", "flywheel that holds the speed fluctuation "
               "at method.delta_target (the exact root of delta(J_f) = target)", "J_f(δ)",
               on_request=True, label=r"flywheel for $\delta$"),
        Output("flywheel_for_delta_classical", "kg m2", "the same by the classical energy "
               "method at constant mean speed", "J_f(δ) classical", on_request=True,
               label=r"flywheel for $\delta$ (classical)"),
    ),
    profiles=(
        Output("crank_speed", "rad s-1", "crank speed over the steady cycle", "ω1",
               label=r"crank speed $\omega_1$"),
        Output("crank_acceleration", "rad s-2", "crank angular acceleration over the "
               "steady cycle", "ε1", label=r"crank acceleration $\varepsilon_1$"),
        Output("motor_torque", "N m", "motor torque over the steady cycle", "M",
               label="motor torque $M$"),
        Output("shaft_torque", "N m", "torque the crank shaft delivers to the linkage, "
               "motor torque - J_A epsilon1 (the kinetostatic balancing moment of the "
               "linkage at the actual speed and acceleration)", "M - J_A ε1",
               label="shaft torque"),
    ),
    profile_dim=Quantity("angle_after_blow", "rad", "crank angle after the blow "
                         "(phi1 - phi1*), over the open cycle", "φ1 - φ1*",
                         label=r"angle after blow $\varphi_1-\varphi_1^*$"),
    profile_coordinate=lambda method: cell_midpoints(method.profile_points, 2.0 * np.pi),
    status=("ok", "not_assemblable", "no_real_synthesis", "degenerate", "no_impact",
            "stalls", "reverses", "singular_inertia", "too_slow", "no_convergence",
            "max_steps", "step_underflow", "nonfinite", "gains_energy",
            "unreachable_speed"),
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

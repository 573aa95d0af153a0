"""Registry entry of the rotary-pendulum impact mechanism (seed 004, dynamics.md §1)."""

from __future__ import annotations

import math

from kernels import pendulum as k
from kernels import rotary_pendulum as kr
from sweep.errors import UserError
from sweep.mechanisms.common import POSITIVE
from sweep.registry import Mechanism, Output, Parameter, register

_POS = POSITIVE

PARAMETERS = (
    Parameter("model", "1", "pendulum model: seed 004's equation (paper), the physically "
              "derived rigid pendulum at constant rotor speed (rigid), a rotor of finite "
              "inertia with a linear motor law (rotor)", default="paper",
              choices={"paper": k.MODEL_PAPER, "rigid": k.MODEL_RIGID,
                       "rotor": kr.MODEL_ROTOR}),
    Parameter("k", "1", "length ratio l1/l2 (k)", default=2.5, **_POS),
    Parameter("xi", "1", "inertia ratio m l2^2/J_c (xi)", default=4.0, **_POS),
    Parameter("kappa", "1", "rigid and rotor models: contact radius over the "
              "centre-of-percussion radius (kappa); default xi/(1 + xi), contact at the "
              "striker's centre", **_POS),
    Parameter("R", "1", "restitution coefficient of the striker on the tool (R)",
              default=0.0, minimum=0.0, maximum=1.0, max_inclusive=False),
    Parameter("omega1", "rad s-1", "rotor angular speed (omega1)", default=20.0, **_POS),
    Parameter("l2", "m", "pendulum length to the striker (l2)", default=0.04, **_POS),
    Parameter("tool", "1", "impact condition: a stop on the rotor at psi = 0 (rotor_stop, "
              "the paper's), or a blade fixed in the frame hit by the striker when it "
              "reaches it with |psi| <= tool_window (lab_window)",
              default="rotor_stop", choices={"rotor_stop": kr.TOOL_ROTOR_STOP,
                                             "lab_window": kr.TOOL_LAB_WINDOW}),
    Parameter("tool_window", "rad", "lab_window: reach of the blade as the largest |psi| at "
              "which the striker meets it (the blade's inner edge is at the striker radius "
              "there)", default=0.2, minimum=0.0, maximum=math.pi / 2, min_inclusive=False),
    Parameter("rotor_inertia_ratio", "1", "rotor model: rotor inertia over the striker's "
              "centroidal inertia (J1/J_c)", default=100.0, minimum=0.0),
    Parameter("motor_slope", "1", "rotor model: slope of the motor law tau_m = s_m "
              "(Omega_idle - phi1') in J_c omega1 (s_m/(J_c omega1))", default=100.0,
              minimum=0.0),
    Parameter("idle_speed", "1", "rotor model: the motor's no-load speed over omega1 "
              "(Omega_idle/omega1); the rotor starts at it", default=1.0, **_POS),
)
OUTPUTS = (
    Output("regime", "1", "steady regime of the impact motion", flags=k.REGIMES),
    Output("amplitude", "rad", "amplitude of the relative swing (A)"),
    Output("frequency_ratio", "1", "frequency coefficient n (psi ~ A sin(n omega1 t)), pi "
           "over the flight time; NaN on the lab blade, where flights end on the blade"),
    Output("period", "s", "period of the free relative oscillation T = 2 pi/(n omega1)"),
    Output("impact_speed", "m s-1", "normal speed of the striker at impact in steady state "
           "(V* = 2 (1+k) omega1 l2/(1-R) on the rotor stop at constant speed)"),
    Output("impact_interval", "rad", "rotor angle between impacts in steady state (tau1; "
           "on the blade, between the impacts opening each contact)"),
    Output("impacts_to_converge", "1", "impacts from rest to the steady state (to "
           "1e-12 by the closed form, to 10 rtol when integrated), or until escape"),
    Output("acceleration_peak", "rad s-2", "peak relative angular acceleration of the "
           "pendulum in steady state"),
    Output("restitution_critical", "1", "largest R with a periodic impact regime (R_crit, "
           "closed-form models on the rotor stop); NaN if none exists or none is known"),
    Output("rotor_speed_ratio", "1", "mean rotor speed over the steady cycle over omega1 "
           "(1 at constant rotor speed)"),
    Output("n_steps", "1", "integration steps, accepted and rejected (0: closed form)"),
    Output("n_rejected", "1", "rejected integration steps among n_steps"),
    Output("n_events", "1", "impact events located by the integrator"),
    Output("method_used", "1", "method that produced the values",
           flags=("closed_form", "rk4", "dopri5")),
)
assert tuple(p.name for p in PARAMETERS) == kr.PARAMETERS
assert tuple(o.name for o in OUTPUTS) == kr.OUTPUTS

METHOD = {
    "integrator": Parameter("integrator", "1", "auto (the closed form where the model has "
                            "one, else DOPRI5 at tol/10), closed_form, rk4 or dopri5",
                            default="auto",
                            choices={"auto": k.INTEGRATOR_AUTO,
                                     "closed_form": k.INTEGRATOR_CLOSED,
                                     "rk4": k.INTEGRATOR_RK4, "dopri5": k.INTEGRATOR_DOPRI5}),
    "rtol": Parameter("rtol", "1", "dopri5 relative tolerance", default=1e-10,
                      minimum=1e-14, maximum=1e-2),
    "atol": Parameter("atol", "1", "dopri5 absolute tolerance (rad, rad per rotor radian)",
                      default=1e-12, minimum=1e-16, maximum=1e-2),
    "dt": Parameter("dt", "1", "rk4 step in rotor radians", default=0.002, minimum=1e-6,
                    maximum=0.5),
    "max_impacts": Parameter("max_impacts", "1", "impacts simulated at most",
                             default=1000, minimum=1, maximum=10**6, integer=True),
    "tol": Parameter("tol", "1", "auto: relative accuracy requested of the outputs",
                     default=1e-8, minimum=1e-11, maximum=1e-2),
}
assert tuple(METHOD) == kr.METHOD


def _check(given: dict) -> None:
    models = given.get("model", {"paper"})
    tools = given.get("tool", {"rotor_stop"})
    if "kappa" in given and models == {"paper"}:
        raise UserError("kappa: used only by model = \"rigid\" or \"rotor\"")
    if "tool_window" in given and "lab_window" not in tools:
        raise UserError("tool_window: used only by tool = \"lab_window\"")
    for name in ("rotor_inertia_ratio", "motor_slope", "idle_speed"):
        if name in given and "rotor" not in models:
            raise UserError(f"{name}: used only by model = \"rotor\"")
    integrators = given.get("method.integrator", {"auto"})
    for key, needs in (("rtol", "dopri5"), ("atol", "dopri5"), ("dt", "rk4"), ("tol", "auto")):
        if "method." + key in given and needs not in integrators:
            raise UserError(f"method.{key}: used only with integrator = \"{needs}\""
                            + ("; auto takes tol" if needs == "dopri5" else ""))
    if "closed_form" in given.get("method.integrator", ()) and (
            "rotor" in models or "lab_window" in tools):
        raise UserError("method.integrator: \"closed_form\" exists only for the paper and "
                        "rigid models on the rotor stop; allowed here: \"auto\", \"rk4\", "
                        "\"dopri5\"")


register(Mechanism(
    name="rotary_pendulum",
    title="Rotary-pendulum impact mechanism: steady impact regime (seed 004)",
    parameters=PARAMETERS,
    outputs=OUTPUTS,
    run=kr.pendulum_run,
    flags=("ok", "escape", "max_steps", "step_underflow", "degenerate", "nonfinite"),
    usable_flags=("escape",),
    method=METHOD,
    method_text="closed form (auto): first integral of seed 004's equation, amplitude by "
                "Newton, half period by Gauss-Legendre, escape threshold v_crit, rigid "
                "pendulum by the AGM elliptic integral, affine impact map (dynamics.md "
                "§1.5, §1.7); or DOPRI5/RK4 with event location on the step interpolant "
                "(sign samples, extremum check) and Newton polishing on exact partial "
                "steps; the rotor model by the generalised Newton impact (§1.3); the lab "
                "blade by a gap function on the striker's polar angle, a kinematic slide "
                "after plastic or accumulated (Zeno) contact; computed once per distinct "
                "case and rescaled by omega1 and l2",
    check=_check,
    whole_axes=("omega1", "l2"),
))

"""Registry entry of the rotary-pendulum impact mechanism (seed 004, dynamics.md §1)."""

from __future__ import annotations

from kernels import pendulum as k
from sweep.errors import UserError
from sweep.mechanisms.common import POSITIVE
from sweep.registry import Mechanism, Output, Parameter, register

_POS = POSITIVE

PARAMETERS = (
    Parameter("model", "1", "pendulum model: seed 004's equation (paper), the physically "
              "derived rigid pendulum (rigid)", default="paper",
              choices={"paper": k.MODEL_PAPER, "rigid": k.MODEL_RIGID, "rotor": 2}),
    Parameter("k", "1", "length ratio l1/l2 (k)", default=2.5, **_POS),
    Parameter("xi", "1", "inertia ratio m l2^2/J_c (xi)", default=4.0, **_POS),
    Parameter("kappa", "1", "rigid model: contact radius over the centre-of-percussion "
              "radius (kappa); default xi/(1 + xi)", **_POS),
    Parameter("R", "1", "restitution coefficient of the striker on the tool (R)",
              default=0.0, minimum=0.0, maximum=1.0, max_inclusive=False),
    Parameter("omega1", "rad s-1", "rotor angular speed (omega1)", default=20.0, **_POS),
    Parameter("l2", "m", "pendulum length to the striker (l2)", default=0.04, **_POS),
    Parameter("tool", "1", "impact condition: the rotor stop at psi = 0 (the paper's)",
              default="rotor_stop", choices={"rotor_stop": k.TOOL_ROTOR_STOP,
                                             "lab_window": 1}),
)
OUTPUTS = (
    Output("regime", "1", "steady regime of the impact motion", flags=k.REGIMES),
    Output("amplitude", "rad", "amplitude of the relative swing (A)"),
    Output("frequency_ratio", "1", "frequency coefficient n (psi ~ A sin(n omega1 t))"),
    Output("period", "s", "period of the free relative oscillation T = 2 pi/(n omega1)"),
    Output("impact_speed", "m s-1", "striker speed at impact in steady state "
           "(V* = omega1 l2 (1 + k + v*); 2 (1+k) omega1 l2/(1-R) on the rotor stop)"),
    Output("impact_interval", "rad", "rotor angle between impacts in steady state (tau1)"),
    Output("impacts_to_converge", "1", "impacts from rest to the steady state (to "
           "1e-12, or 10 rtol when integrated), or until escape"),
    Output("acceleration_peak", "rad s-2", "peak relative angular acceleration of the "
           "pendulum in steady state"),
    Output("restitution_critical", "1", "largest R with a periodic impact regime (R_crit); "
           "NaN if none exists"),
    Output("n_steps", "1", "integration steps, accepted and rejected (0: closed form)"),
    Output("n_events", "1", "impact events located by the integrator"),
    Output("method_used", "1", "method that produced the values",
           flags=("closed_form", "rk4", "dopri5")),
)
assert tuple(p.name for p in PARAMETERS) == k.PARAMETERS
assert tuple(o.name for o in OUTPUTS) == k.OUTPUTS

METHOD = {
    "integrator": Parameter("integrator", "1", "auto (the closed form wherever the model "
                            "has one), closed_form, rk4 or dopri5", default="auto",
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
}
assert tuple(METHOD) == k.METHOD


def _check(given: dict) -> None:
    if "rotor" in given.get("model", set()):
        raise UserError("model: \"rotor\" (finite rotor inertia) is not built yet; allowed "
                        "now: \"paper\", \"rigid\"")
    if "lab_window" in given.get("tool", set()):
        raise UserError("tool: \"lab_window\" is not built yet; allowed now: \"rotor_stop\"")
    if "kappa" in given and given.get("model", {"paper"}) == {"paper"}:
        raise UserError("kappa: used only by model = \"rigid\"")


register(Mechanism(
    name="rotary_pendulum",
    title="Rotary-pendulum impact mechanism: steady impact regime (seed 004)",
    parameters=PARAMETERS,
    outputs=OUTPUTS,
    run=k.pendulum_run,
    flags=("ok", "escape", "max_steps", "step_underflow", "nonfinite"),
    usable_flags=("escape",),
    method=METHOD,
    method_text="closed form (auto): first integral of seed 004's equation, amplitude by "
                "Newton, half period by Gauss-Legendre, escape threshold v_crit, rigid "
                "pendulum by the AGM elliptic integral, affine impact map (dynamics.md "
                "§1.5, §1.7); or DOPRI5/RK4 with event location on the step interpolant "
                "and secant polishing; computed once per (model, k, xi, kappa, R) and "
                "rescaled by omega1 and l2",
    check=_check,
))

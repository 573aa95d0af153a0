"""Registry entry of the leaf-spring balancer (seed 002, dynamics.md §2)."""

from __future__ import annotations

from kernels import balancer as k
from sweep.mechanisms.common import POSITIVE
from sweep.registry import Mechanism, Output, Parameter, register

_POS = POSITIVE

PARAMETERS = (
    Parameter("lambda0", "1", "base ratio l0/l1 (lambda0)", default=3.0, **_POS),
    Parameter("lambda2", "1", "coupler ratio l2/l1 (lambda2)", default=3.5, **_POS),
    Parameter("lambda3", "1", "rocker ratio l3/l1 (lambda3)", default=2.5, **_POS),
    Parameter("sigma", "1", "assembly branch (sigma)", default=1, choices={1: 1, -1: -1}),
    Parameter("f", "1", "speed-change coefficient f = omega/omega0", default=1.0, **_POS),
    Parameter("r", "1", "stiffness ratio r = omega0/p (the paper's omega0/p)", default=1.0,
              **_POS),
    Parameter("eta", "1", "dimensionless damping eta = nu/omega0", default=0.02,
              minimum=0.0, maximum=10.0),
    Parameter("spring_neutral", "1", "neutral angle of the spring: half the swing (the "
              "paper) or the rocker's mean angle (no static moment)", default="half_swing",
              choices={"half_swing": k.NEUTRAL_HALF_SWING, "mean": k.NEUTRAL_MEAN}),
)
OUTPUTS = (
    Output("swing", "rad", "rocker swing (gamma0)"),
    Output("moment_invariant_peak_free", "rad", "peak unbalanced-moment invariant without "
           "the balancer (M_i,max = max |gamma - g|)", "moment = c M_i = I_m omega0^2 M_i/r^2"),
    Output("moment_invariant_peak_balanced", "rad", "peak unbalanced-moment invariant with "
           "the balancer (M_zr,max)"),
    Output("balancing_coefficient", "1", "balancing coefficient K = M_i,max / M_zr,max"),
    Output("dynamic_coefficient_free", "1", "dynamic coefficient without the balancer (K_d)"),
    Output("dynamic_coefficient_balanced", "1", "dynamic coefficient with the balancer "
           "(K_d,zr)"),
    Output("acceleration_invariant_rigid", "1", "peak rocker acceleration invariant "
           "max |d2 gamma/d theta2| (rigid shaft)"),
    Output("harmonics_used", "1", "harmonics of the rocker motion used"),
    Output("truncation_error", "1", "estimated relative truncation error of the "
           "acceleration metrics"),
    Output("resonance_margin", "1", "distance to the nearest resonance, min |D_n|/K"),
)
assert tuple(p.name for p in PARAMETERS) == k.PARAMETERS
assert tuple(o.name for o in OUTPUTS) == k.OUTPUTS

METHOD = {
    "harmonics": Parameter("harmonics", "1", "harmonics of the rocker motion", default="auto",
                           minimum=1, maximum=16384, integer=True, aliases={"auto": 0}),
    "tol": Parameter("tol", "1", "relative tolerance of the metrics (sets the harmonic "
                     "count when harmonics = \"auto\")", default=1e-10, minimum=1e-14,
                     maximum=1e-2),
    "resonance_tol": Parameter("resonance_tol", "1", "flag resonance where |D_n + i E_n| "
                               "< resonance_tol K", default=1e-9, minimum=0.0, maximum=0.1),
}
assert tuple(METHOD) == k.METHOD

register(Mechanism(
    name="spring_balancer",
    title="Leaf-spring balancer on a four-bar: steady state by Fourier series (seed 002)",
    parameters=PARAMETERS,
    outputs=OUTPUTS,
    run=k.balancer_run,
    flags=("ok", "not_assemblable", "resonance", "truncation", "nonfinite"),
    usable_flags=("truncation",),
    method=METHOD,
    method_text="rocker motion from the loop closure (linkages.md §2.1), Fourier "
                "coefficients by rFFT once per geometry, steady state per harmonic in closed "
                "form (dynamics.md §2.5, B6), invariants by their own transfer functions, "
                "maxima over a revolution by dense sampling and Newton refinement",
))

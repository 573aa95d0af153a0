"""Registry entry of the six-link impact mechanism (seed 003, linkages.md §4)."""

from __future__ import annotations

import math

from kernels import six_link as k
from sweep.mechanisms.common import POSITIVE, geometry_tol
from sweep.registry import Mechanism, Output, Parameter, register

_POS = POSITIVE

PARAMETERS = (
    Parameter("lambda2", "1", "stage 1 coupler ratio l2/l1 (lambda2)", default=1.6, **_POS),
    Parameter("lambda3", "1", "stage 1 driven crank ratio l3/l1 (lambda3); the base is "
              "lambda6 = 1 - lambda2 + lambda3", default=1.3, **_POS),
    Parameter("mu4", "1", "stage 2 coupler ratio l4/l3 (the paper's second lambda4)",
              default=1.5, **_POS),
    Parameter("mu5", "1", "stage 2 rocker ratio l5/l3 (lambda5); the base is "
              "mu6 = 1 - mu4 + mu5", default=2.5, **_POS),
    Parameter("beta", "rad", "direction of the stage 2 base DE relative to AD (beta)",
              default=0.0, minimum=-2 * math.pi, maximum=2 * math.pi),
    Parameter("delta", "rad", "offset of the stage 2 crank arm on link 3 (delta)",
              default=0.0, minimum=-2 * math.pi, maximum=2 * math.pi),
    Parameter("direction", "1", "rotation direction of the crank: +1 counter-clockwise",
              default=1, choices={1: 1, -1: -1}),
    Parameter("omega1", "rad s-1", "crank angular speed (|omega1|)", default=30.0, **_POS),
    Parameter("crank_length", "m", "crank length (l1)", default=0.1, **_POS),
)
OUTPUTS = (
    Output("gamma1", "1", "stage 1 node parameter sqrt(lambda6 lambda2/lambda3) (gamma1)"),
    Output("gamma2", "1", "stage 2 node parameter sqrt(mu6 mu4/mu5) (gamma2)"),
    Output("restitution_kinematic", "1", "kinematic restitution coefficient of stage 2 (Rk)"),
    Output("transfer_stage1_low", "1", "stage 1 u31 at its special position, low value "
           "(1 - gamma1)/(1 - lambda6)"),
    Output("transfer_stage1_high", "1", "stage 1 u31 at its special position, high value "
           "(1 + gamma1)/(1 - lambda6)"),
    Output("transfer_impact_1", "1", "u51 at the first impact of the 4 pi cycle"),
    Output("transfer_impact_2", "1", "u51 at the second impact of the 4 pi cycle"),
    Output("transfer_stage1_impact_1", "1", "stage 1 u31 at the first impact"),
    Output("transfer_stage1_impact_2", "1", "stage 1 u31 at the second impact"),
    Output("impact_crank_angle_1", "rad", "crank angle of the first impact in [0, 4 pi)"),
    Output("impact_crank_angle_2", "rad", "crank angle of the second impact in [0, 4 pi)"),
    Output("impact_speed_1", "m s-1", "striker (rocker tip) speed at the first impact"),
    Output("impact_speed_2", "m s-1", "striker (rocker tip) speed at the second impact"),
    Output("transfer_peak", "1", "peak |u51| over the 4 pi cycle"),
    Output("transfer2_peak", "1", "peak |u'51| over the 4 pi cycle"),
    Output("assembly_branch_stage2", "1", "stage 2 assembly branch (sigma2), the impact "
           "branch for the rotation direction"),
)
PROFILES = (Output("rocker_angle", "rad", "stage 2 rocker angle (phi5), from the "
                   "direction D->E, in [0, 2 pi)"),)
assert tuple(p.name for p in PARAMETERS) == k.PARAMETERS
assert tuple(o.name for o in OUTPUTS) == k.OUTPUTS
assert tuple(o.name for o in PROFILES) == k.PROFILES

METHOD = {
    "geometry_tol": geometry_tol("the link-length conditions"),
    "samples": Parameter("samples", "1", "crank angles sampled over 4 pi to find each "
                         "peak, which is then refined to the exact maximum", default=720,
                         minimum=8, maximum=10**6, integer=True),
    "profile_points": Parameter("profile_points", "1", "crank angles of the rocker_angle "
                                "profile over 4 pi (0: none)", default=0, minimum=0,
                                maximum=100000, integer=True),
}
assert tuple(METHOD) == k.METHOD

register(Mechanism(
    name="six_link",
    title="Six-link impact mechanism with alternating branch switching (seed 003)",
    parameters=PARAMETERS,
    outputs=OUTPUTS,
    run=k.six_link_run,
    flags=("ok", "not_assemblable", "nonfinite"),
    method=METHOD,
    method_text="stage 1 on the smooth path through its node (branch alternation rule, "
                "linkages.md §4.3), stage 2 on the impact branch for the rotation direction; "
                "impacts by bisection on phi3(phi1); composition u51 = u31 u53; peaks from a "
                "uniform sample of the 4 pi cycle refined by golden section",
    profiles=PROFILES,
    profile_dim=Parameter("crank_angle", "rad", "crank angle (phi1) over the 4 pi cycle"),
    profile_coordinate=lambda method: k.profile_angles(int(method["profile_points"])),
))

"""Registry entry of the crank-rocker impact four-bar (seed 000, linkages.md §2-3)."""

from __future__ import annotations

from kernels import crank_rocker as k
from sweep.errors import UserError
from sweep.mechanisms.common import POSITIVE, assembly_branch, geometry_tol
from sweep.registry import Mechanism, Output, Parameter, register

_POS = POSITIVE

PARAMETERS = (
    Parameter("type", "1", "impact four-bar type (a: largest rod, b: largest rocker, "
              "c: largest base, general: any four-bar)", default="a",
              choices={"a": k.TYPE_A, "b": k.TYPE_B, "c": k.TYPE_C,
                       "general": k.TYPE_GENERAL}),
    Parameter("R", "1", "physical restitution coefficient of the striker (R); synthesis "
              "makes Rk = -R", default=0.3, minimum=0.0, maximum=1.0,
              min_inclusive=False, max_inclusive=False),
    Parameter("largest_link", "1", "largest link ratio of the type (lambda2 for a, lambda3 "
              "for b, lambda0 for c)", **_POS),
    Parameter("lambda0", "1", "base ratio l0/l1 (lambda0)", **_POS),
    Parameter("lambda2", "1", "connecting rod ratio l2/l1 (lambda2)", **_POS),
    Parameter("lambda3", "1", "rocker ratio l3/l1 (lambda3)", **_POS),
    Parameter("base_root", "1", "type b: which root of the synthesis quadratic is the base",
              default="smaller", choices={"smaller": k.ROOT_SMALLER_BASE,
                                          "larger": k.ROOT_LARGER_BASE}),
    Parameter("crank_length", "m", "crank length (l1)", default=0.1, **_POS),
    Parameter("omega1", "rad s-1", "crank angular velocity (omega1); its sign is the "
              "rotation direction", default=30.0, nonzero=True),
    assembly_branch(),
)

OUTPUTS = (
    Output("lambda0", "1", "base ratio l0/l1 (lambda0)"),
    Output("lambda2", "1", "connecting rod ratio l2/l1 (lambda2)"),
    Output("lambda3", "1", "rocker ratio l3/l1 (lambda3)"),
    Output("gamma", "1", "node parameter sqrt(lambda0 lambda2 / lambda3) (gamma)"),
    Output("restitution_kinematic", "1", "kinematic restitution coefficient (Rk)",
           "u31 after / u31 before the special position; negative for an impact mechanism"),
    Output("transfer_before", "1", "rocker transfer ratio approaching the special position "
           "(u31 at impact)"),
    Output("transfer_after", "1", "rocker transfer ratio leaving the special position"),
    Output("impact_transfer_ratio", "1", "magnitude of the transfer ratio at impact "
           "(|u31(2 pi)| of seed 000's tables)"),
    Output("impact_speed", "m s-1", "rocker tip speed at impact "
           "(|u31| |omega1| lambda3 l1)"),
    Output("crank_turns_fully", "1", "1 if the crank can turn fully, else 0"),
    Output("transmission_angle_min", "rad", "minimum transmission angle over a crank turn",
           "0 for any change-point four-bar: all links are collinear at the special position"),
    Output("transmission_angle_opposite", "rad", "transmission angle at the dead centre "
           "opposite the special position", "the design-relevant transmission angle of an "
           "impact four-bar (its minimum is 0 at the impact by construction)"),
    Output("assembly_branch", "1", "assembly branch used (sigma)"),
    Output("special_crank_angle", "rad", "crank angle of the impact special position "
           "(phi1*)"),
    Output("special_position_count", "1", "number of special positions per crank turn"),
    Output("restitution_kinematic_max", "1", "largest |Rk| reachable with this rocker "
           "ratio (type b only)"),
)
assert tuple(p.name for p in PARAMETERS) == k.PARAMETERS
assert tuple(o.name for o in OUTPUTS) == k.OUTPUTS

# which types use which parameter: a parameter none of the swept types uses is an error
_USED_BY = {
    "R": {"a", "b", "c"},
    "largest_link": {"a", "b", "c"},
    "lambda0": {"b", "general"},
    "lambda2": {"general"},
    "lambda3": {"general"},
    "base_root": {"b"},
}


def _check(given: dict) -> None:
    """Cross-parameter rules; ``given`` maps each parameter the user set to its value set."""
    types = given.get("type") or {"a"}
    for name, users in _USED_BY.items():
        if name in given and not users & types:
            users_text = ", ".join(sorted(users))
            raise UserError(f"{name}: not used by type(s) {', '.join(sorted(types))}; "
                            f"it is used only by type(s) {users_text}")
    synth = types & {"a", "c"}
    if synth and "largest_link" not in given:
        raise UserError(f"largest_link: required for type(s) {', '.join(sorted(synth))} "
                        "(lambda2 for a, lambda0 for c)")
    if "b" in types:
        has_l, has_0 = "largest_link" in given, "lambda0" in given
        if has_l == has_0:
            raise UserError("largest_link: type b needs exactly one of largest_link "
                            "(lambda3) or lambda0")
    if "general" in types:
        for name in ("lambda0", "lambda2", "lambda3"):
            if name not in given:
                raise UserError(f"{name}: required for type general")
    if "lambda0" in given and "b" in types and "general" in types:
        raise UserError("lambda0: ambiguous with types b and general in one sweep; "
                        "run them separately")


register(Mechanism(
    name="crank_rocker",
    title="Crank-rocker impact four-bar: synthesis and kinematic restitution (seed 000)",
    parameters=PARAMETERS,
    outputs=OUTPUTS,
    run=k.crank_rocker_run,
    flags=("ok", "not_assemblable", "no_real_synthesis", "wrong_branch", "nonfinite",
           "degenerate", "no_impact", "second_special_position", "no_special_position"),
    method={"geometry_tol": geometry_tol("the full-turn test")},
    method_text="closed form: synthesis (seed 000 eqs. 10-11, linkages.md §3.1), branch "
                "values at the node from its series expansion (linkages.md §2.4), full-turn "
                "test (§2.5); no loop-closure sampling",
    check=_check,
))

assert k.SIGMA_IMPACT == 0.0  # the code sweep.mechanisms.common declares

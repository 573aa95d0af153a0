"""Crank-rocker impact four-bars of [CR]: synthesis, branch values, Rk (docs/models.md §1-2).

Everything here is closed form: the branch values at the special position come from the
series expansion of docs/models.md §1.5 (equal to the Hessian roots of the node), never
from sampling the loop closure near the node. Parameters arrive as rows of a float64 matrix
in the order of the declaration (categories as the codes below, NaN = not given); outputs
are written by name (``O.gamma``).
"""

import math
from collections import namedtuple

import numpy as np
from numba import njit

from kernels import INLINE_OPTIONS, KERNEL_OPTIONS
from kernels.block import block_arrays, design_block
from kernels.declaration import (BRANCH_FLAGS, POSITIVE, SIGMA_IMPACT, Boundary, Mechanism, Output,
                                 Quantity, assembly_branch, geometry_tol, path,
                                 profile_points)
from kernels.extrema import cell_midpoints
from kernels.fourbar import (CHANGE_POINT_A, CHANGE_POINT_B, CHANGE_POINT_C,
                             change_point_identities, crank_turns_fully,
                             PATH_FREE, path_branch, transmission_angle_half,
                             vector_kinematics)

TYPE_A, TYPE_B, TYPE_C, TYPE_GENERAL = 0, 1, 2, 3  # largest rod, rocker, base; any four-bar
ROOT_SMALLER_BASE, ROOT_LARGER_BASE = 0, 1
#: a type-b discriminant this far below 0 (relative to its terms) is rounding at the bound
BOUND_ROUNDING = 64 * 2.220446049250313e-16
#: the types with a special position by synthesis (the other, "general", given its ratios)
TYPES = ("a", "b", "c")
_LINKS = ("largest_link", "lambda0", "lambda2", "lambda3")
#: the ways each type may be given its geometry ([CR]'s tables are indexed by the
#: type's largest link under its own name: lambda2 for a, lambda3 for b, lambda0 for c)
_GEOMETRY = {
    "a": ({"largest_link"}, {"lambda2"}),
    "b": ({"largest_link"}, {"lambda3"}, {"lambda0"}),
    "c": ({"largest_link"}, {"lambda0"}),
    "general": ({"lambda0", "lambda2", "lambda3"},),
}


def _rules(given: dict) -> str | None:
    """Each swept type must get exactly one of its ways of giving the geometry; the energy
    per blow needs the rocker's inertia; a size and a speed are each given one way."""
    if "blow_energy" in given.get("outputs", ()) and "rocker_inertia" not in given:
        return "rocker_inertia: required for the output blow_energy (the rocker's J about D)"
    for derived, given_as in (("crank_length", "envelope"), ("omega1", "impact_speed_limit")):
        if derived in given and given_as in given:
            return (f"{given_as}: given instead of {derived}, the other is derived from it; "
                    "give one of them")
    types = given.get("type") or {"a"}
    links = {name for name in _LINKS if name in given}
    for t in sorted(types):
        ways = _GEOMETRY[t]
        if links in ways:
            continue
        text = " or ".join(" + ".join(sorted(w)) for w in ways)
        extra = sorted(links - set().union(*ways))
        if extra:
            return (f"{extra[0]}: not used by type {t}, which takes {text}"
                    + ("; run the types separately" if len(types) > 1 else ""))
        missing = sorted(set().union(*ways) - links) if t == "general" else []
        if missing:
            return f"{missing[0]}: required for type general (it takes {text})"
        name = sorted(links)[-1] if links else "largest_link"
        what = "exactly one of" if len(ways) > 1 else ""
        return f"{name}: type {t} takes {what} {text}".replace("  ", " ")
    return None


DECLARATION = Mechanism(
    name="crank_rocker",
    title="Crank-rocker impact four-bar: synthesis and kinematic restitution",
    summary="closed form: synthesis (the paper's eqs. 10-11; the type-b quadratic derived "
            "here), branch values at the node from its series expansion, full-turn test; "
            "no loop-closure sampling",
    references="Crank-rocker impact mechanisms with the largest connecting rod and the "
               "largest base (in Russian, Kyrgyz abstract), Institute of Machine Science, "
               "National Academy of Sciences of the Kyrgyz Republic; the copy received "
               "names neither authors nor year",
    parameters=(
        Quantity("type", "1", "impact four-bar type (a: largest rod, b: largest rocker, "
                 "c: largest base, general: any four-bar)", default="a",
                 choices={"a": TYPE_A, "b": TYPE_B, "c": TYPE_C, "general": TYPE_GENERAL},
                 label="type"),
        Quantity("R", "1", "physical restitution coefficient of the striker (R); synthesis "
                 "makes Rk = -R", symbol="R", default=0.3, minimum=0.0, maximum=1.0,
                 min_inclusive=False, max_inclusive=False, used_when={"type": TYPES},
                 label="restitution $R$"),
        Quantity("largest_link", "1", "largest link ratio of the type (lambda2 for a, "
                 "lambda3 for b, lambda0 for c)", used_when={"type": TYPES}, **POSITIVE,
                 label="largest link ratio"),
        Quantity("lambda0", "1", "base ratio l0/l1 (lambda0); type b: given instead of "
                 "lambda3; type c: its largest link", symbol="λ0",
                 used_when={"type": ("b", "c", "general")}, **POSITIVE,
                 label=r"base ratio $\lambda_0$"),
        Quantity("lambda2", "1", "connecting rod ratio l2/l1 (lambda2); type a: its "
                 "largest link", symbol="λ2", used_when={"type": ("a", "general")},
                 **POSITIVE, label=r"rod ratio $\lambda_2$"),
        Quantity("lambda3", "1", "rocker ratio l3/l1 (lambda3); type b: its largest link",
                 symbol="λ3", used_when={"type": ("b", "general")}, **POSITIVE,
                 label=r"rocker ratio $\lambda_3$"),
        Quantity("base_root", "1", "type b given lambda3: which root of the synthesis "
                 "quadratic is the base", default="smaller",
                 choices={"smaller": ROOT_SMALLER_BASE, "larger": ROOT_LARGER_BASE},
                 used_when={"type": ("b",)}, label="base root"),
        Quantity("crank_length", "m", "crank length (l1); or give envelope", symbol="l1",
                 default=0.1, **POSITIVE, label="crank $l_1$"),
        Quantity("envelope", "m", "overall size: the length of the largest link (the "
                 "linkage's size is mostly its largest link, [CR]); given instead of "
                 "crank_length, the crank length is derived from it",
                 replaces="crank_length", **POSITIVE, label="envelope $L$"),
        Quantity("omega1", "rad s-1", "crank angular velocity (omega1); its sign is the "
                 "rotation direction; or give impact_speed_limit", symbol="ω1", default=30.0,
                 nonzero=True, label=r"crank speed $\omega_1$"),
        Quantity("impact_speed_limit", "m s-1", "the rocker tip's speed limit at impact "
                 "([CR]: 10 m/s); given instead of omega1, the crank turns as fast as keeps "
                 "the blow at it (positive rotation)", replaces="omega1", **POSITIVE,
                 label="impact speed limit"),
        assembly_branch(),
        Quantity("rocker_inertia", "kg m2", "moment of inertia of the rocker and striker "
                 "about the rocker pivot D (J_D3), for the energy per blow", "J_D3",
                 **POSITIVE, label="rocker inertia $J_{D3}$"),
    ),
    outputs=(
        Output("lambda0", "1", "base ratio l0/l1 (lambda0)", "λ0", echoes="lambda0",
               label=r"base ratio $\lambda_0$"),
        Output("lambda2", "1", "connecting rod ratio l2/l1 (lambda2)", "λ2", echoes="lambda2",
               label=r"rod ratio $\lambda_2$"),
        Output("lambda3", "1", "rocker ratio l3/l1 (lambda3)", "λ3", echoes="lambda3",
               label=r"rocker ratio $\lambda_3$"),
        Output("gamma", "1", "node parameter sqrt(lambda0 lambda2 / lambda3) (gamma)", "γ",
               everywhere=True, label=r"node parameter $\gamma$"),
        Output("restitution_kinematic", "1", "kinematic restitution coefficient (Rk)", "Rk",
               "u31 after / u31 before the special position; negative for an impact "
               "mechanism", label="kinematic restitution $R_k$"),
        Output("transfer_before", "1", "rocker transfer ratio approaching the special "
               "position (u31 at impact)", "u31(φ1*−0)", label="$u_{31}$ before the node"),
        Output("transfer_after", "1", "rocker transfer ratio leaving the special position",
               "u31(φ1*+0)", label="$u_{31}$ after the node"),
        Output("impact_transfer_ratio", "1", "magnitude of the transfer ratio at impact "
               "(|u31(2 pi)| of the paper's tables)", "|u31(2π)|", label="$|u_{31}|$ at impact"),
        Output("impact_speed", "m s-1", "rocker tip speed at impact "
               "(|u31| |omega1| lambda3 l1)", label="impact speed $v$"),
        Output("crank_turns_fully", "1", "whether the crank can turn fully",
               flags={"undetermined": -1, "no": 0, "yes": 1}, undetermined="undetermined",
               everywhere=True, label="crank turns fully"),
        Output("transmission_angle_working", "rad", "smallest transmission angle over the "
               "working stroke: the crank turn outside method.working_window around the "
               "special position, the dead centre opposite it included", "μ_work",
               "at the special position itself every change-point four-bar is collinear "
               "(mu = 0); the window leaves out the impact's neighbourhood, where the rocker "
               "is stopped by the tool anyway", label=r"working transmission angle $\mu$"),
        Output("transmission_angle_opposite", "rad", "transmission angle at the dead "
               "centre opposite the special position", "μ", "the design-relevant "
               "transmission angle of an impact four-bar (its minimum is 0 at the impact by "
               "construction)", label=r"transmission angle opposite $\mu$"),
        Output("assembly_branch", "1", "assembly branch used (sigma)", "σ",
               flags=BRANCH_FLAGS, undetermined="undetermined", label=r"branch $\sigma$"),
        Output("special_crank_angle", "rad", "crank angle of the impact special position "
               "(phi1*)", "φ1*", everywhere=True, label=r"node angle $\varphi_1^*$"),
        Output("envelope", "m", "overall size: the length of the largest link", "L_max",
               echoes="envelope", label="envelope $L$"),
        Output("crank_length", "m", "crank length (l1), given or derived from envelope",
               "l1", echoes="crank_length", label="crank $l_1$"),
        Output("omega1", "rad s-1", "crank angular velocity, given or derived from "
               "impact_speed_limit", "ω1", echoes="omega1", label=r"crank speed $\omega_1$"),
        Output("blow_energy", "J", "energy per blow: the rocker's kinetic energy at impact, "
               "J_D3 (u31 omega1)^2 / 2, at the crank speed omega1 (given, or derived from "
               "impact_speed_limit; the machine's own speed and its loss: impact_machine)",
               "E_striker", on_request=True, label="blow energy $E$"),
        Output("blow_rate", "min-1", "blows per minute at the crank speed omega1 (one a "
               "crank turn)", on_request=True, label="blow rate"),
        Output("special_position_count", "1", "number of special positions per crank "
               "turn", diagnostic=True, count=True, label="special positions"),
        Output("restitution_kinematic_max", "1", "largest |Rk| reachable with this rocker "
               "ratio (type b only)", everywhere=True, label="largest $|R_k|$"),
    ),
    profiles=(Output("transfer_ratio", "1", "rocker transfer ratio u31 = dphi3/dphi1 on the "
                     "assembly branch (NaN where the loop cannot close)", "u31",
                     label="transfer ratio $u_{31}$"),
              Output("rocker_angle", "rad", "rocker angle (phi3), from the direction A->D, "
                     "counted within pi of its angle at the special position", "φ3",
                     label=r"rocker angle $\varphi_3$")),
    profile_dim=Quantity("crank_angle", "rad", "crank angle (phi1), from A->D", "φ1",
                         label=r"crank angle $\varphi_1$"),
    profile_coordinate=lambda method: cell_midpoints(method.profile_points,
                                                     cycle_turns(method) * 2.0 * np.pi),
    status=("ok", "not_assemblable", "no_real_synthesis", "wrong_branch", "nonfinite",
            "degenerate", "no_impact", "second_special_position", "no_special_position"),
    # at gamma itself (within geometry_tol) the linkage has a second change point, and the
    # values at the impact's are the ok side's limits: design values, flagged
    usable=("second_special_position",),
    method=(
        geometry_tol("the full-turn test"),
        Quantity("working_window", "rad", "half-width of the window around the special "
                 "position left out of the working stroke's transmission angle (default "
                 "30 degrees)", "δ_w", default=math.pi / 6.0, minimum=0.0, maximum=1.5),
        profile_points("crank angles of the transfer_ratio and rocker_angle profiles over "
                       "the cycle of the path (0: none)"),
        path("the profiles"),
    ),
    rules=_rules,
    boundaries=(
        *(Boundary(frozenset(sides), "types a and c: the largest link reaches gamma = "
                   "(1+R)/(1-R), below which the synthesized linkage cannot close; at gamma "
                   "itself it has a second change point, flagged where its identity holds to "
                   "geometry_tol times the link sum: |L/gamma - 1| <= geometry_tol "
                   "(gamma + 1)^2/(2 gamma)",
                   indicator="gamma")
          for sides in (("ok", "not_assemblable"), ("not_assemblable", "second_special_position"),
                        ("second_special_position", "ok"))),
        Boundary(frozenset(("ok", "no_real_synthesis")), "type b: the rocker reaches "
                 "(gamma + sqrt(gamma^2 - 1))^2, below which no base makes Rk = -R "
                 "(restitution_kinematic_max = R there)", indicator="restitution_kinematic_max"),
    ),
)
P = DECLARATION.parameter_index
O = DECLARATION.output_index
S = DECLARATION.status_codes
TRANSFER_RATIO = DECLARATION.profile_index.transfer_ratio
ROCKER_ANGLE = DECLARATION.profile_index.rocker_angle


@njit(**KERNEL_OPTIONS)
def gamma_from_restitution(r):
    """gamma = (1 + R)/(1 - R): the value of sqrt(lambda0 lambda2/lambda3) that gives Rk = -R."""
    return (1.0 + r) / (1.0 - r)


@njit(**KERNEL_OPTIONS)
def synthesize_largest_rod(lam2, r):
    """Type a (eq. 10 of [CR]): given lambda2 and R, return (lambda0, lambda3)."""
    g2 = gamma_from_restitution(r) ** 2
    return g2 * (lam2 + 1.0) / (g2 + lam2), lam2 * (lam2 + 1.0) / (g2 + lam2)


@njit(**KERNEL_OPTIONS)
def synthesize_largest_base(lam0, r):
    """Type c (eq. 11 of [CR]): given lambda0 and R, return (lambda2, lambda3)."""
    g2 = gamma_from_restitution(r) ** 2
    return g2 * (lam0 + 1.0) / (g2 + lam0), lam0 * (lam0 + 1.0) / (g2 + lam0)


@njit(**KERNEL_OPTIONS)
def synthesize_largest_rocker(lam3, r, larger_base):
    """Type b (derived, docs/models.md §2.1): lambda0, lambda2 are the roots of
    t^2 - (1 + lambda3) t + gamma^2 lambda3 = 0. Returns (lambda0, lambda2), NaN if complex.

    The smaller root is taken from the product of the roots to avoid cancellation. A rocker
    within rounding of the bound (a discriminant above -BOUND_ROUNDING (1 + lambda3)^2, about
    1e-14 relative in lambda3) is the bound itself: one double root; below it, NaN.
    """
    g2 = gamma_from_restitution(r) ** 2
    b = 1.0 + lam3
    disc = b * b - 4.0 * g2 * lam3
    if disc < 0.0:
        if disc < -BOUND_ROUNDING * b * b:
            return math.nan, math.nan
        disc = 0.0
    big = 0.5 * (b + math.sqrt(disc))
    small = g2 * lam3 / big
    if larger_base:
        return big, small
    return small, big


@njit(**KERNEL_OPTIONS)
def synthesize_largest_rocker_from_base(lam0, r):
    """Type b given lambda0: lambda3 = l0(l0-1)/(l0-g^2), lambda2 = g^2(l0-1)/(l0-g^2).

    Returns (lambda2, lambda3), NaN unless lambda0 > gamma^2: for 1 < lambda0 < gamma^2 the
    solution is negative, and for lambda0 < 1 it is positive but not a largest-rocker
    four-bar (lambda3 < 1): no synthesis of type b either way.
    """
    g2 = gamma_from_restitution(r) ** 2
    den = lam0 - g2
    if not den > 0.0:
        return math.nan, math.nan
    lam3 = lam0 * (lam0 - 1.0) / den
    lam2 = g2 * (lam0 - 1.0) / den
    if not (lam3 > 0.0 and lam2 > 0.0 and math.isfinite(lam3) and math.isfinite(lam2)):
        return math.nan, math.nan
    return lam2, lam3


@njit(**KERNEL_OPTIONS)
def branch_values(kind, lam0, gamma, sigma, direction):
    """One-sided transfer ratios (u31 before, u31 after) at the special position
    (docs/models.md §1.5).

    kind is CHANGE_POINT_A/B/C, gamma = sqrt(lambda0 lambda2/lambda3), sigma the assembly
    branch, direction the sign of omega1. From the series expansion:
    u31(phi1* +- 0) = (1 + kappa sigma sgn(eps) gamma)/D with kappa = -1 for b, +1 otherwise,
    D = 1 - lambda0 (a, b) or 1 + lambda0 (c). The crank approaches phi1* from the side
    -direction.
    """
    kappa = -1.0 if kind == CHANGE_POINT_B else 1.0
    inv_den = 1.0 / (1.0 + lam0 if kind == CHANGE_POINT_C else 1.0 - lam0)
    s = kappa * sigma * direction * gamma
    return (1.0 - s) * inv_den, (1.0 + s) * inv_den


@njit(**KERNEL_OPTIONS)
def impact_branch(kind, direction):
    """The assembly branch sigma that gives |Rk| < 1 for this change point and rotation."""
    kappa = -1.0 if kind == CHANGE_POINT_B else 1.0
    return -kappa * direction


@njit(**KERNEL_OPTIONS)
def _first_identity(mask):
    if mask & CHANGE_POINT_A:
        return CHANGE_POINT_A
    if mask & CHANGE_POINT_B:
        return CHANGE_POINT_B
    if mask & CHANGE_POINT_C:
        return CHANGE_POINT_C
    return 0


@njit(**KERNEL_OPTIONS)
def _given(first, second):
    """The first of two alternative inputs that is given (NaN = not given)."""
    return second if math.isnan(first) else first


#: one linkage: its status (S) and the outputs of the declaration by their names (NaN where
#: a value does not exist): lambda0..3, gamma, Rk, u31 before and after the node, |u31
#: before|, the impact speed, whether the crank turns fully (0/1), the transmission angles
#: on the working stroke and opposite the node, the branch sigma, phi1*, the count of
#: special positions, |Rk| max, the envelope, l1 and omega1
LinkagePoint = namedtuple("LinkagePoint", [
    "status", "lambda0", "lambda2", "lambda3", "gamma", "restitution_kinematic",
    "transfer_before", "transfer_after", "impact_transfer_ratio", "impact_speed",
    "crank_turns_fully", "transmission_angle_working", "transmission_angle_opposite",
    "assembly_branch", "special_crank_angle", "special_position_count",
    "restitution_kinematic_max", "envelope", "crank_length", "omega1"])


@njit(**KERNEL_OPTIONS)
def linkage_point(kind_code, r, big, lam0_in, lam2_in, lam3_in, root, l1, w, sigma_code, tol,
                  envelope, speed_limit, window):
    """Evaluate one linkage: its LinkagePoint.

    Works on local scalars and returns everything at once; NaN stands for a value that
    does not exist at this point. ``big``
    is largest_link; the type's own name for its largest link may stand in for it.
    ``envelope`` (not NaN): the largest link's length, from which l1 follows;
    ``speed_limit`` (not NaN): the impact speed from which omega1 > 0 follows; ``window``:
    the half-width around the node left out of the working transmission angle.

    One pass with early exits, in the four numbered steps below: each step may end the pass
    with a status, and the twenty values the steps share go out in one record; split into
    functions, each step would be a compile unit of its own in a first run
    (benchmarks/compile_events.py counts them).
    """
    nan = math.nan
    lam0 = lam2 = lam3 = gamma = rk = before = after = ratio = speed = nan
    turns_out = mu_min = mu_opp = branch = phi_star = count_out = rk_max = nan
    size = nan
    if not math.isnan(envelope):
        l1 = nan  # derived from the envelope below, where the linkage exists
    if not math.isnan(speed_limit):
        w = 1.0  # the direction; the speed itself follows from the limit below
    direction = 1.0 if w > 0.0 else -1.0
    status = S.ok
    for _ in range(1):  # a single pass; "break" ends it early with the status set
        # 1. geometry: echo, or synthesis with Rk = -R ([CR] eqs. 10, 11; for b
        # docs/models.md §2.1)
        if kind_code == TYPE_A:
            lam2 = _given(big, lam2_in)
            lam0, lam3 = synthesize_largest_rod(lam2, r)
            kind = CHANGE_POINT_A
        elif kind_code == TYPE_C:
            lam0 = _given(big, lam0_in)
            lam2, lam3 = synthesize_largest_base(lam0, r)
            kind = CHANGE_POINT_C
        elif kind_code == TYPE_B:
            kind = CHANGE_POINT_B
            lam3 = _given(big, lam3_in)
            if math.isnan(lam3):
                lam0 = lam0_in
                lam2, lam3 = synthesize_largest_rocker_from_base(lam0, r)
            else:
                lam0, lam2 = synthesize_largest_rocker(lam3, r, root == ROOT_LARGER_BASE)
            if lam3 > 0.0:
                g_max = (1.0 + lam3) / (2.0 * math.sqrt(lam3))
                rk_max = (g_max - 1.0) / (g_max + 1.0)
            if math.isnan(lam0) or math.isnan(lam2) or math.isnan(lam3):
                lam0 = lam2 = lam3 = nan
                status = S.no_real_synthesis
                break
        else:
            lam0, lam2, lam3 = lam0_in, lam2_in, lam3_in
            kind = 0

        # 2. change points: every one on the turn, not only the impact one (H10)
        mask = change_point_identities(lam0, lam2, lam3, tol)
        count = (mask & 1) + ((mask >> 1) & 1) + ((mask >> 2) & 1)
        count_out = count
        if kind == 0:
            kind = _first_identity(mask)

        # 3. full-turn feasibility (docs/models.md §1.6) and transmission angles at the two
        # dead centres;
        # at a dead centre that is a change point all links are collinear: mu = 0 exactly
        # (evaluating it there would return sqrt(rounding) ~ 1e-8)
        turns = crank_turns_fully(lam0, 1.0, lam2, lam3, tol)
        turns_out = 1.0 if turns else 0.0
        mu0 = mu_pi = nan
        if turns:
            if mask & (CHANGE_POINT_A | CHANGE_POINT_B):
                mu0 = 0.0
            else:
                mu0 = transmission_angle_half(0.0, 1.0, lam0, 1.0, lam2, lam3, tol)
            if mask & CHANGE_POINT_C:
                mu_pi = 0.0
            else:
                mu_pi = transmission_angle_half(1.0, 0.0, lam0, 1.0, lam2, lam3, tol)
            mu_min = min(mu0, mu_pi)
        if kind != 0:
            gamma = math.sqrt(lam0 * lam2 / lam3)
            phi_star = math.pi if kind == CHANGE_POINT_C else 0.0
            if turns:
                mu_opp = mu0 if kind == CHANGE_POINT_C else mu_pi
            # B coincides with D at the node: one branch slope is infinite (H9)
            if kind != CHANGE_POINT_C and abs(lam0 - 1.0) <= tol * (1.0 + lam0 + lam2 + lam3):
                status = S.degenerate
                break
        largest = max(1.0, lam0, lam2, lam3)
        if not math.isnan(envelope):  # the size given: the crank length follows
            l1 = envelope / largest
        size = largest * l1
        if turns and kind != 0:  # the working stroke: outside the window around the node
            mu_min = working_transmission_angle(lam0, lam2, lam3, phi_star, window, mu_opp,
                                                tol)
        if not turns:
            status = S.not_assemblable
            break
        if kind == 0:
            status = S.no_special_position
            break

        # 4. branch values, Rk and the impact speed on the chosen assembly branch
        impact_sigma = impact_branch(kind, direction)
        sigma = impact_sigma if sigma_code == SIGMA_IMPACT else sigma_code
        before, after = branch_values(kind, lam0, gamma, sigma, direction)
        branch = sigma
        # gamma = 1: one branch value is 0 and the rocker stops at the node: no Rk exists
        rk = after / before if before != 0.0 else nan
        ratio = abs(before)
        if not math.isnan(speed_limit):  # the blow at the limit: the fastest crank
            w = speed_limit / (ratio * lam3 * l1)
        speed = ratio * abs(w) * lam3 * l1
        if gamma <= 1.0:
            status = S.no_impact  # the rocker does not reverse at the node
        elif not (math.isfinite(rk) and math.isfinite(before) and math.isfinite(after)
                  and math.isfinite(speed) and math.isfinite(gamma)
                  and math.isfinite(mu_min)):
            status = S.nonfinite
        elif sigma != impact_sigma:
            status = S.wrong_branch
        elif count > 1:
            status = S.second_special_position
    if math.isnan(before) and not math.isnan(speed_limit):
        w = nan  # no blow, no speed to derive from its limit
    return LinkagePoint(status, lam0, lam2, lam3, gamma, rk, before, after, ratio, speed,
                        turns_out, mu_min, mu_opp, branch, phi_star, count_out, rk_max, size,
                        l1, w)


@njit(**KERNEL_OPTIONS)
def working_transmission_angle(lam0, lam2, lam3, phi_star, window, mu_opposite, tol):
    """The smallest (acute) transmission angle over the crank turn outside
    |phi1 - phi1*| < window. The angle depends on phi1 only through |DB|^2, monotone in
    phi1 between the dead centres, so its extremes over the stroke lie at the window's two
    edges (mirror images: one value) and at the dead centre opposite the node."""
    if window <= 0.0:
        return 0.0  # the node itself: all links collinear
    edge = phi_star + window
    mu_edge = transmission_angle_half(math.sin(0.5 * edge), math.cos(0.5 * edge), lam0, 1.0,
                                      lam2, lam3, tol)
    return min(mu_edge, mu_opposite)


@njit(**INLINE_OPTIONS)
def design(i, pr, settings, out, prof):
    """One grid point (kernels/block.py): its linkage's outputs by name, its status."""
    return _linkage_outputs(pr, settings, out).status


@njit(**INLINE_OPTIONS)
def design_with_profiles(i, pr, settings, out, prof):
    """One grid point with its profiles over settings.angles ([CR] Fig. 2)."""
    lp = _linkage_outputs(pr, settings, out)
    if lp.status == S.ok or lp.status == S.second_special_position:  # the usable statuses
        _rocker_profiles(lp, settings, prof)
    return lp.status


@njit(**INLINE_OPTIONS)
def _linkage_outputs(pr, settings, out):
    """The point's LinkagePoint, its outputs written by name."""
    lp = linkage_point(
        int(pr[P.type]), pr[P.R], pr[P.largest_link], pr[P.lambda0], pr[P.lambda2],
        pr[P.lambda3], int(pr[P.base_root]), pr[P.crank_length], pr[P.omega1], pr[P.sigma],
        settings.geometry_tol, pr[P.envelope], pr[P.impact_speed_limit],
        settings.working_window)
    out[O.lambda0], out[O.lambda2], out[O.lambda3] = lp.lambda0, lp.lambda2, lp.lambda3
    out[O.gamma], out[O.restitution_kinematic] = lp.gamma, lp.restitution_kinematic
    out[O.transfer_before], out[O.transfer_after] = lp.transfer_before, lp.transfer_after
    out[O.impact_transfer_ratio], out[O.impact_speed] = (lp.impact_transfer_ratio,
                                                         lp.impact_speed)
    out[O.crank_turns_fully] = lp.crank_turns_fully
    out[O.transmission_angle_working] = lp.transmission_angle_working
    out[O.transmission_angle_opposite] = lp.transmission_angle_opposite
    out[O.assembly_branch] = lp.assembly_branch
    out[O.special_crank_angle] = lp.special_crank_angle
    out[O.special_position_count] = lp.special_position_count
    out[O.restitution_kinematic_max] = lp.restitution_kinematic_max
    out[O.envelope], out[O.crank_length], out[O.omega1] = (lp.envelope, lp.crank_length,
                                                         lp.omega1)
    return lp


@njit(**INLINE_OPTIONS)
def _rocker_profiles(lp, settings, prof):
    """u31 and the rocker's angle over the cycle ([CR] Fig. 2) into prof."""
    angles = settings.angles
    # the rocker's angle at the node: the profile is counted within pi of it (the swing
    # never wraps)
    c1, s1, c2, s2, c3, s3, u21, u31, du21, du31 = vector_kinematics(
        lp.special_crank_angle, lp.lambda0, 1.0, lp.lambda2, lp.lambda3,
        lp.assembly_branch, settings.geometry_tol)
    node3 = math.atan2(s3, c3)
    for j in range(angles.shape[0]):
        sigma = path_branch(angles[j], lp.assembly_branch, lp.special_crank_angle,
                            int(lp.special_position_count), settings.path)
        c1, s1, c2, s2, c3, s3, u21, u31, du21, du31 = vector_kinematics(
            angles[j], lp.lambda0, 1.0, lp.lambda2, lp.lambda3, sigma, settings.geometry_tol)
        prof[TRANSFER_RATIO, j] = u31
        prof[ROCKER_ANGLE, j] = node3 - math.pi + (math.atan2(s3, c3) - node3
                                                   + math.pi) % (2.0 * math.pi)


#: the method's options the block reads, by name (angles: the profiles' crank angles)
Settings = namedtuple("Settings", ["geometry_tol", "working_window", "angles", "path"])


def cycle_turns(method) -> int:
    """Crank turns of the profiles' cycle: one on the impact path, two on the free path."""
    return 2 if method.path == PATH_FREE else 1


#: the blocks: each design of it by ``design`` (kernels/block.py), cached on disk; with the
#: profiles, compiled only where a sweep asks for them (the four-bar's kinematics over the
#: cycle were a fifth of the example's first compile)
crank_rocker_block = design_block(design, "crank_rocker_block", globals(), KERNEL_OPTIONS)
crank_rocker_profile_block = design_block(design_with_profiles, "crank_rocker_profile_block",
                                          globals(), KERNEL_OPTIONS)


def run(params, method):
    """Entry point: (outputs, status, profiles[2, n, n_angles]). The energy per blow and the
    blow rate only where asked for."""
    n = params.shape[1]
    angles = DECLARATION.profile_coordinate(method)
    out, status, prof = block_arrays(DECLARATION, n, angles)
    block = crank_rocker_profile_block if angles.shape[0] else crank_rocker_block
    block(np.ascontiguousarray(params),
                       Settings(geometry_tol=float(method.geometry_tol),
                                working_window=float(method.working_window), angles=angles,
                                path=int(method.path)),
                       out, status, prof)
    w = out[O.omega1]
    out[O.blow_energy] = (0.5 * params[P.rocker_inertia] * (out[O.transfer_before] * w) ** 2
                          if "blow_energy" in method.outputs else np.nan)
    out[O.blow_rate] = (np.where(np.isfinite(out[O.transfer_before]),
                                 60.0 * np.abs(w) / (2.0 * np.pi), np.nan)
                        if "blow_rate" in method.outputs else np.nan)
    return out, status, prof

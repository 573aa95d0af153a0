"""Crank-rocker impact four-bars of seed 000: synthesis, branch values, Rk (linkages.md §2-3).

Everything here is closed form: the branch values at the special position come from the
series expansion of §2.4 (equal to the Hessian roots of the node), never from sampling the
loop closure near the node. Parameters arrive as rows of a float64 matrix in the order of
PARAMETERS (categories as the codes below, NaN = not given); outputs are written as rows in
the order of OUTPUTS.
"""

import math

import numpy as np
from numba import njit

from kernels import status as st
from kernels import KERNEL_OPTIONS
from kernels.fourbar import (
    CHANGE_POINT_A,
    CHANGE_POINT_B,
    CHANGE_POINT_C,
    change_point_identities,
    crank_turns_fully,
    transmission_angle_half,
)

PARAMETERS = (
    "type", "R", "largest_link", "lambda0", "lambda2", "lambda3", "base_root",
    "crank_length", "omega1", "sigma",
)
OUTPUTS = (
    "lambda0", "lambda2", "lambda3", "gamma", "restitution_kinematic", "transfer_before",
    "transfer_after", "impact_transfer_ratio", "impact_speed", "crank_turns_fully",
    "transmission_angle_min", "transmission_angle_opposite", "assembly_branch",
    "special_crank_angle", "special_position_count", "restitution_kinematic_max",
)
METHOD = ("geometry_tol",)

TYPE_A, TYPE_B, TYPE_C, TYPE_GENERAL = 0, 1, 2, 3  # largest rod, rocker, base; any four-bar
SIGMA_IMPACT = 0.0  # sigma code meaning "the branch that makes the node an impact"
ROOT_SMALLER_BASE, ROOT_LARGER_BASE = 0, 1

_P = {name: i for i, name in enumerate(PARAMETERS)}
_O = {name: i for i, name in enumerate(OUTPUTS)}
P_TYPE, P_R, P_L = _P["type"], _P["R"], _P["largest_link"]
P_LAM0, P_LAM2, P_LAM3 = _P["lambda0"], _P["lambda2"], _P["lambda3"]
P_ROOT, P_L1, P_W, P_SIGMA = _P["base_root"], _P["crank_length"], _P["omega1"], _P["sigma"]
O_LAM0, O_LAM2, O_LAM3, O_GAMMA = _O["lambda0"], _O["lambda2"], _O["lambda3"], _O["gamma"]
O_RK, O_BEFORE, O_AFTER = _O["restitution_kinematic"], _O["transfer_before"], _O["transfer_after"]
O_RATIO, O_SPEED, O_TURNS = _O["impact_transfer_ratio"], _O["impact_speed"], _O["crank_turns_fully"]
O_MU_MIN, O_MU_OPP = _O["transmission_angle_min"], _O["transmission_angle_opposite"]
O_BRANCH, O_PHI_STAR = _O["assembly_branch"], _O["special_crank_angle"]
O_COUNT, O_RK_MAX = _O["special_position_count"], _O["restitution_kinematic_max"]


@njit(**KERNEL_OPTIONS)
def gamma_from_restitution(r):
    """gamma = (1 + R)/(1 - R): the value of sqrt(lambda0 lambda2/lambda3) that gives Rk = -R."""
    return (1.0 + r) / (1.0 - r)


@njit(**KERNEL_OPTIONS)
def synthesize_largest_rod(lam2, r):
    """Type a (eq. 10 of seed 000): given lambda2 and R, return (lambda0, lambda3)."""
    g2 = gamma_from_restitution(r) ** 2
    return g2 * (lam2 + 1.0) / (g2 + lam2), lam2 * (lam2 + 1.0) / (g2 + lam2)


@njit(**KERNEL_OPTIONS)
def synthesize_largest_base(lam0, r):
    """Type c (eq. 11 of seed 000): given lambda0 and R, return (lambda2, lambda3)."""
    g2 = gamma_from_restitution(r) ** 2
    return g2 * (lam0 + 1.0) / (g2 + lam0), lam0 * (lam0 + 1.0) / (g2 + lam0)


@njit(**KERNEL_OPTIONS)
def synthesize_largest_rocker(lam3, r, larger_base, tol):
    """Type b (derived, linkages.md §3.1): lambda0, lambda2 are the roots of
    t^2 - (1 + lambda3) t + gamma^2 lambda3 = 0. Returns (lambda0, lambda2), NaN if complex.

    The smaller root is taken from the product of the roots to avoid cancellation.
    """
    g2 = gamma_from_restitution(r) ** 2
    b = 1.0 + lam3
    disc = b * b - 4.0 * g2 * lam3
    if disc < 0.0:
        if disc < -tol * b * b:
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

    Returns (lambda2, lambda3), NaN where no positive solution exists (lambda0 = gamma^2).
    """
    g2 = gamma_from_restitution(r) ** 2
    den = lam0 - g2
    if den == 0.0:
        return math.nan, math.nan
    lam3 = lam0 * (lam0 - 1.0) / den
    lam2 = g2 * (lam0 - 1.0) / den
    if not (lam3 > 0.0 and lam2 > 0.0 and math.isfinite(lam3) and math.isfinite(lam2)):
        return math.nan, math.nan
    return lam2, lam3


@njit(**KERNEL_OPTIONS)
def branch_values(kind, lam0, gamma, sigma, direction):
    """One-sided transfer ratios (u31 before, u31 after) at the special position (§2.4).

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
def _point(kind_code, r, big, lam0_in, lam2_in, lam3_in, root, l1, w, sigma_code, tol):
    """Evaluate one grid point. Returns (status, outputs in the order of OUTPUTS).

    Works on local scalars and returns everything at once, so the block loop writes each
    output exactly once; NaN stands for a value that does not exist at this point.
    """
    nan = math.nan
    lam0 = lam2 = lam3 = gamma = rk = before = after = ratio = speed = nan
    turns_out = mu_min = mu_opp = branch = phi_star = count_out = rk_max = nan
    direction = 1.0 if w > 0.0 else -1.0
    status = st.OK
    for _ in range(1):  # a single pass; "break" ends it early with the status set
        # 1. geometry: echo, or synthesis with Rk = -R (seed 000 eqs. 10, 11; §3.1 for b)
        if kind_code == TYPE_A:
            lam2 = big
            lam0, lam3 = synthesize_largest_rod(lam2, r)
            kind = CHANGE_POINT_A
        elif kind_code == TYPE_C:
            lam0 = big
            lam2, lam3 = synthesize_largest_base(lam0, r)
            kind = CHANGE_POINT_C
        elif kind_code == TYPE_B:
            kind = CHANGE_POINT_B
            if not math.isnan(lam0_in):
                lam0 = lam0_in
                lam2, lam3 = synthesize_largest_rocker_from_base(lam0, r)
            else:
                lam3 = big
                lam0, lam2 = synthesize_largest_rocker(lam3, r, root == ROOT_LARGER_BASE, tol)
            if lam3 > 0.0:
                g_max = (1.0 + lam3) / (2.0 * math.sqrt(lam3))
                rk_max = (g_max - 1.0) / (g_max + 1.0)
            if math.isnan(lam0) or math.isnan(lam2) or math.isnan(lam3):
                lam0 = lam2 = lam3 = nan
                status = st.NO_REAL_SYNTHESIS
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

        # 3. full-turn feasibility (§2.5) and transmission angles at the two dead centres;
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
                status = st.DEGENERATE
                break
        if not turns:
            status = st.NOT_ASSEMBLABLE
            break
        if kind == 0:
            status = st.NO_SPECIAL_POSITION
            break

        # 4. branch values, Rk and the impact speed on the chosen assembly branch
        impact_sigma = impact_branch(kind, direction)
        sigma = impact_sigma if sigma_code == SIGMA_IMPACT else sigma_code
        before, after = branch_values(kind, lam0, gamma, sigma, direction)
        branch = sigma
        rk = after / before
        ratio = abs(before)
        speed = ratio * abs(w) * lam3 * l1
        if not (math.isfinite(rk) and math.isfinite(before) and math.isfinite(after)
                and math.isfinite(speed) and math.isfinite(gamma) and math.isfinite(mu_min)):
            status = st.NONFINITE
        elif not (gamma > 1.0):
            status = st.NO_IMPACT
        elif sigma != impact_sigma:
            status = st.WRONG_BRANCH
        elif count > 1:
            status = st.SECOND_SPECIAL_POSITION
    return status, (lam0, lam2, lam3, gamma, rk, before, after, ratio, speed, turns_out,
                    mu_min, mu_opp, branch, phi_star, count_out, rk_max)


@njit(**KERNEL_OPTIONS)
def crank_rocker_block(params, method, out, status):
    """Evaluate a block of grid points: params (n_params, n), out (n_outputs, n), status (n,)."""
    tol = method[0]
    for i in range(params.shape[1]):
        code, values = _point(int(params[P_TYPE, i]), params[P_R, i], params[P_L, i],
                              params[P_LAM0, i], params[P_LAM2, i], params[P_LAM3, i],
                              int(params[P_ROOT, i]), params[P_L1, i], params[P_W, i],
                              params[P_SIGMA, i], tol)
        status[i] = code
        for k in range(len(values)):
            out[k, i] = values[k]


def crank_rocker_run(params, method):
    """Registry entry point: (outputs, status, profiles); this mechanism has no profiles."""
    n = params.shape[1]
    out = np.empty((len(OUTPUTS), n))
    status = np.empty(n, dtype=np.int8)
    crank_rocker_block(params, method, out, status)
    return out, status, np.empty((0, n, 0))

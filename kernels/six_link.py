"""Six-link impact mechanism with the largest rocker (seed 003; linkages.md §4).

Stage 1 is a double crank (base lambda6 = 1 - lambda2 + lambda3 over l1, the shortest link)
with a special position at phi1* = 0. With no stop there, it follows the smooth analytic
curve through the node, so its assembly branch flips at every pass:
sigma1 = sigma1_0 (-1)^floor(phi1 / 2pi), with sigma1_0 = +1 (the other choice is the same
motion shifted by one crank turn). Then u31 is continuous and at the node alternates between
(1 - gamma1)/(1 - lambda6) and (1 + gamma1)/(1 - lambda6).

Stage 2 is an impact four-bar of type b driven by link 3 (crank angle phi3 + delta - beta
relative to its base DE, lengths over l3: mu6 = 1 - mu4 + mu5). It keeps its branch: the
impact reverses the rocker. The branch is the impact branch for the actual rotation direction
of link 3, not seed 003's sigma = -1, which holds only for clockwise rotation (§4.2).
Composition: u51 = u31 u53 and u'51 = u'31 u53 + u31^2 u'53.
"""

import math

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS
from kernels import status as st
from kernels.crank_rocker import branch_values, impact_branch
from kernels.elementary import golden_points, golden_shrink
from kernels.fourbar import CHANGE_POINT_B, crank_turns_fully, vector_kinematics

PARAMETERS = ("lambda2", "lambda3", "mu4", "mu5", "beta", "delta", "direction", "omega1",
              "crank_length")
OUTPUTS = (
    "gamma1", "gamma2", "restitution_kinematic", "transfer_stage1_low",
    "transfer_stage1_high", "transfer_impact_1", "transfer_impact_2",
    "transfer_stage1_impact_1", "transfer_stage1_impact_2", "impact_crank_angle_1",
    "impact_crank_angle_2", "impact_speed_1", "impact_speed_2", "transfer_peak",
    "transfer2_peak", "assembly_branch_stage2",
)
PROFILES = ("rocker_angle",)
METHOD = ("geometry_tol", "samples", "profile_points")

SIGMA1_START = 1.0
TWO_PI = 2.0 * math.pi


@njit(**KERNEL_OPTIONS)
def stage1_branch(phi1):
    """The alternation rule: the stage-1 assembly branch on the smooth path at phi1."""
    return SIGMA1_START if math.floor(phi1 / TWO_PI) % 2 == 0 else -SIGMA1_START


@njit(**KERNEL_OPTIONS)
def stage1(phi1, lam6, lam2, lam3, snap):
    """Continuous phi3, u31 and u'31 of stage 1 on the switched (smooth) path.

    phi3 - phi1 stays in (0, 2pi) for a drag link (pi at the node), so phi1 + mod(phi3 - phi1,
    2pi) is the continuous rocker-crank angle; u31 is NaN exactly at a node (0/0, H1).
    """
    c1, s1, c2, s2, c3, s3, u21, u31, du21, du31 = vector_kinematics(
        phi1, lam6, 1.0, lam2, lam3, stage1_branch(phi1), snap)
    rel = (math.atan2(s3, c3) - phi1) % TWO_PI
    return phi1 + rel, u31, du31


@njit(**KERNEL_OPTIONS)
def stage1_node_value(m, lam6, gamma1):
    """u31 on the smooth path at the node phi1 = 2 pi m (closed form, §4.3)."""
    sigma_before = stage1_branch(TWO_PI * m - 1.0)
    return (1.0 + sigma_before * gamma1) / (1.0 - lam6)


@njit(**KERNEL_OPTIONS)
def _impact_angle(target, lam6, lam2, lam3, offset, snap):
    """phi1 in [0, 4 pi] where phi3 + offset = target, by bisection (phi3 is increasing)."""
    lo, hi = 0.0, 2.0 * TWO_PI
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid == lo or mid == hi:
            break
        if stage1(mid, lam6, lam2, lam3, snap)[0] + offset < target:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@njit(**KERNEL_OPTIONS)
def _transfer(phi, lam6, lam2, lam3, mu6, mu4, mu5, sigma2, offset, tol):
    """(u51, u'51) at crank angle phi: stage 1 on its smooth path, stage 2 on sigma2."""
    phi3, u31, du31 = stage1(phi, lam6, lam2, lam3, tol)
    c1, s1, c2, s2, c3, s3, u21, u53, du21, du53 = vector_kinematics(
        phi3 + offset, mu6, 1.0, mu4, mu5, sigma2, tol)
    return u31 * u53, du31 * u53 + u31 * u31 * du53


@njit(**KERNEL_OPTIONS)
def _refine_peak(which, a, b, sampled, lam6, lam2, lam3, mu6, mu4, mu5, sigma2, offset, tol):
    """Golden section for the maximum of |u51| (which = 0) or |u'51| (1) on [a, b], to 1e-10
    of the interval; never below the sampled maximum (a jump at an impact is covered by
    the exact one-sided values)."""
    def value(phi):
        u51, du51 = _transfer(phi, lam6, lam2, lam3, mu6, mu4, mu5, sigma2, offset, tol)
        v = abs(u51) if which == 0 else abs(du51)
        return v if math.isfinite(v) else -1.0

    c, d = golden_points(a, b)
    fc, fd = value(c), value(d)
    while b - a > 1e-10 * (1.0 + abs(a)):
        a, b, c, d, fc, fd, left = golden_shrink(a, b, c, d, fc, fd)
        if left:
            fc = value(c)
        else:
            fd = value(d)
    return max(sampled, fc, fd)


@njit(**KERNEL_OPTIONS)
def _point(lam2, lam3, mu4, mu5, beta, delta, direction, w, l1, tol, n_samples,
           prof_angles, out, prof):
    nan = math.nan
    for k in range(out.shape[0]):
        out[k] = nan
    for j in range(prof.shape[0]):
        prof[j] = nan
    lam6 = 1.0 - lam2 + lam3
    mu6 = 1.0 - mu4 + mu5
    # §4.1: stage 1 l1 < l3 < l2 with l2 - l3 < l1 (a drag link), stage 2 l3 < l4 < l5
    if not (1.0 < lam3 < lam2 and lam2 - lam3 < 1.0 and 1.0 < mu4 < mu5):
        return st.NOT_ASSEMBLABLE
    if not (crank_turns_fully(lam6, 1.0, lam2, lam3, tol)
            and crank_turns_fully(mu6, 1.0, mu4, mu5, tol)):
        return st.NOT_ASSEMBLABLE
    gamma1 = math.sqrt(lam6 * lam2 / lam3)
    gamma2 = math.sqrt(mu6 * mu4 / mu5)
    out[0], out[1] = gamma1, gamma2
    out[2] = (1.0 - gamma2) / (1.0 + gamma2)
    out[3] = (1.0 - gamma1) / (1.0 - lam6)
    out[4] = (1.0 + gamma1) / (1.0 - lam6)
    sigma2 = impact_branch(CHANGE_POINT_B, direction)  # link 3 turns with the crank
    out[15] = sigma2
    offset = delta - beta
    before53, after53 = branch_values(CHANGE_POINT_B, mu6, gamma2, sigma2, direction)

    # the two impacts of a 4 pi cycle: phi3 + delta - beta = 2 pi k (phi3 grows by 4 pi)
    start = math.pi + offset  # phi3 = pi at the node phi1 = 0
    k = math.floor(start / TWO_PI) + 1
    peak = 0.0
    for j in range(2):
        target = TWO_PI * (k + j)
        phi_i = _impact_angle(target, lam6, lam2, lam3, offset, tol)
        u31 = stage1(phi_i, lam6, lam2, lam3, tol)[1]
        m = round(phi_i / TWO_PI)
        if math.isnan(u31) or abs(phi_i - TWO_PI * m) < 1e-12:
            u31 = stage1_node_value(m, lam6, gamma1)  # the impact falls on stage 1's node
        u51 = u31 * before53
        out[5 + j] = u51
        out[7 + j] = u31
        out[9 + j] = phi_i % (2.0 * TWO_PI)
        out[11 + j] = abs(u51) * w * mu5 * lam3 * l1
        peak = max(peak, abs(u51), abs(u31 * after53))

    # peaks of |u51| and |u'51|: a uniform sample of the 4 pi cycle (nodes excluded) finds
    # each maximum's basin, golden section on the exact kinematics refines it
    peak2 = 0.0
    n = 2 * (n_samples // 2)
    spacing = 2.0 * TWO_PI / n
    where1 = where2 = 0.0
    for j in range(n):
        phi = spacing * (j + 0.5)
        u51, du51 = _transfer(phi, lam6, lam2, lam3, mu6, mu4, mu5, sigma2, offset, tol)
        if math.isfinite(u51) and abs(u51) > peak:
            peak, where1 = abs(u51), phi
        if math.isfinite(du51) and abs(du51) > peak2:
            peak2, where2 = abs(du51), phi
    if where1 != 0.0:
        peak = _refine_peak(0, where1 - spacing, where1 + spacing, peak, lam6, lam2, lam3,
                            mu6, mu4, mu5, sigma2, offset, tol)
    if where2 != 0.0:
        peak2 = _refine_peak(1, where2 - spacing, where2 + spacing, peak2, lam6, lam2, lam3,
                             mu6, mu4, mu5, sigma2, offset, tol)
    out[13], out[14] = peak, peak2

    for j in range(prof_angles.shape[0]):
        phi3 = stage1(prof_angles[j], lam6, lam2, lam3, tol)[0]
        c1, s1, c2, s2, c3, s3, u21, u53, du21, du53 = vector_kinematics(
            phi3 + offset, mu6, 1.0, mu4, mu5, sigma2, tol)
        prof[j] = math.atan2(s3, c3) % TWO_PI  # the rocker swings about phi5* = pi

    for k in range(out.shape[0]):
        if not math.isfinite(out[k]):
            return st.NONFINITE
    return st.OK


@njit(**KERNEL_OPTIONS)
def six_link_block(params, tol, n_samples, prof_angles, out, status, prof):
    out_i = np.empty(out.shape[0])
    prof_i = np.empty(prof.shape[2])
    for i in range(params.shape[1]):
        status[i] = _point(params[0, i], params[1, i], params[2, i], params[3, i],
                           params[4, i], params[5, i], params[6, i], params[7, i],
                           params[8, i], tol, n_samples, prof_angles, out_i, prof_i)
        for k in range(out.shape[0]):
            out[k, i] = out_i[k]
        for j in range(prof.shape[2]):
            prof[0, i, j] = prof_i[j]


def profile_angles(n):
    """The crank_angle coordinate of profiles: cell midpoints of the 4 pi cycle."""
    return 4.0 * np.pi * (np.arange(n) + 0.5) / n if n > 0 else np.empty(0)


def six_link_run(params, method):
    """Registry entry point: (outputs, status, profiles[1, n, n_angles])."""
    angles = profile_angles(int(method[2]))
    n = params.shape[1]
    out = np.empty((len(OUTPUTS), n))
    status = np.empty(n, dtype=np.int8)
    prof = np.empty((1, n, angles.shape[0]))
    six_link_block(np.ascontiguousarray(params), method[0], int(method[1]), angles, out,
                   status, prof)
    return out, status, prof

"""Six-link impact mechanism with the largest rocker ([SIX]; docs/models.md §3).

Stage 1 is a double crank (base lambda6 = 1 - lambda2 + lambda3 over l1, the shortest link)
with a special position at phi1* = 0. With no stop there, it follows the smooth analytic
curve through the node, so its assembly branch flips at every pass:
sigma1 = sigma1_0 (-1)^floor(phi1 / 2pi), with sigma1_0 = +1 (the other choice is the same
motion shifted by one crank turn). Then u31 is continuous and at the node alternates between
(1 - gamma1)/(1 - lambda6) and (1 + gamma1)/(1 - lambda6).

Stage 2 is an impact four-bar of type b driven by link 3 (crank angle phi3 + delta - beta
relative to its base DE, lengths over l3: mu6 = 1 - mu4 + mu5). It keeps its branch: the
impact reverses the rocker. The branch is the impact branch for the actual rotation direction
of link 3, not [SIX]'s sigma = -1, which holds only for clockwise rotation (docs/models.md §3.2).
Composition: u51 = u31 u53 and u'51 = u'31 u53 + u31^2 u'53.
"""

import math
from collections import namedtuple

import numpy as np
from numba import njit

from kernels import INLINE_OPTIONS, INNER_OPTIONS, KERNEL_OPTIONS
from kernels.block import block_arrays, design_block
from kernels.crank_rocker import branch_values, impact_branch
from kernels.declaration import (BRANCH_FLAGS, POSITIVE, Mechanism, Output, Quantity,
                                 geometry_tol, peak_samples, profile_points)
from kernels.extrema import cell_midpoints, clustered_points, peak_search
from kernels.fourbar import CHANGE_POINT_B, crank_turns_fully, vector_kinematics


#: the profiles' coordinate: the crank angle over the 4 pi cycle, at cell midpoints
CYCLE_ANGLE = Quantity("crank_angle", "rad", "crank angle (phi1) over the 4 pi cycle", "φ1",
                       label=r"crank angle $\varphi_1$")


def cycle_angles(method) -> np.ndarray:
    """The crank angles of the profiles: method.profile_points cell midpoints of 4 pi."""
    return cell_midpoints(method.profile_points, 4.0 * np.pi)


DECLARATION = Mechanism(
    name="six_link",
    title="Six-link impact mechanism with alternating branch switching",
    summary="stage 1 on the smooth path through its node (branch alternation rule), stage 2 "
            "on the impact branch for the rotation direction; impacts by bisection on "
            "phi3(phi1); composition u51 = u31 u53; peaks from a uniform sample of the 4 pi "
            "cycle refined by golden section",
    references="K. Zh. Ziyaliev, O. K. Chinbaev, Zh. Zh. Dyushembaev, Kinematics of a "
               "six-link impact mechanism with the largest rocker (in Russian), Issyk-Kul "
               "State University; the copy received gives no year (the mechanism was "
               "patented in 2022)",
    parameters=(
        Quantity("lambda2", "1", "stage 1 coupler ratio l2/l1 (lambda2)", "λ2", default=1.6,
                 **POSITIVE, label=r"stage 1 rod $\lambda_2$"),
        Quantity("lambda3", "1", "stage 1 driven crank ratio l3/l1 (lambda3); the base is "
                 "lambda6 = 1 - lambda2 + lambda3", "λ3", default=1.3, **POSITIVE,
                 label=r"stage 1 crank $\lambda_3$"),
        Quantity("mu4", "1", "stage 2 coupler ratio l4/l3 (the paper's second lambda4)",
                 "λ4 (stage 2)", default=1.5, **POSITIVE, label=r"stage 2 rod $\mu_4$"),
        Quantity("mu5", "1", "stage 2 rocker ratio l5/l3 (the paper's lambda5); the base "
                 "is mu6 = 1 - mu4 + mu5", "λ5", default=2.5, **POSITIVE,
                 label=r"stage 2 rocker $\mu_5$"),
        Quantity("beta", "rad", "direction of the stage 2 base DE relative to AD (beta)", "β",
                 default=0.0, minimum=-2 * math.pi, maximum=2 * math.pi, label=r"phase $\beta$"),
        Quantity("delta", "rad", "offset of the stage 2 crank arm on link 3 (delta)", "δ",
                 default=0.0, minimum=-2 * math.pi, maximum=2 * math.pi,
                 label=r"arm offset $\delta$"),
        Quantity("direction", "1", "rotation direction of the crank: +1 counter-clockwise",
                 default=1, choices={1: 1, -1: -1}, label="direction"),
        Quantity("omega1", "rad s-1", "crank angular speed (|omega1|)", "ω1", default=30.0,
                 **POSITIVE, label=r"crank speed $\omega_1$"),
        Quantity("crank_length", "m", "crank length (l1)", "l1", default=0.1, **POSITIVE,
                 label="crank $l_1$"),
        Quantity("rocker_inertia", "kg m2", "moment of inertia of the stage-2 rocker and "
                 "striker about its pivot (J5), for the energy per blow", "J5", **POSITIVE,
                 label="rocker inertia $J_5$"),
    ),
    outputs=(
        Output("gamma1", "1", "stage 1 node parameter sqrt(lambda6 lambda2/lambda3) "
               "(gamma1)", "γ1", label=r"stage 1 node $\gamma_1$"),
        Output("gamma2", "1", "stage 2 node parameter sqrt(mu6 mu4/mu5) (gamma2)", "γ2",
               label=r"stage 2 node $\gamma_2$"),
        Output("restitution_kinematic", "1", "kinematic restitution coefficient of stage 2 "
               "(Rk)", "Rk", label="kinematic restitution $R_k$"),
        Output("transfer_stage1_low", "1", "stage 1 u31 at its special position, low value "
               "(1 - gamma1)/(1 - lambda6)", label="stage 1 $u_{31}$ low"),
        Output("transfer_stage1_high", "1", "stage 1 u31 at its special position, high "
               "value (1 + gamma1)/(1 - lambda6)", label="stage 1 $u_{31}$ high"),
        Output("transfer_impact_1", "1", "u51 at the first impact of the 4 pi cycle", "u51",
               label="$u_{51}$ at impact 1"),
        Output("transfer_impact_2", "1", "u51 at the second impact of the 4 pi cycle",
               "u51", label="$u_{51}$ at impact 2"),
        Output("transfer_stage1_impact_1", "1", "stage 1 u31 at the first impact", "u31",
               label="$u_{31}$ at impact 1"),
        Output("transfer_stage1_impact_2", "1", "stage 1 u31 at the second impact", "u31",
               label="$u_{31}$ at impact 2"),
        Output("impact_crank_angle_1", "rad", "crank angle of the first impact in "
               "[0, 4 pi)", "φ1", label=r"impact 1 at $\varphi_1$"),
        Output("impact_crank_angle_2", "rad", "crank angle of the second impact in "
               "[0, 4 pi)", "φ1", label=r"impact 2 at $\varphi_1$"),
        Output("impact_speed_1", "m s-1", "striker (rocker tip) speed at the first impact",
               label="impact speed 1"),
        Output("impact_speed_2", "m s-1", "striker (rocker tip) speed at the second impact",
               label="impact speed 2"),
        Output("transfer_peak", "1", "peak |u51| over the 4 pi cycle", "|u51|max",
               label="peak $|u_{51}|$"),
        Output("transfer2_peak", "1", "peak |u'51| over the 4 pi cycle", "|u′51|max",
               label="peak $|u'_{51}|$"),
        Output("assembly_branch_stage2", "1", "stage 2 assembly branch (sigma2), the impact "
               "branch for the rotation direction", "σ2", flags=BRANCH_FLAGS,
               undetermined="undetermined", label=r"stage 2 branch $\sigma_2$"),
        Output("blow_energy_1", "J", "energy of the first blow of the 4 pi cycle: the stage-2 "
               "rocker's kinetic energy at it, J5 (u51 omega1)^2 / 2", on_request=True,
               label="blow energy 1"),
        Output("blow_energy_2", "J", "energy of the second blow of the 4 pi cycle",
               on_request=True, label="blow energy 2"),
        Output("blow_rate", "min-1", "blows per minute (two per 4 pi cycle: one a crank "
               "turn)", on_request=True, label="blow rate"),
    ),
    rules=lambda given: (
        "rocker_inertia: required for the outputs blow_energy_1 and blow_energy_2 (the "
        "stage-2 rocker's J about its pivot)"
        if given.get("outputs", set()) & {"blow_energy_1", "blow_energy_2"}
        and "rocker_inertia" not in given else None),
    profiles=(Output("rocker_angle", "rad", "stage 2 rocker angle (phi5), from the "
                     "direction D->E, in [0, 2 pi)", "φ5", label=r"rocker angle $\varphi_5$"),
              Output("link3_angle", "rad", "link 3 angle (phi3) on the switching path, "
                     "from the direction A->D, counted on (phi1 < phi3 < phi1 + 2 pi)", "φ3",
                     on_request=True, label=r"link 3 angle $\varphi_3$ (switching)"),
              Output("link3_angle_branch_plus", "rad", "link 3 angle on stage 1's branch "
                     "sigma1 = +1 throughout ([SIX]'s second law, formula (2)), counted as "
                     "link3_angle", "φ3 (σ1 = +1)", on_request=True,
                     label=r"$\varphi_3$ on $\sigma_1 = +1$"),
              Output("link3_angle_branch_minus", "rad", "link 3 angle on stage 1's branch "
                     "sigma1 = -1 throughout ([SIX]'s first law, formula (1)), counted as "
                     "link3_angle", "φ3 (σ1 = −1)", on_request=True,
                     label=r"$\varphi_3$ on $\sigma_1 = -1$"),
              Output("transfer_stage2", "1", "stage 2 transfer ratio u53 = dphi5/dphi3 on "
                     "its impact branch", "u53", on_request=True, label="stage 2 ratio $u_{53}$")),
    profile_dim=CYCLE_ANGLE,
    profile_coordinate=cycle_angles,
    status=("ok", "not_assemblable", "nonfinite"),
    method=(
        geometry_tol("the link-length conditions"),
        peak_samples("samples", "crank angles sampled over 4 pi to find each peak, which "
                     "is then refined to the exact maximum", 720, 8),
        profile_points("crank angles of the rocker_angle profile over 4 pi (0: none)"),
    ),
)
O = DECLARATION.output_index
#: the outputs this kernel computes: the energies per blow after them come from run()
KERNEL_ROWS = DECLARATION.output_index.blow_energy_1
P = DECLARATION.parameter_index
S = DECLARATION.status_codes
ROCKER_ANGLE = DECLARATION.profile_index.rocker_angle
LINK3_ANGLE = DECLARATION.profile_index.link3_angle
LINK3_PLUS = DECLARATION.profile_index.link3_angle_branch_plus
LINK3_MINUS = DECLARATION.profile_index.link3_angle_branch_minus
TRANSFER_STAGE2 = DECLARATION.profile_index.transfer_stage2
#: per impact of the 4 pi cycle: rows of u51, stage-1 u31, crank angle, speed
IMPACT_ROWS = ((O.transfer_impact_1, O.transfer_stage1_impact_1, O.impact_crank_angle_1,
                O.impact_speed_1),
               (O.transfer_impact_2, O.transfer_stage1_impact_2, O.impact_crank_angle_2,
                O.impact_speed_2))

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
def link3_on_branch(phi1, lam6, lam2, lam3, sigma1, snap):
    """phi3 on one fixed stage-1 branch ([SIX]'s laws, Fig. 4), counted as stage1 counts."""
    c1, s1, c2, s2, c3, s3, u21, u31, du21, du31 = vector_kinematics(
        phi1, lam6, 1.0, lam2, lam3, sigma1, snap)
    return phi1 + (math.atan2(s3, c3) - phi1) % TWO_PI


@njit(**KERNEL_OPTIONS)
def blow_transfer(phi1, lam6, lam2, lam3, gamma1, snap):
    """Stage 1's u31 at a blow's crank angle phi1 (unreduced): on the smooth path, or its
    closed-form value where the blow falls on stage 1's node (0/0 there)."""
    u31 = stage1(phi1, lam6, lam2, lam3, snap)[1]
    m = round(phi1 / TWO_PI)
    if math.isnan(u31) or abs(phi1 - TWO_PI * m) < 1e-12:
        u31 = stage1_node_value(m, lam6, gamma1)
    return u31


@njit(**KERNEL_OPTIONS)
def stage1_node_value(m, lam6, gamma1):
    """u31 on the smooth path at the node phi1 = 2 pi m (closed form, docs/models.md §3.3)."""
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
def assemblable(lam2, lam3, mu4, mu5, tol):
    """Both stages as [SIX] builds them (docs/models.md §3.1): stage 1 l1 < l3 < l2 with
    l2 - l3 < l1 (a drag link), stage 2 l3 < l4 < l5, and both cranks turn fully."""
    if not (1.0 < lam3 < lam2 and lam2 - lam3 < 1.0 and 1.0 < mu4 < mu5):
        return False
    return (crank_turns_fully(1.0 - lam2 + lam3, 1.0, lam2, lam3, tol)
            and crank_turns_fully(1.0 - mu4 + mu5, 1.0, mu4, mu5, tol))


@njit(**KERNEL_OPTIONS)
def impact_angles(lam6, lam2, lam3, offset, tol):
    """The crank angles of the two impacts of a 4 pi cycle, where stage 2 is at its node:
    phi3 + delta - beta = 2 pi k (phi3 grows by 4 pi; offset = delta - beta). In [0, 4 pi]
    before reduction modulo 4 pi (the caller reduces them)."""
    start = math.pi + offset  # phi3 = pi at the node phi1 = 0
    k = math.floor(start / TWO_PI) + 1
    impacts = np.empty(2)
    for j in range(2):
        impacts[j] = _impact_angle(TWO_PI * (k + j), lam6, lam2, lam3, offset, tol)
    return impacts


@njit(**KERNEL_OPTIONS)
def _transfer(phi, lam6, lam2, lam3, mu6, mu4, mu5, sigma2, offset, tol):
    """(u51, u'51) at crank angle phi: stage 1 on its smooth path, stage 2 on sigma2."""
    phi3, u31, du31 = stage1(phi, lam6, lam2, lam3, tol)
    c1, s1, c2, s2, c3, s3, u21, u53, du21, du53 = vector_kinematics(
        phi3 + offset, mu6, 1.0, mu4, mu5, sigma2, tol)
    return u31 * u53, du31 * u53 + u31 * u31 * du53


@njit(**KERNEL_OPTIONS)
def _abs_u51(phi, data):
    return abs(_transfer(phi, *data)[0])


@njit(**KERNEL_OPTIONS)
def _abs_du51(phi, data):
    return abs(_transfer(phi, *data)[1])


_golden_u51, _refine_u51 = peak_search(_abs_u51)
_golden_du51, _refine_du51 = peak_search(_abs_du51)
#: the search keeps this far [rad] from a piece's ends (an impact, stage 1's node): the
#: transfer functions divide by sin(phi3 - phi2), which loses digits nearer a node. u51's
#: one-sided values there are closed form and candidates of their own; u'51's is taken
#: this far inside, within about |u''51| END_MARGIN
END_MARGIN = 1e-7
#: sample points approach the margin geometrically, to 2^-CLUSTER_DEPTH of the piece
CLUSTER_DEPTH = 20
#: golden section brackets a peak's crank angle to this [rad]
PEAK_LOCATION = 1e-10


@njit(**KERNEL_OPTIONS)
def _cycle_peaks(data, n_samples, impacts, peak):
    """Peaks of |u51| and |u'51| over the 4 pi cycle, by its smooth pieces: between the two
    impacts (where u53 jumps) and stage 1's nodes at 0, 2 pi, 4 pi (where u31 has a narrow
    spike as lambda6 -> 1), each sampled with points clustered towards its ends, every
    sampled local maximum refined by golden section (kernels/extrema.py). ``peak``: the
    one-sided values at the ends already known."""
    breaks = np.array([0.0, TWO_PI, 2.0 * TWO_PI, impacts[0], impacts[1]])
    breaks.sort()
    peak2 = 0.0
    for piece in range(breaks.shape[0] - 1):
        a, b = breaks[piece] + END_MARGIN, breaks[piece + 1] - END_MARGIN
        if b - a <= END_MARGIN:
            continue
        n = max(8, int(n_samples * (b - a) / (2.0 * TWO_PI)))
        xs = clustered_points(a, b, n, int(CLUSTER_DEPTH))
        u51 = np.empty(xs.shape[0])
        du51 = np.empty(xs.shape[0])
        for j in range(xs.shape[0]):
            u, du = _transfer(xs[j], *data)
            u51[j], du51[j] = abs(u), abs(du)
        peak = max(peak, _refine_u51(data, xs, u51, PEAK_LOCATION))
        peak2 = max(peak2, _refine_du51(data, xs, du51, PEAK_LOCATION))
    return peak, peak2


@njit(**INLINE_OPTIONS)
def design(i, pr, settings, out, prof):
    """One grid point (kernels/block.py): its outputs by name, its profiles over the 4 pi
    cycle, its status."""
    return six_link_point(pr[P.lambda2], pr[P.lambda3], pr[P.mu4], pr[P.mu5], pr[P.beta],
                          pr[P.delta], pr[P.direction], pr[P.omega1], pr[P.crank_length],
                          settings.geometry_tol, settings.samples, settings.angles,
                          settings.figures, out, prof)


@njit(**INNER_OPTIONS)
def six_link_point(lam2, lam3, mu4, mu5, beta, delta, direction, w, l1, tol, n_samples,
                   prof_angles, figures, out, prof):
    """One six-link: its outputs into out (NaN where a value does not exist), its profiles
    at prof_angles into prof[profile, angle], its status."""
    lam6 = 1.0 - lam2 + lam3
    mu6 = 1.0 - mu4 + mu5
    if not assemblable(lam2, lam3, mu4, mu5, tol):
        return S.not_assemblable
    gamma1 = math.sqrt(lam6 * lam2 / lam3)
    gamma2 = math.sqrt(mu6 * mu4 / mu5)
    out[O.gamma1], out[O.gamma2] = gamma1, gamma2
    out[O.restitution_kinematic] = (1.0 - gamma2) / (1.0 + gamma2)
    out[O.transfer_stage1_low] = (1.0 - gamma1) / (1.0 - lam6)
    out[O.transfer_stage1_high] = (1.0 + gamma1) / (1.0 - lam6)
    sigma2 = impact_branch(int(CHANGE_POINT_B), direction)  # link 3 turns with the crank
    out[O.assembly_branch_stage2] = sigma2
    offset = delta - beta
    before53, after53 = branch_values(int(CHANGE_POINT_B), mu6, gamma2, sigma2, direction)

    peak = 0.0
    impacts = impact_angles(lam6, lam2, lam3, offset, tol)
    for j in range(2):
        phi_i = impacts[j]
        impacts[j] = phi_i % (2.0 * TWO_PI)
        u31 = blow_transfer(phi_i, lam6, lam2, lam3, gamma1, tol)
        u51 = u31 * before53
        row_u51, row_u31, row_angle, row_speed = IMPACT_ROWS[j]
        out[row_u51] = u51
        out[row_u31] = u31
        out[row_angle] = phi_i % (2.0 * TWO_PI)
        out[row_speed] = abs(u51) * w * mu5 * lam3 * l1
        peak = max(peak, abs(u51), abs(u31 * after53))

    # u51 at stage 1's nodes (0 and 2 pi; 4 pi repeats 0): its closed-form node values
    for m in range(2):
        phi3 = stage1(TWO_PI * m, lam6, lam2, lam3, tol)[0]
        u53 = vector_kinematics(phi3 + offset, mu6, 1.0, mu4, mu5, sigma2, tol)[7]
        node = abs(stage1_node_value(m, lam6, gamma1) * u53)
        peak = max(peak, node if math.isfinite(node) else 0.0)
    data = (lam6, lam2, lam3, mu6, mu4, mu5, sigma2, offset, tol)
    peak, peak2 = _cycle_peaks(data, n_samples, impacts, peak)
    out[O.transfer_peak], out[O.transfer2_peak] = peak, peak2

    for j in range(prof_angles.shape[0]):
        phi1 = prof_angles[j]
        phi3 = stage1(phi1, lam6, lam2, lam3, tol)[0]
        c1, s1, c2, s2, c3, s3, u21, u53, du21, du53 = vector_kinematics(
            phi3 + offset, mu6, 1.0, mu4, mu5, sigma2, tol)
        prof[ROCKER_ANGLE, j] = math.atan2(s3, c3) % TWO_PI  # the rocker swings about pi
        if figures:  # [SIX] Figs. 4 and 6, where asked for
            prof[LINK3_ANGLE, j] = phi3
            prof[TRANSFER_STAGE2, j] = u53
            prof[LINK3_PLUS, j] = link3_on_branch(phi1, lam6, lam2, lam3, 1.0, tol)
            prof[LINK3_MINUS, j] = link3_on_branch(phi1, lam6, lam2, lam3, -1.0, tol)

    for k in range(KERNEL_ROWS):
        if not math.isfinite(out[k]):
            return S.nonfinite
    return S.ok


#: the method's options the block reads, by name (figures: the profiles of [SIX] Figs. 4
#: and 6 are asked for)
Settings = namedtuple("Settings", ["geometry_tol", "samples", "angles", "figures"])
#: the profiles on request, for [SIX] Figs. 4 and 6
FIGURE_PROFILES = ("link3_angle", "link3_angle_branch_plus", "link3_angle_branch_minus",
                   "transfer_stage2")


#: the block: each design of it by ``design`` (kernels/block.py), cached on disk
six_link_block = design_block(design, "six_link_block", globals(), KERNEL_OPTIONS)


def run(params, method):
    """Entry point: (outputs, status, profiles[1, n, n_angles])."""
    angles = cycle_angles(method)
    n = params.shape[1]
    out, status, prof = block_arrays(DECLARATION, n, angles)
    six_link_block(np.ascontiguousarray(params),
                   Settings(geometry_tol=float(method.geometry_tol),
                            samples=int(method.samples), angles=angles,
                            figures=bool(set(FIGURE_PROFILES) & set(method.outputs))),
                   out, status, prof)
    w, j5 = params[P.omega1], params[P.rocker_inertia]
    for energy, transfer in ((O.blow_energy_1, O.transfer_impact_1),
                             (O.blow_energy_2, O.transfer_impact_2)):
        out[energy] = (0.5 * j5 * (out[transfer] * w) ** 2
                       if DECLARATION.outputs[energy].name in method.outputs else np.nan)
    out[O.blow_rate] = (np.where(np.isfinite(out[O.transfer_impact_1]),
                                 60.0 * np.abs(w) / (2.0 * np.pi), np.nan)
                        if "blow_rate" in method.outputs else np.nan)
    return out, status, prof

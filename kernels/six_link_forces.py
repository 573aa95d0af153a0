"""Kinetostatics of the six-link impact mechanism ([SIX]; docs/models.md §3.4).

The six-link is two four-bars sharing link 3 (docs/models.md §3.1): stage 1 (crank 1,
coupler 2, link 3 about D, base AD) and stage 2 (link 3's arm DF at delta from DC, coupler
4, rocker 5 about E, base DE at beta from AD). At each crank angle, on the path of
kernels/six_link.py (stage 1 switching branch at its node, stage 2 on its impact branch):

1. stage 2 by the one dyad solver (kernels.kinetostatics.dyad_reactions), its crank being
   link 3's arm with angle phi3 + delta - beta, speed omega3 = u31 omega1 and acceleration
   epsilon3 = u'31 omega1^2 + u31 epsilon1, and no mass of its own (link 3's is stage 1's);
2. the force the stage-2 coupler puts on link 3 at F, moved to D as a force and a couple
   (the same loads on the rigid link 3), as stage 1's external load on its rocker;
3. stage 1 by the same solver: its reactions and the balancing moment on the crank, from
   virtual work over all five moving links (stage 2 through the couple's work).

Joints: A (crank, base), B (crank, coupler 2), C (coupler 2, link 3), D (link 3, base), F
(link 3's arm, coupler 4), G (coupler 4, rocker 5), E (rocker 5, base); [SIX]'s figure of the
assembly is lost, the letters F and G are ours. Forces F_ij act on link i from link j (base:
6). The rigid dyad is singular at stage 1's nodes (phi1 = 0, 2 pi) and at the impacts (stage
2's node): the peaks are taken outside a window around each, the cycle work and RMS of M_b on
the open pieces between them (M_b stays finite: virtual work needs no reactions).
"""

import math
from collections import namedtuple

import numpy as np
from numba import njit

from kernels import INLINE_OPTIONS, INNER_OPTIONS, KERNEL_OPTIONS
from kernels import kinetostatics as ks
from kernels import six_link as sl
from kernels.block import block_arrays, design_block
from kernels.crank_rocker import impact_branch
from kernels.declaration import (Mechanism, Output, Quantity, geometry_tol, peak_samples,
                                 profile_points)
from kernels.extrema import CLUSTER, clustered_points, peak_search
from kernels.fourbar import CHANGE_POINT_B, PATH_IMPACT

#: the stage geometry and drive, as six_link declares them
_GEOMETRY = ("lambda2", "lambda3", "mu4", "mu5", "beta", "delta", "direction", "omega1",
             "crank_length")
_SIX = {q.name: q for q in sl.DECLARATION.parameters}
_NONNEG = dict(minimum=0.0)
#: illustrative links for the default six-link (l1 = 0.1 m): [SIX] gives no masses
_MASS = {1: 2.0, 2: 3.0, 3: 4.0, 4: 3.0, 5: 8.0}
_LENGTH = {1: 0.1, 2: 0.16, 3: 0.13, 4: 0.195, 5: 0.325}
#: link i: its name, its first joint (the origin of its centroid), the line it runs along
_LINK = {1: ("crank", "A", "AB"), 2: ("stage 1 coupler", "B", "BC"),
         3: ("link 3", "D", "DC"), 4: ("stage 2 coupler", "F", "FG"),
         5: ("rocker (striker)", "E", "EG")}
_WINDOWED = ("outside |phi1 - phi1*| < special_window at stage 1's nodes and the "
             "impacts' windows (special_window in link 3's angle)")
#: a ratio's mark on a chart: below it the six-link carries less than the single four-bar
_EQUAL = ((1.0, "1: as the single four-bar"),)
_AT_BLOWS = ("outside a window of special_window in link 3's angle (phi3) at the "
             "impacts")
#: the joints: (peak output's joint letter, force F_ij, what acts on what, the link it is
#: resolved on)
JOINTS = (("A", "F16", "base force on the crank", "crank"),
          ("B", "F21", "crank pin force on the stage 1 coupler", "stage 1 coupler"),
          ("C", "F32", "stage 1 coupler force on link 3", "link 3's arm DC"),
          ("D", "F36", "base force on link 3", "link 3's arm DC"),
          ("F", "F43", "link 3's force on the stage 2 coupler", "stage 2 coupler"),
          ("G", "F54", "stage 2 coupler force on the rocker", "rocker"),
          ("E", "F56", "base force on the rocker", "rocker"))


def _link_quantities(i: int) -> tuple:
    """Mass, centroid (along, across) and centroidal inertia of link i, named as
    linkage_forces names them."""
    link, origin, line = _LINK[i]
    mass, length = _MASS[i], _LENGTH[i]
    return (
        Quantity(f"m{i}", "kg", f"{link} mass (m{i})", f"m{i}", default=mass, **_NONNEG,
                 label=f"{link} mass $m_{i}$"),
        Quantity(f"s{i}", "1", f"{link} centroid along {line}, fraction of its length "
                 f"from {origin}", default=0.5, label=f"{link} centroid $s_{i}$"),
        Quantity(f"q{i}", "m", f"{link} centroid offset across the link", default=0.0,
                 label=f"{link} offset $q_{i}$"),
        Quantity(f"J{i}", "kg m2", f"{link} centroidal moment of inertia (I_S{i})",
                 f"I_S{i}", default=mass * length**2 / 12.0, **_NONNEG,
                 label=f"{link} inertia $I_{{S{i}}}$"),
    )


DECLARATION = Mechanism(
    name="six_link_forces",
    title="Kinetostatics of the six-link impact mechanism",
    summary="both stages by the Assur-dyad vector route of linkage_forces (stage 2 first, "
            "its load on link 3 then stage 1's), the balancing moment by virtual work, on "
            "the switching path of six_link over the 4 pi cycle; cycle work and RMS by "
            "Gauss-Legendre on the open pieces between stage 1's nodes and the impacts, "
            "peaks from a clustered sample outside a window around each refined by golden "
            "section",
    references=sl.DECLARATION.references,
    parameters=(
        *(_SIX[name] for name in _GEOMETRY),
        Quantity("epsilon1", "rad s-2", "crank angular acceleration (epsilon1, "
                 "counter-clockwise positive)", "ε1", default=0.0,
                 label=r"crank acceleration $\varepsilon_1$"),
        *(q for i in _LINK for q in _link_quantities(i)),
        Quantity("tilt", "rad", "inclination of the base AD to the horizontal", "θ",
                 default=0.0, minimum=-math.pi, maximum=math.pi, label=r"tilt $\theta$"),
        Quantity("g", "m s-2", "gravitational acceleration", "g", default=9.81, **_NONNEG,
                 label="gravity $g$"),
    ),
    outputs=(
        *(Output(f"force_peak_{joint}", "N", f"peak |{force}| at {joint} over the 4 pi "
                 "cycle", f"|{force}|max", _WINDOWED if joint in "ABCD" else _AT_BLOWS,
                 label=rf"peak $|F_{{{force[1:]}}}|$ at {joint}")
          for joint, force, _, _ in JOINTS),
        Output("balancing_moment_peak", "N m", "peak |M_b| over the 4 pi cycle (balancing "
               "moment on the crank)", "|M_b|max", _AT_BLOWS, label="peak $|M_b|$"),
        Output("balancing_moment_rms", "N m", "RMS of the balancing moment over the 4 pi "
               "cycle", label="RMS $M_b$"),
        Output("cycle_work", "J", "work of the balancing moment over the 4 pi cycle (two "
               "blows; integral of M_b dphi1 along the motion)", "∮M_b dφ1", "equals the "
               "kinetic energy the two blows take at constant omega1", label="cycle work"),
        Output("single_stage_omega1", "rad s-1", "crank speed of the single impact four-bar "
               "(stage 2 alone, its crank driven directly) with the same mean energy per "
               "blow: |omega1| sqrt((u31_1^2 + u31_2^2)/2), u31 at the two blows", "ω1,single",
               label=r"single four-bar $\omega_1$"),
        *(Output(f"force_ratio_{joint}", "1", f"peak |{force}| at {joint} over the single "
                 f"four-bar's peak at its {where} ([SIX]'s claim: below 1, lower loads)",
                 f"|{force}|max ratio", _AT_BLOWS, marks=_EQUAL,
                 label=f"load at {joint}, six-link / four-bar")
          for joint, force, where in (("F", "F43", "crank pin"),
                                      ("G", "F54", "coupler-rocker joint"),
                                      ("E", "F56", "rocker pivot"))),
        Output("force_ratio_max", "1", "the largest joint force peak of the six-link over "
               "the single four-bar's (every joint of each)", "max |F| ratio", _WINDOWED,
               marks=_EQUAL, label="largest load, six-link / four-bar"),
        Output("drive_torque_ratio", "1", "peak balancing moment |M_b| of the six-link over "
               "the single four-bar's (each crank does the same work a turn: one blow's "
               "loss)", "|M_b|max ratio", _AT_BLOWS, marks=_EQUAL,
               label="drive torque, six-link / four-bar"),
    ),
    profiles=(
        *ks.reaction_profiles(JOINTS, magnitude=True),
        Output("balancing_moment", "N m", "balancing moment on the crank (M_b, virtual "
               "work)", "M_b", label="balancing moment $M_b$"),
    ),
    profile_dim=sl.CYCLE_ANGLE,
    profile_coordinate=sl.cycle_angles,
    status=("ok", "not_assemblable", "nonfinite"),
    method=(
        geometry_tol("the link-length conditions"),
        Quantity("special_window", "rad", "half-width of the window around stage 1's "
                 "nodes and the impacts excluded from peaks", "δ", default=0.01,
                 minimum=0.0, maximum=0.5, min_inclusive=False),
        Quantity("quadrature_points", "1", "Gauss-Legendre points per open piece of the "
                 "cycle for the cycle work and RMS", default=200, minimum=2, maximum=5000,
                 integer=True),
        peak_samples("peak_samples", "crank angles sampled over 4 pi to find each peak, "
                     "which is then refined to the exact maximum", 721, 8),
        profile_points("crank angles of the profiles over 4 pi (0: no profiles)"),
    ),
)
P = DECLARATION.parameter_index
O = DECLARATION.output_index
F = DECLARATION.profile_index
S = DECLARATION.status_codes
#: the four-bar kinetostatics' parameter rows, which each stage fills
FB = ks.DECLARATION.parameter_index
#: the peaks' rows: the seven joints, then |M_b|
PEAK_ROWS = (O.force_peak_A, O.force_peak_B, O.force_peak_C, O.force_peak_D,
             O.force_peak_F, O.force_peak_G, O.force_peak_E, O.balancing_moment_peak)
N_PEAKS = 8
#: the peaks windowed at every break (stage 1's joints A, B, C, D), and those windowed at
#: the blows only (stage 2's joints F, G, E and M_b)
STAGE1_PEAKS = (0, 1, 2, 3)
BLOW_PEAKS = (4, 5, 6, 7)
N_OUTPUTS = len(DECLARATION.outputs)
#: golden section brackets a peak's crank angle to this [rad]
PEAK_LOCATION = 1e-9
TWO_PI = 2.0 * math.pi

#: one design's two stages as the dyad solver takes them: the four-bar parameter vectors of
#: stage 1 (pr1) and stage 2 (pr2), their result vectors, and what joins them
Stages = namedtuple("Stages", ["lam6", "lam2", "lam3", "sigma2", "offset", "cos_beta",
                               "sin_beta", "arm", "delta", "omega1", "epsilon1", "tol",
                               "gravity1", "gravity2", "pr1", "pr2", "res1", "res2"])


@njit(**KERNEL_OPTIONS)
def fill_stage(pr, l0, l1, l2, l3, crank, coupler, rocker, omega1, epsilon1):
    """A four-bar kinetostatics vector (rows FB): lengths, its crank's, coupler's and
    rocker's (m, s, q, J), the crank's drive; no external load, a fixed base (gravity is
    passed apart)."""
    pr[:] = 0.0
    pr[FB.l0], pr[FB.l1], pr[FB.l2], pr[FB.l3] = l0, l1, l2, l3
    pr[FB.m1], pr[FB.s1], pr[FB.q1], pr[FB.J1] = crank
    pr[FB.m2], pr[FB.s2], pr[FB.q2], pr[FB.J2] = coupler
    pr[FB.m3], pr[FB.s3], pr[FB.q3], pr[FB.J3] = rocker
    pr[FB.omega1], pr[FB.epsilon1] = omega1, epsilon1
    pr[FB.base_motion] = ks.BASE_FIXED


@njit(**KERNEL_OPTIONS)
def solve(phi1, st):
    """Both stages at crank angle phi1 into st.res1 (stage 1: F16 as F14, F21, F32, F36 as
    F34, M_b) and st.res2 (stage 2: F43 as F21, F54 as F32, F56 as F34), in the layout of
    kernels.kinetostatics (N_RESULT). False where a loop cannot close."""
    phi3, u31, du31 = sl.stage1(phi1, st.lam6, st.lam2, st.lam3, st.tol)
    if not (math.isfinite(phi3) and math.isfinite(u31) and math.isfinite(du31)):
        return False
    pr1, pr2, res2 = st.pr1, st.pr2, st.res2
    pr2[FB.omega1] = u31 * st.omega1
    pr2[FB.epsilon1] = du31 * st.omega1 * st.omega1 + u31 * st.epsilon1
    g2x, g2y = st.gravity2
    if not ks.dyad_reactions(phi3 + st.offset, pr2, st.sigma2, res2, st.tol, g2x, g2y,
                             0.0, 0.0):
        return False
    # the stage-2 coupler's force on link 3 at F (stage 1's frame), as a force at D and the
    # couple of its arm DF
    fx2, fy2 = -res2[ks.R_F21X], -res2[ks.R_F21Y]
    fx = st.cos_beta * fx2 - st.sin_beta * fy2
    fy = st.sin_beta * fx2 + st.cos_beta * fy2
    arm_angle = phi3 + st.delta
    c3, s3 = math.cos(phi3), math.sin(phi3)
    pr1[FB.external_force_normal] = fx * c3 + fy * s3
    pr1[FB.external_force] = -fx * s3 + fy * c3
    pr1[FB.external_moment] = st.arm * (math.cos(arm_angle) * fy - math.sin(arm_angle) * fx)
    g1x, g1y = st.gravity1
    return ks.dyad_reactions(phi1, pr1, sl.stage1_branch(phi1), st.res1, st.tol, g1x, g1y,
                             0.0, 0.0)


@njit(**KERNEL_OPTIONS)
def peak_quantity(q, st):
    """The magnitude of joint q's reaction (A, B, C, D, F, G, E) or |M_b| (q = 7) from a
    solution."""
    if q < 4:
        return ks.peak_quantity(q, st.res1)
    if q < 7:
        return ks.peak_quantity(q - 3, st.res2)  # stage 2's B, C, D are F, G, E
    return ks.peak_quantity(ks.PEAK_MB, st.res1)


@njit(**KERNEL_OPTIONS)
def solve_near(phi1, st):
    """solve at phi1, or where that is exactly one of stage 1's nodes (u'31 is 0/0 there),
    at phi1 + 1e-9 on the smooth path: its limit."""
    return solve(phi1, st) or solve(phi1 + 1e-9, st)


@njit(**KERNEL_OPTIONS)
def _peak_at(phi, data):
    q, st = data
    if not solve_near(phi, st):
        return math.nan
    return peak_quantity(q, st)


_golden_peak, _refine_peak = peak_search(_peak_at)


@njit(**KERNEL_OPTIONS)
def windowed_peaks(st, breaks, windows, n_peak, quantities, best):
    """The peaks of ``quantities`` (rows of peak_quantity) on the pieces between the
    increasing ``breaks``, outside |phi1 - breaks[k]| < windows[k], into best: a sample
    clustered towards the windows' edges, golden section around every sampled local maximum
    (kernels/extrema.py). False where a loop cannot close."""
    for piece in range(breaks.shape[0] - 1):
        a, b = breaks[piece] + windows[piece], breaks[piece + 1] - windows[piece + 1]
        if b <= a:
            continue
        n = max(8, int(n_peak * (b - a) / (2.0 * TWO_PI)))
        xs = clustered_points(a, b, n, int(CLUSTER))
        values = np.empty((len(quantities), xs.shape[0]))
        for j in range(xs.shape[0]):
            if not solve_near(xs[j], st):
                return False
            for k in range(len(quantities)):
                values[k, j] = peak_quantity(quantities[k], st)
        for k in range(len(quantities)):
            q = quantities[k]
            best[q] = max(best[q], _refine_peak((q, st), xs, values[k], PEAK_LOCATION))
    return True


@njit(**KERNEL_OPTIONS)
def cycle_breaks(impacts):
    """The ends of the 4 pi cycle's smooth pieces: stage 1's nodes 0, 2 pi, 4 pi and the
    two impacts, increasing (an impact on a node repeats it: an empty piece)."""
    breaks = np.array([0.0, TWO_PI, 2.0 * TWO_PI, impacts[0], impacts[1]])
    breaks.sort()
    return breaks


@njit(**KERNEL_OPTIONS)
def stages_of(pr, settings):
    """The design's two stages (Stages, its four-bar vectors filled) and its blows: their
    crank angles, raw, and link 3's ratio u31 at each."""
    tol = settings.geometry_tol
    lam2, lam3, mu4, mu5 = pr[P.lambda2], pr[P.lambda3], pr[P.mu4], pr[P.mu5]
    lam6, mu6 = 1.0 - lam2 + lam3, 1.0 - mu4 + mu5
    direction = pr[P.direction]
    w1, e1 = direction * pr[P.omega1], pr[P.epsilon1]
    l1 = pr[P.crank_length]
    l3 = lam3 * l1
    beta, delta = pr[P.beta], pr[P.delta]
    g, tilt = pr[P.g], pr[P.tilt]
    pr1, pr2 = settings.pr1, settings.pr2
    fill_stage(pr1, lam6 * l1, l1, lam2 * l1, l3, (pr[P.m1], pr[P.s1], pr[P.q1], pr[P.J1]),
               (pr[P.m2], pr[P.s2], pr[P.q2], pr[P.J2]),
               (pr[P.m3], pr[P.s3], pr[P.q3], pr[P.J3]), w1, e1)
    # stage 2's crank is link 3's arm: its mass is stage 1's
    fill_stage(pr2, mu6 * l3, l3, mu4 * l3, mu5 * l3, (0.0, 0.0, 0.0, 0.0),
               (pr[P.m4], pr[P.s4], pr[P.q4], pr[P.J4]),
               (pr[P.m5], pr[P.s5], pr[P.q5], pr[P.J5]), 0.0, 0.0)
    st = Stages(lam6, lam2, lam3, impact_branch(int(CHANGE_POINT_B), direction),
                delta - beta, math.cos(beta), math.sin(beta), l3, delta, w1, e1, tol,
                (-g * math.sin(tilt), -g * math.cos(tilt)),
                (-g * math.sin(tilt + beta), -g * math.cos(tilt + beta)), pr1, pr2,
                settings.res1, settings.res2)
    impacts = sl.impact_angles(lam6, lam2, lam3, delta - beta, tol)
    blow_u31 = np.empty(2)
    for j in range(2):
        blow_u31[j] = sl.blow_transfer(impacts[j], lam6, lam2, lam3,
                                       math.sqrt(lam6 * lam2 / lam3), tol)
    return st, impacts, blow_u31


@njit(**KERNEL_OPTIONS)
def cycle_integrals(st, breaks, gl_x, gl_w):
    """(cycle work, RMS) of M_b over the 4 pi cycle: Gauss-Legendre on each open piece (M_b
    jumps at a blow); NaN where a loop cannot close."""
    work = 0.0
    square = 0.0
    for piece in range(breaks.shape[0] - 1):
        a, b = breaks[piece], breaks[piece + 1]
        half = 0.5 * (b - a)
        if half <= 0.0:
            continue
        for k in range(gl_x.shape[0]):
            if not solve(a + half * (gl_x[k] + 1.0), st):
                return math.nan, math.nan
            mb = st.res1[ks.R_MB]
            work += half * gl_w[k] * mb
            square += half * gl_w[k] * mb * mb
    return work, math.sqrt(square / (2.0 * TWO_PI))


@njit(**KERNEL_OPTIONS)
def cycle_peak_values(st, impacts, blow_u31, breaks, window, n_peak, best):
    """The eight peaks into best, each outside its windows: stage 1's joints at every break
    (their dyad is singular at stage 1's nodes, and they carry stage 2's load at the blows),
    stage 2's joints and M_b at the blows only (link 3 passes stage 1's nodes smoothly). A
    blow's window is ``window`` in link 3's angle (phi3), as the single four-bar's in its
    crank's: both stage 2s are then as near their singular dyad at its edges."""
    first = 0 if impacts[0] <= impacts[1] else 1
    blows = np.array([impacts[first], impacts[1 - first], impacts[first] + 2.0 * TWO_PI])
    at_blows = np.array([window / blow_u31[first], window / blow_u31[1 - first],
                         window / blow_u31[first]])
    windows = np.full(breaks.shape[0], window)
    for k in range(breaks.shape[0]):
        for j in range(2):
            if breaks[k] == impacts[j]:
                windows[k] = max(window, at_blows[0 if j == first else 1])
    return (windowed_peaks(st, breaks, windows, n_peak, STAGE1_PEAKS, best)
            and windowed_peaks(st, blows, at_blows, n_peak, BLOW_PEAKS, best))


@njit(**KERNEL_OPTIONS)
def cycle_profiles(st, breaks, angles, prof):
    """The rigid-model reactions and M_b at every angle into prof (NaN exactly at a break)."""
    for j in range(angles.shape[0]):
        phi = angles[j]
        at_break = False
        for k in range(breaks.shape[0]):
            at_break = at_break or abs(phi - breaks[k]) < 1e-12
        if at_break or not solve(phi, st):
            continue
        res1, res2 = st.res1, st.res2
        prof[F.F16_n, j], prof[F.F16_t, j] = res1[ks.R_F14N], res1[ks.R_F14T]
        prof[F.F21_n, j], prof[F.F21_t, j] = res1[ks.R_F21N], res1[ks.R_F21T]
        prof[F.F32_n, j], prof[F.F32_t, j] = res1[ks.R_F32N], res1[ks.R_F32T]
        prof[F.F36_n, j], prof[F.F36_t, j] = res1[ks.R_F34N], res1[ks.R_F34T]
        prof[F.F43_n, j], prof[F.F43_t, j] = res2[ks.R_F21N], res2[ks.R_F21T]
        prof[F.F54_n, j], prof[F.F54_t, j] = res2[ks.R_F32N], res2[ks.R_F32T]
        prof[F.F56_n, j], prof[F.F56_t, j] = res2[ks.R_F34N], res2[ks.R_F34T]
        for n, t, size in ((F.F16_n, F.F16_t, F.F16), (F.F21_n, F.F21_t, F.F21),
                           (F.F32_n, F.F32_t, F.F32), (F.F36_n, F.F36_t, F.F36),
                           (F.F43_n, F.F43_t, F.F43), (F.F54_n, F.F54_t, F.F54),
                           (F.F56_n, F.F56_t, F.F56)):
            prof[size, j] = math.hypot(prof[n, j], prof[t, j])
        prof[F.balancing_moment, j] = res1[ks.R_MB]


@njit(**KERNEL_OPTIONS)
def single_four_bar(st, speed, window, n_peak, single):
    """[SIX]'s claim: the peaks (kernels.kinetostatics' PEAK_*) of stage 2 alone, its crank
    driven directly at ``speed``, with the same links 4 and 5 (its crank massless, as link
    3's arm), into single. Uses st.pr2 and st.res2 (the six-link's are done with)."""
    pr2 = st.pr2
    pr2[FB.omega1], pr2[FB.epsilon1] = speed, 0.0
    g2x, g2y = st.gravity2
    return ks.cycle_peaks(pr2, (st.sigma2, 0.0, 1, PATH_IMPACT), st.res2, st.tol,
                          (g2x, g2y, 0.0, 0.0), int(CHANGE_POINT_B), 1, window, n_peak, 1,
                          single)


@njit(**INNER_OPTIONS)
def forces_point(pr, settings, out, prof):
    """One six-link's loads: outputs into out, profiles into prof, its status."""
    if not sl.assemblable(pr[P.lambda2], pr[P.lambda3], pr[P.mu4], pr[P.mu5],
                          settings.geometry_tol):
        return S.not_assemblable
    st, impacts, blow_u31 = stages_of(pr, settings)
    for j in range(2):
        impacts[j] = impacts[j] % (2.0 * TWO_PI)
    breaks = cycle_breaks(impacts)
    work, rms = cycle_integrals(st, breaks, settings.gl_x, settings.gl_w)
    if math.isnan(work):
        return S.not_assemblable
    out[O.balancing_moment_rms] = rms
    out[O.cycle_work] = pr[P.direction] * work

    window, n_peak = settings.window, settings.n_peak
    best = np.full(N_PEAKS, -math.inf)
    if not cycle_peak_values(st, impacts, blow_u31, breaks, window, n_peak, best):
        return S.not_assemblable
    for q in range(N_PEAKS):
        out[PEAK_ROWS[q]] = best[q]
    cycle_profiles(st, breaks, settings.angles, prof)

    # the single four-bar at the speed of the same mean energy per blow
    speed = st.omega1 * math.sqrt(0.5 * np.sum(blow_u31 ** 2))
    single = np.full(ks.N_PEAKS, -math.inf)
    if not single_four_bar(st, speed, window, n_peak // 2, single):
        return S.not_assemblable
    out[O.single_stage_omega1] = abs(speed)
    out[O.force_ratio_F] = out[O.force_peak_F] / single[ks.PEAK_B]
    out[O.force_ratio_G] = out[O.force_peak_G] / single[ks.PEAK_C]
    out[O.force_ratio_E] = out[O.force_peak_E] / single[ks.PEAK_D]
    six_max = 0.0
    for q in range(N_PEAKS - 1):
        six_max = max(six_max, out[PEAK_ROWS[q]])
    out[O.force_ratio_max] = six_max / max(single[ks.PEAK_A], single[ks.PEAK_B],
                                           single[ks.PEAK_C], single[ks.PEAK_D])
    out[O.drive_torque_ratio] = out[O.balancing_moment_peak] / single[ks.PEAK_MB]

    for k in range(N_OUTPUTS):
        if not math.isfinite(out[k]):
            return S.nonfinite
    return S.ok


@njit(**INLINE_OPTIONS)
def design(i, pr, settings, out, prof):
    """One grid point (kernels/block.py)."""
    return forces_point(pr, settings, out, prof)


#: the method's options the block reads, by name, and its scratch: each stage's four-bar
#: parameter vector (pr1, pr2) and result vector (res1, res2)
Settings = namedtuple("Settings", ["geometry_tol", "window", "gl_x", "gl_w", "n_peak",
                                   "angles", "pr1", "pr2", "res1", "res2"])


#: the block: each design of it by ``design`` (kernels/block.py), cached on disk
six_link_forces_block = design_block(design, "six_link_forces_block", globals(),
                                     KERNEL_OPTIONS)


def run(params, method):
    """Entry point: (outputs, status, profiles[n_profiles, n, n_angles])."""
    gl_x, gl_w = np.polynomial.legendre.leggauss(method.quadrature_points)
    angles = sl.cycle_angles(method)
    n = params.shape[1]
    out, status, prof = block_arrays(DECLARATION, n, angles)
    n_fb = len(ks.DECLARATION.parameters)
    settings = Settings(geometry_tol=float(method.geometry_tol),
                        window=float(method.special_window), gl_x=gl_x, gl_w=gl_w,
                        n_peak=int(method.peak_samples), angles=angles,
                        pr1=np.empty(n_fb), pr2=np.empty(n_fb),
                        res1=np.empty(ks.N_RESULT), res2=np.empty(ks.N_RESULT))
    six_link_forces_block(np.ascontiguousarray(params), settings, out, status, prof)
    return out, status, prof

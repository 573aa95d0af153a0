"""Kinetostatics of the impact four-bar and of GUIM-1's additional rocker ([GUIM];
docs/models.md §4).

Per crank angle: the joint reactions by the Assur-dyad route of docs/models.md §4.2
(tangential parts from moments about C, normal parts from the dyad force balance, then the
crank), and the balancing moment M_b. M_b is taken from virtual work (docs/models.md §4.2),
which needs no reactions: the reaction route gives it as infinity times zero at a special
position (H11), the virtual-work route stays finite and exact. Over a cycle: windowed peaks,
the RMS of M_b and the cycle work by Gauss-Legendre quadrature (one-sided at the node, H13).

GUIM-1 variant: the base (the main rocker) turns with angular velocity Omega_b and
acceleration E_b about a pivot O, with A at r_OA in the base frame; absolute accelerations add
the transport and Coriolis terms a = a_rel + 2 Omega_b k x v_rel + E_b k x r - Omega_b^2 r
(all in base-frame components; gravity enters through the instantaneous tilt).
"""

import math
from collections import namedtuple

import numpy as np
from numba import njit

from kernels import INLINE_OPTIONS, INNER_OPTIONS, KERNEL_OPTIONS
from kernels.block import block_arrays, design_block
from kernels.crank_rocker import impact_branch
from kernels.declaration import (BRANCH_FLAGS, POSITIVE, SIGMA_IMPACT, Mechanism, Output,
                                 Quantity, assembly_branch, geometry_tol, path,
                                 profile_points)
from kernels.extrema import CLUSTER, cell_midpoints, clustered_points, peak_search
from kernels.fourbar import (
    CHANGE_POINT_A,
    CHANGE_POINT_B,
    CHANGE_POINT_C,
    PATH_FREE,
    change_point_identities,
    crank_turns_fully,
    path_branch,
    vector_kinematics,
)

BASE_FIXED, BASE_ROTATING, BASE_HARMONIC = 0, 1, 2
#: a harmonic base motion repeats after q crank turns where its frequency ratio is p/q;
#: the cycle of the outputs is those q turns, q at most this
MAX_BASE_TURNS = 12

# defaults: the kinetostatic test mechanism ([CR] Table 1, lambda2 = 2.5, R = 0.3,
# crank 0.1 m, tilt 25 degrees, 30 rad/s), so that the example runs as it is
_L1 = 0.1
_L0, _L2, _L3 = 2.029159519725557 * _L1, 2.5 * _L1, 1.470840480274443 * _L1
_NONNEG = dict(minimum=0.0)
_ROTATING = {"base_motion": ("rotating",)}
_HARMONIC = {"base_motion": ("harmonic",)}
_MOVING = {"base_motion": ("rotating", "harmonic")}
_WINDOWED = "outside |phi1 - phi1*| < special_window at a special position"

def reaction_profiles(joints, magnitude: bool = False) -> tuple:
    """The profiles of joint reactions, each resolved along and across a link: for each
    (joint, force, what acts on what, the link), its normal (along) and tangential (across)
    components, ``F21_n`` and ``F21_t``; with ``magnitude``, then each one's magnitude,
    ``F21``."""
    resolved = tuple(Output(f"{force}_{c}", "N", f"{what} {side} the {link} ({force} {part})",
                            f"{force}^{mark}", label=rf"$F_{{{force[1:]}}}$ {side} {link}")
                     for _, force, what, link in joints
                     for c, side, part, mark in (("n", "along", "normal", "n"),
                                                 ("t", "across", "tangential", "τ")))
    if not magnitude:
        return resolved
    return resolved + tuple(Output(force, "N", f"{what}, magnitude (|{force}|)", f"|{force}|",
                                   label=rf"$|F_{{{force[1:]}}}|$ at {joint}")
                            for joint, force, what, link in joints)


def _rules(given: dict) -> str | None:
    """A harmonic base motion must repeat after a few crank turns: nu = p/q, q <= 12."""
    from fractions import Fraction

    for nu in given.get("base_frequency_ratio", ()):
        if "harmonic" not in given.get("base_motion", ()):
            break
        q = Fraction(nu).limit_denominator(MAX_BASE_TURNS)
        if abs(float(q) - nu) > 1e-9 * max(1.0, nu):
            return (f"base_frequency_ratio: {nu!r} does not repeat within {MAX_BASE_TURNS} "
                    "crank turns; give p/q with q <= 12 (e.g. 0.5, 1, 2/3 as 0.6666666666666666)")
    return None


DECLARATION = Mechanism(
    name="linkage_forces",
    title="Kinetostatics of the impact four-bar and GUIM-1's additional rocker",
    summary="Assur-dyad vector route for the reactions, balancing moment by virtual work, "
            "loop closure in factored form; cycle work and RMS by Gauss-Legendre on the "
            "open cycle, peaks from a uniform sample outside the special-position window "
            "refined by golden section",
    references="Power calculation of the GUIM-1 impact mechanism with an additional rocker "
               "arm (in Russian), Vestnik of Issyk-Kul State University no. 50, 2021; the "
               "copy received does not name the authors",
    parameters=(
        Quantity("l0", "m", "base length AD (l0)", "l0", default=_L0, **POSITIVE,
                 label="base $l_0$"),
        Quantity("l1", "m", "crank length AB (l1)", "l1", default=_L1, **POSITIVE,
                 label="crank $l_1$"),
        Quantity("l2", "m", "coupler length BC (l2)", "l2", default=_L2, **POSITIVE,
                 label="coupler $l_2$"),
        Quantity("l3", "m", "rocker length DC (l3)", "l3", default=_L3, **POSITIVE,
                 label="rocker $l_3$"),
        Quantity("m1", "kg", "crank mass (m1)", "m1", default=2.0, **_NONNEG,
                 label="crank mass $m_1$"),
        Quantity("m2", "kg", "coupler mass (m2)", "m2", default=3.0, **_NONNEG,
                 label="coupler mass $m_2$"),
        Quantity("m3", "kg", "rocker mass (m3)", "m3", default=8.0, **_NONNEG,
                 label="rocker mass $m_3$"),
        Quantity("s1", "1", "crank centroid along AB, fraction of l1 from A", default=0.5,
                 label="crank centroid $s_1$"),
        Quantity("s2", "1", "coupler centroid along BC, fraction of l2 from B",
                 default=0.48, label="coupler centroid $s_2$"),
        Quantity("s3", "1", "rocker centroid along DC, fraction of l3 from D",
                 default=0.11 / _L3, label="rocker centroid $s_3$"),
        Quantity("q1", "m", "crank centroid offset across the link", default=0.01,
                 label="crank offset $q_1$"),
        Quantity("q2", "m", "coupler centroid offset across the link", default=-0.02,
                 label="coupler offset $q_2$"),
        Quantity("q3", "m", "rocker centroid offset across the link", default=0.015,
                 label="rocker offset $q_3$"),
        Quantity("J1", "kg m2", "crank centroidal moment of inertia (I_S1)", "I_S1",
                 default=2 * 0.1**2 / 12 + 0.001, **_NONNEG, label="crank inertia $I_{S1}$"),
        Quantity("J2", "kg m2", "coupler centroidal moment of inertia (I_S2)", "I_S2",
                 default=3 * 0.25**2 / 12, **_NONNEG, label="coupler inertia $I_{S2}$"),
        Quantity("J3", "kg m2", "rocker centroidal moment of inertia (I_S3)", "I_S3",
                 default=8 * 0.15**2 / 12 + 0.02, **_NONNEG, label="rocker inertia $I_{S3}$"),
        Quantity("omega1", "rad s-1", "crank angular velocity (omega1); 0 gives statics",
                 "ω1", default=30.0, label=r"crank speed $\omega_1$"),
        Quantity("epsilon1", "rad s-2", "crank angular acceleration (epsilon1)", "ε1",
                 default=0.0, label=r"crank acceleration $\varepsilon_1$"),
        Quantity("tilt", "rad", "inclination of the base AD to the horizontal (gamma + psi "
                 "of the paper)", "γ + ψ", default=math.radians(25.0), minimum=-math.pi,
                 maximum=math.pi, label=r"tilt $\theta$"),
        Quantity("g", "m s-2", "gravitational acceleration", "g", default=9.81, **_NONNEG,
                 label="gravity $g$"),
        assembly_branch(),
        Quantity("external_force", "N", "external force on the rocker, across it "
                 "(positive towards increasing phi3)", default=0.0, label="load across rocker"),
        Quantity("external_force_normal", "N", "external force on the rocker, along D->C",
                 default=0.0, label="load along rocker"),
        Quantity("external_force_arm", "m", "distance from D along the rocker where the "
                 "external force acts", default=0.0, label="load arm"),
        Quantity("external_moment", "N m", "external couple on the rocker "
                 "(counter-clockwise)", default=0.0, label="load couple"),
        Quantity("base_motion", "1", "fixed base; the additional rocker's base turning "
                 "with the main rocker (GUIM-1) as a frozen snapshot (rotating: Omega_b and "
                 "E_b held over the cycle); or as a motion (harmonic: the main rocker swings "
                 "base_amplitude sin(base_frequency_ratio phi1 + base_phase), gravity "
                 "turning with it)", default="fixed",
                 choices={"fixed": BASE_FIXED, "rotating": BASE_ROTATING,
                          "harmonic": BASE_HARMONIC}, label="base motion"),
        Quantity("base_omega", "rad s-1", "main rocker angular velocity (Omega_b), held "
                 "over the cycle", "Ω_b", default=0.0, used_when=_ROTATING,
                 label=r"base speed $\Omega_b$"),
        Quantity("base_epsilon", "rad s-2", "main rocker angular acceleration (E_b), held "
                 "over the cycle", "E_b", default=0.0, used_when=_ROTATING,
                 label="base acceleration $E_b$"),
        Quantity("base_amplitude", "rad", "amplitude of the main rocker's swing about the "
                 "tilt (A_b)", "A_b", default=0.0, minimum=0.0, maximum=math.pi,
                 used_when=_HARMONIC, label="base swing $A_b$"),
        Quantity("base_frequency_ratio", "1", "the main rocker's frequency over the crank's "
                 "(nu = p/q with q <= 12: the motion repeats after q crank turns)", "ν",
                 default=1.0, minimum=0.0, min_inclusive=False, used_when=_HARMONIC,
                 label=r"base frequency $\nu$"),
        Quantity("base_phase", "rad", "phase of the main rocker's swing at phi1 = 0",
                 "φ_b", default=0.0, used_when=_HARMONIC, label=r"base phase $\varphi_b$"),
        Quantity("crank_pivot_x", "m", "crank pivot A relative to the main rocker pivot O, "
                 "along the base", default=0.0, used_when=_MOVING, label="crank pivot $x_A$"),
        Quantity("crank_pivot_y", "m", "crank pivot A relative to the main rocker pivot O, "
                 "across the base", default=0.0, used_when=_MOVING, label="crank pivot $y_A$"),
    ),
    outputs=(
        Output("force_peak_A", "N", "peak |F14| at the crank pivot A over a cycle",
               "|F14|max", _WINDOWED, label="peak $|F_{14}|$ at A"),
        Output("force_peak_B", "N", "peak |F21| at the crank pin B over a cycle",
               "|F21|max", _WINDOWED, label="peak $|F_{21}|$ at B"),
        Output("force_peak_C", "N", "peak |F32| at the coupler-rocker joint C over a cycle",
               "|F32|max", _WINDOWED, label="peak $|F_{32}|$ at C"),
        Output("force_peak_D", "N", "peak |F34| at the rocker pivot D over a cycle",
               "|F34|max", _WINDOWED, label="peak $|F_{34}|$ at D"),
        Output("balancing_moment_peak", "N m", "peak |M_b| over a cycle (balancing "
               "moment)", "|M_b|max", label="peak $|M_b|$"),
        Output("balancing_moment_rms", "N m", "RMS of the balancing moment over a cycle",
               label="RMS $M_b$"),
        Output("cycle_work", "J", "work of the balancing moment per cycle (integral of M_b "
               "dphi1 along the motion)", "∮M_b dφ1", "equals the kinetic energy lost at "
               "impact for constant omega1 on the impact branch", label="cycle work"),
        Output("special_crank_angle", "rad", "crank angle of the special position at which "
               "the cycle starts (the impact node phi1*); a second one, where the linkage "
               "has two, lies pi later", "φ1*", label=r"node angle $\varphi_1^*$"),
        Output("assembly_branch", "1", "assembly branch used (sigma)", "σ",
               flags=BRANCH_FLAGS, undetermined="undetermined", label=r"branch $\sigma$"),
    ),
    profiles=(
        *reaction_profiles((("B", "F21", "crank pin force on the coupler", "coupler"),
                            ("D", "F34", "base force on the rocker", "rocker"),
                            ("C", "F32", "coupler force on the rocker", "rocker"),
                            ("A", "F14", "base force on the crank", "crank"))),
        Output("balancing_moment", "N m", "balancing moment on the crank (M_b, virtual "
               "work)", "M_b", label="balancing moment $M_b$"),
    ),
    profile_dim=Quantity("crank_angle", "rad", "crank angle (phi1), from A->D", "φ1",
                         label=r"crank angle $\varphi_1$"),
    profile_coordinate=lambda method: cell_midpoints(
        method.profile_points, (2 if method.path == PATH_FREE else 1) * 2.0 * np.pi),
    status=("ok", "not_assemblable", "special_position", "nonfinite", "degenerate",
            "second_special_position", "no_special_position"),
    usable=("special_position", "second_special_position"),
    rules=_rules,
    method=(
        geometry_tol("the special-position window"),
        Quantity("special_window", "rad", "half-width of the window around a special "
                 "position excluded from peaks (delta)", "δ", default=0.01, minimum=0.0,
                 maximum=0.5, min_inclusive=False),
        Quantity("quadrature_points", "1", "Gauss-Legendre points for the cycle work and "
                 "RMS", default=200, minimum=2, maximum=5000, integer=True),
        Quantity("peak_samples", "1", "crank angles sampled to find each peak, which is "
                 "then refined to the exact maximum", default=361, minimum=3,
                 maximum=10**6, integer=True),
        path("the outputs and profiles ([GUIM] Fig. 4 draws the free one)"),
        profile_points("crank angles of the profiles (0: no profiles)"),
    ),
)
P = DECLARATION.parameter_index
O = DECLARATION.output_index
F = DECLARATION.profile_index
S = DECLARATION.status_codes

#: the quantities whose peaks are outputs, and their output rows
PEAK_A, PEAK_B, PEAK_C, PEAK_D, PEAK_MB = range(5)
N_PEAKS = 5
PEAK_ROWS = (O.force_peak_A, O.force_peak_B, O.force_peak_C, O.force_peak_D,
             O.balancing_moment_peak)
#: golden section brackets a peak's crank angle to this [rad]: the value is then exact to
#: O(bracket^2), far below round-off
PEAK_LOCATION = 1e-9
#: outputs that must be finite for a point to be ok
CHECKED_ROWS = PEAK_ROWS + (O.balancing_moment_rms, O.cycle_work)

#: layout of the per-angle result vector of ``joint_forces``
R_F14X, R_F14Y, R_F21X, R_F21Y, R_F32X, R_F32Y, R_F34X, R_F34Y = range(8)
R_MB, R_MB_REACTION = 8, 9
R_F21N, R_F21T, R_F34N, R_F34T, R_F32N, R_F32T, R_F14N, R_F14T = range(10, 18)
N_RESULT = 18


@njit(**KERNEL_OPTIONS)
def _cross(ax, ay, bx, by):
    return ax * by - ay * bx


@njit(**KERNEL_OPTIONS)
def joint_forces(phi1, pr, sigma, res, snap=0.0):
    """Joint reactions and balancing moment at crank angle phi1 (see dyad_reactions)."""
    gx, gy, wb, eb = base_state(phi1, pr)
    return dyad_reactions(phi1, pr, sigma, res, snap, gx, gy, wb, eb)


@njit(**KERNEL_OPTIONS)
def base_state(phi1, pr):
    """The base at crank angle phi1: gravity in the base frame and its angular velocity and
    acceleration, (gx, gy, Omega_b, E_b). Fixed: -g (sin tilt, cos tilt), 0, 0; rotating
    (the frozen snapshot): the given Omega_b and E_b; harmonic (the motion): the main rocker
    at theta_b = A sin(nu phi1 + phase) with phi1 = omega1 t, so Omega_b = A nu omega1
    cos(.), E_b = A nu (epsilon1 cos(.) - nu omega1^2 sin(.)), and gravity turned by
    theta_b."""
    tilt, g = pr[P.tilt], pr[P.g]
    mode = pr[P.base_motion]
    if mode == BASE_HARMONIC:
        a, nu = pr[P.base_amplitude], pr[P.base_frequency_ratio]
        w1, e1 = pr[P.omega1], pr[P.epsilon1]
        arg = nu * phi1 + pr[P.base_phase]
        sa, ca = math.sin(arg), math.cos(arg)
        theta = tilt + a * sa
        return (-g * math.sin(theta), -g * math.cos(theta), a * nu * w1 * ca,
                a * nu * (e1 * ca - nu * w1 * w1 * sa))
    if mode == BASE_ROTATING:
        return (-g * math.sin(tilt), -g * math.cos(tilt), pr[P.base_omega],
                pr[P.base_epsilon])
    return -g * math.sin(tilt), -g * math.cos(tilt), 0.0, 0.0


@njit(**KERNEL_OPTIONS)
def base_turns(pr):
    """The crank turns after which the outputs' cycle closes: 1 for a fixed or frozen base;
    for the harmonic base the smallest q <= MAX_BASE_TURNS with nu q whole (0: none)."""
    if pr[P.base_motion] != BASE_HARMONIC:
        return 1
    nu = pr[P.base_frequency_ratio]
    for q in range(1, MAX_BASE_TURNS + 1):
        if abs(nu * q - round(nu * q)) <= 1e-9 * q * max(1.0, nu):
            return q
    return 0


@njit(**KERNEL_OPTIONS)
def dyad_reactions(phi1, pr, sigma, res, snap, gx, gy, wb, eb):
    """Joint reactions and balancing moment at crank angle phi1 (docs/models.md §4.2): the
    kinetostatics of the four-bar as its crank and the dyad BCD, solved in closed form (the
    one dyad solver: the impact machine's dynamic forces use it too).

    pr holds one point's parameters (rows P of the declaration); res (length N_RESULT) gets the
    vectors F14, F21, F32, F34 (force on link i by link j, mechanism frame), M_b from virtual
    work and from the reactions, and the normal/tangential components relative to the coupler
    (F21), rocker (F34, F32) and crank (F14). Returns False where the loop cannot close.
    snap: see kernels.fourbar.dyad_factors (the point kernel passes geometry_tol).
    (gx, gy, wb, eb): gravity in the base frame and the base's angular velocity and
    acceleration at this crank angle (base_state), computed once per point where they do
    not change over the cycle.

    One function, read top to bottom as the steps of docs/models.md §4.2 (kinematics, loads,
    tangential parts, normal parts, the crank, virtual work): they share some forty local
    scalars, which a split would pass through records on every call of the hot loop.
    """
    l0, l1, l2, l3 = pr[P.l0], pr[P.l1], pr[P.l2], pr[P.l3]
    m1, m2, m3 = pr[P.m1], pr[P.m2], pr[P.m3]
    p1, p2, p3 = pr[P.s1] * l1, pr[P.s2] * l2, pr[P.s3] * l3  # centroid along each link [m]
    q1, q2, q3 = pr[P.q1], pr[P.q2], pr[P.q3]
    j1, j2, j3 = pr[P.J1], pr[P.J2], pr[P.J3]
    w1, e1 = pr[P.omega1], pr[P.epsilon1]
    f_t, f_n = pr[P.external_force], pr[P.external_force_normal]
    arm, m_ext = pr[P.external_force_arm], pr[P.external_moment]
    rotating = pr[P.base_motion] != BASE_FIXED
    oax = pr[P.crank_pivot_x] if rotating else 0.0
    oay = pr[P.crank_pivot_y] if rotating else 0.0

    c1, s1, c2, s2, c3, s3, u21, u31, du21, du31 = vector_kinematics(phi1, l0, l1, l2, l3,
                                                                       sigma, snap)
    if math.isnan(c3) or math.isnan(u31):
        return False
    w2, w3 = u21 * w1, u31 * w1
    e2 = du21 * w1 * w1 + u21 * e1
    e3 = du31 * w1 * w1 + u31 * e1
    # positions (origin A): centroid offsets rho_i = p_i e_i + q_i n_i
    r1x, r1y = p1 * c1 - q1 * s1, p1 * s1 + q1 * c1
    r2x, r2y = p2 * c2 - q2 * s2, p2 * s2 + q2 * c2
    r3x, r3y = p3 * c3 - q3 * s3, p3 * s3 + q3 * c3
    bx, by = l1 * c1, l1 * s1
    cx, cy = l0 + l3 * c3, l3 * s3
    sx1, sy1 = r1x, r1y
    sx2, sy2 = bx + r2x, by + r2y
    sx3, sy3 = l0 + r3x, r3y
    # relative velocities and accelerations (base frame)
    vx1, vy1 = -w1 * r1y, w1 * r1x
    vbx, vby = -w1 * by, w1 * bx
    vx2, vy2 = vbx - w2 * r2y, vby + w2 * r2x
    vx3, vy3 = -w3 * r3y, w3 * r3x
    ax1, ay1 = -e1 * r1y - w1 * w1 * r1x, e1 * r1x - w1 * w1 * r1y
    abx, aby = -e1 * by - w1 * w1 * bx, e1 * bx - w1 * w1 * by
    ax2, ay2 = abx - e2 * r2y - w2 * w2 * r2x, aby + e2 * r2x - w2 * w2 * r2y
    ax3, ay3 = -e3 * r3y - w3 * w3 * r3x, e3 * r3x - w3 * w3 * r3y
    if rotating:  # transport + Coriolis, r measured from the base pivot O
        wb2 = wb * wb
        ox, oy = oax + sx1, oay + sy1
        ax1 += -2.0 * wb * vy1 - eb * oy - wb2 * ox
        ay1 += 2.0 * wb * vx1 + eb * ox - wb2 * oy
        ox, oy = oax + sx2, oay + sy2
        ax2 += -2.0 * wb * vy2 - eb * oy - wb2 * ox
        ay2 += 2.0 * wb * vx2 + eb * ox - wb2 * oy
        ox, oy = oax + sx3, oay + sy3
        ax3 += -2.0 * wb * vy3 - eb * oy - wb2 * ox
        ay3 += 2.0 * wb * vx3 + eb * ox - wb2 * oy
    ea1, ea2, ea3 = e1 + eb, e2 + eb, e3 + eb  # absolute angular accelerations

    # applied + inertia loads (d'Alembert), excluding joint forces
    w1x, w1y = m1 * (gx - ax1), m1 * (gy - ay1)
    w2x, w2y = m2 * (gx - ax2), m2 * (gy - ay2)
    w3x, w3y = m3 * (gx - ax3), m3 * (gy - ay3)
    fex = f_n * c3 - f_t * s3  # external force on the rocker, given in the rocker frame
    fey = f_n * s3 + f_t * c3
    px, py = l0 + arm * c3, arm * s3
    mom1 = -j1 * ea1
    mom2 = -j2 * ea2
    mom3 = -j3 * ea3 + m_ext

    # tangential parts from moments about C (eqs. 1-2)
    f21t = (_cross(sx2 - cx, sy2 - cy, w2x, w2y) + mom2) / l2
    f34t = (_cross(sx3 - cx, sy3 - cy, w3x, w3y) + _cross(px - cx, py - cy, fex, fey)
            + mom3) / l3
    # normal parts from the dyad balance F21 + F34 + W2 + W3 = 0 (eqs. 3-4)
    w3x_all, w3y_all = w3x + fex, w3y + fey
    vx = -(f21t * -s2 + f34t * -s3 + w2x + w3x_all)
    vy = -(f21t * c2 + f34t * c3 + w2y + w3y_all)
    det = _cross(c2, s2, c3, s3)  # sin(phi3 - phi2)
    f21n = _cross(vx, vy, c3, s3) / det
    f34n = _cross(c2, s2, vx, vy) / det
    f21x, f21y = f21n * c2 - f21t * s2, f21n * s2 + f21t * c2
    f34x, f34y = f34n * c3 - f34t * s3, f34n * s3 + f34t * c3
    f32x, f32y = -(f34x + w3x_all), -(f34y + w3y_all)
    # the crank (eq. 8 and 9-11)
    mb_reaction = -(_cross(bx, by, -f21x, -f21y) + _cross(sx1, sy1, w1x, w1y) + mom1)
    f14x, f14y = f21x - w1x, f21y - w1y

    # M_b by virtual work: sum of m (a - g).dr/dphi1 + J eps u - Q_ext; no reactions needed
    d1x, d1y = -r1y, r1x
    d2x, d2y = -by - u21 * r2y, bx + u21 * r2x
    d3x, d3y = -u31 * r3y, u31 * r3x
    dpx, dpy = -u31 * arm * s3, u31 * arm * c3
    mb = (m1 * ((ax1 - gx) * d1x + (ay1 - gy) * d1y) + j1 * ea1
          + m2 * ((ax2 - gx) * d2x + (ay2 - gy) * d2y) + j2 * ea2 * u21
          + m3 * ((ax3 - gx) * d3x + (ay3 - gy) * d3y) + j3 * ea3 * u31
          - (fex * dpx + fey * dpy) - m_ext * u31)

    res[R_F14X], res[R_F14Y], res[R_F21X], res[R_F21Y] = f14x, f14y, f21x, f21y
    res[R_F32X], res[R_F32Y], res[R_F34X], res[R_F34Y] = f32x, f32y, f34x, f34y
    res[R_MB], res[R_MB_REACTION] = mb, mb_reaction
    res[R_F21N], res[R_F21T] = f21n, f21t
    res[R_F34N], res[R_F34T] = f34n, f34t
    res[R_F32N], res[R_F32T] = f32x * c3 + f32y * s3, -f32x * s3 + f32y * c3
    res[R_F14N], res[R_F14T] = f14x * c1 + f14y * s1, -f14x * s1 + f14y * c1
    return True


@njit(**KERNEL_OPTIONS)
def peak_quantity(q, res):
    """|F_A|, |F_B|, |F_C|, |F_D| or |M_b| (q = PEAK_A ... PEAK_MB) from a solution."""
    if q == PEAK_A:
        return math.sqrt(res[R_F14X] ** 2 + res[R_F14Y] ** 2)
    if q == PEAK_B:
        return math.sqrt(res[R_F21X] ** 2 + res[R_F21Y] ** 2)
    if q == PEAK_C:
        return math.sqrt(res[R_F32X] ** 2 + res[R_F32Y] ** 2)
    if q == PEAK_D:
        return math.sqrt(res[R_F34X] ** 2 + res[R_F34Y] ** 2)
    return abs(res[R_MB])


@njit(**KERNEL_OPTIONS)
def _forces_at(phi, pr, branch, res, tol, base):
    """dyad_reactions at crank angle phi with the base state ``base`` (gx, gy, Omega_b, E_b)
    computed once for the point, or anew at each angle where the base moves (harmonic), on
    the branch the path takes there: branch = (sigma, node, count, path) as
    kernels.fourbar.path_branch reads them."""
    if pr[P.base_motion] == BASE_HARMONIC:
        gx, gy, wb, eb = base_state(phi, pr)
    else:
        gx, gy, wb, eb = base
    sigma, node, count, path = branch
    return dyad_reactions(phi, pr, path_branch(phi, sigma, node, count, path), res, tol, gx,
                          gy, wb, eb)


@njit(**KERNEL_OPTIONS)
def _peak_at(phi, data):
    """Quantity q at crank angle phi (NaN where the loop cannot close); data as packed by
    _point."""
    q, pr, branch, res, tol, base = data
    if not _forces_at(phi, pr, branch, res, tol, base):
        return math.nan
    return peak_quantity(q, res)


_golden_peak, _refine_peak = peak_search(_peak_at)


@njit(**KERNEL_OPTIONS)
def cycle_pieces(kind, count, window):
    """The smooth pieces of a crank cycle outside the windows around its special positions
    (H10, H11): (starts, ends). The cycle starts at the impact node phi1*; a second node sits
    at phi1* + pi. Without a special position the cycle is one periodic piece."""
    start = math.pi if kind == CHANGE_POINT_C else 0.0
    if kind == 0:
        return np.array([0.0]), np.array([2.0 * math.pi])
    if count > 1:
        return (np.array([start + window, start + math.pi + window]),
                np.array([start + math.pi - window, start + 2.0 * math.pi - window]))
    return np.array([start + window]), np.array([start + 2.0 * math.pi - window])


@njit(**KERNEL_OPTIONS)
def cycle_peaks(pr, branch, res, tol, base, kind, count, window, n_peak, turns, best):
    """The peaks of |F_A|, |F_B|, |F_C|, |F_D| and |M_b| over ``turns`` crank turns outside
    |phi1 - node| < window (H11: F^n ~ 1/dphi1), into best (N_PEAKS, maxima with what it
    holds), piece by piece: the window's edges, a sample clustered towards them, and golden
    section on the exact kinetostatics around every sampled local maximum
    (kernels/extrema.py). False where the loop cannot close."""
    lows, highs = cycle_pieces(kind, count, window)
    for turn in range(turns):
        for piece in range(lows.shape[0]):
            shift = 2.0 * math.pi * turn
            xs = clustered_points(lows[piece] + shift, highs[piece] + shift,
                                  max(3, n_peak // lows.shape[0]), int(CLUSTER))
            values = np.empty((N_PEAKS, xs.shape[0]))
            for j in range(xs.shape[0]):
                if not _forces_at(xs[j], pr, branch, res, tol, base):
                    return False
                for q in range(N_PEAKS):
                    values[q, j] = peak_quantity(q, res)
            for q in range(N_PEAKS):
                best[q] = max(best[q], _refine_peak((q, pr, branch, res, tol, base), xs,
                                                    values[q], PEAK_LOCATION))
    return True


@njit(**KERNEL_OPTIONS)
def cycle_profiles(pr, branch, res, tol, base, kind, count, start, angles, prof):
    """The rigid-model reactions and M_b at every angle into prof[profile, angle] (NaN only
    exactly at a node: ``count`` of them a turn from ``start``, where the dyad is
    singular)."""
    for j in range(angles.shape[0]):
        phi = angles[j]
        at_node = False
        if kind != 0:  # nodes every 2 pi / count from start
            spacing = 2.0 * math.pi / (2 if count > 1 else 1)
            offset = (phi - start) % spacing
            at_node = min(offset, spacing - offset) < 1e-12
        if at_node or not _forces_at(phi, pr, branch, res, tol, base):
            continue
        prof[F.F21_n, j], prof[F.F21_t, j] = res[R_F21N], res[R_F21T]
        prof[F.F34_n, j], prof[F.F34_t, j] = res[R_F34N], res[R_F34T]
        prof[F.F32_n, j], prof[F.F32_t, j] = res[R_F32N], res[R_F32T]
        prof[F.F14_n, j], prof[F.F14_t, j] = res[R_F14N], res[R_F14T]
        prof[F.balancing_moment, j] = res[R_MB]


@njit(**INLINE_OPTIONS)
def design(i, pr, settings, out, prof):
    """One grid point (kernels/block.py): status, the scalar outputs (out) and the
    profiles (prof[k, j])."""
    tol, window, gl_x, gl_w = (settings.geometry_tol, settings.window, settings.gl_x,
                               settings.gl_w)
    n_peak, prof_angles, res = settings.n_peak, settings.angles, settings.res
    l0, l1, l2, l3 = pr[P.l0], pr[P.l1], pr[P.l2], pr[P.l3]
    w1 = pr[P.omega1]
    direction = -1.0 if w1 < 0.0 else 1.0
    if not crank_turns_fully(l0, l1, l2, l3, tol):
        return S.not_assemblable
    mask = change_point_identities(l0 / l1, l2 / l1, l3 / l1, tol)
    count = (mask & 1) + ((mask >> 1) & 1) + ((mask >> 2) & 1)
    kind = 0
    if mask & CHANGE_POINT_A:
        kind = CHANGE_POINT_A
    elif mask & CHANGE_POINT_B:
        kind = CHANGE_POINT_B
    elif mask & CHANGE_POINT_C:
        kind = CHANGE_POINT_C
    sigma = pr[P.sigma]
    if sigma == SIGMA_IMPACT:
        if kind == 0:
            return S.no_special_position  # no impact branch to choose: give sigma
        sigma = impact_branch(kind, direction)
    out[O.assembly_branch] = sigma
    if kind != 0 and kind != CHANGE_POINT_C and abs(l0 - l1) <= tol * (l0 + l1 + l2 + l3):
        return S.degenerate
    start = math.pi if kind == CHANGE_POINT_C else 0.0  # cycle (phi1*, phi1* + 2 pi)
    if kind != 0:
        out[O.special_crank_angle] = start
    base = base_state(0.0, pr)  # gravity and the base's motion, unless the base swings
    turns = base_turns(pr)  # the outputs' cycle: the crank turns after which all repeats
    if turns == 0:
        return S.nonfinite
    free = settings.path == PATH_FREE and kind != 0
    if free and turns % 2 == 1:
        turns *= 2  # the free path repeats after two crank turns
    branch = (sigma, start, count if kind != 0 else 0, settings.path)

    # cycle work and RMS of M_b: Gauss-Legendre on each open piece between special
    # positions (M_b jumps at a node: one-sided there, never integrated across), over the
    # turns of the cycle; the work per crank turn
    pieces = 2 if count > 1 else 1
    half = math.pi / pieces
    work = 0.0
    square = 0.0
    for turn in range(turns):
        for piece in range(pieces):
            left = start + 2.0 * math.pi * turn + 2.0 * half * piece
            for k in range(gl_x.shape[0]):
                if not _forces_at(left + half * (gl_x[k] + 1.0), pr, branch, res, tol, base):
                    return S.not_assemblable
                work += half * gl_w[k] * res[R_MB]
                square += half * gl_w[k] * res[R_MB] * res[R_MB]
    out[O.balancing_moment_rms] = math.sqrt(square / (2.0 * math.pi * turns))
    out[O.cycle_work] = direction * work / turns  # energy delivered by the drive per turn

    # peaks outside the windows around the nodes
    best = np.full(N_PEAKS, -math.inf)
    if not cycle_peaks(pr, branch, res, tol, base, kind, count, window, n_peak, turns, best):
        return S.not_assemblable
    for q in range(N_PEAKS):
        out[PEAK_ROWS[q]] = best[q]

    cycle_profiles(pr, branch, res, tol, base, kind, count, start, prof_angles, prof)
    for k in CHECKED_ROWS:
        if not math.isfinite(out[k]):
            return S.nonfinite
    if count > 1:
        return S.second_special_position
    if kind != 0:
        return S.special_position  # peaks are windowed: the rigid-model supremum is infinite
    return S.ok


#: the method's options the block reads, by name, and its scratch (res: one angle's
#: result vector, N_RESULT)
Settings = namedtuple("Settings", ["geometry_tol", "window", "gl_x", "gl_w", "n_peak",
                                   "angles", "res", "path"])


#: the block: each design of it by ``design`` (kernels/block.py), cached on disk
linkage_forces_block = design_block(design, "linkage_forces_block", globals(), KERNEL_OPTIONS)


def run(params, method):
    """Entry point: (outputs, status, profiles[n_profiles, n, n_angles])."""
    gl_x, gl_w = np.polynomial.legendre.leggauss(method.quadrature_points)
    angles = DECLARATION.profile_coordinate(method)
    n = params.shape[1]
    out, status, prof = block_arrays(DECLARATION, n, angles)
    settings = Settings(geometry_tol=float(method.geometry_tol),
                        window=float(method.special_window), gl_x=gl_x, gl_w=gl_w,
                        n_peak=int(method.peak_samples), angles=angles,
                        res=np.empty(N_RESULT), path=int(method.path))
    linkage_forces_block(np.ascontiguousarray(params), settings, out, status, prof)
    return out, status, prof

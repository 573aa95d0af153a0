"""Four-bar loop closure and transfer functions (docs/models.md §1), shared by every mechanism.

Notation (docs/models.md §1.1): A = (0, 0) and D = (l0, 0); crank AB = l1 at angle phi1, coupler
BC = l2 at phi2, rocker DC = l3 at phi3; assembly branch sigma = +1/-1 with
phi3 = theta_DB + sigma*psi.

Everything is written in the cancellation-free factored form of docs/models.md §1.2: at a
change point one factor of P or Q vanishes exactly and keeps its full relative accuracy,
where the papers' arccos form loses half the digits (hard case H2).
"""

import math

from numba import njit

from kernels import KERNEL_OPTIONS
from kernels.elementary import atan_fast

#: identity bits of the three change-point families (docs/models.md §1.5), l1 = 1
CHANGE_POINT_A = 1  # lambda0 + lambda3 = 1 + lambda2, node at (phi1, phi3) = (0, 0)
CHANGE_POINT_B = 2  # lambda0 + lambda2 = 1 + lambda3, node at (0, pi)
CHANGE_POINT_C = 4  # lambda0 + 1 = lambda2 + lambda3, node at (pi, pi)

#: |DB|^2 below this times (l0 + l1)^2 counts as B on D: the square of a distance under
#: ~1e-140 of the link scale is subnormal and has lost its digits
B_ON_D = 1e-280


@njit(**KERNEL_OPTIONS)
def dyad_factors(phi1, l0, l1, l2, l3, snap=0.0):
    """Squared distance d^2 = |DB|^2 and the closure factors P, Q of docs/models.md §1.2.

    P*Q = (2 l3 d sin psi)^2; the loop closes at phi1 iff P >= 0 and Q >= 0.

    snap: a constant factor smaller than snap*(sum of links) is taken as exactly 0, i.e. a
    linkage classified as a change point is modelled as an exact one. Without it, lengths
    rounded to binary (l1 = 0.1 m) leave a residual ~1e-17 that unfolds the node into an
    avoided crossing: u31 drifts by 5e-4 at 1e-6 rad and u'31 grows like 1/dphi1^2.
    """
    return dyad_factors_half(math.sin(0.5 * phi1), math.cos(0.5 * phi1), l0, l1, l2, l3, snap)


@njit(**KERNEL_OPTIONS)
def dyad_factors_half(sh, ch, l0, l1, l2, l3, snap=0.0):
    """dyad_factors from sh = sin(phi1/2), ch = cos(phi1/2): exact at the dead centres."""
    four = 4.0 * l0 * l1
    limit = snap * (l0 + l1 + l2 + l3)
    fp = l2 + l3 - l0 - l1
    fq1 = l0 - l1 - l2 + l3
    fq2 = l0 - l1 + l2 - l3
    if abs(fp) <= limit:
        fp = 0.0
    if abs(fq1) <= limit:
        fq1 = 0.0
    if abs(fq2) <= limit:
        fq2 = 0.0
    d2 = (l0 - l1) * (l0 - l1) + four * sh * sh
    p = fp * (l2 + l3 + l0 + l1) + four * ch * ch
    q = fq1 * fq2 + four * sh * sh
    return d2, p, q


@njit(**KERNEL_OPTIONS)
def closure_vectors(sh, ch, l0, l1, l2, l3, sigma, snap=0.0):
    """The loop closure (docs/models.md §1.2) as unit vectors: the one solver of this package.

    From sh = sin(phi1/2), ch = cos(phi1/2): returns (c1, s1, c2, s2, c3, s3, d2, root) with
    (ci, si) = (cos, sin) of phi_i, d2 = |DB|^2 and root = sqrt(P Q); NaNs where the loop
    cannot close. phi3 = theta_DB + sigma psi is built by rotating the unit vector D->B by
    sigma psi, with cos psi = (l3^2 + d^2 - l2^2)/(2 l3 d) and sin psi = sqrt(PQ)/(2 l3 d):
    the factored P, Q keep the vanishing factor exact at a change point, and no arccos is
    taken (hard cases H2-H4).
    """
    nan = math.nan
    d2, p, q = dyad_factors_half(sh, ch, l0, l1, l2, l3, snap)
    if p < 0.0 or q < 0.0:
        return nan, nan, nan, nan, nan, nan, nan, nan
    if d2 <= B_ON_D * (l0 + l1) * (l0 + l1):
        # B on D (H9): the rocker angle is undefined, and |DB|^2 would underflow anyway
        return nan, nan, nan, nan, nan, nan, nan, nan
    s1 = 2.0 * sh * ch
    c1 = (ch - sh) * (ch + sh)
    root = math.sqrt(p * q)
    bx, by = l1 * c1 - l0, l1 * s1
    inv = 1.0 / (2.0 * l3 * d2)
    cpsi = (l3 * l3 + d2 - l2 * l2) * inv
    spsi = sigma * root * inv
    c3 = bx * cpsi - by * spsi
    s3 = by * cpsi + bx * spsi
    norm3 = math.sqrt(c3 * c3 + s3 * s3)
    c3 /= norm3
    s3 /= norm3
    cx = l0 + l3 * c3 - l1 * c1
    cy = l3 * s3 - l1 * s1
    norm2 = math.sqrt(cx * cx + cy * cy)
    return c1, s1, cx / norm2, cy / norm2, c3, s3, d2, root


@njit(**KERNEL_OPTIONS)
def loop_closure(phi1, l0, l1, l2, l3, sigma, snap=0.0):
    """Coupler and rocker angles (phi2, phi3) [rad] at crank angle phi1 on branch sigma.

    Returns NaN, NaN where the links cannot close (P < 0 or Q < 0). Angles in (-pi, pi];
    compare them modulo 2pi. snap: see dyad_factors.
    """
    c1, s1, c2, s2, c3, s3, d2, root = closure_vectors(
        math.sin(0.5 * phi1), math.cos(0.5 * phi1), l0, l1, l2, l3, sigma, snap)
    if math.isnan(c3):
        return math.nan, math.nan
    return math.atan2(s2, c2), math.atan2(s3, c3)


@njit(**KERNEL_OPTIONS)
def _stable_u31(c1, s1, d2, root, l0, l1, l2, l3, sigma):
    """u31 = dtheta_DB/dphi1 + sigma dpsi/dphi1 (docs/models.md §1.4); 0/0 = NaN at the node."""
    if root == 0.0:
        return math.nan  # the node itself (H1), or a dead position of the dyad
    return (l1 * (l1 - l0 * c1) / d2
            - sigma * l0 * l1 * s1 * (d2 + l2 * l2 - l3 * l3) / (d2 * root))


@njit(**KERNEL_OPTIONS)
def transfer_ratio(phi1, l0, l1, l2, l3, sigma, snap=0.0):
    """Rocker transfer ratio u31 = dphi3/dphi1 in the stable closed form of docs/models.md §1.4.

    Exact to ~1e-15 away from a special position and to ~3e-8 at |dphi1| = 1e-8 from it;
    NaN exactly at the special position (0/0, hard case H1) and where the loop cannot close.
    """
    sh, ch = math.sin(0.5 * phi1), math.cos(0.5 * phi1)
    d2, p, q = dyad_factors_half(sh, ch, l0, l1, l2, l3, snap)
    if p < 0.0 or q < 0.0:
        return math.nan
    return _stable_u31((ch - sh) * (ch + sh), 2.0 * sh * ch, d2, math.sqrt(p * q),
                       l0, l1, l2, l3, sigma)


@njit(**KERNEL_OPTIONS)
def vector_kinematics(phi1, l0, l1, l2, l3, sigma, snap=0.0):
    """Unit vectors of the links and the transfer functions (docs/models.md §1.3-1.4).

    Returns (c1, s1, c2, s2, c3, s3, u21, u31, u21', u31') with (ci, si) = (cos, sin) of
    phi_i and u'_k1 = d^2 phi_k/dphi1^2; NaNs where the loop cannot close. Angle
    differences are cross and dot products of the unit vectors: two trigonometric calls per
    crank angle, for kernels that evaluate thousands of angles per grid point. The
    second-order functions divide by sin(phi3 - phi2) and are 0/0 at the special position.
    """
    c1, s1, c2, s2, c3, s3, d2, root = closure_vectors(
        math.sin(0.5 * phi1), math.cos(0.5 * phi1), l0, l1, l2, l3, sigma, snap)
    if math.isnan(c3):
        n = math.nan
        return n, n, n, n, n, n, n, n, n, n
    s32 = s3 * c2 - c3 * s2  # sin(phi3 - phi2)
    c32 = c3 * c2 + s3 * s2
    u31 = _stable_u31(c1, s1, d2, root, l0, l1, l2, l3, sigma)
    u21 = l1 * (s1 * c3 - c1 * s3) / (l2 * s32)
    du31 = (l1 * (c1 * c2 + s1 * s2) + l2 * u21 * u21 - l3 * u31 * u31 * c32) / (l3 * s32)
    du21 = (l1 * (c1 * c3 + s1 * s3) + l2 * u21 * u21 * c32 - l3 * u31 * u31) / (l2 * s32)
    return c1, s1, c2, s2, c3, s3, u21, u31, du21, du31


@njit(**KERNEL_OPTIONS)
def transfer_functions(phi1, l0, l1, l2, l3, sigma, snap=0.0):
    """(phi2, phi3, u21, u31, u21', u31') at crank angle phi1: vector_kinematics as angles."""
    c1, s1, c2, s2, c3, s3, u21, u31, du21, du31 = vector_kinematics(phi1, l0, l1, l2, l3,
                                                                       sigma, snap)
    return math.atan2(s2, c2), math.atan2(s3, c3), u21, u31, du21, du31


#: the paths a linkage with special positions can take over its crank angle
PATH_IMPACT, PATH_FREE = 0, 1


@njit(**KERNEL_OPTIONS)
def path_branch(phi1, sigma, node, count, path):
    """The assembly branch at crank angle phi1 on ``path``: on the impact path the branch
    sigma throughout (the stop reverses the rocker at each node); on the free path (no stop,
    [CR] §2, [GUIM] Fig. 4) the smooth curve through each node, so the branch flips at every
    pass: sigma just after the node ``node``, -sigma just before it, with ``count`` nodes a
    turn spaced 2 pi / count apart (docs/models.md §1.5)."""
    if path != PATH_FREE or count == 0:
        return sigma
    passes = math.floor((phi1 - node) * count / (2.0 * math.pi))
    return sigma if passes % 2 == 0 else -sigma


@njit(**KERNEL_OPTIONS)
def change_point_identities(lam0, lam2, lam3, tol):
    """Bit mask of the change-point identities that hold (l1 = 1), docs/models.md §1.5.

    Each identity is one way of splitting the four links into two pairs of equal sum (the
    Grashof defect s + l - p - q = 0); tol is relative to the sum of the links.
    """
    scale = tol * (1.0 + lam0 + lam2 + lam3)
    mask = 0
    if abs(lam0 + lam3 - 1.0 - lam2) <= scale:
        mask |= CHANGE_POINT_A
    if abs(lam0 + lam2 - 1.0 - lam3) <= scale:
        mask |= CHANGE_POINT_B
    if abs(lam0 + 1.0 - lam2 - lam3) <= scale:
        mask |= CHANGE_POINT_C
    return mask


@njit(**KERNEL_OPTIONS)
def crank_turns_fully(l0, l1, l2, l3, tol):
    """Link 1 turns fully iff l0 + l1 <= l2 + l3 and |l0 - l1| >= |l2 - l3| (docs/models.md §1.6).

    At a change point one inequality holds with equality, so it is tested with a tolerance
    relative to the sum of the links; otherwise rounding would decide feasibility.
    """
    slack = tol * (l0 + l1 + l2 + l3)
    return (l0 + l1 <= l2 + l3 + slack) and (abs(l0 - l1) >= abs(l2 - l3) - slack)


@njit(**KERNEL_OPTIONS)
def transmission_angle(phi1, l0, l1, l2, l3, tol):
    """Acute transmission angle (between coupler and rocker, folded to [0, pi/2]) at phi1.

    A factor P or Q that is negative by less than tol*(sum of links)^2 is rounding at a
    change point (the node itself) and is taken as 0; a larger negative one gives NaN.
    """
    return transmission_angle_half(math.sin(0.5 * phi1), math.cos(0.5 * phi1),
                                   l0, l1, l2, l3, tol)


@njit(**KERNEL_OPTIONS)
def transmission_angle_half(sh, ch, l0, l1, l2, l3, tol):
    """transmission_angle from sin and cos of phi1/2 (exact 0/1 at the dead centres)."""
    d2, p, q = dyad_factors_half(sh, ch, l0, l1, l2, l3, 0.0)
    slack = tol * (l0 + l1 + l2 + l3) ** 2
    if p < -slack or q < -slack:
        return math.nan
    q = max(q, 0.0)
    if p <= 0.0:
        return 0.0  # coupler and rocker folded back on each other: mu = pi, folded 0
    # tan(mu/2) = sin(mu)/(1 + cos(mu)) = sqrt(Q/P), since 2 l2 l3 + l2^2 + l3^2 - d^2 = P
    mu = 2.0 * atan_fast(math.sqrt(q / p))
    return min(mu, math.pi - mu)

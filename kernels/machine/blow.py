"""The blow at the node (docs/machine.md §2): the node's one-sided inertias, and the
generalised Newton impact (law G): the tool's impulse with Newton's law on the rocker, then
a plastic capture onto the departure branch with the one-sided inertias; it never gains
energy. The kinematic law (law S: the rocker reverses with -R and the crank follows the
departure branch) is there for comparison; it can create energy."""

import math
from collections import namedtuple

from numba import njit

from kernels import INNER_OPTIONS
from kernels.machine.declaration import LAW_KINEMATIC
from kernels.machine.dynamics import kinematics

#: the node: the one-sided inertias J- = T-' M3 T- (arriving), J+ = T+' M3 T+ (leaving) and
#: the cross inertia J+- = T+' M3 T- of the tangents T- = (1, u21-, u31-) at the cycle's
#: end and T+ at its start; m_r = M33 - M13^2/M11, the rocker's inertia about D with the
#: crank free; the one-sided ratios u31-, u31+, u21-, u21+; the form M11, M13, M33 in the
#: velocity coordinates (omega1, omega3) of the node's plane; c21 = (AB . rho2)/l1 there
Node = namedtuple("Node", ["j_before", "j_after", "j_cross", "rocker_inertia", "u31_before",
                           "u31_after", "u21_before", "u21_after", "m11", "m13", "m33",
                           "c21"])
#: a blow: the crank speed after it, the tool's impulse Pi, the kinetic energy lost, the
#: energy delivered to the material, the capture's loss
Blow = namedtuple("Blow", ["w_plus", "impulse", "loss", "tool", "capture"])


@njit(**INNER_OPTIONS)
def node(m):
    """The Node of the Machine ``m``."""
    lk, ms = m.linkage, m.masses
    start = lk.start
    cb, sb, c2b, s2b, c3b, s3b, u21m, u31m, _, _ = kinematics(start + 2.0 * math.pi, lk)
    ca, sa, c2a, s2a, c3a, s3a, u21p, u31p, _, _ = kinematics(start, lk)
    l1, ja, m2l1, jb2, jd3 = lk.l1, m.ja, ms.m2l1, ms.jb2, ms.jd3
    c12, s12 = ca * c2a + sa * s2a, sa * c2a - ca * s2a
    c21 = ms.p2 * c12 + ms.q2 * s12
    a11, a12 = ja + m2l1 * l1, m2l1 * c21  # M3 = [[a11, a12, 0], [a12, jb2, 0], [0, 0, jd3]]

    def form(x1, x2, x3, y1, y2, y3):
        return a11 * x1 * y1 + a12 * (x1 * y2 + x2 * y1) + jb2 * x2 * y2 + jd3 * x3 * y3

    jm = form(1.0, u21m, u31m, 1.0, u21m, u31m)
    jp = form(1.0, u21p, u31p, 1.0, u21p, u31p)
    jpm = form(1.0, u21p, u31p, 1.0, u21m, u31m)
    b = (u21p - u21m) / (u31p - u31m)  # omega2 = a omega1 + b omega3 on the node's plane
    a = u21m - b * u31m
    m11 = form(1.0, a, 0.0, 1.0, a, 0.0)
    m13 = form(1.0, a, 0.0, 0.0, b, 1.0)
    m33 = form(0.0, b, 1.0, 0.0, b, 1.0)
    mr = m33 - m13 * m13 / m11 if m11 > 0.0 else m33
    return Node(j_before=jm, j_after=jp, j_cross=jpm, rocker_inertia=mr, u31_before=u31m,
                u31_after=u31p, u21_before=u21m, u21_after=u21p, m11=m11, m13=m13, m33=m33,
                c21=c21)


@njit(**INNER_OPTIONS)
def blow(w_minus, r, law, nd, m):
    """The blow at crank speed w_minus on material of restitution r by ``law``: a Blow.
    Law G: Pi = -(1 + R) m_r omega3- from Newton's law on the rocker, then
    J+ omega1+ = J+- omega1- + u31+ Pi (the departure tangent's momentum kept); law S:
    omega1+ = (-R/Rk) omega1-, Pi from the same balance."""
    jm, jp, jpm = nd.j_before, nd.j_after, nd.j_cross
    u31m, u31p = nd.u31_before, nd.u31_after
    w3 = u31m * w_minus
    tool = 0.5 * (1.0 - r * r) * nd.rocker_inertia * w3 * w3
    if law == LAW_KINEMATIC:
        w_plus = -r * u31m / u31p * w_minus
        impulse = (jp * w_plus - jpm * w_minus) / u31p
        loss = 0.5 * jm * w_minus * w_minus - 0.5 * jp * w_plus * w_plus
        return Blow(w_plus=w_plus, impulse=impulse, loss=loss, tool=tool, capture=loss - tool)
    impulse = -(1.0 + r) * nd.rocker_inertia * w3
    w_plus = (jpm * w_minus + u31p * impulse) / jp
    # the capture's Carnot loss as a quadratic form of the velocity it removes: the loss
    # as a difference of kinetic energies cancels where the flywheel is heavy
    capture = capture_loss(w_minus, r, w_plus, nd, m)
    return Blow(w_plus=w_plus, impulse=impulse, loss=tool + capture, tool=tool,
                capture=capture)


@njit(**INNER_OPTIONS)
def capture_loss(w_minus, r, w_plus, nd, m):
    """Law G's capture loss |qdot_m - omega1+ T+|^2_M3 / 2: the velocity just after the
    tool's impulse (in the node's plane, omega2 = a omega1 + b omega3) against the
    departure motion omega1+ T+ it is captured onto (docs/machine.md §2)."""
    u31m, u31p, u21m, u21p = nd.u31_before, nd.u31_after, nd.u21_before, nd.u21_after
    ms = m.masses
    l1, ja, m2l1, jb2, jd3 = m.linkage.l1, m.ja, ms.m2l1, ms.jb2, ms.jd3
    b = (u21p - u21m) / (u31p - u31m)
    a = u21m - b * u31m
    w3 = u31m * w_minus
    d3 = -(1.0 + r) * w3
    d1 = -nd.m13 / nd.m11 * d3
    w1m, w3m = w_minus + d1, w3 + d3
    e1 = w1m - w_plus
    e2 = a * w1m + b * w3m - w_plus * u21p
    e3 = w3m - w_plus * u31p
    return 0.5 * ((ja + m2l1 * l1) * e1 * e1 + 2.0 * m2l1 * nd.c21 * e1 * e2
                  + jb2 * e2 * e2 + jd3 * e3 * e3)

"""An independent model of the crank-driven impact machine, for the tests: plain numpy loop
closure (arccos for the dyad, the velocity and acceleration analysis as 2 x 2 linear
solves), the reduced inertia from the kinetic energy of each link, the generalised forces
from the potential, law G from the node's inertia matrix, and the revolution integrated in
time by SciPy's DOP853 with events (docs/machine.md). Nothing here calls the kernels.

The loop closure's arccos loses digits next to the node, so a revolution is integrated
from ANGLE_OFF after the blow to ANGLE_OFF before the next, the two short ends closed by
collocation on the crank angle with the one-sided values at the node (the paper's closed
forms (1 +- gamma)/(1 -+ lambda0)); its error is O(ANGLE_OFF^5).
"""

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

ANGLE_OFF = 1e-3


@dataclass
class Machine:
    l0: float
    l1: float
    l2: float
    l3: float
    sigma: float
    start: float  # the node's crank angle, 0 (types a, b) or pi (c)
    m1: float
    m2: float
    m3: float
    p1: float
    q1: float
    p2: float
    q2: float
    p3: float
    q3: float
    j1: float
    j2: float
    j3: float
    flywheel: float
    tilt: float
    g: float
    load: tuple  # (Fx, Fy) in the base frame
    load_point: tuple  # (along, across) on the rocker from D
    load_moment: float
    motor: str  # "linear" or "constant"
    stall_torque: float
    idle_speed: float
    restitution: float

    @property
    def crank_inertia(self):
        return self.j1 + self.m1 * (self.p1 ** 2 + self.q1 ** 2) + self.flywheel

    def gravity(self):
        return (-self.g * math.sin(self.tilt), -self.g * math.cos(self.tilt))


def positions(mc: Machine, phi):
    """(phi2, phi3) by the textbook dyad: arccos at D."""
    bx, by = mc.l1 * math.cos(phi) - mc.l0, mc.l1 * math.sin(phi)  # D -> B
    d2 = bx * bx + by * by
    d = math.sqrt(d2)
    cos_psi = min(1.0, max(-1.0, (mc.l3 ** 2 + d2 - mc.l2 ** 2) / (2 * mc.l3 * d)))
    phi3 = math.atan2(by, bx) + mc.sigma * math.acos(cos_psi)
    cx = mc.l0 + mc.l3 * math.cos(phi3) - mc.l1 * math.cos(phi)
    cy = mc.l3 * math.sin(phi3) - mc.l1 * math.sin(phi)
    return math.atan2(cy, cx), phi3


def _solve2(a11, a12, a21, a22, b1, b2):
    det = a11 * a22 - a12 * a21
    return (b1 * a22 - a12 * b2) / det, (a11 * b2 - a21 * b1) / det


def velocities(mc: Machine, phi, phi2, phi3):
    """(u21, u31) from the loop's velocity equations, a 2 x 2 solve."""
    return _solve2(-mc.l2 * math.sin(phi2), mc.l3 * math.sin(phi3),
                   mc.l2 * math.cos(phi2), -mc.l3 * math.cos(phi3),
                   mc.l1 * math.sin(phi), -mc.l1 * math.cos(phi))


def accelerations(mc: Machine, phi, phi2, phi3, u21, u31):
    """(u21', u31') from the loop's acceleration equations."""
    return _solve2(-mc.l2 * math.sin(phi2), mc.l3 * math.sin(phi3),
                   mc.l2 * math.cos(phi2), -mc.l3 * math.cos(phi3),
                   mc.l1 * math.cos(phi) + mc.l2 * u21 ** 2 * math.cos(phi2)
                   - mc.l3 * u31 ** 2 * math.cos(phi3),
                   mc.l1 * math.sin(phi) + mc.l2 * u21 ** 2 * math.sin(phi2)
                   - mc.l3 * u31 ** 2 * math.sin(phi3))


def rotate(angle, v):
    c, s = math.cos(angle), math.sin(angle)
    return (c * v[0] - s * v[1], s * v[0] + c * v[1])


def perp(v):
    return (-v[1], v[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1]


def add(*vectors):
    return (sum(v[0] for v in vectors), sum(v[1] for v in vectors))


def scale(k, v):
    return (k * v[0], k * v[1])


def centroids(mc: Machine, phi, phi2, phi3):
    """The centroid offsets rho_i (from A, B, D) and the crank vector AB."""
    return (rotate(phi, (mc.p1, mc.q1)), rotate(phi2, (mc.p2, mc.q2)),
            rotate(phi3, (mc.p3, mc.q3)), (mc.l1 * math.cos(phi), mc.l1 * math.sin(phi)))


def inertia_terms(mc: Machine, phi, u21, u31, phi2, phi3):
    """J = sum of m |v_S / omega1|^2 + J_i u_i1^2, each link's velocity built as vectors."""
    r1, r2, r3, ab = centroids(mc, phi, phi2, phi3)
    v1 = perp(r1)
    v2 = add(perp(ab), scale(u21, perp(r2)))
    v3 = scale(u31, perp(r3))
    return (mc.flywheel + mc.j1 + mc.m1 * dot(v1, v1) + mc.m2 * dot(v2, v2)
            + mc.j2 * u21 ** 2 + mc.m3 * dot(v3, v3) + mc.j3 * u31 ** 2), (v1, v2, v3)


def potential(mc: Machine, phi):
    """V: gravity on the three centroids and the conservative load (the force fixed in the
    base frame at its point on the rocker, the couple times phi3)."""
    phi2, phi3 = positions(mc, phi)
    r1, r2, r3, ab = centroids(mc, phi, phi2, phi3)
    g = mc.gravity()
    s1, s2, s3 = r1, add(ab, r2), add((mc.l0, 0.0), r3)
    point = add((mc.l0, 0.0), rotate(phi3, mc.load_point))
    return (-(mc.m1 * dot(g, s1) + mc.m2 * dot(g, s2) + mc.m3 * dot(g, s3))
            - dot(mc.load, point) - mc.load_moment * phi3)


def generalized_force(mc: Machine, phi, u21, u31, phi2, phi3, velocities_):
    v1, v2, v3 = velocities_
    g = mc.gravity()
    rp = rotate(phi3, mc.load_point)
    return (mc.m1 * dot(g, v1) + mc.m2 * dot(g, v2) + mc.m3 * dot(g, v3)
            + u31 * (dot(mc.load, perp(rp)) + mc.load_moment))


def state(mc: Machine, phi):
    """(J, J', Q) at crank angle phi; J' = 2 sum m v.v' + 2 J u u' through the acceleration
    analysis (v' of each centroid: d/dphi of perp(rho) is -u rho)."""
    phi2, phi3 = positions(mc, phi)
    u21, u31 = velocities(mc, phi, phi2, phi3)
    du21, du31 = accelerations(mc, phi, phi2, phi3, u21, u31)
    j, vel = inertia_terms(mc, phi, u21, u31, phi2, phi3)
    r1, r2, r3, ab = centroids(mc, phi, phi2, phi3)
    v1, v2, v3 = vel
    a1 = scale(-1.0, r1)
    a2 = add(scale(-1.0, ab), scale(du21, perp(r2)), scale(-u21 ** 2, r2))
    a3 = add(scale(du31, perp(r3)), scale(-u31 ** 2, r3))
    dj = 2 * (mc.m1 * dot(v1, a1) + mc.m2 * dot(v2, a2) + mc.j2 * u21 * du21
              + mc.m3 * dot(v3, a3) + mc.j3 * u31 * du31)
    return j, dj, generalized_force(mc, phi, u21, u31, phi2, phi3, vel)


def force_at_node(mc: Machine, tangent):
    """Q at the node on one side, from the one-sided tangent (1, u21, u31)."""
    phi2, phi3 = positions(mc, mc.start)
    r1, r2, r3, ab = centroids(mc, mc.start, phi2, phi3)
    _, u21, u31 = tangent
    vel = (perp(r1), add(perp(ab), scale(u21, perp(r2))), scale(u31, perp(r3)))
    return generalized_force(mc, mc.start, u21, u31, phi2, phi3, vel)


def motor(mc: Machine, w):
    if mc.motor == "constant":
        return mc.stall_torque
    return mc.stall_torque * (1.0 - w / mc.idle_speed)


def node(mc: Machine, lam0, gamma, kind):
    """One-sided tangents at the node from the paper's closed forms, and M3 there."""
    den = (1.0 + lam0) if kind == "c" else (1.0 - lam0)
    kappa = -1.0 if kind == "b" else 1.0
    s = kappa * mc.sigma * gamma
    u31m, u31p = (1.0 - s) / den, (1.0 + s) / den  # before (approaching), after
    phi2, phi3 = positions(mc, mc.start)  # collinear: the node's configuration
    c21 = rotate(phi2 - mc.start, (mc.p2, mc.q2))[0]  # (AB . rho2)/l1

    def u21(u31):  # the loop's real part: no division by sin(phi3 - phi2)
        return (mc.l3 * u31 * np.cos(phi3 - phi2) - mc.l1 * np.cos(mc.start - phi2)) / mc.l2

    ja = mc.crank_inertia
    m3 = np.array([[ja + mc.m2 * mc.l1 ** 2, mc.m2 * mc.l1 * c21, 0.0],
                   [mc.m2 * mc.l1 * c21, mc.j2 + mc.m2 * (mc.p2 ** 2 + mc.q2 ** 2), 0.0],
                   [0.0, 0.0, mc.j3 + mc.m3 * (mc.p3 ** 2 + mc.q3 ** 2)]])
    tm = np.array([1.0, u21(u31m), u31m])
    tp = np.array([1.0, u21(u31p), u31p])
    return m3, tm, tp


def law_g(m3, tm, tp, w_minus, r):
    """Law G: (w_plus, Pi, dE, dE_tool, dE_capture) from the node's velocity plane."""
    basis = np.column_stack([tm, tp])  # q = a T- + b T+; in (omega1, omega3) coordinates
    to_plane = np.linalg.inv(np.array([[1.0, 1.0], [tm[2], tp[2]]]))
    v = basis @ to_plane  # 3 x 2: (omega1, omega3) -> (omega1, omega2, omega3)
    form = v.T @ m3 @ v
    mr = form[1, 1] - form[0, 1] ** 2 / form[0, 0]
    w3 = tm[2] * w_minus
    impulse = -(1.0 + r) * mr * w3
    jp, jpm = tp @ m3 @ tp, tp @ m3 @ tm
    w_plus = (jpm * w_minus + tp[2] * impulse) / jp
    after_tool = v @ np.array([w_minus - form[0, 1] / form[0, 0] * (-(1 + r) * w3),
                               -r * w3])
    gap = after_tool - w_plus * tp
    loss = 0.5 * (tm @ m3 @ tm) * w_minus ** 2 - 0.5 * jp * w_plus ** 2
    return w_plus, impulse, loss, 0.5 * (1 - r * r) * mr * w3 ** 2, 0.5 * gap @ m3 @ gap


def end_segment(mc: Machine, t_a, points):
    """T and the quadratures over a short segment [a, b] of the crank angle, from T at a:
    3-stage Lobatto IIIA collocation (order 4) on dT/dphi = M(omega) + Q, the stages
    solved by fixed-point iteration; the time, the motor's work and int M^2 dt by
    Simpson's rule. points: ((phi, J, Q) at a, at the midpoint, at b)."""
    (pa, ja, qa), (pm, jm, qm), (pb, jb, qb) = points
    h = pb - pa
    wa = math.sqrt(2 * t_a / ja)
    t_m, t_b = t_a, t_a
    for _ in range(30):
        wm, wb = math.sqrt(2 * t_m / jm), math.sqrt(2 * t_b / jb)
        fa, fm, fb = motor(mc, wa) + qa, motor(mc, wm) + qm, motor(mc, wb) + qb
        t_m = t_a + h * (5 * fa / 24 + fm / 3 - fb / 24)
        t_b = t_a + h * (fa + 4 * fm + fb) / 6
    speeds = (wa, math.sqrt(2 * t_m / jm), math.sqrt(2 * t_b / jb))

    def simpson(f):
        return h * (f(speeds[0]) + 4 * f(speeds[1]) + f(speeds[2])) / 6

    return (t_b, speeds[2], simpson(lambda w: 1 / w), simpson(lambda w: motor(mc, w)),
            simpson(lambda w: motor(mc, w) ** 2 / w))


def revolution(mc: Machine, w_plus, m3, tm, tp, rtol=1e-12):
    """A revolution in time from the blow's exit: DOP853 on (phi, omega, W_motor,
    int M^2 dt, W_Q) with events at the end and at the speed extrema; the two ends within
    ANGLE_OFF of the node by collocation (end_segment). Returns a dict of what it found."""
    j_plus, j_minus = tp @ m3 @ tp, tm @ m3 @ tm
    start, end = mc.start + ANGLE_OFF, mc.start + 2 * np.pi - ANGLE_OFF

    def point(phi):
        j, _, q = state(mc, phi)
        return phi, j, q

    t1, w1, time0, work0, sq0 = end_segment(
        mc, 0.5 * j_plus * w_plus ** 2, ((mc.start, j_plus, force_at_node(mc, tp)),
                                         point(mc.start + 0.5 * ANGLE_OFF), point(start)))

    def rhs(t, y):
        j, dj, q = state(mc, y[0])
        torque = motor(mc, y[1])
        return [y[1], (torque + q - 0.5 * dj * y[1] ** 2) / j, torque * y[1], torque ** 2,
                q * y[1]]

    def at_end(t, y):
        return y[0] - end
    at_end.terminal, at_end.direction = True, 1

    def extremum(t, y):
        j, dj, q = state(mc, y[0])
        return motor(mc, y[1]) + q - 0.5 * dj * y[1] ** 2

    def stall(t, y):
        return y[1]
    stall.terminal, stall.direction = True, -1

    sol = solve_ivp(rhs, (0.0, 1e3), [start, w1, 0.0, 0.0, 0.0], method="DOP853",
                    rtol=rtol, atol=1e-14, events=(at_end, extremum, stall))
    if sol.t_events[2].size:
        return {"stalls": True}
    y_end = sol.y_events[0][0]
    speeds = [w_plus, w1, y_end[1]] + [y[1] for y in sol.y_events[1]]
    j_end = state(mc, end)[0]
    t_minus, w_minus, time1, work1, sq1 = end_segment(
        mc, 0.5 * j_end * y_end[1] ** 2, (point(end), point(end + 0.5 * ANGLE_OFF),
                                           (mc.start + 2 * np.pi, j_minus,
                                            force_at_node(mc, tm))))
    speeds.append(w_minus)
    return {"stalls": False, "w_minus": w_minus, "w_min": min(speeds), "w_max": max(speeds),
            "period": time0 + sol.t_events[0][0] + time1,
            "motor_work": work0 + y_end[2] + work1, "torque_squared": sq0 + y_end[3] + sq1}


def steady(mc: Machine, m3, tm, tp, w0, rtol=1e-12, tol=1e-11, max_revolutions=40):
    """The fixed point of the section map by the secant method from w0, and its outputs."""
    def image(w):
        rev = revolution(mc, w, m3, tm, tp, rtol)
        return law_g(m3, tm, tp, rev["w_minus"], mc.restitution)[0], rev

    w_prev, (f_prev_image, _) = w0, image(w0)
    f_prev = f_prev_image - w0
    w = f_prev_image
    for _ in range(max_revolutions):
        w_next, rev = image(w)
        f = w_next - w
        if abs(f) <= tol * w or f == f_prev:
            break
        w, w_prev, f_prev = w - f * (w - w_prev) / (f - f_prev), w, f
    w_plus_next, impulse, loss, tool, capture = law_g(m3, tm, tp, rev["w_minus"],
                                                      mc.restitution)
    period = rev["period"]
    ja = mc.crank_inertia
    j_d3 = m3[2, 2]
    lows = [motor(mc, rev["w_min"]), motor(mc, rev["w_max"])]
    return {
        "mean_crank_speed": 2 * np.pi / period,
        "speed_fluctuation": (rev["w_max"] - rev["w_min"]) * period / (2 * np.pi),
        "crank_speed_before_blow": rev["w_minus"],
        "crank_speed_after_blow": w_plus_next,
        "crank_speed_jump": w_plus_next - rev["w_minus"],
        "tool_impulse": impulse,
        "crank_impulse": ja * (w_plus_next - rev["w_minus"]),
        "motor_torque_peak": max(abs(x) for x in lows),
        "motor_torque_rms": np.sqrt(rev["torque_squared"] / period),
        "motor_power_mean": rev["motor_work"] / period,
        "blow_energy": 0.5 * j_d3 * (tm[2] * rev["w_minus"]) ** 2,
        "blow_loss": loss,
        "energy_to_material": tool,
        "capture_loss": capture,
        "blow_rate": 60 / period,
        "cycle_period": period,
    }


def synthesis(kind, largest, r):
    """(lambda0, lambda2, lambda3, sigma, node angle) of a type for Rk = -r ([CR] eqs.
    10-11; type b: the smaller root of t^2 - (1 + lambda3) t + gamma^2 lambda3 as base)."""
    g2 = ((1 + r) / (1 - r)) ** 2
    if kind == "a":
        return g2 * (largest + 1) / (g2 + largest), largest, \
            largest * (largest + 1) / (g2 + largest), -1.0, 0.0
    if kind == "c":
        return largest, g2 * (largest + 1) / (g2 + largest), \
            largest * (largest + 1) / (g2 + largest), -1.0, np.pi
    b = 1 + largest
    small = (b - np.sqrt(b * b - 4 * g2 * largest)) / 2
    return small, b - small, largest, 1.0, 0.0


def build(params: dict, kind="a", largest=2.5, design_r=None) -> tuple:
    """A Machine from the kernel's parameter names (defaults: the test machine), with its
    synthesis; and (lambda0, gamma) for the node."""
    p = dict(DEFAULTS, **params)
    r = p["R"]
    lam0, lam2, lam3, sigma, start = synthesis(kind, largest, r if design_r is None
                                               else design_r)
    l1 = p["crank_length"]
    mc = Machine(lam0 * l1, l1, lam2 * l1, lam3 * l1, sigma, start, p["m1"], p["m2"],
                 p["m3"], p["s1"] * l1, p["q1"], p["s2"] * lam2 * l1, p["q2"],
                 p["s3"] * lam3 * l1, p["q3"], p["J1"], p["J2"], p["J3"],
                 p["flywheel_inertia"], p["tilt"], p["g"],
                 (p["load_force_x"], p["load_force_y"]), (p["load_arm"], p["load_offset"]),
                 p["load_moment"], p["motor_law"], p["stall_torque"], p["idle_speed"], r)
    return mc, lam0, np.sqrt(lam0 * lam2 / lam3)


DEFAULTS = dict(R=0.3, crank_length=0.1, m1=2.0, m2=3.0, m3=8.0, s1=0.5, s2=0.48,
                s3=0.11 / (0.1 * 1.470840480274443), q1=0.01, q2=-0.02, q3=0.015,
                J1=2 * 0.1 ** 2 / 12 + 0.001, J2=3 * 0.25 ** 2 / 12,
                J3=8 * 0.15 ** 2 / 12 + 0.02, flywheel_inertia=5.0, tilt=np.radians(25.0),
                g=9.81, load_force_x=0.0, load_force_y=0.0, load_arm=0.0, load_offset=0.0,
                load_moment=0.0, motor_law="linear", stall_torque=1200.0, idle_speed=32.0)


def simulate(params: dict, kind="a", largest=2.5, design_r=None, rtol=1e-12):
    """The steady-state outputs of a design by this independent model."""
    mc, lam0, gamma = build(params, kind, largest, design_r)
    m3, tm, tp = node(mc, lam0, gamma, kind)
    c = law_g(m3, tm, tp, 1.0, mc.restitution)[2]  # the loss is quadratic in the speed
    if mc.motor == "constant":
        w0 = np.sqrt(2 * np.pi * mc.stall_torque / c)
    else:
        a, b = c / (2 * np.pi), mc.stall_torque / mc.idle_speed
        w0 = (-b + np.sqrt(b * b + 4 * a * mc.stall_torque)) / (2 * a)
    return steady(mc, m3, tm, tp, w0, rtol)

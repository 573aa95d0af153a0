"""The lab-fixed blade (lab_window, docs/models.md §5.5, H11), composed with a model into a
``Contact`` (see tools.py): the contact point is at radius rho = sqrt(X), X = k^2 + 1 +
2k cos psi, and at the polar angle G = phi1 + beta(psi), beta = atan2(sin psi, k + cos psi);
the blade is radial at lab angle 0 (mod 2 pi) and reaches in down to the striker's radius
at |psi| = window. The gap is G against the blade's faces at G = lower and lower + 2 pi; a
face met with |psi| > window is passed (the striker goes inside the blade). Newton's law
acts on the normal speed rho G', G' = phi1' + h psi', h = dbeta/dpsi (J = (1, h)). After a
plastic contact (R = 0, or an accumulated chatter) the striker slides along the face while
pressed into it: a flight of the constrained system (kernels/impact) until the pressing
vanishes (release) or |psi| reaches the blade's edge. Escape: |psi| rising through pi.
Data: (lower, window, k, level, side), the last contact's face level and side (+1: met
rising, -1: falling, 0: slid off the edge) (LOWER ... SIDE).
"""


import math

import numpy as np
from numba import njit

from kernels import INNER_OPTIONS, INLINE_OPTIONS
from kernels.extrema import peak_search
from kernels.impact import Contact, System, no_coast
from kernels.impact.events import make_illinois
from kernels.impact.flight import EXACT_REACH, Flight, make_flight
from kernels.impact.attractors import radical_inverse
from kernels.impact.outcomes import FLIGHT_EVENT, NO_COST
from kernels.impact.runge_kutta import OTHER_METHODS
from kernels.impact.tangent import (DDPSI, DPHI, DPSI, DT, DW, Field,
                                    make_acceleration_differential, make_event_carry,
                                    make_variational)
from kernels.impact.tuples import relative_scales

from kernels.pendulum.tools import TWO_PI, never

#: the blade's data (lower, window, k, level, side): the lower face's lab angle, the reach,
#: k, the last contact's face level and side (+1 met rising, -1 falling, 0 slid off)
LOWER, WINDOW, K, LEVEL, SIDE = range(5)
SECTION_MIN_FLIGHT = 0.1  # blade: an impact after a shorter flight continues an episode
LAB_HORIZON = 200.0 * math.pi  # rotor radians without a contact: regime no_impact

@njit(**INLINE_OPTIONS)
def beta(psi, k):
    """Polar angle of the contact point ahead of the rotor arm."""
    return math.atan2(math.sin(psi), k + math.cos(psi))


@njit(**INLINE_OPTIONS)
def h_ratio(psi, k):
    """h = dbeta/dpsi = (1 + k cos psi)/X."""
    return (1.0 + k * math.cos(psi)) / (k * k + 1.0 + 2.0 * k * math.cos(psi))


@njit(**INLINE_OPTIONS)
def h_slope(psi, k):
    """dh/dpsi = k (1 - k^2) sin psi / X^2."""
    x = k * k + 1.0 + 2.0 * k * math.cos(psi)
    return k * (1.0 - k * k) * math.sin(psi) / (x * x)


@njit(**INLINE_OPTIONS)
def h_curvature(psi, k):
    """d2h/dpsi2 = k (1 - k^2) (X cos psi + 4 k sin^2 psi)/X^3."""
    s, c = math.sin(psi), math.cos(psi)
    x = k * k + 1.0 + 2.0 * k * c
    return k * (1.0 - k * k) * (x * c + 4.0 * k * s * s) / (x * x * x)


@njit(**INNER_OPTIONS)
def face_psi(target, psi, k):
    """psi on a face, beta(psi) = target (Newton from psi)."""
    for _ in range(50):
        step = (beta(psi, k) - target) / h_ratio(psi, k)
        psi -= step
        if abs(step) <= 1e-15:
            break
    return psi


@njit(**INLINE_OPTIONS)
def _fixed_exit_tangent(tangent, d, t, y, data, t1, y1, data1, p, settings):
    """A slide at constant rotor speed ends where the face alone decides (the release, or
    the blade's edge): its exit does not depend on its entry."""
    tangent[:, :d] = 0.0
    return True


def _gap_acceleration_change(model):
    """``change(y, p, k, a_psi, c) -> (d G'', d psi'')``: how the free normal acceleration
    of the blade, G'' = phi1'' + h psi'' + h' psi'^2, and the free psi'' change along a
    perturbation c in coordinates (dt, dphi1, dphi1', dpsi, dpsi'), at a state whose free
    psi'' is a_psi: the model's Jacobian and h's first two derivatives. The one gradient
    of the pressing, for the chatter's accumulation point and the slide's release."""
    differential = make_acceleration_differential(model, 2 if model.driven else 4)
    psi_of, dpsi_of = model.psi, model.dpsi

    @njit(**INLINE_OPTIONS)
    def change(y, p, k, a_psi, c):
        psi, v = psi_of(y), dpsi_of(y)
        hs = h_slope(psi, k)
        da_phi, da_psi = differential(y, p, c)
        return (da_phi + h_ratio(psi, k) * da_psi
                + (hs * a_psi + h_curvature(psi, k) * v * v) * c[DPSI]
                + 2.0 * hs * v * c[DDPSI]), da_psi

    return change


SLIDE_SAMPLES = 128  # pressing samples along a kinematic slide (a release is bracketed)


@njit(**INLINE_OPTIONS)
def after_slide(released, data):
    """The blade data after a slide: off the blade's edge the striker is past the face, in
    the direction it pressed (side 0: no face was just met)."""
    lower, window, k, level, side = data
    if released:
        return data
    return lower, window, k, level if side > 0.0 else level - TWO_PI, 0.0


def _kinematic_slide(model, free_gap_acceleration):
    """The slide at constant rotor speed, in closed form: on the face G = level the rotor
    angle is the time, so psi follows from beta(psi) = level - tau, and psi' = -1/h. psi
    falls monotonically (h > 0 for |psi| < pi/2) from the contact to the blade's edge
    -window; the release is the first sign change of the pressing sampled along it
    (SLIDE_SAMPLES, Illinois on the bracket); psi'' = -h'/h^3 on the face, its peak
    refined by golden section. No integration: closed form before integration."""
    compose, psi_of = model.compose, model.psi

    @njit(**INNER_OPTIONS)
    def face_pressing(psi, data):
        """side * G''_free on the face at psi: > 0 keeps the contact."""
        p, k, side = data
        tt, y = compose(0.0, 0.0, 1.0, psi, -1.0 / h_ratio(psi, k))
        return side * free_gap_acceleration(tt, y, p, k)

    @njit(**INNER_OPTIONS)
    def face_acceleration(psi, data):
        p, k, side = data
        hr = h_ratio(psi, k)
        return abs(h_slope(psi, k) / (hr * hr * hr))

    release_root = make_illinois(face_pressing)
    _, refine_face_peak = peak_search(face_acceleration)

    @njit(**INNER_OPTIONS)
    def slide(t, y, data, p, settings, refine):
        """Ride the face from the contact (zero normal speed) until released or off the
        blade's edge: (released, t, y, data, amplitude, peak, cost)."""
        lower, window, k, level, side = data
        fd = (p, k, side)
        psi_c = psi_of(y)
        end = -window
        released = False
        prev, f_prev = psi_c, face_pressing(psi_c, fd)
        for j in range(1, SLIDE_SAMPLES + 1):
            q = psi_c + (end - psi_c) * j / SLIDE_SAMPLES
            f = face_pressing(q, fd)
            if f <= 0.0:
                released = True
                # pressed where the contact was decided (pressed()), released by q
                end = q if f_prev <= 0.0 else release_root(fd, q, prev, f, f_prev, 1e-15)[0]
                break
            prev, f_prev = q, f
        peak = 0.0
        if refine:
            xs = np.linspace(end, psi_c, SLIDE_SAMPLES + 1)
            values = np.empty(xs.shape[0])
            for j in range(xs.shape[0]):
                values[j] = face_acceleration(xs[j], fd)
            peak = refine_face_peak(fd, xs, values, 1e-12 * (psi_c - end) + 1e-300)
        t_end = level - beta(end, k)
        t_end, y_end = compose(t_end, t_end, 1.0, end, -1.0 / h_ratio(end, k))
        return (released, t_end, y_end, after_slide(released, data),
                max(abs(psi_c), abs(end)), peak, NO_COST)

    return slide, _fixed_exit_tangent


def _constrained_slide(model, gap_change, methods):
    """The slide of a rotor of finite inertia: a flight of the constrained system (psi,
    psi') on the face G = level, the rotor angle phi1 = level - beta(psi) and speed -h psi';
    psi'' keeps G'' = 0 with the contact force along J = (1, h), until the pressing
    vanishes (release) or |psi| reaches the blade's edge. Returns the slide and its tangent
    (the variational equations of the constrained system, kernels/impact/tangent.py)."""
    compose, accelerations, response = model.compose, model.accelerations, model.response
    response_slope, psi_of, dpsi_of = model.response_slope, model.psi, model.dpsi
    rotor_speed = model.rotor_speed
    carry = make_event_carry(2)

    @njit(**INLINE_OPTIONS)
    def on_face(t, s, sp):
        p, level, k = sp
        psi, dpsi = s
        return compose(t, level - beta(psi, k), -h_ratio(psi, k) * dpsi, psi, dpsi)

    @njit(**INLINE_OPTIONS)
    def face_terms(t, s, sp):
        """On the face at s: the state y, h, the free accelerations, M^-1 J^T, the free
        G'' that the contact force cancels, and psi'' on the face."""
        p, level, k = sp
        psi, dpsi = s
        tt, y = on_face(t, s, sp)
        hr = h_ratio(psi, k)
        a_phi, a_psi = accelerations(tt, y, p)
        g2 = a_phi + hr * a_psi + h_slope(psi, k) * dpsi * dpsi
        x_phi, x_psi = response(y, 1.0, hr, p)
        return y, hr, a_psi, x_phi, x_psi, g2, a_psi - x_psi * g2 / (x_phi + hr * x_psi)

    @njit(**INNER_OPTIONS)
    def slide_state(t, s, sp):
        """(psi'' on the face, the free G'' that the contact force cancels)."""
        y, hr, a_psi, x_phi, x_psi, g2, acc = face_terms(t, s, sp)
        return acc, g2

    @njit(**INLINE_OPTIONS)
    def slide_rhs(s, sp):
        acc, g2 = slide_state(0.0, s, sp)
        return s[1], acc

    @njit(**INLINE_OPTIONS)
    def slide_values(t, s, data):
        sp, side, window = data
        acc, g2 = slide_state(t, s, sp)
        return side * g2, abs(s[0]) - window

    @njit(**INLINE_OPTIONS)
    def slide_rates(t, s, ds, data):
        return math.nan, math.copysign(1.0, s[0]) * ds[0]

    @njit(**INLINE_OPTIONS)
    def slide_on_event(e, t, s, f, data, p):
        return True, data

    @njit(**INLINE_OPTIONS)
    def slide_start(t, s, f, data, p):
        return 0.0, 0.0

    @njit(**INLINE_OPTIONS)
    def slide_monitor(t, s, f):
        return s[0], f[0], f[1]

    slide_flight, _ = make_flight(System(slide_rhs, relative_scales, slide_values,
                                         slide_rates, (-1, 1), slide_on_event, slide_start,
                                         slide_monitor, methods=methods))

    @njit(**INNER_OPTIONS)
    def slide(t, y, data, p, settings, refine):
        """As the kinematic slide, by integration."""
        lower, window, k, level, side = data
        sp = (p, level, k)
        psi = psi_of(y)
        s0 = (psi, -rotor_speed(y) / h_ratio(psi, k))
        fl = slide_flight(t, s0, sp, (sp, side, window), settings, refine)
        t_end, y_end = on_face(fl.t, fl.y, sp)
        released = fl.event == 0
        return (released, t_end, y_end, after_slide(released, data), fl.amplitude, fl.peak,
                fl.cost)

    @njit(**INNER_OPTIONS)
    def face_field(s, sp):
        """On the face at s = (psi, psi'): psi'' and its gradient in s, the free G'' (the
        pressing) and its gradient, by the chain rule through the face (phi1 = level -
        beta(psi), phi1' = -h psi'), the model's Jacobian and d(M^-1 J^T)/dpsi."""
        p, level, k = sp
        psi, v = s
        y, hr, a_psi, x_phi, x_psi, g2, acc = face_terms(0.0, s, sp)
        hs = h_slope(psi, k)
        # along the face: d/dpsi moves phi1 by -h and phi1' by -h' psi'; d/dpsi' moves
        # phi1' by -h
        g2_psi, dpsi_psi = gap_change(y, p, k, a_psi, (0.0, -hr, -hs * v, 1.0, 0.0))
        g2_v, dpsi_v = gap_change(y, p, k, a_psi, (0.0, 0.0, -hr, 0.0, 1.0))
        dx_phi, dx_psi = response_slope(y, 1.0, hr, 0.0, hs, p)
        jx = x_phi + hr * x_psi
        djx = dx_phi + hr * dx_psi + hs * x_psi
        acc_psi = dpsi_psi - (dx_psi * g2 + x_psi * g2_psi) / jx + x_psi * g2 * djx / (jx * jx)
        acc_v = dpsi_v - x_psi * g2_v / jx
        return acc, acc_psi, acc_v, g2, g2_psi, g2_v

    @njit(**INLINE_OPTIONS)
    def face_jacobian(s, sp):
        acc, acc_psi, acc_v, g2, g2_psi, g2_v = face_field(s, sp)
        return 0.0, 1.0, acc_psi, acc_v

    flow_derivative = make_variational(Field(slide_rhs, face_jacobian, relative_scales), 2,
                                       methods)

    @njit(**INNER_OPTIONS)
    def slide_tangent(tangent, d, t, y, data, t1, y1, data1, p, settings):
        """The columns through a slide from (t, y) just after the law to its end (t1, y1):
        onto the face (psi' = -phi1'/h), along the constrained flow by its variational
        equations, through the end event (the release where side G'' falls to 0, or the
        blade's edge, |psi| = window; after_slide's side 0 says which), off the face."""
        lower, window, k, level, side = data
        sp = (p, level, k)
        psi, w = psi_of(y), rotor_speed(y)
        h0, slope0 = h_ratio(psi, k), h_slope(psi, k)
        reached, m = flow_derivative(t, (psi, -w / h0), t1, sp, settings)
        if not reached:
            return False
        s1 = (psi_of(y1), dpsi_of(y1))
        f1 = slide_rhs(s1, sp)
        acc, acc_psi, acc_v, g2, g2_psi, g2_v = face_field(s1, sp)
        if data1[SIDE] != 0.0:
            e_psi, e_v = side * g2_psi, side * g2_v
        else:
            e_psi, e_v = math.copysign(1.0, s1[0]), 0.0
        e_dot = e_psi * f1[0] + e_v * f1[1]
        h1, slope1 = h_ratio(s1[0], k), h_slope(s1[0], k)
        for j in range(d):
            dpsi0 = tangent[DPSI, j]
            dv0 = -tangent[DW, j] / h0 + w * slope0 / (h0 * h0) * dpsi0
            (a, b), dt1 = carry(m, (dpsi0, dv0), tangent[DT, j], f1, (e_psi, e_v), e_dot)
            tangent[DT, j] = dt1
            tangent[DPHI, j] = -h1 * a
            tangent[DW, j] = -slope1 * s1[1] * a - h1 * b
            tangent[DPSI, j] = a
            tangent[DDPSI, j] = b
        return math.isfinite(e_dot) and e_dot != 0.0

    return slide, slide_tangent


#: rotor radians kept clear of a blade contact around each passage of psi = 0 when coasting,
#: beyond the passage's own reach and the step that holds the crossing (whose time is the
#: chord's zero, inside that step)
COAST_MARGIN = 0.01


def _swing_coast(model):
    """The coast of a driven pendulum's free flight past the blade (System.coast): at
    constant rotor speed the free swing is symmetric, so the state half a swing (tau1, the
    model's swing, in closed form) on is the same state negated, and a contact needs
    |psi| <= window, i.e. a time within t_w (the swing's bound) of a passage of psi = 0,
    at a rotor angle within beta(window) of a face. The passages ahead (every tau1 from
    the last, t_cross) are checked against the faces, and the time up to the spell of the
    first that could meet one (within its reach of a face, and not yet behind) is skipped,
    up to the flight's horizon: whole half swings, and where the flight is the model's
    closed form (``closed_form``) the rest too, by exact steps; the faces passed meanwhile
    move on as the events would have moved them. What stays is integrated as before: the
    spells around the passages near a face (and without the closed form, the time to the
    next spell that is less than a half swing) (docs/models.md §5.5)."""
    swing, psi_of, rhs = model.swing, model.psi, model.rhs
    has_exact = model.exact is not None
    exact, exact_length = (model.exact, model.exact_length) if has_exact else (None, None)

    @njit(**INNER_OPTIONS)
    def coast(t_cross, crossings, h, t, y, f, data, p, time_left, memo, closed_form):
        if crossings < 2:  # one whole swing flown first: its amplitude and peak are known
            return 0.0, t_cross, y, f, data, memo, 0
        lower, window, k, level, side = data
        tau1, t_window = memo
        if math.isnan(tau1):
            memo = swing(y, p, window)
        tau1, t_window = memo
        if not (tau1 > 0.0 and t_window < math.inf):
            return 0.0, t_cross, y, f, data, memo, 0
        # a passage this near a face may meet it (the crossing's time is the chord's zero,
        # inside a step of h), within this time of the passage
        reach = t_window + beta(window, k) + h + COAST_MARGIN
        spell = t_window + h + COAST_MARGIN
        clear = time_left  # the time from t that no contact can end
        for j in range(int((t + time_left - t_cross) / tau1) + 2):
            passage = t_cross + j * tau1
            if passage + spell < t:
                continue  # its spell is behind
            x = (passage - lower) % TWO_PI  # passage j against the faces
            if min(x, TWO_PI - x) <= reach:
                clear = passage - spell - t
                break
        if not clear > 0.0:
            return 0.0, t_cross, y, f, data, memo, 0
        halves = int(clear / tau1)
        if has_exact and closed_form:
            skip, rest = clear, clear - tau1 * halves
        elif halves > 0:
            skip, rest = tau1 * halves, 0.0
        else:
            return 0.0, t_cross, y, f, data, memo, 0
        y0, f0 = y, f
        if halves % 2 == 1:
            y, f = (-y[0], -y[1]), (-f[0], -f[1])
        steps = 0
        if has_exact and closed_form and rest > 0.0:
            while rest > 0.0:  # NaN ends it too
                length = min(rest, exact_length(y, p, EXACT_REACH))
                if not length > 0.0:  # a state the exact flow cannot move: no coast
                    return 0.0, t_cross, y0, f0, data, memo, 0
                y = exact(y, length, p)
                rest -= length
                steps += 1
            f = rhs(y, p)
        # the last passage at or before the landing (any within rounding of it is clear)
        t_cross += tau1 * math.floor((t + skip - t_cross) / tau1)
        passed = math.floor(((t - lower) + beta(psi_of(y), k) + skip) / TWO_PI)
        if passed > 0.0:
            lower += TWO_PI * passed
            level, side = lower, 1.0
        return skip, t_cross, y, f, (lower, window, k, level, side), memo, steps

    return coast


def blade_section_start(model):
    """``start(key, data, p) -> (t, y, data)``: the section contact (before its law) of a
    blade cycle from its key (psi, G', phi1'), on the face at lab angle 0 (G = 0), met
    rising where G' > 0 (SIDE +1), else falling."""
    compose = model.compose

    @njit(**INLINE_OPTIONS)
    def start(key, data, p):
        lower, window, k, level, side = data
        psi, rate, w = key[0], key[1], key[2]
        phi1 = 0.0 - beta(psi, k)
        t, y = compose(phi1, phi1, w, psi, (rate - w) / h_ratio(psi, k))
        return t, y, (lower, window, k, 0.0, 1.0 if rate > 0.0 else -1.0)

    return start


def lab_window(model, methods=OTHER_METHODS):
    """The lab-fixed blade composed with a model (see the module docstring); ``methods``:
    those compiled into its flights beside DOPRI5 (System)."""
    psi_of, dpsi_of, monitor = model.psi, model.dpsi, model.monitor
    compose, rotor_angle, rotor_speed = model.compose, model.rotor_angle, model.rotor_speed
    accelerations, response = model.accelerations, model.response
    starting_speed = model.starting_speed

    @njit(**INLINE_OPTIONS)
    def values(t, y, data):
        """G against each face, (phi1 - face) + beta: the rotor angle grows without bound,
        and (phi1 + beta) - face would lose the gap's last digits to its magnitude (a
        chatter bounce 1e-15 deep at phi1 = 30 was lost)."""
        lower, k = data[LOWER], data[K]
        phi1, b = rotor_angle(t, y), beta(psi_of(y), k)
        return (phi1 - (lower + TWO_PI)) + b, (phi1 - lower) + b, abs(psi_of(y)) - math.pi

    @njit(**INLINE_OPTIONS)
    def rates(t, y, dy, data):
        k = data[K]
        psi, dpsi = psi_of(y), monitor(t, y, dy)[1]
        g_rate = rotor_speed(y) + h_ratio(psi, k) * dpsi
        return g_rate, g_rate, math.copysign(1.0, psi) * dpsi

    @njit(**INLINE_OPTIONS)
    def on_event(e, t, y, f, data, p):
        lower, window, k = data[LOWER], data[WINDOW], data[K]
        if e == 2:
            return True, data  # escape
        level = lower + TWO_PI if e == 0 else lower
        side = 1.0 if e == 0 else -1.0
        if abs(psi_of(y)) <= window:
            return True, (lower, window, k, level, side)
        # inside the blade's reach: passed, the faces move on
        return False, (level if e == 0 else lower - TWO_PI, window, k, level, side)

    @njit(**INNER_OPTIONS)
    def free_gap_acceleration(t, y, p, k):
        """G'' of the free motion: phi1'' + h psi'' + h' psi'^2."""
        a_phi, a_psi = accelerations(t, y, p)
        psi, dpsi = psi_of(y), dpsi_of(y)
        return a_phi + h_ratio(psi, k) * a_psi + h_slope(psi, k) * dpsi * dpsi

    @njit(**INLINE_OPTIONS)
    def start_gap(t, y, f, data, p):
        k = data[K]
        g_rate = rotor_speed(y) + h_ratio(psi_of(y), k) * dpsi_of(y)
        return g_rate, free_gap_acceleration(t, y, p, k)

    speed_bound = model.speed_bound

    @njit(**INLINE_OPTIONS)
    def clear_time(y, values_now, data, p):
        """No event within this time (System.clear_time), nor a zero of psi (the coast
        takes the step that holds one as the bound of its time, _swing_coast): each face's
        gap G moves at |G'| = |phi1' + h psi'| <= |phi1'| + max|h| max|psi'|, psi and the
        escape's |psi| - pi at |psi'| <= max|psi'| (the model's speed_bound); h is
        monotonic in cos psi, so max|h| is its value at psi = 0 or pi, 1/|1 - k| (1/2 at
        k = 1)."""
        k = data[K]
        g0, g1, g2 = values_now  # values(t, y, data): the flight has them at hand
        speed = speed_bound(y, p)
        h_max = max(1.0 / (1.0 + k), 1.0 / abs(1.0 - k) if k != 1.0 else 0.5)
        face = min(abs(g0), abs(g1)) / (abs(rotor_speed(y)) + h_max * speed)
        return min(face, min(abs(g2), abs(psi_of(y))) / speed) if speed > 0.0 else face

    free_flight, _ = make_flight(System(model.rhs, model.scales, values, rates, (1, -1, 1),
                                        on_event, start_gap, monitor,
                                        _swing_coast(model) if model.driven else no_coast,
                                        model.exact, model.exact_length, methods,
                                        clear_time if speed_bound is not None else None))
    shift = model.shift

    @njit(**INNER_OPTIONS)
    def flight(t, y, p, data, settings, refine):
        """The free flight with the rotor angle measured from the last contact's face: it
        grows without bound, and a chatter bounce 1e-15 deep is below the rounding of a
        rotor angle of 30 (the time, at constant speed). A contact ends exactly on its
        face."""
        lower, window, k, level, side = data
        t_rel, y_rel = shift(t, y, -level)
        fl = free_flight(t_rel, y_rel, p, (lower - level, window, k, 0.0, side), settings,
                         refine)
        t_end, y_end = shift(fl.t, fl.y, level)
        lower2, window2, k2, level2, side2 = fl.data
        level2 += level
        if fl.outcome == FLIGHT_EVENT and fl.event < 2:
            # exactly on the face: psi from the rotor angle, whose rounding grows with it
            phi1, psi = rotor_angle(t_end, y_end), psi_of(y_end)
            t_end, y_end = compose(t_end, phi1, rotor_speed(y_end),
                                   face_psi(level2 - phi1, psi, k), dpsi_of(y_end))
        return Flight(fl.outcome, fl.event, t_end, y_end, fl.f,
                      (lower2 + level, window2, k2, level2, side2), fl.amplitude, fl.peak,
                      fl.cost)

    gap_change = _gap_acceleration_change(model)
    if model.driven:
        slide, slide_tangent = _kinematic_slide(model, free_gap_acceleration)
    else:
        slide, slide_tangent = _constrained_slide(model, gap_change, methods)

    @njit(**INLINE_OPTIONS)
    def first(p, data, start):
        """Start 0: at rest relative to the rotor on the blade's working face (met rising):
        the first impact at once, as on the rotor stop. Start j: on that face at psi =
        window (2 x_j - 1), closing at G' = 2 x'_j phi1' (Halton points in bases 3 and 2)."""
        lower, window, k, level, side = data
        t0, y0 = compose(0.0, 0.0, starting_speed(p), 0.0, 0.0)
        w = rotor_speed(y0)
        psi, dpsi = 0.0, 0.0
        if start > 0:
            psi = window * (2.0 * radical_inverse(start, int(3)) - 1.0)
            dpsi = (2.0 * radical_inverse(start, int(2)) - 1.0) * w / h_ratio(psi, k)
        phi1 = 0.0 - beta(psi, k)  # 0.0, not -0.0, at rest
        t, y = compose(phi1, phi1, w, psi, dpsi)
        return t, y, (lower, window, k, 0.0, 1.0)

    @njit(**INLINE_OPTIONS)
    def key(t, y, data, p):
        k = data[K]
        return (psi_of(y), rotor_speed(y) + h_ratio(psi_of(y), k) * dpsi_of(y),
                rotor_speed(y))

    @njit(**INLINE_OPTIONS)
    def from_key(key, t, y, data, p):
        return t, y

    @njit(**INLINE_OPTIONS)
    def jacobian(t, y, data):
        return 1.0, h_ratio(psi_of(y), data[K])

    @njit(**INLINE_OPTIONS)
    def normal_speed(t, y, data, p):
        """G' towards the face (> 0: closing) of the last contact."""
        k, side = data[K], data[SIDE]
        return side * (rotor_speed(y) + h_ratio(psi_of(y), k) * dpsi_of(y))

    @njit(**INLINE_OPTIONS)
    def striker_speed(t, y, data, p):
        """The contact point's normal speed rho |G'| in omega1 l_contact units."""
        k = data[K]
        psi = psi_of(y)
        return (math.sqrt(k * k + 1.0 + 2.0 * k * math.cos(psi))
                * abs(rotor_speed(y) + h_ratio(psi, k) * dpsi_of(y)))

    @njit(**INLINE_OPTIONS)
    def normal_acceleration(t, y, data, p):
        return abs(free_gap_acceleration(t, y, p, data[K]))

    @njit(**INLINE_OPTIONS)
    def gap_rate_after(t, y, data, p):
        return -1.0  # Newton's law on G' always reverses (or zeroes) the approach

    @njit(**INLINE_OPTIONS)
    def pressing(t, y, data, p):
        """The free G'' into the face of the last contact, with zero normal speed."""
        k, side = data[K], data[SIDE]
        psi = psi_of(y)
        tt, on = compose(t, rotor_angle(t, y), rotor_speed(y), psi,
                         -rotor_speed(y) / h_ratio(psi, k))
        return side * free_gap_acceleration(tt, on, p, k)

    @njit(**INLINE_OPTIONS)
    def pressed(t, y, data, p):
        """Does a contact with zero normal speed start a slide? The pressing at the contact,
        or, where it vanishes (at psi = 0 both h' and psi'' vanish: a degenerate touch),
        just along the slide, where psi has fallen."""
        now = pressing(t, y, data, p)
        if abs(now) > 1e-9:
            return now > 0.0
        k = data[K]
        psi = psi_of(y) - 1e-6
        tt, y2 = compose(t, data[LEVEL] - beta(psi, k), rotor_speed(y), psi, dpsi_of(y))
        return pressing(tt, y2, data, p) > 0.0

    @njit(**INLINE_OPTIONS)
    def settle(t, y, data, p, dt):
        """The chatter's accumulation point, dt later (the ballistic tail, H6, P-O14): the
        rotor turned on by its speed times dt, psi on the face, no normal speed."""
        k, level = data[K], data[LEVEL]
        w = rotor_speed(y)
        phi1 = rotor_angle(t, y) + w * dt
        psi = face_psi(level - phi1, psi_of(y), k)
        return compose(t + dt, phi1, w, psi, -w / h_ratio(psi, k))

    @njit(**INNER_OPTIONS)
    def accumulation_tangent(tangent, d, t, y, data, p, r):
        """The columns from a contact (t, y) whose chatter accumulates to its accumulation
        point (``settle`` after the tail 2 R |v_n|/(|G''| (1 - R)), the contact's own
        formula), which it returns: the tail's time moves with the approach speed and
        the free G'' (the model's Jacobian), the rotor turns on at its speed, psi follows
        the face, the normal speed is zero."""
        k, side = data[K], data[SIDE]
        g = free_gap_acceleration(t, y, p, k)
        if not abs(g) > 0.0:
            return True, t, y  # no accumulation point: the law acts at the contact
        psi, v, w = psi_of(y), dpsi_of(y), rotor_speed(y)
        hr, hs = h_ratio(psi, k), h_slope(psi, k)
        a_psi = accelerations(t, y, p)[1]
        approach = side * (w + hr * v)
        tail = 2.0 * r * abs(approach) / (abs(g) * (1.0 - r))
        t1, y1 = settle(t, y, data, p, tail)
        h1 = h_ratio(psi_of(y1), k)
        slope1 = h_slope(psi_of(y1), k)
        for j in range(d):
            c = (tangent[DT, j], tangent[DPHI, j], tangent[DW, j], tangent[DPSI, j],
                 tangent[DDPSI, j])
            d_approach = side * (c[DW] + hr * c[DDPSI] + hs * v * c[DPSI])
            dg = gap_change(y, p, k, a_psi, c)[0]
            d_tail = 2.0 * r / (1.0 - r) * (math.copysign(1.0, approach) * d_approach / abs(g)
                                            - abs(approach) * math.copysign(1.0, g) * dg
                                            / (g * g))
            dphi = c[DPHI] + c[DW] * tail + w * d_tail
            dpsi = -dphi / h1
            tangent[DT, j] = c[DT] + d_tail
            tangent[DPHI, j] = dphi
            tangent[DPSI, j] = dpsi
            tangent[DDPSI, j] = -c[DW] / h1 + w * slope1 / (h1 * h1) * dpsi
        return True, t1, y1

    @njit(**INLINE_OPTIONS)
    def flight_data(data):
        """The faces around the striker after a contact: behind it if it bounced off the
        face it met rising, ahead if falling; past the face after sliding off its edge."""
        lower, window, k, level, side = data
        new_lower = level - TWO_PI if side > 0.0 else level
        return new_lower, window, k, level, side

    @njit(**INLINE_OPTIONS)
    def event_gradient(t, y, data):
        """g = phi1 + beta(psi) - face: (1, h, 0)."""
        return 1.0, h_ratio(psi_of(y), data[K]), 0.0

    @njit(**INLINE_OPTIONS)
    def jacobian_slope(t, y, data):
        return 0.0, h_slope(psi_of(y), data[K])

    @njit(**INLINE_OPTIONS)
    def edge_distance(t, y, data):
        """How far inside the blade's reach a contact is: window - |psi| [rad]."""
        return data[WINDOW] - abs(psi_of(y))

    return Contact(model=model, flight=flight, slide=slide, first=first, key=key,
                   from_key=from_key, jacobian=jacobian, normal_speed=normal_speed,
                   striker_speed=striker_speed, normal_acceleration=normal_acceleration,
                   gap_rate_after=gap_rate_after, pressed=pressed, settle=settle,
                   escapes_before=never, flight_data=flight_data, escape_event=2,
                   min_flight=SECTION_MIN_FLIGHT, horizon=LAB_HORIZON, smooth=False,
                   event_gradient=event_gradient, jacobian_slope=jacobian_slope,
                   slide_tangent=slide_tangent, accumulation_tangent=accumulation_tangent,
                   edge_distance=edge_distance)

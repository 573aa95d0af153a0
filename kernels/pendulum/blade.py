"""The lab-fixed blade (lab_window, docs/models.md §5.5, H11), composed with a model into a
``Contact`` (see tools.py): the contact point is at radius rho = sqrt(X), X = k^2 + 1 +
2k cos psi, and at the polar angle G = phi1 + beta(psi), beta = atan2(sin psi, k + cos psi);
the blade is radial at lab angle 0 (mod 2 pi) and reaches in down to the striker's radius
at |psi| = window. The gap is G against the blade's faces at G = lower and lower + 2 pi; a
face met with |psi| > window is passed (the striker goes inside the blade). Newton's law
acts on the normal speed rho G', G' = phi1' + h psi', h = dbeta/dpsi (J = (1, h)); the
geometry is in blade_geometry.py. After a plastic contact (R = 0, or an accumulated chatter)
the striker slides along the face while pressed into it (blade_slide.py). Escape: |psi|
rising through pi. Data: (lower, window, k, level, side), the last contact's face level and
side (+1: met rising, -1: falling, 0: slid off the edge) (blade_geometry.LOWER ... SIDE).
"""

import math

from numba import njit

from kernels import INNER_OPTIONS, INLINE_OPTIONS
from kernels.impact import Contact, System, no_coast
from kernels.impact.flight import EXACT_REACH, Flight, make_flight
from kernels.impact.attractors import radical_inverse
from kernels.impact.outcomes import FLIGHT_EVENT
from kernels.impact.runge_kutta import OTHER_METHODS
from kernels.impact.tangent import DDPSI, DPHI, DPSI, DT, DW

from kernels.pendulum.blade_geometry import (K, LEVEL, LOWER, SIDE, WINDOW, beta, face_psi,
                                             h_ratio, h_slope)
from kernels.pendulum.blade_slide import (constrained_slide, gap_acceleration_change,
                                          kinematic_slide)
from kernels.pendulum.tools import TWO_PI, never

SECTION_MIN_FLIGHT = 0.1  # blade: an impact after a shorter flight continues an episode
LAB_HORIZON = 200.0 * math.pi  # rotor radians without a contact: regime no_impact

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

    gap_change = gap_acceleration_change(model)
    if model.driven:
        slide, slide_tangent = kinematic_slide(model, free_gap_acceleration)
    else:
        slide, slide_tangent = constrained_slide(model, gap_change, methods)

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

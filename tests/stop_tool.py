"""A tool defined outside the package: a stop fixed on the rotor at psi = psi_s, met when the
pendulum swings up to it, with Newton's law on the relative speed (psi'+ = -R psi'-).

It is the test problem of the hard cases H3 (a grazing contact), H4 (a bounce shorter than a
step) and H6 (a chatter accumulating in finite time), for any of the three models, and the
worked example of docs/impact_core.md: a tool is a ``Contact`` built from a model's functions
and the core's factories, and adding one touches neither the core nor the models. This one
flies as the rotor stop does (its flight, at the stop's own angle) and brings its own
impact law. (The
rotor stop of the mechanism sits at psi = 0, the pendulum's own equilibrium, where the
restoring acceleration vanishes: a contact there is never tangential and a bounce never
returns, so these cases live on this stop.)

Data: (psi_s,). Events: 0 the stop (psi rising through psi_s), 1 escape (psi falling
through -pi). A contact that ends a chatter, or a plastic one, sticks to the stop for good
(the slide returns at once, not released).
"""

import math

from numba import njit

from kernels import INLINE_OPTIONS
from kernels.impact import Contact, System
from kernels.impact.flight import make_flight
from kernels.impact.attractors import radical_inverse
from kernels.impact.outcomes import NO_COST
from kernels.pendulum.tools import never, no_edge, no_slope, stop_flight


@njit(**INLINE_OPTIONS)
def same(data):
    return data


@njit(**INLINE_OPTIONS)
def no_accumulation_tangent(tangent, d, t, y, data, p, r):
    return False, t, y


def relative_stop(model):
    """The stop composed with a model (kernels/pendulum/models.py)."""
    psi_of, dpsi_of, compose = model.psi, model.dpsi, model.compose
    rotor_angle, rotor_speed, accelerations = (model.rotor_angle, model.rotor_speed,
                                               model.accelerations)

    flight = stop_flight(model)  # the rotor stop's flight, at the stop's own angle

    @njit(**INLINE_OPTIONS)
    def first(p, data, start):
        t, y = compose(0.0, 0.0, 1.0, data[0], 0.0)
        return t, y, data

    @njit(**INLINE_OPTIONS)
    def key(t, y, data, p):
        return psi_of(y), dpsi_of(y)

    @njit(**INLINE_OPTIONS)
    def from_key(x, t, y, data, p):
        return t, y

    @njit(**INLINE_OPTIONS)
    def jacobian(t, y, data):
        return 0.0, 1.0  # the relative speed: the stop turns with the rotor

    @njit(**INLINE_OPTIONS)
    def normal_speed(t, y, data, p):
        return dpsi_of(y)

    @njit(**INLINE_OPTIONS)
    def normal_acceleration(t, y, data, p):
        return abs(accelerations(t, y, p)[1])

    @njit(**INLINE_OPTIONS)
    def gap_rate_after(t, y, data, p):
        return dpsi_of(y)

    @njit(**INLINE_OPTIONS)
    def pressed(t, y, data, p):
        return accelerations(t, y, p)[1] > 0.0

    @njit(**INLINE_OPTIONS)
    def settle(t, y, data, p, dt):
        """The chatter's accumulation point dt later: on the stop, at rest on it."""
        w = rotor_speed(y)
        return compose(t + dt, rotor_angle(t, y) + w * dt, w, data[0], 0.0)

    @njit(**INLINE_OPTIONS)
    def stick(t, y, data, p, settings, refine):
        return False, t, y, data, abs(psi_of(y)), 0.0, NO_COST

    @njit(**INLINE_OPTIONS)
    def event_gradient(t, y, data):
        return 0.0, 1.0, 0.0  # g = psi - psi_s

    @njit(**INLINE_OPTIONS)
    def no_slide_tangent(tangent, d, t, y, data, t1, y1, data1, p, settings):
        return False  # the test tool's stick carries no tangent (its multiplier is NaN)

    return Contact(model=model, flight=flight, slide=stick, first=first, key=key,
                   from_key=from_key, jacobian=jacobian, normal_speed=normal_speed,
                   striker_speed=normal_speed, normal_acceleration=normal_acceleration,
                   gap_rate_after=gap_rate_after, pressed=pressed, settle=settle,
                   escapes_before=never, flight_data=same, escape_event=1, min_flight=0.0,
                   horizon=1e3, smooth=False, event_gradient=event_gradient,
                   jacobian_slope=no_slope, slide_tangent=no_slide_tangent,
                   accumulation_tangent=no_accumulation_tangent, edge_distance=no_edge)


def mirrored_stop(model):
    """The rotor stop met from the other side: a stop on the rotor at psi = 0 that the
    pendulum swings down onto (psi falling through 0), with the rotor stop's law mirrored
    (J = (1 + k, -1): the normal speed (1 + k) phi1' - psi'). For a model at constant rotor
    speed, whose equation is odd in psi, every flight and contact is the rotor stop's
    mirror image (psi -> -psi), so its steady state is the rotor stop's: the toy impact
    surface of tests/test_pendulum_table.py, built through the table of systems. Data:
    (0, k), as the rotor stop's. Events: 0 the stop, 1 escape (psi rising through pi)."""
    psi_of, dpsi_of, compose = model.psi, model.dpsi, model.compose
    rotor_angle, rotor_speed, monitor = model.rotor_angle, model.rotor_speed, model.monitor
    critical_speed, accelerations = model.critical_speed, model.accelerations

    @njit(**INLINE_OPTIONS)
    def values(t, y, data):
        return -psi_of(y), math.pi - psi_of(y)

    @njit(**INLINE_OPTIONS)
    def rates(t, y, dy, data):
        rate = monitor(t, y, dy)[1]
        return -rate, -rate

    @njit(**INLINE_OPTIONS)
    def on_event(e, t, y, f, data, p):
        return True, data

    @njit(**INLINE_OPTIONS)
    def start_gap(t, y, f, data, p):
        angle, rate, accel = monitor(t, y, f)
        return -rate, -accel

    flight = make_flight(System(model.rhs, model.scales, values, rates, (1, -1), on_event,
                                start_gap, monitor))[0]

    @njit(**INLINE_OPTIONS)
    def first(p, data, start):
        """Start 0: at rest on the stop; start j: arriving with psi' = -2 (1 + k) x_j."""
        speed = 2.0 * (1.0 + data[1]) * radical_inverse(start, int(2))
        t, y = compose(0.0, 0.0, p[-1], 0.0, -speed)
        return t, y, data

    @njit(**INLINE_OPTIONS)
    def key(t, y, data, p):
        return rotor_speed(y), -dpsi_of(y)

    @njit(**INLINE_OPTIONS)
    def from_key(x, t, y, data, p):
        return compose(t, rotor_angle(t, y), x[0], 0.0, -x[1])

    @njit(**INLINE_OPTIONS)
    def jacobian(t, y, data):
        return 1.0 + data[1], -1.0

    @njit(**INLINE_OPTIONS)
    def normal_speed(t, y, data, p):
        return (1.0 + data[1]) * rotor_speed(y) - dpsi_of(y)

    @njit(**INLINE_OPTIONS)
    def normal_acceleration(t, y, data, p):
        return abs(accelerations(t, y, p)[1])

    @njit(**INLINE_OPTIONS)
    def gap_rate_after(t, y, data, p):
        return -dpsi_of(y)  # the pendulum must leave the stop upwards

    @njit(**INLINE_OPTIONS)
    def in_place(t, y, data, p, dt):
        return t, y

    @njit(**INLINE_OPTIONS)
    def no_slide(t, y, data, p, settings, refine):
        return True, t, y, data, 0.0, 0.0, NO_COST

    @njit(**INLINE_OPTIONS)
    def escapes_before(t, y, data, p):
        return dpsi_of(y) >= critical_speed(p)

    @njit(**INLINE_OPTIONS)
    def event_gradient(t, y, data):
        return 0.0, -1.0, 0.0  # g = -psi

    @njit(**INLINE_OPTIONS)
    def no_slide_tangent(tangent, d, t, y, data, t1, y1, data1, p, settings):
        return True

    return Contact(model=model, flight=flight, slide=no_slide, first=first, key=key,
                   from_key=from_key, jacobian=jacobian, normal_speed=normal_speed,
                   striker_speed=normal_speed, normal_acceleration=normal_acceleration,
                   gap_rate_after=gap_rate_after, pressed=never, settle=in_place,
                   escapes_before=escapes_before, flight_data=same, escape_event=1,
                   min_flight=0.0, horizon=math.inf, smooth=True,
                   event_gradient=event_gradient, jacobian_slope=no_slope,
                   slide_tangent=no_slide_tangent,
                   accumulation_tangent=no_accumulation_tangent, edge_distance=no_edge)

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
from kernels.impact import Contact
from kernels.impact.outcomes import NO_COST
from kernels.pendulum.tools import stop_flight


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
    def never(t, y, data, p):
        return False

    @njit(**INLINE_OPTIONS)
    def same(data):
        return data

    @njit(**INLINE_OPTIONS)
    def event_gradient(t, y, data):
        return 0.0, 1.0, 0.0  # g = psi - psi_s

    @njit(**INLINE_OPTIONS)
    def no_slope(t, y, data):
        return 0.0, 0.0

    @njit(**INLINE_OPTIONS)
    def no_edge(t, y, data):
        return math.inf

    @njit(**INLINE_OPTIONS)
    def no_slide_tangent(tangent, d, t, y, data, t1, y1, data1, p, settings):
        return False  # the test tool's stick carries no tangent (its multiplier is NaN)

    @njit(**INLINE_OPTIONS)
    def no_accumulation_tangent(tangent, d, t, y, data, p, r):
        return False, t, y

    return Contact(model, flight, stick, first, key, from_key, jacobian, normal_speed,
                   normal_speed, normal_acceleration, gap_rate_after, pressed, settle, never,
                   same, 1, 0.0, 1e3, False, event_gradient, no_slope, no_slide_tangent,
                   no_accumulation_tangent, no_edge)

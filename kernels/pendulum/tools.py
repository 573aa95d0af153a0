"""What the rotary pendulum strikes: the tools, each a gap function, an impact law and (where
the striker can ride the tool) a slide, composed with a model (kernels/pendulum/models.py)
into a ``Contact``: the flight of the integration core plus what the impact map needs at a
contact. Here the rotor stop and what every tool shares; the lab-fixed blade in blade.py.

rotor_stop (the paper's): the striker meets the tool when psi reaches 0 from below (a stop on
the rotor); Newton's law acts on the striker's normal speed in the lab, (1 + k) phi1' + psi'
in omega1 l_contact units (contact Jacobian J = (1 + k, 1) on (phi1', psi')), with phi1' the
rotor speed: at constant rotor speed psi'+ = -(1 + k)(1 + R) - R psi'- (the paper's law (5)).
Escape: psi falling through -pi (the pendulum goes over the top). Data: (level, k), the
stop's angle and k (STOP_LEVEL, STOP_K).
"""


import math

from numba import njit

from kernels import INLINE_OPTIONS
from kernels.impact import Contact, System
from kernels.impact.attractors import radical_inverse
from kernels.impact.flight import make_flight
from kernels.impact.outcomes import NO_COST
from kernels.impact.runge_kutta import OTHER_METHODS

TWO_PI = 2.0 * math.pi
#: the rotor stop's data (level, k): the stop's angle and k
STOP_LEVEL, STOP_K = range(2)
@njit(**INLINE_OPTIONS)
def never(t, y, data, p):
    return False


@njit(**INLINE_OPTIONS)
def no_slope(t, y, data):
    return 0.0, 0.0  # a contact Jacobian that does not change with psi


@njit(**INLINE_OPTIONS)
def no_edge(t, y, data):
    return math.inf


@njit(**INLINE_OPTIONS)
def _no_slide_tangent(tangent, d, t, y, data, t1, y1, data1, p, settings):
    return True  # the tool has no slide


@njit(**INLINE_OPTIONS)
def _settle_in_place(tangent, d, t, y, data, p, r):
    return True, t, y  # the accumulated law acts where the contact is


def stop_section_start(model):
    """``start(key, data, p) -> (t, y, data)``: the section contact (before its law) of a
    rotor-stop cycle from its key, (phi1', psi') at psi = 0, the rotor angle at 0."""
    compose = model.compose

    @njit(**INLINE_OPTIONS)
    def start(key, data, p):
        t, y = compose(0.0, 0.0, key[0], 0.0, key[1])
        return t, y, data

    return start


def stop_flight(model, methods=OTHER_METHODS):
    """The free flight of a pendulum below a stop fixed on the rotor at psi = data[STOP_LEVEL]:
    events 0, the stop (psi rising through it), and 1, escape (psi falling through -pi);
    ``methods``: those compiled in beside DOPRI5 (System)."""
    psi_of, monitor = model.psi, model.monitor

    @njit(**INLINE_OPTIONS)
    def values(t, y, data):
        return psi_of(y) - data[STOP_LEVEL], psi_of(y) + math.pi

    @njit(**INLINE_OPTIONS)
    def rates(t, y, dy, data):
        rate = monitor(t, y, dy)[1]
        return rate, rate

    @njit(**INLINE_OPTIONS)
    def on_event(e, t, y, f, data, p):
        return True, data

    @njit(**INLINE_OPTIONS)
    def start_gap(t, y, f, data, p):
        angle, rate, accel = monitor(t, y, f)
        return rate, accel

    return make_flight(System(model.rhs, model.scales, values, rates, (1, -1), on_event,
                              start_gap, monitor, methods=methods))[0]


def rotor_stop(model, methods=OTHER_METHODS):
    """The rotor stop composed with a model (see the module docstring); ``methods``: those
    compiled into its flights beside DOPRI5 (System)."""
    psi_of, dpsi_of = model.psi, model.dpsi
    critical_speed, accelerations = model.critical_speed, model.accelerations
    compose, rotor_angle, rotor_speed = model.compose, model.rotor_angle, model.rotor_speed
    starting_speed = model.starting_speed
    flight = stop_flight(model, methods)

    @njit(**INLINE_OPTIONS)
    def first(p, data, start):
        """Start 0: at rest on the stop, the rotor at its starting speed: the first impact
        at once. Start j: arriving at the stop with psi' = 2 (1 + k) x_j (Halton point in
        base 2; the steady arrival speed at R = 0 is 1 + k)."""
        speed = 2.0 * (1.0 + data[STOP_K]) * radical_inverse(start, int(2))
        t, y = compose(0.0, 0.0, starting_speed(p), 0.0, speed)
        return t, y, data

    @njit(**INLINE_OPTIONS)
    def key(t, y, data, p):
        return rotor_speed(y), dpsi_of(y)

    @njit(**INLINE_OPTIONS)
    def from_key(key, t, y, data, p):
        """The pre-impact state with this key, at the rotor angle of (t, y)."""
        return compose(t, rotor_angle(t, y), key[0], 0.0, key[1])

    @njit(**INLINE_OPTIONS)
    def jacobian(t, y, data):
        return 1.0 + data[STOP_K], 1.0

    @njit(**INLINE_OPTIONS)
    def normal_speed(t, y, data, p):
        return (1.0 + data[STOP_K]) * rotor_speed(y) + dpsi_of(y)

    @njit(**INLINE_OPTIONS)
    def normal_acceleration(t, y, data, p):
        return abs(accelerations(t, y, p)[1])

    @njit(**INLINE_OPTIONS)
    def gap_rate_after(t, y, data, p):
        """psi' after the impact: the pendulum must leave the stop (psi' < 0); a light rotor
        thrown back by the impact leaves it at rest or pushes it on (degenerate)."""
        return dpsi_of(y)

    @njit(**INLINE_OPTIONS)
    def settle(t, y, data, p, dt):
        return t, y

    @njit(**INLINE_OPTIONS)
    def no_slide(t, y, data, p, settings, refine):
        return True, t, y, data, 0.0, 0.0, NO_COST

    @njit(**INLINE_OPTIONS)
    def flight_data(data):
        return data

    @njit(**INLINE_OPTIONS)
    def escapes_before(t, y, data, p):
        """A driven pendulum launched from the stop faster than its critical speed goes
        over the top: decided in closed form, not by a horizon (H1, H2, H12)."""
        return -dpsi_of(y) >= critical_speed(p)

    @njit(**INLINE_OPTIONS)
    def event_gradient(t, y, data):
        return 0.0, 1.0, 0.0  # g = psi - stop

    return Contact(model=model, flight=flight, slide=no_slide, first=first, key=key,
                   from_key=from_key, jacobian=jacobian, normal_speed=normal_speed,
                   striker_speed=normal_speed, normal_acceleration=normal_acceleration,
                   gap_rate_after=gap_rate_after, pressed=never, settle=settle,
                   escapes_before=escapes_before, flight_data=flight_data, escape_event=1,
                   min_flight=0.0, horizon=math.inf, smooth=True,
                   event_gradient=event_gradient, jacobian_slope=no_slope,
                   slide_tangent=_no_slide_tangent, accumulation_tangent=_settle_in_place,
                   edge_distance=no_edge)

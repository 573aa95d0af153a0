"""The integration core: flights between impacts and the impact map, for any system.

It knows nothing about pendulums. A mechanism describes itself as a ``System`` (what flies)
and an impact law (what happens at a contact); the core is specialised to it by factories
(numba functions closing over the system's functions, so numba's cache keys them).

The contract:

1. A state is a tuple of floats of the system's own size; ``rhs(y, p)`` returns its
   derivative, ``scales(y0, y1, rtol, atol)`` the error scale of each component.
2. Steps are explicit Runge-Kutta: DOPRI5 (embedded error, PI step control, dense cubic
   Hermite output) or classical RK4 at a fixed step (runge_kutta.py). A partial step of
   length s from a step's start is the state at t + s to the method's order: events, turning
   points and peaks are polished on those, never on the interpolant alone.
3. The first step after a restart on a surface is capped by the ballistic return time of
   the gap the flight leaves (``start_gap``), so a short bounce is not stepped over (H4).
4. Events are the zero crossings, each in one direction, of ``event_values(t, y, data)``;
   ``event_rates(t, y, dy, data)`` are their time derivatives. They are found on the
   interpolant (chord bound, sign samples, an extremum check for grazing whose value is
   taken on an exact partial step, Illinois), polished by Newton on exact partial steps,
   never at the restart point, never from a step that starts beyond the level (events.py).
5. ``on_event(e, t, y, f, data, p) -> (terminal, data)``: a terminal event ends the flight;
   another (a pass by the tool) updates the system data and the flight goes on.
6. ``monitor(t, y, f) -> (angle, rate, acceleration)``: the quantity whose amplitude and
   peak acceleration a flight reports (turning points and peaks polished with ``refine``).
   Where the free motion is periodic, the system's ``coast`` may skip time that no event
   can end (half periods, and where the flight is the exact flow's, the rest by it), from
   the second zero crossing of the monitored angle on (the amplitude and peak are then
   those of one whole swing already flown).
7. A flight ends in one of outcomes.FLIGHT_*, with its cost as a Counters record
   (accepted and rejected steps, events). A step whose error estimate is not finite is
   rejected; an RK4 step (no estimate) into a state that is not finite ends the flight.
8. The impact map (impact_map.py) alternates contacts and flights on a mechanism with two
   generalised coordinates, a carrier (a rotor, possibly driven at constant speed) and a
   body: Newton's law on the normal speed through the body's impulse response, the
   accumulation of a chatter sequence (Zeno) into sticking or sliding, the tool's slide,
   escape, a budget of impacts, period classification on section states, and Aitken's
   extrapolation where the map is smooth.
"""

import math
from collections import namedtuple

from numba import njit

from kernels import INLINE_OPTIONS
from kernels.impact.runge_kutta import OTHER_METHODS


@njit(**INLINE_OPTIONS)
def no_coast(t_cross, crossings, h, t, y, f, data, p, time_left, memo, closed_form):
    return 0.0, t_cross, y, f, data, memo, 0


#: what flies: the vector field, error scales, events (values, rates, directions, what each
#: does), the start gap for the first-step cap, the monitored quantity, and where the free
#: motion is periodic between events, a coast past the time that no event can end
#: (``coast(t_cross, crossings, h, t, y, f, data, p, time_left, memo, closed_form) ->
#: (skip, t_cross, y, f, data, memo, steps)``, called after every step from the monitored
#: angle's second zero crossing on, the last crossing's time estimated as t_cross within
#: the step h that held it, the crossings counted from the flight's start; skip: the time
#: added to t, and t_cross, y and f at its end; memo: two floats the coast keeps between
#: calls of one flight, NaN at its start; closed_form: whether the flight is the exact
#: flow's; steps: the exact steps it took, counted with the flight's); where the flow is
#: known in closed form, ``exact(y, h, p)`` and ``exact_length(y, p, length)``, its step
#: for runge_kutta.METHOD_EXACT; ``methods``: those compiled into its flights beside DOPRI5
#: (runge_kutta.make_stepper; a pendulum block made without DOP853 solves by DOPRI5 where it
#: is asked for, systems.make_block); ``clear_time(y, values_now, data, p)``: a time within
#: which no event can fire from the state y, whose event values are ``values_now`` (a lower
#: bound, from bounds on the events' rates), up to which an exact flight that refines
#: nothing steps past exact_length
System = namedtuple("System", ["rhs", "scales", "event_values", "event_rates", "directions",
                               "on_event", "start_gap", "monitor", "coast", "exact",
                               "exact_length", "methods", "clear_time"],
                    defaults=(no_coast, None, None, OTHER_METHODS, None))

#: what happens at a contact, for the impact map (impact_map.py). ``model``: the flying
#: body's functions the map needs (namedtuple fields response(y, J_phi, J_psi, p) = M^-1 J^T
#: on the (rotor, body) velocities, compose(t, phi, w, psi, dpsi) -> (t, y), and the
#: accessors rotor_angle(t, y), rotor_speed(y), psi(y), dpsi(y)); the flight and the slide (a
#: flight of the constrained system); the start of the sequence; the section state that
#: classifies cycles (and the state rebuilt from one); the contact Jacobian; the normal speed
#: (gap units, > 0 closing) and the striker's (for the outputs); the free normal acceleration
#: (for the chatter's accumulation point); the gap's rate after the law (< 0: the contact
#: opens); whether a contact at zero speed is pressed into a slide; the state at a chatter's
#: accumulation point; a closed-form escape before a flight; the system data for the flight
#: after a contact; which flight event is an escape; the shortest flight that opens a new
#: section; the flights' horizon; and whether the section map is smooth (Aitken may
#: extrapolate it). For the tangent of the map (tangent.py): the gradient of the contact
#: surface in (phi1, psi, psi') at a contact, d/dpsi of the contact Jacobian, the tangent
#: through a slide (slide_tangent(tangent, d, t, y, data, t1, y1, data1, p, settings) from
#: just after the law to the slide's end) and to a chatter's accumulation point
#: (accumulation_tangent(tangent, d, t, y, data, p, r) -> (ok, t, y) there); and the
#: distance of a contact from the tool's edge (inf: the tool has none)
Contact = namedtuple("Contact", [
    "model", "flight", "slide", "first", "key", "from_key", "jacobian", "normal_speed",
    "striker_speed", "normal_acceleration", "gap_rate_after", "pressed", "settle",
    "escapes_before", "flight_data", "escape_event", "min_flight", "horizon", "smooth",
    "event_gradient", "jacobian_slope", "slide_tangent", "accumulation_tangent",
    "edge_distance"])

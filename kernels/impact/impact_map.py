"""The impact map: contacts and flights from the start of a sequence to its steady cycle.

``make_impact_map(contact, jump_early)`` specialises the driver to a ``Contact``
(kernels/impact/__init__.py) and returns a ``Driver`` whose ``steady(p, data, r, settings,
max_impacts, tol, log) -> Steady`` runs a sequence:

1. a contact: Newton's law on the normal speed along the contact Jacobian, through the
   model's impulse response; a bounce that would leave slower than SPEED_EPS ends a chatter
   sequence at its accumulation point (the ballistic tail 2 R v/(g (1 - R)), H6, P-O14),
   where the law acts with R = 0; a plastic contact (R = 0, or such an accumulation) that
   the free motion presses into the tool then rides it (the tool's slide), else it leaves
   at zero normal speed; a contact that does not open after the law is degenerate;
   on a smooth map with R = 0 (``jump_early``: the map is then constant) the first section
   is the cycle;
2. a flight to the next contact, or escape, or the horizon (no impact);
3. a section is the contact opening an episode (after a free flight of at least the tool's
   min_flight); its state (``key``) classifies the cycle: p sections repeating the p before
   to ``tol`` (period p <= MAX_PERIOD);
4. on a smooth map (``jump_early``: an affine map of reversible flights) Aitken's
   extrapolation from the start and two sections jumps to the fixed point, checked by the
   next section; otherwise, once period 1 is found, Aitken on the last three sections
   removes the geometric tail, checked by the cycle's residual (H13);
5. the steady cycle is run once more with ``refine`` (turning points and peaks polished),
   which gives the outputs;
6. the budget ``max_impacts``: without a cycle, not periodic where the map has stopped
   contracting, else max_steps.
"""

import math
from collections import namedtuple

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS, INNER_OPTIONS
from kernels.impact.outcomes import (FLIGHT_EVENT, FLIGHT_HORIZON, FLIGHT_NONFINITE,
                                     FLIGHT_UNDERFLOW, NO_COST, SEQUENCE_CYCLE,
                                     SEQUENCE_DEGENERATE, SEQUENCE_ESCAPE, SEQUENCE_MAX_STEPS,
                                     SEQUENCE_NO_IMPACT, SEQUENCE_NONFINITE,
                                     SEQUENCE_NOT_PERIODIC, SEQUENCE_UNDERFLOW, add)

SPEED_EPS = 1e-7  # a bounce slower than this ends a chatter sequence (H6)
MAX_PERIOD = 8
MAX_CONTACTS_PER_SECTION = 200  # a chatter sequence longer than this is not a cycle

#: what a sequence returns: its outcome (outcomes.SEQUENCE_*), the cycle's period and
#: whether it accumulates a chatter, and over the cycle the amplitude, the free-flight time,
#: the rotor angle and time elapsed, the summed striker speed at its section contacts and
#: the peak acceleration; the sections before the cycle; the cost of the whole sequence
Steady = namedtuple("Steady", ["outcome", "period", "chatter", "amplitude", "flight_time",
                               "rotor_angle", "elapsed", "speed", "peak", "impacts", "cost"])
#: the driver's functions: the whole sequence, one section, one contact, Newton's law
Driver = namedtuple("Driver", ["steady", "section", "contact", "restitute"])
#: what a section returns: its outcome (SEQUENCE_CYCLE: it reached the next section), the
#: state there, whether it chattered, its amplitude, peak, free-flight time and cost
Section = namedtuple("Section", ["outcome", "t", "y", "data", "chatter", "amplitude", "peak",
                                 "flight_time", "cost"])


@njit(**KERNEL_OPTIONS)
def classify_period(history, count, tol, max_period):
    """Smallest p <= max_period such that the last cycle of p states of an impact map
    repeats the cycle before it (within tol, relative); 0 if none. history rows 0..count-1
    are the states at successive sections."""
    last = count - 1
    for p in range(1, max_period + 1):
        if last - 2 * p < 0:
            return 0
        same = True
        for q in range(p):
            a, b = last - q, last - q - p
            for i in range(history.shape[1]):
                if abs(history[a, i] - history[b, i]) > tol * max(1.0, abs(history[a, i])):
                    same = False
        if same:
            return p
    return 0


@njit(**KERNEL_OPTIONS)
def aitken(x0, x1, x2):
    """Aitken's delta-squared limit of x0, x1, x2; x2 itself unless the differences shrink
    geometrically (ratio in (-0.95, 0.95))."""
    d1, d2 = x1 - x0, x2 - x1
    if d1 == 0.0 or d2 == d1 or not abs(d2 / d1) < 0.95:
        return x2
    return x2 - d2 * d2 / (d2 - d1)


def make_impact_map(c, jump_early):
    """The driver of a Contact (see the module docstring)."""
    model = c.model
    flight, slide = c.flight, c.slide
    first, key_of, from_key, jacobian = c.first, c.key, c.from_key, c.jacobian
    normal_speed, striker_speed, normal_acceleration = (c.normal_speed, c.striker_speed,
                                                        c.normal_acceleration)
    gap_rate_after, pressed, settle = c.gap_rate_after, c.pressed, c.settle
    escapes_before, flight_data = c.escapes_before, c.flight_data
    escape_event, min_flight, smooth = c.escape_event, c.min_flight, c.smooth
    response, compose = model.response, model.compose
    psi_of, dpsi_of = model.psi, model.dpsi
    rotor_angle, rotor_speed = model.rotor_angle, model.rotor_speed

    @njit(**INNER_OPTIONS)
    def restitute(t, y, data, p, r):
        """Newton's law on the normal speed: v_n+ = -r v_n-, the impulse along J through
        the model's response M^-1 J^T."""
        j_phi, j_psi = jacobian(t, y, data)
        x_phi, x_psi = response(y, j_phi, j_psi, p)
        w, dpsi = rotor_speed(y), dpsi_of(y)
        impulse = -(1.0 + r) * (j_phi * w + j_psi * dpsi) / (j_phi * x_phi + j_psi * x_psi)
        return compose(t, rotor_angle(t, y), w + x_phi * impulse, psi_of(y),
                       dpsi + x_psi * impulse)

    @njit(**INNER_OPTIONS)
    def contact(t, y, data, p, r, settings, refine):
        """A contact: (opens, t, y, data, chatter, amplitude, peak, cost)."""
        approach = normal_speed(t, y, data, p)
        # the chatter accumulates once the bounce it would start falls below SPEED_EPS:
        # its flight would be shorter than the resolution of the event search
        zeno = r * abs(approach) < SPEED_EPS if r > 0.0 else abs(approach) < SPEED_EPS
        if zeno and r > 0.0:
            g2 = normal_acceleration(t, y, data, p)
            if g2 > 0.0:  # the chatter's accumulation point (H6)
                t, y = settle(t, y, data, p, 2.0 * r * abs(approach) / (g2 * (1.0 - r)))
        t, y = restitute(t, y, data, p, 0.0 if zeno else r)
        # a plastic contact pressed into the tool rides it (the law first: on a rotor of
        # finite inertia the impulse also changes the rotor's speed)
        if (r == 0.0 or zeno) and pressed(t, y, data, p):
            released, t, y, data, amplitude, peak, cost = slide(t, y, data, p, settings,
                                                                refine)
            return True, t, y, data, zeno, amplitude, peak, cost
        return gap_rate_after(t, y, data, p) < 0.0, t, y, data, zeno, 0.0, 0.0, NO_COST

    @njit(**INNER_OPTIONS)
    def section(t, y, data, p, r, settings, refine):
        """From a section contact (before its law) to the next section contact."""
        chatter = False
        amplitude = peak = flight_time = 0.0
        cost = NO_COST
        for _ in range(MAX_CONTACTS_PER_SECTION):
            opens, t, y, data, zeno, a, pk, spent = contact(t, y, data, p, r, settings,
                                                            refine)
            cost = add(cost, spent)
            chatter = chatter or zeno
            amplitude, peak = max(amplitude, a), max(peak, pk)
            if not opens:
                return Section(SEQUENCE_DEGENERATE, t, y, data, chatter, amplitude, peak,
                               flight_time, cost)
            if escapes_before(t, y, data, p):  # decided in closed form (H1, H2, H12)
                return Section(SEQUENCE_ESCAPE, t, y, data, chatter, amplitude, peak,
                               flight_time, cost)
            fl = flight(t, y, p, flight_data(data), settings, refine)
            cost = add(cost, fl.cost)
            amplitude, peak = max(amplitude, fl.amplitude), max(peak, fl.peak)
            if fl.outcome != FLIGHT_EVENT or fl.event == escape_event:
                outcome = (SEQUENCE_ESCAPE if fl.outcome == FLIGHT_EVENT else
                           SEQUENCE_NO_IMPACT if fl.outcome == FLIGHT_HORIZON else
                           SEQUENCE_UNDERFLOW if fl.outcome == FLIGHT_UNDERFLOW else
                           SEQUENCE_NONFINITE if fl.outcome == FLIGHT_NONFINITE else
                           SEQUENCE_MAX_STEPS)
                return Section(outcome, fl.t, fl.y, fl.data, chatter, amplitude, peak,
                               flight_time, cost)
            duration = fl.t - t
            flight_time += duration
            t, y, data = fl.t, fl.y, fl.data
            if duration >= min_flight:
                return Section(SEQUENCE_CYCLE, t, y, data, chatter, amplitude, peak,
                               flight_time, cost)
        return Section(SEQUENCE_NOT_PERIODIC, t, y, data, chatter, amplitude, peak,
                       flight_time, cost)

    @njit(**INNER_OPTIONS)
    def cycle(t, y, data, p, r, settings, period):
        """The steady cycle with refined flights: (outcome, chatter, amplitude, flight time,
        rotor angle, elapsed, speed, peak, residual, cost, end state)."""
        t0, phi0, key0 = t, rotor_angle(t, y), key_of(t, y, data, p)
        chatter = False
        amplitude = peak = flight_time = speed = 0.0
        cost = NO_COST
        for _ in range(period):
            speed += striker_speed(t, y, data, p)
            s = section(t, y, data, p, r, settings, bool(True))  # not a literal: see steady
            cost = add(cost, s.cost)
            chatter = chatter or s.chatter
            amplitude, peak = max(amplitude, s.amplitude), max(peak, s.peak)
            flight_time += s.flight_time
            t, y, data = s.t, s.y, s.data
            if s.outcome != SEQUENCE_CYCLE:
                return (s.outcome, chatter, amplitude, flight_time, 0.0, 0.0, speed, peak,
                        math.inf, cost)
        key = key_of(t, y, data, p)
        residual = 0.0
        for i in range(len(key)):
            residual = max(residual, abs(key[i] - key0[i]))
        return (SEQUENCE_CYCLE, chatter, amplitude, flight_time, rotor_angle(t, y) - phi0,
                t - t0, speed, peak, residual, cost)

    @njit(**INNER_OPTIONS)
    def steady(p, data0, r, settings, max_impacts, tol, log):
        """The sequence from its start to its steady cycle; log[j] gets (rotor angle mod
        2 pi, psi) at section j (the last row takes any beyond)."""
        t, y, data = first(p, data0)
        key = key_of(t, y, data, p)
        history = np.empty((max_impacts + 2, len(key)))
        count = 0
        period = 0
        cost = NO_COST
        jumped = False
        speculative = Steady(SEQUENCE_MAX_STEPS, 0, False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0,
                             NO_COST)
        while count <= max_impacts:
            key = key_of(t, y, data, p)
            for i in range(len(key)):
                history[count, i] = key[i]
            slot = min(count, log.shape[0] - 1)
            log[slot, 0], log[slot, 1] = rotor_angle(t, y) % (2.0 * math.pi), psi_of(y)
            count += 1
            period = classify_period(history, count, tol, MAX_PERIOD)
            if period > 0:
                break
            # an affine map of slope r = 0 is constant: its first section is the cycle
            constant = jump_early and r == 0.0
            # bool(): a literal would compile every function below twice (True, False)
            refine = bool(constant)
            if jump_early and count == 3:
                # the start and two sections fix an affine map: jump to its fixed point by
                # Aitken's delta-squared; the next section, refined, is expected to confirm
                x = (aitken(history[0, 0], history[1, 0], history[2, 0]),
                     aitken(history[0, 1], history[1, 1], history[2, 1]))
                t, y = from_key(x, t, y, data, p)
                key = key_of(t, y, data, p)
                for i in range(len(key)):
                    history[count - 1, i] = key[i]
                refine = jumped = True
            speed = striker_speed(t, y, data, p)
            t_start, phi_start = t, rotor_angle(t, y)
            s = section(t, y, data, p, r, settings, refine)
            cost = add(cost, s.cost)
            if s.outcome != SEQUENCE_CYCLE:
                return Steady(s.outcome, 0, s.chatter, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, count,
                              cost)
            t, y, data = s.t, s.y, s.data
            if refine:
                speculative = Steady(SEQUENCE_CYCLE, 1, s.chatter, s.amplitude,
                                     s.flight_time, rotor_angle(t, y) - phi_start,
                                     t - t_start, speed, s.peak, 0, NO_COST)
            if constant:
                return Steady(SEQUENCE_CYCLE, 1, s.chatter, s.amplitude, s.flight_time,
                              speculative.rotor_angle, speculative.elapsed,
                              striker_speed(t, y, data, p), s.peak, 1, cost)
        impacts = count - 2 * period
        if period == 0:
            recent = older = 0.0
            for i in range(history.shape[1]):
                recent = max(recent, abs(history[count - 1, i] - history[count - 2, i]))
                older = max(older, abs(history[count // 2, i] - history[count // 2 - 1, i]))
            outcome = (SEQUENCE_NOT_PERIODIC if count >= 20 and recent > 0.1 * older else
                       SEQUENCE_MAX_STEPS)
            return Steady(outcome, 0, False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, max_impacts, cost)
        if jumped and period == 1 and speculative.outcome == SEQUENCE_CYCLE:
            return Steady(SEQUENCE_CYCLE, 1, speculative.chatter, speculative.amplitude,
                          speculative.flight_time, speculative.rotor_angle,
                          speculative.elapsed, speculative.speed, speculative.peak, impacts,
                          cost)
        # the steady cycle from where the sequence is (on the cycle, to tol); at period 1 on
        # a smooth map from Aitken's extrapolation of the last three sections instead, kept
        # if the cycle's residual beats the last iteration's step (H13)
        last_step = 0.0
        for i in range(history.shape[1]):
            last_step = max(last_step, abs(history[count - 1, i] - history[count - 2, i]))
        t_run, y_run = t, y
        extrapolated = period == 1 and count >= 3 and not jump_early and smooth
        if extrapolated:
            x = (aitken(history[count - 3, 0], history[count - 2, 0], history[count - 1, 0]),
                 aitken(history[count - 3, 1], history[count - 2, 1], history[count - 1, 1]))
            t_run, y_run = from_key(x, t, y, data, p)
        result = cycle(t_run, y_run, data, p, r, settings, period)
        cost = add(cost, result[9])
        if extrapolated and result[8] > last_step:
            result = cycle(t, y, data, p, r, settings, period)
            cost = add(cost, result[9])
        outcome, chatter, amplitude, flight_time, angle, elapsed, speed, peak = result[:8]
        if outcome != SEQUENCE_CYCLE:  # the cycle did not repeat after all
            return Steady(SEQUENCE_MAX_STEPS, 0, chatter, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
                          impacts, cost)
        return Steady(SEQUENCE_CYCLE, period, chatter, amplitude, flight_time, angle, elapsed,
                      speed, peak, impacts, cost)

    return Driver(steady, section, contact, restitute)

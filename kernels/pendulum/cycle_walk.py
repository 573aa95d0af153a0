"""A steady cycle the integration core found, walked as time histories and loads: any period,
on either tool (the rotor model on the rotor stop, every model on the blade; the
constant-speed models on the stop have their cycle in closed form, histories.driven_cycle).

The cycle's contacts, slides and flights are found again from its row's section state (the
tool's key, the contact before its law) by the core's own Newton law, slides and flights at
HISTORY_TOL (kernels/impact/impact_map.py: the contact and flight functions the sweep ran),
then each flight and slide is walked by histories.py's RK4 walk from where it starts, with
the phases of the whole cycle that fall in it. Each impact adds its Impulses (the impulse
through the hinge, the drive's angular impulse at constant speed) and its loss: the kinetic
energy it takes from the rotor model; (1 - R^2) I_A (dpsi'/(1 + R))^2/2 at constant speed
(I_A = J_c + m l_cm^2 the striker's inertia about its hinge, dpsi'/(1 + R) the normal speed
it loses, in psi').

On a slide the striker rides the blade's face, G = phi1 + beta(psi) constant: its
accelerations are the free ones plus the face's reaction lambda along J = (1, h) through the
model's response M^-1 J^T, lambda = -G''_free/(J M^-1 J^T). The reaction is a force F on the
striker's tip along the face's normal (its virtual work F rho dG = lambda dG): F = lambda/rho
in the rotor model's units, F = I_A (psi''_c - psi''_free)/(rho h) at constant speed (the
driven response is M^-1 J^T up to scale). The hinge then carries m a_cm - F n, and a drive
at constant speed supplies dH_O/dt less F's moment rho F about O.

A cycle that accumulates a chatter has no walk here (its values stay NaN): its infinitely
many bounces are the core's closed-form tail, not a motion to sample.
"""

import math
from collections import namedtuple

import numpy as np
from numba import njit

from kernels import INLINE_OPTIONS, INNER_OPTIONS, KERNEL_OPTIONS
from kernels.cache import module_level
from kernels.impact.impact_map import MAX_CONTACTS_PER_SECTION, make_contact, make_restitute
from kernels.impact.outcomes import FLIGHT_EVENT
from kernels.pendulum import histories
from kernels.pendulum.blade import blade_section_start
from kernels.pendulum.blade_geometry import h_ratio, h_slope
from kernels.pendulum.histories import (CYCLE_ANGLE, CYCLE_TIME, CYCLE_WORK, HINGE_IMPULSE,
                                        IMPACT_LOSS, MEAN_TORQUE, PEAK_HINGE, PEAK_TORQUE,
                                        Sample, hinge_and_moment, impact_impulses, make_walk)
from kernels.pendulum.models import (kinetic_energy, paper_acceleration, rotor_accelerations,
                                     rotor_response)
from kernels.pendulum.systems import CONTACTS, DATA, PARAMETERS, Lazy
from kernels.pendulum.table import SYSTEMS
from kernels.pendulum.tools import stop_section_start

#: the tolerance of the flights that find the cycle's contacts again (DOPRI5)
HISTORY_TOL = 1e-12
#: the columns of a state in the logs: time, rotor angle and speed, psi, psi'
T, PHI, W, PSI, DPSI = range(5)
#: the kinds of a stretch of the cycle between contacts
FLIGHT, SLIDE = range(2)
#: each tool's section contact from its key
SECTION_STARTS = {"rotor_stop": stop_section_start, "lab_window": blade_section_start}


# ---------------------------------------------------------------- the face's reaction

#: a state on the face: psi'' and the rotor's phi1'' under the reaction, and the reaction as
#: a force on the striker's tip along the face's normal [m l2 omega1^2]
OnFace = namedtuple("OnFace", ["rotor", "swing", "force"])


@njit(**INLINE_OPTIONS)
def _radius(psi, k):
    return math.sqrt(k * k + 1.0 + 2.0 * k * math.cos(psi))  # O to the tip, in l2


@njit(**INLINE_OPTIONS)
def _normal(geometry, psi):
    """The face's normal (along G) in the pendulum's axes: (-sin delta, cos delta)."""
    delta = math.atan2(math.sin(psi), geometry.l1 + math.cos(psi)) - psi
    return -math.sin(delta), math.cos(delta)


@njit(**INLINE_OPTIONS)
def _driven_on_face(psi, dpsi, free, geometry):
    """OnFace at constant rotor speed from psi''_free."""
    l1, l_cm, j_c = geometry
    hr, hs = h_ratio(psi, l1), h_slope(psi, l1)
    swing = -hs * dpsi * dpsi / hr  # G'' = h psi'' + h' psi'^2 = 0
    return OnFace(0.0, swing, (j_c + l_cm * l_cm) * (swing - free) / (_radius(psi, l1) * hr))


def _driven_slide_walk(free):
    """The walk along the face of a constant-speed model whose psi''_free is
    ``free(psi, psi', p)``: state (psi, psi', work)."""

    @njit(**INLINE_OPTIONS)
    def rhs(y, q):
        p, geometry = q
        face = _driven_on_face(y[0], y[1], free(y[0], y[1], p), geometry)
        along, across, moment = hinge_and_moment(geometry, 1.0, 0.0, y[0], y[1], face.swing)
        return (y[1], face.swing, moment - _radius(y[0], geometry.l1) * face.force)

    @njit(**INLINE_OPTIONS)
    def loads(t, y, f, q):
        p, geometry = q
        face = _driven_on_face(y[0], y[1], free(y[0], y[1], p), geometry)
        along, across, moment = hinge_and_moment(geometry, 1.0, 0.0, y[0], y[1], face.swing)
        n_along, n_across = _normal(geometry, y[0])
        return Sample(y[0], y[1], face.swing, t, along + face.force * n_along,
                      across + face.force * n_across, f[2])

    return make_walk(rhs, loads)


@njit(**INLINE_OPTIONS)
def _paper_free(psi, dpsi, p):
    k, xi = p
    return paper_acceleration(psi, dpsi, k, xi)


@njit(**INLINE_OPTIONS)
def _rigid_free(psi, dpsi, p):
    k, kappa = p
    return -kappa * k * math.sin(psi)


@njit(**INLINE_OPTIONS)
def _rotor_on_face(y, p, geometry):
    """OnFace of the rotor model at its state (phi1, phi1', psi, psi', ...)."""
    k_cm, xi, j1, slope, idle = p
    w, psi, dpsi = y[1], y[2], y[3]
    k = geometry.l1
    hr = h_ratio(psi, k)
    a_phi, a_psi = rotor_accelerations(w, psi, dpsi, k_cm, xi, j1, slope, idle)
    x_phi, x_psi = rotor_response((y[0], w, psi, dpsi), 1.0, hr, p)
    reaction = -(a_phi + hr * a_psi + h_slope(psi, k) * dpsi * dpsi) / (x_phi + hr * x_psi)
    return OnFace(a_phi + x_phi * reaction, a_psi + x_psi * reaction,
                  geometry.j_c * reaction / _radius(psi, k))


@njit(**INLINE_OPTIONS)
def _rotor_slide_rhs(y, q):
    p, geometry = q
    k_cm, xi, j1, slope, idle = p
    face = _rotor_on_face(y, p, geometry)
    return (y[1], face.rotor, y[3], face.swing, slope * (idle - y[1]) * y[1])


@njit(**INLINE_OPTIONS)
def _rotor_slide_loads(t, y, f, q):
    p, geometry = q
    k_cm, xi, j1, slope, idle = p
    face = _rotor_on_face(y, p, geometry)
    along, across, moment = hinge_and_moment(geometry, y[1], face.rotor, y[2], y[3],
                                             face.swing)
    n_along, n_across = _normal(geometry, y[2])
    return Sample(y[2], y[3], face.swing, y[0], along + face.force * n_along,
                  across + face.force * n_across, geometry.j_c * slope * (idle - y[1]))


#: each model's walks: along a flight (histories.py) and along the blade's face
WALKS = {"paper": (histories.paper_walk, _driven_slide_walk(_paper_free)),
         "rigid": (histories.rigid_walk, _driven_slide_walk(_rigid_free)),
         "rotor": (histories.rotor_walk, make_walk(_rotor_slide_rhs, _rotor_slide_loads))}


# ---------------------------------------------------------------- the cycle

def make_contacts(c):
    """``stretches(t, y, data, p, r, settings, period, before, after, starts, ends, kinds)
    -> (impacts, stretches)``: a cycle of ``period`` sections from its section contact
    (t, y, data): each contact's state before and after its law (rows of before and after,
    columns T ... DPSI), each flight's and slide's starting state (starts), end time and
    kind (FLIGHT, SLIDE); (-1, -1) where the cycle chatters, runs out of rows or a flight
    ends otherwise than on the tool."""
    contact = make_contact(c, make_restitute(c))
    flight, flight_data, min_flight, escape = c.flight, c.flight_data, c.min_flight, c.escape_event
    model = c.model
    psi_of, dpsi_of = model.psi, model.dpsi
    rotor_angle, rotor_speed = model.rotor_angle, model.rotor_speed

    @njit(**INLINE_OPTIONS)
    def store(states, n, t, y):
        states[n, T], states[n, PHI], states[n, W] = t, rotor_angle(t, y), rotor_speed(y)
        states[n, PSI], states[n, DPSI] = psi_of(y), dpsi_of(y)

    @njit(**INNER_OPTIONS)
    def stretches(t, y, data, p, r, settings, period, before, after, starts, ends, kinds):
        n = m = sections = 0
        while sections < period:
            if m + 2 > starts.shape[0]:
                return -1, -1
            store(before, n, t, y)
            (opens, t, y, data, slid, zeno, amplitude, peak, cost, t_law,
             y_law) = contact(t, y, data, p, r, settings, True)
            if (zeno and r > 0.0) or not opens:
                return -1, -1
            store(after, n, t_law, y_law)
            n += 1
            if slid:
                store(starts, m, t_law, y_law)
                ends[m], kinds[m] = t, SLIDE
                m += 1
            fl = flight(t, y, p, flight_data(data), settings, True)
            if fl.outcome != FLIGHT_EVENT or fl.event == escape:
                return -1, -1
            store(starts, m, t, y)
            ends[m], kinds[m] = fl.t, FLIGHT
            m += 1
            if fl.t - t >= min_flight:
                sections += 1
            t, y, data = fl.t, fl.y, fl.data
        return n, m

    return stretches


def make_cycle_walk(system, contact):
    """``walk(case, key, period, r, settings, geometry, phases, out, loads) -> bool``: the
    histories (out[row, phase]) and loads (loads[:], histories.N_LOADS) of a system's
    steady cycle from its row's key (see the module docstring); False, all NaN, where the
    cycle has no walk."""
    parameters, data_of = PARAMETERS[system.model], DATA[system.tool]
    start = SECTION_STARTS[system.tool](contact.model)
    flight_walk, slide_walk = WALKS[system.model]
    stretches = make_contacts(contact)
    driven, slides = contact.model.driven, system.slide
    compose, rotor_angle = contact.model.compose, contact.model.rotor_angle

    @njit(**INLINE_OPTIONS)
    def walk_state(s, phi0):
        """The walk's state (its work 0) from a logged state."""
        if driven:
            return (s[PSI], s[DPSI], 0.0)
        return (s[PHI] - phi0, s[W], s[PSI], s[DPSI], 0.0)

    @njit(**INLINE_OPTIONS)
    def walk(kind, q, y, t0, duration, local, out):
        if slides and kind == SLIDE:
            return slide_walk(q, y, t0, duration, local, out)
        return flight_walk(q, y, t0, duration, local, out)

    @njit(**KERNEL_OPTIONS)
    def cycle_walk(case, key, period, r, settings, geometry, phases, out, loads):
        p = parameters(case)
        t, y, data = start(key, data_of(case), p)
        rows = max(period, 1) * MAX_CONTACTS_PER_SECTION
        before, after, starts = np.empty((rows, 5)), np.empty((rows, 5)), np.empty((rows, 5))
        ends, kinds = np.empty(rows), np.empty(rows, np.int64)
        n, m = stretches(t, y, data, p, r, settings, period, before, after, starts, ends,
                         kinds)
        if n < 0:
            return False
        t0, phi0 = t, rotor_angle(t, y)  # the cycle's first contact
        duration = ends[m - 1] - t0
        l1, l_cm, j_c = geometry
        q = (p, geometry)
        peak_hinge = peak_torque = work = loss = hinge = angle = 0.0
        i = 0  # the next phase
        for j in range(m):
            t_from, t_to = starts[j, T] - t0, ends[j] - t0
            first = i
            while i < phases.shape[0] and (phases[i] * duration < t_to or j == m - 1):
                i += 1
            local = (phases[first:i] * duration - t_from) / (t_to - t_from)
            walked = walk(kinds[j], q, walk_state(starts[j], phi0), t_from, t_to - t_from,
                          local, out[:, first:i])
            peak_hinge = max(peak_hinge, walked.hinge)
            peak_torque = max(peak_torque, walked.torque)
            work += walked.work if driven else j_c * walked.work
            angle = walked.angle
        for j in range(n):
            b, a = before[j], after[j]
            dpsi = a[DPSI] - b[DPSI]
            impulse = impact_impulses(geometry, b[PSI], a[W] - b[W], dpsi)
            hinge = max(hinge, math.hypot(impulse.along, impulse.across))
            if driven:
                work += impulse.drive
                loss += 0.5 * (1.0 - r * r) * (j_c + l_cm * l_cm) * (dpsi / (1.0 + r)) ** 2
            else:
                loss += j_c * (kinetic_energy(compose(b[T], b[PHI], b[W], b[PSI], b[DPSI])[1], p)
                               - kinetic_energy(compose(a[T], a[PHI], a[W], a[PSI],
                                                        a[DPSI])[1], p))
        loads[PEAK_HINGE], loads[PEAK_TORQUE] = peak_hinge, peak_torque
        loads[CYCLE_WORK], loads[IMPACT_LOSS], loads[HINGE_IMPULSE] = work, loss, hinge
        loads[CYCLE_TIME], loads[CYCLE_ANGLE] = duration, angle
        if driven:
            loads[MEAN_TORQUE] = work / duration
        else:  # the motor law is linear: its mean is at the mean speed
            k_cm, xi, j1, slope, idle = p
            loads[MEAN_TORQUE] = j_c * slope * (idle - angle / duration)
        return True

    return cycle_walk


def _entry_point(system):
    walk = make_cycle_walk(system, CONTACTS[system.model, system.tool, ()])
    return module_level(walk, f"{system.model}_on_{system.tool}_cycle_walk", globals(),
                        KERNEL_OPTIONS)


#: each system's compiled cycle walk by (system,), made on first use
CYCLE_WALKS = Lazy(((system,) for system in SYSTEMS), _entry_point)

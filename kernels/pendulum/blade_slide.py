"""The striker's slide along a face of the lab-fixed blade after a plastic contact (R = 0, or
an accumulated chatter), while pressed into it, until the pressing vanishes (release) or
|psi| reaches the blade's edge: at constant rotor speed in closed form
(``kinematic_slide``), with a rotor of finite inertia a flight of the constrained system
(``constrained_slide``, kernels/impact); each with its tangent. Also the one gradient of the
pressing (``gap_acceleration_change``), which the chatter's accumulation point uses too.
"""

import math

import numpy as np
from numba import njit

from kernels import INNER_OPTIONS, INLINE_OPTIONS
from kernels.extrema import peak_search
from kernels.impact import System
from kernels.impact.events import make_illinois
from kernels.impact.flight import make_flight
from kernels.impact.outcomes import NO_COST
from kernels.impact.tangent import (DDPSI, DPHI, DPSI, DT, DW, Field,
                                    make_acceleration_differential, make_event_carry,
                                    make_variational)
from kernels.impact.tuples import relative_scales

from kernels.pendulum.blade_geometry import SIDE, beta, h_curvature, h_ratio, h_slope
from kernels.pendulum.tools import TWO_PI


@njit(**INLINE_OPTIONS)
def _fixed_exit_tangent(tangent, d, t, y, data, t1, y1, data1, p, settings):
    """A slide at constant rotor speed ends where the face alone decides (the release, or
    the blade's edge): its exit does not depend on its entry."""
    tangent[:, :d] = 0.0
    return True


def gap_acceleration_change(model):
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


def kinematic_slide(model, free_gap_acceleration):
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


def constrained_slide(model, gap_change, methods):
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

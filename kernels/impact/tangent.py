"""The tangent of the impact map: how a small change of a section state propagates through
one steady cycle, and the multipliers of the cycle's section map.

A perturbation is carried as coordinates (dt, dphi1, dphi1', dpsi, dpsi') at an event
point: the shift of the event's time and of the state there (at constant rotor speed
dphi1 = dt and dphi1' = 0; the model converts, ``tangent_state`` / ``tangent_coordinates``).
A cycle's perturbations are the columns of a 5 x d matrix, one per section coordinate.

- Along a flight from (t0, y0) to the event at t1: the variational equations dY/dt = Df Y,
  Y(t0) = I, integrated with the state by the same Runge-Kutta steps and step-size control
  (flight.make_timed_flight on the augmented state, its error control covering Y, the last
  step cut to land on t1, which the flight located already); at fixed time the
  perturbation is Y dy0 - f(t1) dt0 (an autonomous flow started dt0 later), and the event
  moves by dt1 = -g . dy / (dg/dt) (the saltation of the event time; g's gradient from the
  tool, ``event_gradient``).
- At an impact: the derivative of Newton's law v+ = v - (1 + R) x (J v)/(J x) (x = M^-1 J^T)
  with respect to the velocities and, through J and M, to psi.
- At a chatter accumulated into a contact (the Zeno guard's jump to the accumulation
  point, the ballistic tail 2 R v_n/(g (1 - R))): the derivative of the tool's settle,
  through the tail's time, then of the plastic law there (``Contact.accumulation_tangent``).
- Through a slide (``Contact.slide_tangent``): at constant rotor speed the exit is decided by
  the face alone (the release, or the blade's edge), so the tangent is zero; a slide of the
  rotor model is a flight of the constrained system on the face, carried like a free
  flight by the same variational flight (``make_variational`` on the face's vector field)
  and the saltation of its end event.
- The section map's Jacobian is the d x d block of the chosen coordinates (the rotor speed
  unless it is constant, psi where the section surface moves with the rotor, psi'); the
  other coordinates are fixed by the surface or are exact symmetries (a shift of time for an
  autonomous system, of the rotor angle on the rotor stop), whose neutral multiplier 1 is
  not one of the pattern.
"""

import functools
import math
from collections import namedtuple

import numpy as np
from numba import njit

from kernels import INNER_OPTIONS, INLINE_OPTIONS
from kernels.impact.flight import make_timed_flight
from kernels.impact.runge_kutta import OTHER_METHODS
from kernels.impact.tuples import relative_scales

#: the rows of a perturbation's coordinates
DT, DPHI, DW, DPSI, DDPSI = 0, 1, 2, 3, 4
MAX_SECTION_DIMENSION = 3

#: a vector field for the variational equations: rhs(y, p), its Jacobian (row-major) and
#: the error scales (a model, or the constrained system of a slide)
Field = namedtuple("Field", ["rhs", "jacobian", "scales"])

#: what the cycle's driver calls to carry the tangent (make_tracker); ``start`` the section
#: basis, ``flight`` and ``law`` the updates, ``multiplier`` the leading multiplier
Tracker = namedtuple("Tracker", ["start", "flight", "law", "multiplier"])


def _generated(name: str, args: str, body: list[str], namespace: dict):
    exec(f"def {name}({args}):\n" + "\n".join("    " + line for line in body), namespace)
    return njit(**INLINE_OPTIONS)(namespace[name])


def make_variational(model, n, methods=OTHER_METHODS):
    """``flow_derivative(t0, y0, t1, p, settings) -> (reached, Y)``: the derivative Y (row-
    major n x n) of the flow of ``model`` (a Field: a model, or a slide's constrained
    system) from t0 to t1 at y0, by the variational equations on the augmented state."""
    ns = {"rhs": model.rhs, "jacobian": model.jacobian, "scales": model.scales,
          "relative_scales": relative_scales}
    y = "(" + ", ".join(f"z[{i}]" for i in range(n)) + ",)"
    products = [" + ".join(f"J[{i * n + k}] * z[{n + k * n + j}]" for k in range(n))
                for i in range(n) for j in range(n)]
    rhs = _generated("augmented_rhs", "z, p", [
        f"y = {y}", "f = rhs(y, p)", "J = jacobian(y, p)",
        "return (" + ", ".join([f"f[{i}]" for i in range(n)] + products) + ",)"], ns)
    z1 = y.replace("z[", "w[")
    tangent = "(" + ", ".join(f"z[{i}]" for i in range(n, n + n * n)) + ",)"
    scales = _generated("augmented_scales", "z, w, rtol, atol", [
        f"a = scales({y}, {z1}, rtol, atol)",
        f"b = relative_scales({tangent}, {tangent.replace('z[', 'w[')}, rtol, atol)",
        "return (" + ", ".join([f"a[{i}]" for i in range(n)]
                               + [f"b[{i}]" for i in range(n * n)]) + ",)"], ns)
    identity = ", ".join("1.0" if i == j else "0.0" for i in range(n) for j in range(n))
    extend = _generated("extend", "y", [f"return {y.replace('z[', 'y[')[:-2]}, {identity},)"],
                        ns)
    matrix = _generated("matrix", "z", [f"return {tangent}"], ns)

    fly = make_timed_flight(rhs, scales, methods)

    @njit(**INNER_OPTIONS)
    def flow_derivative(t0, y0, t1, p, settings):
        reached, z = fly(t0, extend(y0), t1, p, settings)
        return reached, matrix(z)

    return flow_derivative


@njit(**INNER_OPTIONS)
def leading_multiplier(a, d):
    """(|mu|, arg mu in [0, pi]) of the eigenvalue of largest modulus of the d x d matrix
    a (d <= 3): the characteristic polynomial's roots in closed form (a real root of the
    cubic by Newton from beyond its roots, the rest by deflation)."""
    if d == 1:
        return abs(a[0, 0]), (math.pi if a[0, 0] < 0.0 else 0.0)
    if d == 2:
        tr, det = a[0, 0] + a[1, 1], a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
        return _quadratic_leading(-tr, det)
    tr = a[0, 0] + a[1, 1] + a[2, 2]
    minors = (a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0] + a[0, 0] * a[2, 2] - a[0, 2] * a[2, 0]
              + a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1])
    det = (a[0, 0] * (a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1])
           - a[0, 1] * (a[1, 0] * a[2, 2] - a[1, 2] * a[2, 0])
           + a[0, 2] * (a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]))
    c2, c1, c0 = -tr, minors, -det  # mu^3 + c2 mu^2 + c1 mu + c0
    if not (math.isfinite(c2) and math.isfinite(c1) and math.isfinite(c0)):
        return math.nan, math.nan
    bound = 1.0 + max(abs(c2), max(abs(c1), abs(c0)))  # Cauchy: every root inside
    x = bound if c0 <= 0.0 else -bound  # the cubic's sign there points at a real root
    for _ in range(200):
        f = ((x + c2) * x + c1) * x + c0
        df = (3.0 * x + 2.0 * c2) * x + c1
        if df == 0.0:
            break
        step = f / df
        x -= step
        if abs(step) <= 1e-16 * max(1.0, abs(x)):
            break
    # the other two: mu^2 + (c2 + x) mu + (c1 + x (c2 + x))
    modulus, angle = _quadratic_leading(c2 + x, c1 + x * (c2 + x))
    if abs(x) > modulus:
        return abs(x), (math.pi if x < 0.0 else 0.0)
    return modulus, angle


@njit(**INNER_OPTIONS)
def _quadratic_leading(b, c):
    """The root of largest modulus of mu^2 + b mu + c."""
    disc = b * b - 4.0 * c
    if disc >= 0.0:
        root = -0.5 * (b + math.copysign(math.sqrt(disc), b))  # no cancellation
        if root == 0.0:
            return 0.0, 0.0
        other = c / root
        big = root if abs(root) >= abs(other) else other
        return abs(big), (math.pi if big < 0.0 else 0.0)
    return math.sqrt(c), math.acos(max(-1.0, min(1.0, -0.5 * b / math.sqrt(c))))


def _matrix_vector(n):
    """``product(m, v)``: the row-major n x n matrix m times the n-tuple v, as a tuple,
    straight-line (no array on the heap: it runs at every stage of a variational step)."""
    rows = [" + ".join(f"m[{i * n + k}] * v[{k}]" for k in range(n)) for i in range(n)]
    return _generated("product", "m, v", ["return (" + ", ".join(rows) + ",)"], {})


def make_event_carry(n):
    """``carry(m, dy0, dt0, f1, grad, rate) -> (dy, dt1)``: a perturbation (dt0, dy0) of a
    flight's start carried to its end event, for the flow derivative m (row-major n x n):
    at fixed time m dy0 - f1 dt0 (the flow started dt0 later), then the event moves by
    dt1 = -(grad . dy)/rate (the saltation of the event time; rate = grad . f1) and the
    state with it. One rule for free flights and slides."""
    rows = [" + ".join([f"-f1[{i}] * dt0"] + [f"m[{i * n + k}] * dy0[{k}]" for k in range(n)])
            for i in range(n)]
    moved = " + ".join(f"grad[{i}] * fixed[{i}]" for i in range(n))
    return _generated("carry", "m, dy0, dt0, f1, grad, rate", [
        "fixed = (" + ", ".join(rows) + ",)",
        f"dt1 = -({moved}) / rate",
        "return (" + ", ".join(f"fixed[{i}] + f1[{i}] * dt1" for i in range(n)) + ",), dt1"],
        {})


def make_acceleration_differential(model, n):
    """``differential(y, p, c) -> (d phi1'', d psi'')``: how the free accelerations change
    along a perturbation c in coordinates (dt, dphi1, dphi1', dpsi, dpsi'), by the model's
    Jacobian (the flow is autonomous: dt does not enter)."""
    state, coordinates, jacobian = model.tangent_state, model.tangent_coordinates, model.jacobian
    product = _matrix_vector(n)

    @njit(**INNER_OPTIONS)
    def differential(y, p, c):
        q = coordinates(0.0, product(jacobian(y, p), state(c)))
        return q[DW], q[DDPSI]

    return differential


@functools.cache
def make_tracker(c, n, methods=OTHER_METHODS):
    """The tangent's updates for a Contact (see the module docstring): the section's
    coordinates at the start, through a flight, through a contact, and the multiplier;
    ``methods``: those compiled into its flights beside DOPRI5 (make_timed_flight)."""
    driven, gradient = c.model.driven, c.event_gradient

    @njit(**INNER_OPTIONS)
    def start(t, y, data, basis):
        """The section's coordinates as columns of ``basis`` (5 x 3): the rotor speed (if
        it is a state), psi (if the section surface moves with the rotor), psi'; the rotor
        angle from the surface; time and (on the rotor stop) the rotor angle are symmetries
        and held. Returns d and the coordinate rows."""
        g_phi, g_psi, g_dpsi = gradient(t, y, data)
        rows = np.zeros(MAX_SECTION_DIMENSION, np.int64)
        d = 0
        if not driven:
            rows[d] = DW
            d += 1
        if g_phi != 0.0:
            rows[d] = DPSI
            d += 1
        rows[d] = DDPSI
        d += 1
        basis[:, :] = 0.0
        for j in range(d):
            basis[rows[j], j] = 1.0
            if g_phi != 0.0:
                basis[DPHI, j] = -(g_psi * basis[DPSI, j] + g_dpsi * basis[DDPSI, j]) / g_phi
                if driven:
                    basis[DT, j] = basis[DPHI, j]
        return d, rows

    @njit(**INNER_OPTIONS)
    def multiplier(tangent, d, rows):
        a = np.empty((d, d))
        for i in range(d):
            for j in range(d):
                a[i, j] = tangent[rows[i], j]
        return leading_multiplier(a, d)

    return Tracker(start, make_tangent_flight(c, n, methods), make_tangent_law(c),
                   multiplier)


def make_tangent_flight(c, n, methods=OTHER_METHODS):
    """The columns carried through a flight: the variational equations to the event and
    its time's shift (the saltation at a moving event); ``methods`` as make_tracker's."""
    model, gradient = c.model, c.event_gradient
    state, coordinates = model.tangent_state, model.tangent_coordinates
    monitor, rotor_speed = model.monitor, model.rotor_speed
    flow_derivative = make_variational(model, n, methods)
    carry = make_event_carry(n)

    @njit(**INNER_OPTIONS)
    def flight(tangent, d, t0, y0, t1, y1, f1, data1, p, settings):
        """Carry the columns from the event at t0 to the event at t1 (data1: the system
        data at the arrival). False if the variational flight failed."""
        if d == 0:
            return True
        reached, m = flow_derivative(t0, y0, t1, p, settings)
        if not reached:
            return False
        g_phi, g_psi, g_dpsi = gradient(t1, y1, data1)
        angle, rate, accel = monitor(t1, y1, f1)
        g_dot = g_phi * rotor_speed(y1) + g_psi * rate + g_dpsi * accel
        grad = state((0.0, g_phi, 0.0, g_psi, g_dpsi))  # in the model's state
        for j in range(d):
            dy0 = state((tangent[DT, j], tangent[DPHI, j], tangent[DW, j], tangent[DPSI, j],
                         tangent[DDPSI, j]))
            dy, dt1 = carry(m, dy0, tangent[DT, j], f1, grad, g_dot)
            out = coordinates(dt1, dy)
            for i in range(5):
                tangent[i, j] = out[i]
        return math.isfinite(g_dot) and g_dot != 0.0

    return flight


def make_tangent_law(c):
    """The columns carried through a contact: an accumulated chatter's settle, Newton's law
    differentiated, the slide's tangent."""
    model, driven = c.model, c.model.driven
    response, response_slope = model.response, model.response_slope
    rotor_speed, dpsi_of = model.rotor_speed, model.dpsi
    jacobian, jacobian_slope = c.jacobian, c.jacobian_slope
    slide_tangent, accumulation_tangent = c.slide_tangent, c.accumulation_tangent

    @njit(**INNER_OPTIONS)
    def law(tangent, d, t, y, data, t_law, y_law, t1, y1, data1, p, r, slid, zeno,
            settings):
        """Through a contact from (t, y) before its law to (t1, y1) after it (and after its
        slide, which starts at (t_law, y_law)): an accumulated chatter's settle, Newton's
        law differentiated, the slide's tangent. False where the tangent failed."""
        if d == 0:
            return True
        ok = True
        if zeno and r > 0.0:  # to the accumulation point; the law there is plastic
            ok, t, y = accumulation_tangent(tangent, d, t, y, data, p, r)
            r = 0.0
        j_phi, j_psi = jacobian(t, y, data)
        dj_phi, dj_psi = jacobian_slope(t, y, data)
        x_phi, x_psi = response(y, j_phi, j_psi, p)
        dx_phi, dx_psi = response_slope(y, j_phi, j_psi, dj_phi, dj_psi, p)
        w, v = rotor_speed(y), dpsi_of(y)
        jv, jx = j_phi * w + j_psi * v, j_phi * x_phi + j_psi * x_psi
        q = jv / jx
        dq = ((dj_phi * w + dj_psi * v) / jx
              - jv * (dj_phi * x_phi + dj_psi * x_psi + j_phi * dx_phi + j_psi * dx_psi)
              / (jx * jx))
        for j in range(d):
            dw, dpsi, ddpsi = tangent[DW, j], tangent[DPSI, j], tangent[DDPSI, j]
            dimpulse = (1.0 + r) * (j_phi * dw + j_psi * ddpsi) / jx
            bend = (1.0 + r) * dpsi
            if not driven:
                tangent[DW, j] = dw - x_phi * dimpulse - bend * (dx_phi * q + x_phi * dq)
            tangent[DDPSI, j] = ddpsi - x_psi * dimpulse - bend * (dx_psi * q + x_psi * dq)
        if slid:
            ok = ok and slide_tangent(tangent, d, t_law, y_law, data, t1, y1, data1, p,
                                      settings)
        return ok

    return law




@njit(**INLINE_OPTIONS)
def _no_start(t, y, data, basis):
    return int(0), np.zeros(MAX_SECTION_DIMENSION, np.int64)  # int(): see kernels/__init__.py


@njit(**INLINE_OPTIONS)
def _no_flight(tangent, d, t0, y0, t1, y1, f1, data1, p, settings):
    return True


@njit(**INLINE_OPTIONS)
def _no_law(tangent, d, t, y, data, t_law, y_law, t1, y1, data1, p, r, slid, zeno,
            settings):
    return True


@njit(**INLINE_OPTIONS)
def _no_multiplier(tangent, d, rows):
    return math.nan, math.nan


#: a driver without the tangent (its sweeps do not ask for multipliers): nothing compiled
NO_TRACKER = Tracker(_no_start, _no_flight, _no_law, _no_multiplier)

"""The transient's accelerators on a smooth map: Aitken's extrapolation (an affine map from
the start and two sections), the fixed point of the affine map through the last four
sections (minimal polynomial extrapolation) and Broyden's quasi-Newton steps after it, and
the impacts from rest counted on the map's linearisation past a jump (docs/impact_core.md,
H13)."""

import functools
import math
from collections import namedtuple

from numba import njit

from kernels import INNER_OPTIONS, KERNEL_OPTIONS

#: the transient's jumps so far (make_accelerators): the count at the last jump, whether
#: Broyden's steps are under way and have converged, the secant Jacobian of P(x) - x
#: (row-major) and its last pair (x, P(x) - x), the state before the last Broyden step,
#: and the count at the first jump with the last section from rest before it
Acceleration = namedtuple("Acceleration", ["jumped_at", "secant", "converged", "jac",
                                           "x_secant", "f_secant", "t_orbit", "y_orbit",
                                           "first_jump", "x_rest"])


@njit(**KERNEL_OPTIONS)
def aitken(x0, x1, x2):
    """Aitken's delta-squared limit of x0, x1, x2; x2 itself unless the differences shrink
    geometrically (ratio in (-0.95, 0.95))."""
    d1, d2 = x1 - x0, x2 - x1
    if d1 == 0.0 or d2 == d1 or not abs(d2 / d1) < 0.95:
        return x2
    return x2 - d2 * d2 / (d2 - d1)


@njit(**KERNEL_OPTIONS)
def fixed_point_jump(history, count):
    """The fixed point of the 2-D affine map through the last four sections x0..x3 (rows
    count-4 .. count-1), and the map's secant Jacobian: with d_j = x_{j+1} - x_j the map's
    linear part A solves A d0 = d1, A d1 = d2 (minimal polynomial extrapolation), and the
    fixed point x* = x3 + (I - A)^-1 A d2, exact for an affine map (a smooth map near its
    fixed point is one to second order). Where d0 and d1 are parallel (one mode left) the
    ratio q of d2 to d1 stands for A = q I. Returns (jump, x*, J), J = A - I row-major
    (the Jacobian of x -> P(x) - x, for ``secant_step``): no jump unless both eigenvalues
    of A lie inside |l| < 0.95 and the jump is at most 20 times the last difference (a map
    that is not yet near affine)."""
    a, b, c, d = (history[count - 4], history[count - 3], history[count - 2],
                  history[count - 1])
    d0x, d0y = b[0] - a[0], b[1] - a[1]
    d1x, d1y = c[0] - b[0], c[1] - b[1]
    d2x, d2y = d[0] - c[0], d[1] - c[1]
    none = (False, (d[0], d[1]), (0.0, 0.0, 0.0, 0.0))
    det = d0x * d1y - d1x * d0y
    if abs(det) > 1e-6 * math.hypot(d0x, d0y) * math.hypot(d1x, d1y):
        a11, a12 = (d1x * d1y - d2x * d0y) / det, (d2x * d0x - d1x * d1x) / det
        a21, a22 = (d1y * d1y - d2y * d0y) / det, (d2y * d0x - d1y * d1x) / det
    else:
        norm = d1x * d1x + d1y * d1y
        if norm == 0.0:
            return none
        a11 = a22 = (d1x * d2x + d1y * d2y) / norm
        a12 = a21 = 0.0
    tr, dt = a11 + a22, a11 * a22 - a12 * a21
    disc = tr * tr - 4.0 * dt
    if disc < 0.0:
        largest = math.sqrt(dt)  # a complex pair: |l|^2 = det A
    else:
        largest = 0.5 * (abs(tr) + math.sqrt(disc))
    if not largest < 0.95:
        return none
    jac = (a11 - 1.0, a12, a21, a22 - 1.0)
    ax, ay = a11 * d2x + a12 * d2y, a21 * d2x + a22 * d2y
    ok, step = _solve2(jac, (-ax, -ay))  # (I - A)^-1 A d2
    x = (d[0] + step[0], d[1] + step[1])
    if not (ok and math.hypot(step[0], step[1]) <= 20.0 * math.hypot(d2x, d2y)):
        return none
    return True, x, jac


@njit(**KERNEL_OPTIONS)
def _solve2(a, v):
    """(ok, a^-1 v) for the row-major 2 x 2 matrix a (ok False where a is singular)."""
    det = a[0] * a[3] - a[1] * a[2]
    if det == 0.0 or not math.isfinite(det):
        return False, (0.0, 0.0)
    return True, ((a[3] * v[0] - a[1] * v[1]) / det, (a[0] * v[1] - a[2] * v[0]) / det)


@njit(**KERNEL_OPTIONS)
def secant_step(jac, x0, f0, x1, f1):
    """Broyden's quasi-Newton step for a fixed point of a 2-D map P, on F(x) = P(x) - x:
    the secant Jacobian jac (row-major) is updated by the pair x0 -> x1 (F(x0) = f0, F(x1) =
    f1) so that it maps x1 - x0 to f1 - f0 (the least change, Broyden's good update), and
    the step from x1 is -jac^-1 f1. Returns (ok, jac, step); not ok where the residual did
    not shrink (|f1| >= |f0|: the map is not near its linearisation), the updated jac is
    singular, or the step exceeds 20 times the residual (a multiplier within 0.05 of 1)."""
    sx, sy = x1[0] - x0[0], x1[1] - x0[1]
    ss = sx * sx + sy * sy
    a, b, c, d = jac
    if ss > 0.0:
        rx = f1[0] - f0[0] - (a * sx + b * sy)
        ry = f1[1] - f0[1] - (c * sx + d * sy)
        a, b, c, d = a + rx * sx / ss, b + rx * sy / ss, c + ry * sx / ss, d + ry * sy / ss
    jac = (a, b, c, d)
    residual = math.hypot(f1[0], f1[1])
    ok, step = _solve2(jac, (-f1[0], -f1[1]))
    ok = (ok and residual < math.hypot(f0[0], f0[1])
          and math.hypot(step[0], step[1]) <= 20.0 * residual)
    return ok, jac, step


@njit(**KERNEL_OPTIONS)
def impacts_past_jump(jac, row, x, fixed, tol, limit):
    """The impacts from rest to the steady state of a sequence that jumped: ``x`` is its
    last section from rest (row ``row``, before the first jump) and the sequence from rest
    carries on there by the map's linearisation at its fixed point, x -> fixed + (I + jac)
    (x - fixed) (jac: the secant Jacobian of P(x) - x). Counted as the plain iteration's
    classification counts (period 1 at the first row n whose step from row n - 1 is within
    tol, relative: n - 1 impacts), at most ``limit``."""
    ex, ey = x[0] - fixed[0], x[1] - fixed[1]
    sx, sy = max(1.0, abs(fixed[0])), max(1.0, abs(fixed[1]))
    for n in range(row + 1, limit + 2):
        dx, dy = jac[0] * ex + jac[1] * ey, jac[2] * ex + jac[3] * ey
        if not (abs(dx) > tol * sx or abs(dy) > tol * sy):
            return n - 1
        ex, ey = ex + dx, ey + dy
    return limit


@njit(**KERNEL_OPTIONS)
def aitken_jump(history, last):
    """The 2-D section state by Aitken's delta-squared on rows last - 2 .. last of
    ``history``, each coordinate on its own: the fixed point of an affine map from three
    of its iterates (the start and two sections, on a map known to be affine), or the
    geometric tail removed from the last three sections of a converged sequence."""
    return (aitken(history[last - 2, 0], history[last - 1, 0], history[last, 0]),
            aitken(history[last - 2, 1], history[last - 1, 1], history[last, 1]))


@functools.cache
def make_accelerators(c):
    """The transient's jumps on a Contact with a 2-D section state: ``land`` moves the
    sequence to a section state, ``fixed_point`` jumps to the fixed point of the affine map
    through the last four sections (fixed_point_jump), ``broyden`` takes Broyden's step one
    section after a jump (secant_step). Each returns the new Acceleration and (t, y)."""
    key_of, from_key = c.key, c.from_key

    @njit(**INNER_OPTIONS)
    def land(x, t, y, data, p, history, row):
        """The state with section state x at the rotor angle of (t, y), written as row
        ``row`` of ``history`` (the section it replaces)."""
        t, y = from_key(x, t, y, data, p)
        key = key_of(t, y, data, p)
        for i in range(len(key)):
            history[row, i] = key[i]
        return t, y

    @njit(**INNER_OPTIONS)
    def fixed_point(a, history, count, t, y, data, p):
        jump, x, jac = fixed_point_jump(history, count)
        if not jump:  # the last secant Jacobian stays (impacts_past_jump counts on it)
            return (Acceleration(jumped_at=a.jumped_at, secant=a.secant, converged=a.converged,
                                 jac=a.jac, x_secant=a.x_secant, f_secant=a.f_secant,
                                 t_orbit=a.t_orbit, y_orbit=a.y_orbit,
                                 first_jump=a.first_jump, x_rest=a.x_rest), t, y)
        x_from = (history[count - 1, 0], history[count - 1, 1])
        x_secant = (history[count - 2, 0], history[count - 2, 1])
        f_secant = (x_from[0] - x_secant[0], x_from[1] - x_secant[1])
        t, y = land(x, t, y, data, p, history, count - 1)
        first = a.first_jump == 0  # the first jump: where the sequence from rest ends
        return (Acceleration(jumped_at=count, secant=True, converged=a.converged, jac=jac,
                             x_secant=x_secant, f_secant=f_secant, t_orbit=a.t_orbit,
                             y_orbit=a.y_orbit, first_jump=count if first else a.first_jump,
                             x_rest=x_from if first else a.x_rest), t, y)

    @njit(**INNER_OPTIONS)
    def broyden(a, history, count, t, y, data, p, repeat_tol):
        """One section after a jump to x (row count - 2), at P(x): Broyden's step to the
        fixed point; converged at the first step within repeat_tol (the steps shrink
        superlinearly, so where it lands is well within it); where the step fails (not
        near the map's linearisation) plain sections go on, jumps later."""
        x = (history[count - 2, 0], history[count - 2, 1])
        f = (history[count - 1, 0] - x[0], history[count - 1, 1] - x[1])
        going, jac, step = secant_step(a.jac, a.x_secant, a.f_secant, x, f)
        if not going:
            return (Acceleration(jumped_at=a.jumped_at, secant=False, converged=False,
                                 jac=jac, x_secant=x, f_secant=f, t_orbit=a.t_orbit,
                                 y_orbit=a.y_orbit, first_jump=a.first_jump,
                                 x_rest=a.x_rest), t, y)
        to = (x[0] + step[0], x[1] + step[1])
        t_orbit, y_orbit = t, y
        t, y = land(to, t, y, data, p, history, count - 1)
        converged = (abs(step[0]) <= repeat_tol * max(1.0, abs(to[0]))
                     and abs(step[1]) <= repeat_tol * max(1.0, abs(to[1])))
        return (Acceleration(jumped_at=count, secant=True, converged=converged, jac=jac,
                             x_secant=x, f_secant=f, t_orbit=t_orbit, y_orbit=y_orbit,
                             first_jump=a.first_jump, x_rest=a.x_rest), t, y)

    return land, fixed_point, broyden

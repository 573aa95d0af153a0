"""The impact map: contacts and flights from the start of a sequence to its steady cycle.

``make_impact_map(contact, jump_early)`` specialises the driver to a ``Contact``
(kernels/impact/__init__.py) and returns a ``Driver`` whose ``steady(p, data, r, settings,
repeat_tol, log, start, known) -> (Steady, t, y, data)`` runs a sequence, and ``settle``
the same from a given state (auto's second stage goes on from the first one's cycle); one
factory each: the law, a contact, a section, the transient and its accelerators, the
refined cycle, the whole sequence:

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
   next section; on another smooth map with a 2-D section (the rotor model on its stop)
   the transient jumps to the fixed point of the affine map through its last four
   sections (fixed_point_jump), then goes on by Broyden's quasi-Newton steps, one after
   each section, from that map's secant Jacobian (secant_step: superlinear, each step's
   error a fraction of the last), to the first step within tol; where a step fails (the
   residual grew) plain sections go on, another jump after four, three sections confirm,
   and Aitken on the last three removes the geometric tail; the cycle's residual checks
   either (H13). Flights per steady state: 12.1 plain, 9.2 with the jump alone, 7.8 with
   Broyden's steps. The impacts from rest past the first jump are counted on the map's
   linearisation (impacts_past_jump), not the sections flown;
5. the steady cycle is run once more with ``refine`` (turning points and peaks polished),
   which gives the outputs;
6. the budget ``max_impacts``: without a cycle, not periodic where the map has stopped
   contracting, else max_steps; not periodic already at a checkpoint (a power of two of
   sections) where the steps between sections have stopped shrinking by more than the
   budget's verdict allows (settles_nowhere), so that a quasi-periodic or chaotic
   sequence does not fly the whole budget;
7. with ``stability``, the refined run of the cycle also carries the tangent of the section
   map (tangent.py) for its leading multiplier, and every cycle reports its margins: the
   slowest and fastest impact, and the smallest distance of an impact from the tool's edge;
8. ``start`` picks the starting state (0: at rest, the tool's ``first``; others for the
   attractor count); a sequence that reaches a section state of a cycle in ``known``
   (those other starts found, known_attractor), or contracts onto one (captured_by),
   stops there as that cycle.
"""

import math
from collections import namedtuple

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS, INLINE_OPTIONS, INNER_OPTIONS
from kernels.impact.tangent import MAX_SECTION_DIMENSION, NO_TRACKER, make_tracker
from kernels.impact.runge_kutta import OTHER_METHODS
from kernels.impact.tuples import from_row
from kernels.impact.outcomes import (FLIGHT_EVENT, FLIGHT_HORIZON, FLIGHT_NONFINITE,
                                     FLIGHT_UNDERFLOW, NO_COST, SEQUENCE_CYCLE,
                                     SEQUENCE_DEGENERATE, SEQUENCE_ESCAPE, SEQUENCE_MAX_STEPS,
                                     SEQUENCE_NO_IMPACT, SEQUENCE_NONFINITE,
                                     SEQUENCE_NOT_PERIODIC, SEQUENCE_UNDERFLOW, add)

SPEED_EPS = 1e-7  # a bounce slower than this ends a chatter sequence (H6)
MAX_PERIOD = 8
PERIOD_SEPARATION = 1000.0  # see classify_period
MAX_CONTACTS_PER_SECTION = 200  # a chatter sequence longer than this is not a cycle
IMPACTS_COUNTED = 100000  # the longest transient counted past a jump
#: two section states are one attractor's when they agree to this (relative to max(1, |x|))
ATTRACTOR_TOL = 1e-6
#: the columns of a row of known cycles (``known``): how its sequence ended, its period, 1
#: if it chatters, and from KNOWN.key on its section state
KNOWN = namedtuple("KnownColumns", ["outcome", "period", "chatter", "key"])(0, 1, 2, 3)

#: what a sequence returns: its outcome (outcomes.SEQUENCE_*), the cycle's period and
#: whether it accumulates a chatter, and over the cycle the amplitude, the free-flight time,
#: the rotor angle and time elapsed, the summed striker speed at its section contacts and
#: the peak acceleration; the sections before the cycle; the cost of the whole sequence;
#: the cycle's margins (``Margins``); the section state (key) of its cycle that has the
#: smallest first component (the same for every phase of a period-n cycle)
Steady = namedtuple("Steady", ["outcome", "period", "chatter", "amplitude", "flight_time",
                               "rotor_angle", "elapsed", "speed", "peak", "impacts", "cost",
                               "margins", "key"])
#: how far a steady cycle is from changing: the slowest and fastest striker speed of its
#: impacts, the smallest distance of an impact from the tool's edge, and the section map's
#: leading multiplier (modulus, argument; NaN unless the tangent was carried)
Margins = namedtuple("Margins", ["speed_min", "speed_max", "edge", "modulus", "angle"])
NO_MARGINS = Margins(math.nan, math.nan, math.nan, math.nan, math.nan)
#: the driver's functions: the whole sequence from a start and from a state, one section,
#: one contact, Newton's law
Driver = namedtuple("Driver", ["steady", "settle", "section", "contact", "restitute"])
#: the refined steady cycle (``cycle``): its outcome, chatter, amplitude, free-flight time,
#: rotor angle and time elapsed, summed striker speed at its sections, peak acceleration,
#: how far its section state is from repeating after the period (``residual``), its cost,
#: margins and canonical section state
Cycle = namedtuple("Cycle", ["outcome", "chatter", "amplitude", "flight_time", "rotor_angle",
                             "elapsed", "speed", "peak", "residual", "cost", "margins", "key"])
#: the transient's jumps so far (make_accelerators): the count at the last jump, whether
#: Broyden's steps are under way and have converged, the secant Jacobian of P(x) - x
#: (row-major) and its last pair (x, P(x) - x), the state before the last Broyden step,
#: and the count at the first jump with the last section from rest before it
Acceleration = namedtuple("Acceleration", ["jumped_at", "secant", "converged", "jac",
                                           "x_secant", "f_secant", "t_orbit", "y_orbit",
                                           "first_jump", "x_rest"])
#: how the transient ended (make_transient): with a result already (``ended``: no cycle, or
#: the constant map's), or with its count of sections, the period found, the state and
#: cost there, its jumps, whether it jumped early (an affine map) and the cycle that jump's
#: refined section gave (``steady``)
Transient = namedtuple("Transient", ["ended", "steady", "count", "period", "t", "y", "data",
                                     "cost", "acceleration", "jumped"])
#: what a section returns: its outcome (SEQUENCE_CYCLE: it reached the next section), the
#: state there, whether it chattered, its amplitude, peak, free-flight time and cost, the
#: slowest and fastest striker speed at its contacts, their smallest distance from the
#: tool's edge, and whether the tangent went through it
Section = namedtuple("Section", ["outcome", "t", "y", "data", "chatter", "amplitude", "peak",
                                 "flight_time", "cost", "speed_min", "speed_max", "edge",
                                 "tangent_ok"])


@njit(**INLINE_OPTIONS)
def relative_distance(x, y, scale):
    """max_i |x_i - y_i| / max(1, |scale_i|): how far apart two section states are, relative
    where a component is large and absolute where it is small (the period's repeat, a
    known attractor, a capture)."""
    apart = 0.0
    for i in range(len(x)):
        apart = max(apart, abs(x[i] - y[i]) / max(1.0, abs(scale[i])))
    return apart


@njit(**KERNEL_OPTIONS)
def classify_period(history, count, tol, max_period):
    """Smallest p <= max_period such that the last cycle of p states of an impact map
    repeats the cycle before it (within tol, relative); 0 if none (yet). history rows
    0..count-1 are the states at successive sections.

    A p > 1 counts only when its p states lie apart by more than PERIOD_SEPARATION times
    the repeat's residual and tol: a period-1 transient whose multiplier mu is near -1
    alternates, and its two-step residual is |1 + mu| times its one-step difference, so it
    would pass as period 2 long before it converges (a period-1 design with mu = -0.94 was
    reported as period_n with the two-fold map's mu^2); and where the map's rounding
    exceeds tol, a period-2 cycle failed its own repeat and passed as period 4 (with mu^2).
    A genuine p-cycle's residual keeps falling while its states stay apart: it is
    classified a little later."""
    last = count - 1
    for p in range(1, max_period + 1):
        if last - 2 * p < 0:
            return 0
        residual = 0.0
        for q in range(p):
            a, b = last - q, last - q - p
            residual = max(residual, relative_distance(history[a], history[b], history[a]))
        if residual > tol:
            continue
        spread = math.inf  # the closest two states of the p-cycle
        for j in range(1, p):
            spread = min(spread, relative_distance(history[last], history[last - j],
                                                   history[last]))
        if spread > PERIOD_SEPARATION * max(residual, tol):
            return p
        return 0  # a lower period still converging: go on iterating
    return 0


@njit(**KERNEL_OPTIONS)
def radical_inverse(j, base):
    """The j-th point of van der Corput's sequence in ``base``, in [0, 1): starting states
    that fill their range evenly whatever their number, the same at every N (Halton's
    sequence over bases 2, 3, 5)."""
    x, scale = 0.0, 1.0 / base
    while j > 0:
        x += (j % base) * scale
        j //= base
        scale /= base
    return x


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
def _solve2(m, v):
    """(ok, m^-1 v) for the row-major 2 x 2 matrix m (ok False where m is singular)."""
    det = m[0] * m[3] - m[1] * m[2]
    if det == 0.0 or not math.isfinite(det):
        return False, (0.0, 0.0)
    return True, ((m[3] * v[0] - m[1] * v[1]) / det, (m[0] * v[1] - m[2] * v[0]) / det)


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


@njit(**KERNEL_OPTIONS)
def known_attractor(known, key):
    """The row of ``known`` (columns KNOWN) whose cycle's section state ``key`` is, to
    ATTRACTOR_TOL; -1 if none. Rows of sequences that ended without a cycle never
    match."""
    for a in range(known.shape[0]):
        if known[a, KNOWN.outcome] != SEQUENCE_CYCLE:
            continue
        state = known[a, KNOWN.key:KNOWN.key + len(key)]
        if not relative_distance(key, state, state) > ATTRACTOR_TOL:
            return a
    return -1


#: a start is captured by a known cycle (captured_by) once its section states of the cycle's
#: phase come within this of the cycle's, each step at most CAPTURE_RATIO of the one before;
#: two cycles whose section states lie within about twice this of each other may then count
#: as one attractor (a start passing that near the other's state looks captured)
CAPTURE_DISTANCE = 1e-4
CAPTURE_RATIO = 0.9


@njit(**KERNEL_OPTIONS)
def captured_by(known, history, count):
    """The row of ``known`` (columns KNOWN) whose cycle the sequence of section states
    ``history`` (rows 0..count-1) is contracting onto: of its last three states p apart (p
    the cycle's period), each is nearer the cycle's state than the one before by at least
    CAPTURE_RATIO, the last within CAPTURE_DISTANCE (relative, as ATTRACTOR_TOL); its own
    steps shrink by CAPTURE_RATIO too, and the cycle's state lies within the reach of their
    geometric tail (ratio/(1 - ratio) times the last): a sequence that converges elsewhere
    stops contracting onto it, its steps vanishing while its distance stays. -1 if none."""
    last = count - 1
    reach = CAPTURE_RATIO / (1.0 - CAPTURE_RATIO)
    for a in range(known.shape[0]):
        if known[a, KNOWN.outcome] != SEQUENCE_CYCLE:
            continue
        p = int(known[a, KNOWN.period])
        if last - 2 * p < 0:
            continue
        cycle = known[a, KNOWN.key:KNOWN.key + history.shape[1]]
        x0, x1, x2 = history[last - 2 * p], history[last - p], history[last]
        d0, d1 = relative_distance(x0, cycle, cycle), relative_distance(x1, cycle, cycle)
        d2 = relative_distance(x2, cycle, cycle)
        s1, s2 = relative_distance(x1, x0, cycle), relative_distance(x2, x1, cycle)
        if (d2 <= CAPTURE_DISTANCE and d2 <= CAPTURE_RATIO * d1 and d1 <= CAPTURE_RATIO * d0
                and s2 <= CAPTURE_RATIO * s1 and d2 <= reach * s2):
            return a
    return -1


@njit(**INLINE_OPTIONS)
def ended(steady, count, t, y, data, acceleration):
    """A transient that ended with its result ``steady`` already (no cycle, the constant
    map's, a known one's)."""
    return Transient(ended=bool(True), steady=steady, count=count, period=int(0), t=t, y=y,
                     data=data, cost=steady.cost, acceleration=acceleration,
                     jumped=bool(False))


@njit(**INLINE_OPTIONS)
def on_known(cycle, key, impacts, cost):
    """The Steady of a sequence that reached the section state ``key`` of a known cycle
    (``cycle``: a row of known cycles, columns KNOWN): its outcome, period and chatter;
    its values are that cycle's, not computed again."""
    return Steady(outcome=SEQUENCE_CYCLE, period=int(cycle[KNOWN.period]),
                  chatter=cycle[KNOWN.chatter] > 0.0,
                  amplitude=0.0, flight_time=0.0, rotor_angle=0.0, elapsed=0.0, speed=0.0,
                  peak=0.0, impacts=impacts, cost=cost, margins=NO_MARGINS, key=key)


#: an early verdict needs the weighted Birkhoff averages of the section states over the
#: last two quarters to agree to this, relative to the states' spread
BIRKHOFF_AGREEMENT = 1e-6


@njit(**KERNEL_OPTIONS)
def birkhoff_average(history, first, last, i):
    """The weighted Birkhoff average of component i of rows first .. last - 1 of
    ``history``, weights exp(-1/(s (1 - s))) at s = (j + 1/2)/(last - first) (Das, Saiki,
    Sander and Yorke, Nonlinearity 30, 2017): on a quasi-periodic orbit it converges faster
    than any power of the length, on a chaotic one like its square root."""
    total = weights = 0.0
    for j in range(first, last):
        s = (j - first + 0.5) / (last - first)
        w = math.exp(-1.0 / (s * (1.0 - s)))
        total += w * history[j, i]
        weights += w
    return total / weights


@njit(**KERNEL_OPTIONS)
def settles_nowhere(history, count, settings, repeat_tol):
    """The early verdict "not periodic" for a quasi-periodic sequence, at section counts n
    that are powers of two from settings.verdict_from, below the budget N =
    settings.max_impacts. Over the last half of the sequence, split into two quarters:
    (1) each component's weighted Birkhoff averages over the quarters agree to
    BIRKHOFF_AGREEMENT of its spread (a quasi-periodic orbit, or a periodic one; a chaotic
    one's agree to about 1e-2: it flies the budget, as it may still end without an
    impact, as 3 of 120 random blade designs did); (2) for every period p <= MAX_PERIOD,
    the differences of states p sections apart (relative, as classify_period takes them)
    stay above 1000 repeat_tol, and over the last quarter are, on average and at their
    largest, at least 0.1^(n/(4N)) of those over the quarter before: no cycle is near (9
    designs of the stability example, converging slowly to a period-n cycle, passed (1)
    and the steps of p = 1 alone). A transient whose differences shrink geometrically by
    rho a section passes (2) only where rho >= 0.1^(1/N), which the budget's own verdict
    (not_periodic: the step at N over a tenth of the one at N/2, rho > 0.1^(2/N)) calls
    not periodic too."""
    n, budget = count, settings.max_impacts
    if settings.verdict_from <= 0 or n < settings.verdict_from or n >= budget or (
            n & (n - 1)) != 0:
        return False
    quarter = n // 4
    for i in range(history.shape[1]):
        spread = 0.0
        for j in range(n - 2 * quarter, n):
            spread = max(spread, abs(history[j, i] - history[n - 1, i]))
        drift = abs(birkhoff_average(history, n - 2 * quarter, n - quarter, i)
                    - birkhoff_average(history, n - quarter, n, i))
        if not drift <= BIRKHOFF_AGREEMENT * spread:
            return False
    floor = 0.1 ** (n / (4.0 * budget))
    for p in range(1, MAX_PERIOD + 1):
        mean, largest, smallest = np.zeros(2), np.zeros(2), math.inf
        for half in range(2):
            for j in range(n - (2 - half) * quarter, n - (1 - half) * quarter):
                step = relative_distance(history[j], history[j - p], history[j])
                mean[half] += step / quarter
                largest[half] = max(largest[half], step)
                if half == 1:
                    smallest = min(smallest, step)
        if not (smallest > 1000.0 * repeat_tol and mean[1] >= floor * mean[0]
                and largest[1] >= floor * largest[0]):
            return False
    return True


@njit(**KERNEL_OPTIONS)
def not_periodic(history, count):
    """How a sequence that found no cycle within its budget ended: not periodic where its
    map has stopped contracting (its last step is over a tenth of the one half-way), else
    still converging (max_steps)."""
    recent = older = 0.0
    for i in range(history.shape[1]):
        recent = max(recent, abs(history[count - 1, i] - history[count - 2, i]))
        older = max(older, abs(history[count // 2, i] - history[count // 2 - 1, i]))
    return (SEQUENCE_NOT_PERIODIC if count >= 20 and recent > 0.1 * older else
            SEQUENCE_MAX_STEPS)


@njit(**INLINE_OPTIONS)
def no_cycle(outcome, chatter, impacts, cost, key):
    """The Steady of a sequence that ended without a cycle."""
    return Steady(outcome=outcome, period=0, chatter=chatter, amplitude=0.0, flight_time=0.0,
                  rotor_angle=0.0, elapsed=0.0, speed=0.0, peak=0.0, impacts=impacts,
                  cost=cost, margins=NO_MARGINS, key=key)


@njit(**INLINE_OPTIONS)
def of_cycle(period, c, impacts, cost):
    """The Steady of a sequence whose cycle of ``period`` sections is ``c`` (a Cycle, or a
    Steady: its values and margins)."""
    return Steady(outcome=SEQUENCE_CYCLE, period=period, chatter=c.chatter,
                  amplitude=c.amplitude, flight_time=c.flight_time,
                  rotor_angle=c.rotor_angle, elapsed=c.elapsed, speed=c.speed, peak=c.peak,
                  impacts=impacts, cost=cost, margins=c.margins, key=c.key)


@njit(**INLINE_OPTIONS)
def with_cost(s, impacts, cost):
    """The Steady ``s`` with its impacts from the start and its cost replaced (a sequence
    solved in stages: the impacts one stage counted, the cost of all)."""
    if s.outcome != SEQUENCE_CYCLE:
        return no_cycle(s.outcome, s.chatter, impacts, cost, s.key)
    return of_cycle(s.period, s, impacts, cost)


def make_impact_map(c, jump_early, stability=False, known_cycles=True, second_stage=True,
                    methods=OTHER_METHODS):
    """The driver of a Contact (see the module docstring); with ``stability`` the steady
    cycle also carries the tangent of the section map (tangent.py) for its multipliers,
    its flights with ``methods`` compiled in beside DOPRI5 (the Contact's; DOP853 never:
    make_timed_flight);
    without ``known_cycles`` a sequence never looks for the cycles of other starts (a
    single start: their search is not compiled in); without ``second_stage`` the sequence
    from a state (``settle``) is called only by ``steady`` and inlined into it."""
    tracker = make_tracker(c, 2 if c.model.driven else 4, methods) if stability else NO_TRACKER
    restitute = make_restitute(c)
    contact = make_contact(c, restitute)
    section = make_section(c, contact, tracker)
    cycle = make_cycle(c, section, tracker)
    transient = make_transient(c, jump_early, section, known_cycles)
    steady, settle = make_steady(c, jump_early, transient, cycle, second_stage)
    return Driver(steady=steady, settle=settle, section=section, contact=contact,
                  restitute=restitute)


def make_restitute(c):
    """Newton's law of a Contact: ``restitute(t, y, data, p, r) -> (t, y)``."""
    jacobian, response, compose = c.jacobian, c.model.response, c.model.compose
    psi_of, dpsi_of = c.model.psi, c.model.dpsi
    rotor_angle, rotor_speed = c.model.rotor_angle, c.model.rotor_speed

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

    return restitute


def make_contact(c, restitute):
    """A contact of a Contact, from its approach to where it opens or its slide ends."""
    normal_speed, normal_acceleration = c.normal_speed, c.normal_acceleration
    gap_rate_after, pressed, settle, slide = c.gap_rate_after, c.pressed, c.settle, c.slide

    @njit(**INNER_OPTIONS)
    def contact(t, y, data, p, r, settings, refine):
        """A contact: (opens, t, y, data, slid, chatter, amplitude, peak, cost, t_law,
        y_law); (t_law, y_law) just after the law, where a slide starts."""
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
            released, t1, y1, data1, amplitude, peak, cost = slide(t, y, data, p,
                                                                   settings, refine)
            return True, t1, y1, data1, True, zeno, amplitude, peak, cost, t, y
        return (gap_rate_after(t, y, data, p) < 0.0, t, y, data, False, zeno, 0.0, 0.0,
                NO_COST, t, y)

    return contact


def make_section(c, contact, tracker):
    """One section of a Contact: its contacts and flights up to the next section."""
    _, track_flight, track_law, _ = tracker
    flight, flight_data, escapes_before = c.flight, c.flight_data, c.escapes_before
    striker_speed, edge_distance = c.striker_speed, c.edge_distance
    escape_event, min_flight = c.escape_event, c.min_flight

    @njit(**INNER_OPTIONS)
    def section(t, y, data, p, r, settings, refine, tangent, d):
        """From a section contact (before its law) to the next section contact; the first
        d columns of ``tangent`` are carried along (tangent.py)."""
        chatter = False
        amplitude = peak = flight_time = 0.0
        speed_min, speed_max, edge = math.inf, 0.0, math.inf
        tangent_ok = True
        cost = NO_COST
        for _ in range(MAX_CONTACTS_PER_SECTION):
            speed = striker_speed(t, y, data, p)
            speed_min, speed_max = min(speed_min, speed), max(speed_max, speed)
            edge = min(edge, edge_distance(t, y, data))
            t0, y0, data0 = t, y, data
            (opens, t, y, data, slid, zeno, a, pk, spent, t_law,
             y_law) = contact(t, y, data, p, r, settings, refine)
            tangent_ok = tangent_ok and track_law(tangent, d, t0, y0, data0, t_law, y_law,
                                                  t, y, data, p, r, slid, zeno, settings)
            cost = add(cost, spent)
            # a plastic contact cannot chatter: its zero-speed touch (a graze, as where a
            # slide's release meets the face again) is not a bounce sequence
            chatter = chatter or (zeno and r > 0.0)
            amplitude, peak = max(amplitude, a), max(peak, pk)
            if not opens:
                return Section(SEQUENCE_DEGENERATE, t, y, data, chatter, amplitude, peak,
                               flight_time, cost, speed_min, speed_max, edge, tangent_ok)
            if escapes_before(t, y, data, p):  # decided in closed form (H1, H2, H12)
                return Section(SEQUENCE_ESCAPE, t, y, data, chatter, amplitude, peak,
                               flight_time, cost, speed_min, speed_max, edge, tangent_ok)
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
                               flight_time, cost, speed_min, speed_max, edge, tangent_ok)
            tangent_ok = tangent_ok and track_flight(tangent, d, t, y, fl.t, fl.y, fl.f,
                                                     fl.data, p, settings)
            duration = fl.t - t
            flight_time += duration
            t, y, data = fl.t, fl.y, fl.data
            if duration >= min_flight:
                return Section(SEQUENCE_CYCLE, t, y, data, chatter, amplitude, peak,
                               flight_time, cost, speed_min, speed_max, edge, tangent_ok)
        return Section(SEQUENCE_NOT_PERIODIC, t, y, data, chatter, amplitude, peak,
                       flight_time, cost, speed_min, speed_max, edge, tangent_ok)

    return section


def make_cycle(c, section, tracker):
    """The refined steady cycle of a Contact, with its margins and, with the tangent
    (``tracker``), its leading multiplier: ``cycle(...) -> Cycle``."""
    track_start, _, _, track_multiplier = tracker
    key_of, striker_speed, rotor_angle = c.key, c.striker_speed, c.model.rotor_angle

    @njit(**INNER_OPTIONS)
    def cycle(t, y, data, p, r, settings, period):
        """The steady cycle of ``period`` sections from (t, y), with refined flights."""
        t0, phi0, key0 = t, rotor_angle(t, y), key_of(t, y, data, p)
        chatter = False
        amplitude = peak = flight_time = speed = 0.0
        speed_min, speed_max, edge = math.inf, 0.0, math.inf
        cost = NO_COST
        tangent = np.empty((5, MAX_SECTION_DIMENSION))
        d, rows = track_start(t, y, data, tangent)
        tangent_ok = True
        canonical = key0
        for _ in range(period):
            here = key_of(t, y, data, p)
            if here[0] < canonical[0]:
                canonical = here
            speed += striker_speed(t, y, data, p)
            s = section(t, y, data, p, r, settings, bool(True), tangent, d)  # see steady
            cost = add(cost, s.cost)
            chatter = chatter or s.chatter
            amplitude, peak = max(amplitude, s.amplitude), max(peak, s.peak)
            flight_time += s.flight_time
            speed_min, speed_max = min(speed_min, s.speed_min), max(speed_max, s.speed_max)
            edge, tangent_ok = min(edge, s.edge), tangent_ok and s.tangent_ok
            t, y, data = s.t, s.y, s.data
            if s.outcome != SEQUENCE_CYCLE:
                return Cycle(outcome=s.outcome, chatter=chatter, amplitude=amplitude,
                             flight_time=flight_time, rotor_angle=0.0, elapsed=0.0,
                             speed=speed, peak=peak, residual=math.inf, cost=cost,
                             margins=NO_MARGINS, key=canonical)
        key = key_of(t, y, data, p)
        residual = 0.0
        for i in range(len(key)):
            residual = max(residual, abs(key[i] - key0[i]))
        modulus = angle = math.nan
        if tangent_ok:
            modulus, angle = track_multiplier(tangent, d, rows)
        return Cycle(outcome=SEQUENCE_CYCLE, chatter=chatter, amplitude=amplitude,
                     flight_time=flight_time, rotor_angle=rotor_angle(t, y) - phi0,
                     elapsed=t - t0, speed=speed, peak=peak, residual=residual, cost=cost,
                     margins=Margins(speed_min, speed_max, edge, modulus, angle),
                     key=canonical)

    return cycle


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


def make_record(c):
    """``record(t, y, data, p, history, row, log) -> key``: a section's state into row
    ``row`` of ``history``, and its rotor angle (mod 2 pi) and psi into ``log`` (its last
    row takes any beyond)."""
    key_of, rotor_angle, psi_of = c.key, c.model.rotor_angle, c.model.psi

    @njit(**INNER_OPTIONS)
    def record(t, y, data, p, history, row, log):
        key = key_of(t, y, data, p)
        for i in range(len(key)):
            history[row, i] = key[i]
        slot = min(row, log.shape[0] - 1)
        log[slot, 0], log[slot, 1] = rotor_angle(t, y) % (2.0 * math.pi), psi_of(y)
        return key

    return record


def make_transient(c, jump_early, section, known_cycles=True):
    """The transient of a Contact: ``transient(p, data, r, settings, repeat_tol, log, t, y,
    history, known) -> Transient``, sections from (t, y) until p of them repeat
    (``history`` holds their states), one is on a cycle of ``known`` (known_attractor,
    captured_by; with ``known_cycles`` only),
    or the sequence settles nowhere (settles_nowhere); accelerated where the map allows
    it: on an affine map (``jump_early``) by Aitken's jump from the start and two
    sections (aitken_jump), on another smooth map with a 2-D section by fixed-point jumps
    and Broyden's steps (make_accelerators)."""
    key_of, striker_speed, rotor_angle = c.key, c.striker_speed, c.model.rotor_angle
    smooth = c.smooth
    land, fixed_point, broyden = make_accelerators(c)
    record = make_record(c)

    @njit(**INNER_OPTIONS)
    def transient(p, data, r, settings, repeat_tol, log, t, y, history, known):
        no_tangent = np.empty((5, 0))  # the transient's sections carry no tangent
        smooth_2d = not jump_early and smooth and history.shape[1] == 2
        a = Acceleration(jumped_at=1, secant=False, converged=False, jac=(0.0, 0.0, 0.0, 0.0),
                         x_secant=(0.0, 0.0), f_secant=(0.0, 0.0), t_orbit=t, y_orbit=y,
                         first_jump=0, x_rest=(0.0, 0.0))
        # int(): a literal 0 would compile record for the literal too (kernels/__init__.py)
        count, period, cost, jumped = int(0), int(0), NO_COST, False
        speculative = no_cycle(SEQUENCE_MAX_STEPS, False, 0, NO_COST, key_of(t, y, data, p))
        while count <= settings.max_impacts:
            key = record(t, y, data, p, history, count, log)
            count += 1
            hit = -1
            if known_cycles:  # its own test, so that numba prunes it for a single start
                hit = known_attractor(known, key)
                if hit < 0:  # captured on its way: the cycle's own state stands for it
                    hit = captured_by(known, history, count)
                    if hit >= 0:
                        key = from_row(key, known[hit], int(KNOWN.key))
            period = classify_period(history, count, repeat_tol, MAX_PERIOD)
            # on a cycle found before: that attractor (its values are known); or, away from
            # the accelerators' jumps, a sequence as not periodic as its budget would find it
            if hit >= 0 or (period == 0 and not a.secant and 2 * a.jumped_at < count
                            and settles_nowhere(history, count, settings, repeat_tol)):
                return ended(on_known(known[hit], key, count, cost) if hit >= 0 else no_cycle(
                    SEQUENCE_NOT_PERIODIC, False, settings.max_impacts, cost, key),
                    count, t, y, data, a)
            # right after a transient jump, one section more: Aitken at the end needs three
            # sections of the map's own (a jumped state's section repeats it only to tol)
            if period > 0 and not (a.jumped_at > 1 and count < a.jumped_at + 2):
                break
            # an affine map of slope r = 0 is constant: its first section is the cycle
            constant = jump_early and r == 0.0
            refine = bool(constant)  # bool(): see kernels/__init__.py
            if smooth:  # its own test, so that numba prunes the jumps of a map without them
                if a.secant and count == a.jumped_at + 1:
                    a, t, y = broyden(a, history, count, t, y, data, p, repeat_tol)
                    if a.converged:
                        period = 1
                        break
                elif smooth_2d and count - a.jumped_at >= 3:
                    a, t, y = fixed_point(a, history, count, t, y, data, p)
            if jump_early and count == 3:  # the next section, refined, is to confirm it
                t, y = land(aitken_jump(history, 2), t, y, data, p, history, count - 1)
                refine = jumped = True
            speed = striker_speed(t, y, data, p)
            t_start, phi_start = t, rotor_angle(t, y)
            s = section(t, y, data, p, r, settings, refine, no_tangent, int(0))
            cost = add(cost, s.cost)
            if s.outcome != SEQUENCE_CYCLE:
                return ended(no_cycle(s.outcome, s.chatter, count, cost,
                                      key_of(t, y, data, p)), count, t, y, data, a)
            t, y, data = s.t, s.y, s.data
            if refine:
                # one impact a cycle on a smooth map: no edge, the multiplier in closed form
                speculative = Steady(
                    outcome=SEQUENCE_CYCLE, period=1, chatter=s.chatter,
                    amplitude=s.amplitude, flight_time=s.flight_time,
                    rotor_angle=rotor_angle(t, y) - phi_start, elapsed=t - t_start,
                    speed=speed, peak=s.peak, impacts=0, cost=NO_COST,
                    margins=Margins(speed, speed, math.inf, math.nan, math.nan),
                    key=key_of(t, y, data, p))
            if constant:
                return ended(Steady(
                    outcome=SEQUENCE_CYCLE, period=1, chatter=s.chatter,
                    amplitude=s.amplitude, flight_time=s.flight_time,
                    rotor_angle=speculative.rotor_angle, elapsed=speculative.elapsed,
                    speed=striker_speed(t, y, data, p), peak=s.peak, impacts=1, cost=cost,
                    margins=speculative.margins, key=speculative.key), count, t, y, data, a)
        return Transient(ended=bool(False), steady=speculative, count=count, period=period, t=t,
                         y=y, data=data, cost=cost, acceleration=a, jumped=jumped)

    return transient


def make_steady(c, jump_early, transient, cycle, second_stage=True):
    """The whole sequence of a Contact: ``steady(p, data, r, settings, repeat_tol, log,
    start, known) -> (Steady, t, y, data)`` from a starting state (see the module
    docstring), and ``settle(p, data, r, settings, repeat_tol, log, t, y, known)`` the
    same from the state (t, y, data); each also returns the state its cycle ran from."""
    first, key_of, from_key, smooth = c.first, c.key, c.from_key, c.smooth

    # one caller (steady) where no second stage goes on from a state: inlined into it, one
    # function fewer to compile
    @njit(**(INNER_OPTIONS if second_stage else INLINE_OPTIONS))
    def settle(p, data, r, settings, repeat_tol, log, t, y, known):
        """The sequence from (t, y, data) to its steady cycle, within settings.max_impacts,
        its cycle's section states repeating to ``repeat_tol``; log[j] gets (rotor angle
        mod 2 pi, psi) at section j (the last row takes any beyond). It stops at a section
        state of a cycle in ``known`` (known_attractor), and reports that cycle's outcome,
        period, chatter and this section state, without its values. Returns the Steady and
        the state on the cycle its values were run from (where the sequence ended, without
        one)."""
        history = np.empty((settings.max_impacts + 2, len(key_of(t, y, data, p))))
        tr = transient(p, data, r, settings, repeat_tol, log, t, y, history, known)
        if tr.ended:
            return tr.steady, tr.t, tr.y, tr.data
        count, period, a, cost = tr.count, tr.period, tr.acceleration, tr.cost
        t, y, data = tr.t, tr.y, tr.data
        impacts = count - 2 * period
        if smooth:  # (a map without jumps: pruned, as in the transient)
            if a.first_jump > 0 and period == 1:  # the impacts from rest, not the sections
                impacts = impacts_past_jump(a.jac, a.first_jump - 1, a.x_rest,
                                            (history[count - 1, 0], history[count - 1, 1]),
                                            repeat_tol, IMPACTS_COUNTED)
        if period == 0:
            return no_cycle(not_periodic(history, count), False, settings.max_impacts, cost,
                            key_of(t, y, data, p)), t, y, data
        if tr.jumped and period == 1 and tr.steady.outcome == SEQUENCE_CYCLE:
            return of_cycle(1, tr.steady, impacts, cost), t, y, data
        # the steady cycle from where the sequence is (on the cycle, to tol); at period 1 on
        # a smooth map from Aitken's extrapolation of the last three sections instead, kept
        # if the cycle's residual beats the last iteration's step (H13)
        last_step = 0.0
        for i in range(history.shape[1]):
            last_step = max(last_step, abs(history[count - 1, i] - history[count - 2, i]))
        t_run, y_run = t, y
        extrapolated = False
        if smooth:
            extrapolated = period == 1 and count >= 3 and not jump_early and not a.converged
            if extrapolated:
                t_run, y_run = from_key(aitken_jump(history, count - 1), t, y, data, p)
        result = cycle(t_run, y_run, data, p, r, settings, period)
        cost = add(cost, result.cost)
        if extrapolated and result.residual > last_step:
            t_run, y_run = t, y
            result = cycle(t, y, data, p, r, settings, period)
            cost = add(cost, result.cost)
        if a.converged and result.residual > repeat_tol * max(
                1.0, abs(history[count - 1, 0]), abs(history[count - 1, 1])):
            t_run, y_run = a.t_orbit, a.y_orbit
            result = cycle(a.t_orbit, a.y_orbit, data, p, r, settings, period)
            cost = add(cost, result.cost)
        if result.outcome != SEQUENCE_CYCLE:  # the cycle did not repeat after all
            return (no_cycle(SEQUENCE_MAX_STEPS, result.chatter, impacts, cost, result.key),
                    t_run, y_run, data)
        return of_cycle(period, result, impacts, cost), t_run, y_run, data

    @njit(**INNER_OPTIONS)
    def steady(p, data0, r, settings, repeat_tol, log, start, known):
        """The sequence from starting state number ``start`` (0: at rest, the tool's
        ``first``), as ``settle``."""
        t, y, data = first(p, data0, start)
        return settle(p, data, r, settings, repeat_tol, log, t, y, known)

    return steady, settle

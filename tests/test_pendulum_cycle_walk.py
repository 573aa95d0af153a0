"""The time histories and loads of a steady cycle the integration core found (issue 64 item 3:
every model on the blade, and cycles of any period), each against an independent method
(tests/blade_reference.py simulates the rigid model's regimes; here every model, its forces
and the face's reaction, from the geometry of tests/pendulum_twins.py):

- the impulses of an impact (through the hinge, the tool's, the drive's angular impulse)
  against a Newton-Euler solve of the striker written in the lab's Cartesian coordinates;
- the blade's cycle found again by SciPy (a shooting on the state after the cycle's first
  law, DOP853 at rtol 1e-12, its own faces and Newton law), the profiles compared to 1e-8,
  the hinge force and the drive's torque from the Cartesian acceleration of the striker's
  centre, the peaks by a dense search;
- the drive's work per cycle against the impacts' losses (the energy balance).
"""

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

import sweep
from kernels.pendulum import histories

from tests.pendulum_twins import beta, h_ratio, h_slope
from tests.test_pendulum_loads import L2, LOADS, MASS, PROFILES, dense_peak, geometry

OMEGA = 30.0


def perp(v):
    return np.array([-v[1], v[0]])


def cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


def newton_euler_impulses(l1, lc, jc, psi, dw, dpsi):
    """The striker (mass 1, hinge A at l1 on the rotor's arm along x, tip at 1 from A) in
    the lab: unknowns the hinge's impulse H on it and the tool's P along the normal n
    across the radius O -> tip; returns H on the rotor along and across the pendulum, P
    and the drive's angular impulse Delta H_O - r_tip x P n."""
    e1, e2 = np.array([1.0, 0.0]), np.array([math.cos(psi), math.sin(psi)])
    r_a, r_cm, r_tip = l1 * e1, l1 * e1 + lc * e2, l1 * e1 + e2
    n = perp(r_tip / np.linalg.norm(r_tip))
    spin = dw + dpsi
    dv = dw * perp(r_a) + spin * lc * perp(e2)
    rows = [[1.0, 0.0, n[0]], [0.0, 1.0, n[1]],
            [-(r_a - r_cm)[1], (r_a - r_cm)[0], cross(r_tip - r_cm, n)]]
    hx, hy, p = np.linalg.solve(rows, [dv[0], dv[1], jc * spin])
    h = np.array([hx, hy])
    moment = jc * spin + cross(r_cm, dv)
    return -h @ e2, -h @ perp(e2), p, moment - cross(r_tip, p * n)


def test_an_impacts_impulses_against_newton_euler_in_the_lab():
    rng = np.random.default_rng(641)
    for _ in range(200):
        k, xi, kappa = rng.uniform(0.3, 4.0), rng.uniform(0.2, 5.0), rng.uniform(0.5, 2.0)
        psi, dw, dpsi = rng.uniform(-1.2, 1.2), rng.normal(), rng.normal(scale=3.0)
        l1, lc, jc = geometry(k, xi, kappa)
        got = histories.impact_impulses(histories.Striker(l1, lc, jc), psi, dw, dpsi)
        want = newton_euler_impulses(l1, lc, jc, psi, dw, dpsi)
        np.testing.assert_allclose(tuple(got), want, rtol=1e-12, atol=1e-12)


# ---------------------------------------------------------------- the blade, by SciPy

def h_of(psi, k):
    return h_ratio(psi, k), h_slope(psi, k)


class Striker:
    """A model's striker in the lab (m = 1, l2 = 1, omega1 = 1; state (phi1, phi1', psi,
    psi')): its free and face-held accelerations, and the face's force F on its tip from
    Newton-Euler about the hinge A (the paper's equation is not a rigid body's: there F is
    what moves its psi'' off the free one through the striker's inertia about A)."""

    def __init__(self, model, k, xi, kappa, j1=None, slope=None, idle=None):
        self.model, self.k = model, k
        self.l1, self.lc, self.jc = geometry(k, xi, kappa)
        self.ia = self.jc + self.lc ** 2
        self.xi, self.kappa, self.j1, self.slope, self.idle = xi, kappa, j1, slope, idle

    def mass_and_forces(self, w, psi, v):
        l1, lc, jc = self.l1, self.lc, self.jc
        c, s = math.cos(psi), math.sin(psi)
        big_j1, big_slope = self.j1 * jc, self.slope * jc
        m12 = jc + lc * lc + l1 * lc * c
        m = np.array([[big_j1 + jc + l1 * l1 + lc * lc + 2 * l1 * lc * c, m12],
                      [m12, jc + lc * lc]])
        g = np.array([big_slope * (self.idle - w) + l1 * lc * s * (2 * w * v + v * v),
                      -l1 * lc * s * w * w])
        return m, g

    def free(self, y):
        phi, w, psi, v = y
        if self.model == "rotor":
            return np.linalg.solve(*self.mass_and_forces(w, psi, v))
        k = self.k
        if self.model == "rigid":
            return np.array([0.0, -self.kappa * k * math.sin(psi)])
        x = k * k + 1 + 2 * k * math.cos(psi)
        return np.array([0.0, -k * x / (1 + self.xi * x) * (v * v + self.xi) * math.sin(psi)])

    def on_face(self, y):
        """(phi1'', psi'') held on the face, G'' = phi1'' + h psi'' + h' psi'^2 = 0."""
        phi, w, psi, v = y
        h, dh = h_of(psi, self.k)
        if self.model != "rotor":
            return np.array([0.0, -dh * v * v / h])
        m, g = self.mass_and_forces(w, psi, v)
        kkt = np.array([[m[0, 0], m[0, 1], -1.0], [m[1, 0], m[1, 1], -h], [1.0, h, 0.0]])
        return np.linalg.solve(kkt, [g[0], g[1], -dh * v * v])[:2]

    def frame(self, y):
        phi, w, psi, v = y
        e1 = np.array([math.cos(phi), math.sin(phi)])
        e2 = np.array([math.cos(phi + psi), math.sin(phi + psi)])
        return e1, e2

    def loads(self, y, acc, held):
        """The hinge's force on the rotor (along, across the pendulum), the face's force F
        and the drive's torque (m l2 omega1^2 units)."""
        phi, w, psi, v = y
        e1, e2 = self.frame(y)
        r_a, r_tip = self.l1 * e1, self.l1 * e1 + e2
        r_cm = r_a + self.lc * e2
        a_a = self.l1 * (acc[0] * perp(e1) - w * w * e1)
        w2, a2 = w + v, acc[0] + acc[1]
        a_cm = a_a + self.lc * (a2 * perp(e2) - w2 * w2 * e2)
        n = perp(r_tip / np.linalg.norm(r_tip))
        force = 0.0
        if held:
            if self.model == "paper":
                free = self.free(y)[1]
                h = h_of(psi, self.k)[0]
                force = self.ia * (acc[1] - free) / (np.linalg.norm(r_tip) * h)
            else:  # Newton-Euler about A: I_A a2 + m (r_cm - r_A) x a_A = (r_tip - r_A) x F n
                force = (self.ia * a2 + self.lc * cross(e2, a_a)) / cross(e2, n)
        hinge = -(a_cm - force * n)
        if self.model == "rotor":
            torque = self.slope * self.jc * (self.idle - w)
        else:  # dH_O/dt less F's moment about O
            torque = self.jc * a2 + cross(r_cm, a_cm) - cross(r_tip, force * n)
        return hinge @ e2, hinge @ perp(e2), force, torque

    def pressing(self, y, side):
        phi, w, psi, v = y
        h, dh = h_of(psi, self.k)
        a = self.free(y)
        return side * (a[0] + h * a[1] + dh * v * v)

    def plastic(self, y):
        """Newton's law at R = 0 on the normal speed G' = phi1' + h psi'."""
        phi, w, psi, v = y
        h = h_of(psi, self.k)[0]
        if self.model != "rotor":
            return np.array([phi, w, psi, -w / h])
        m = self.mass_and_forces(w, psi, v)[0]
        kkt = np.array([[m[0, 0], m[0, 1], -1.0], [m[1, 0], m[1, 1], -h], [1.0, h, 0.0]])
        dw, dv, _ = np.linalg.solve(kkt, [0.0, 0.0, -(w + h * v)])
        return np.array([phi, w + dw, psi, v + dv])


def blade_cycle(striker, y0, side, window, period, until=math.inf):
    """The cycle at R = 0 from the state y0 after its first law (on the face G = 0, met
    rising: side 1, or falling: -1): slide where pressed, fly, meet the face and so on for
    ``period`` sections (a flight of 0.1 or longer ends one); returns the stretches (t0,
    t1, sol, held), each a SciPy solution, the state after the last law and its side; with
    ``until``, the stretches up to that time only."""
    opts = dict(method="DOP853", rtol=1e-12, atol=1e-13, dense_output=True)
    k = striker.k
    t, y, level, stretches, sections = 0.0, np.array(y0, float), 0.0, [], 0

    def g_of(yy):
        return yy[0] + beta(yy[2], k)

    def held(tt, yy):
        a = striker.on_face(yy)
        return [yy[1], a[0], yy[3], a[1]]

    def free(tt, yy):
        a = striker.free(yy)
        return [yy[1], a[0], yy[3], a[1]]

    while sections < period:
        def release(tt, yy):
            return striker.pressing(yy, side)

        def edge(tt, yy):
            return abs(yy[2]) - window
        release.terminal = edge.terminal = True
        release.direction, edge.direction = -1, 1
        off_edge = False
        if striker.pressing(y, side) > 0:
            sol = solve_ivp(held, (t, t + 50), y, events=[release, edge], **opts)
            stretches.append((t, sol.t[-1], sol, True))
            if sol.t[-1] >= until:
                return stretches, None, None
            off_edge = len(sol.t_events[1]) > 0
            t, y = sol.t[-1], sol.y[:, -1]
        # as the blade's flight_data: past the face off its edge, else behind or ahead
        lower = level if off_edge or side < 0 else level - 2 * math.pi
        start = t
        while True:  # a flight, passing the faces met outside the blade's reach
            def up(tt, yy):
                return g_of(yy) - (lower + 2 * math.pi)

            def down(tt, yy):
                return g_of(yy) - lower
            up.terminal = down.terminal = True
            up.direction, down.direction = 1, -1
            sol = solve_ivp(free, (t, t + 200), y, events=[up, down], **opts)
            hit = [(te, e) for e, times in enumerate(sol.t_events) for te in times
                   if te > t + 1e-9]
            assert hit, "no face met"
            te, e = min(hit)
            stretches.append((t, te, sol, False))
            if te >= until:
                return stretches, None, None
            t, y = te, sol.sol(te)
            level = lower + 2 * math.pi if e == 0 else lower
            side = 1.0 if e == 0 else -1.0
            if abs(y[2]) <= window:
                break
            lower = level if e == 0 else lower - 2 * math.pi
        if t - start >= 0.1:
            sections += 1
        y = striker.plastic(y)
    return stretches, y, side


def state_at(stretches, tau):
    """The state at tau of a cycle's stretches, and whether it is held on the face."""
    t0, t1, sol, held = next(s for s in stretches if s[0] <= tau <= s[1])
    return sol.sol(tau), held


def run_blade(model, grid, **fixed):
    return sweep.decode(sweep.run({
        "mechanism": "rotary_pendulum", "grid": grid,
        "fixed": {"model": model, "tool": "lab_window", "R": 0.0, "omega1": OMEGA, "l2": L2,
                  "striker_mass": MASS, **fixed},
        "outputs": ["amplitude", "impact_interval", "regime", "rotor_speed_ratio", *LOADS,
                    *PROFILES],
        "method": {"profile_points": 40, "tol": 1e-11, "max_impacts": 300}}))


def check_against_scipy(point, striker, window):
    """The atlas's cycle at this point against SciPy's from its first phase (see the
    module docstring); returns the period."""
    w1 = OMEGA
    force, torque = MASS * L2 * w1 ** 2, MASS * L2 ** 2 * w1 ** 2
    psi0, v0 = float(point.swing_angle[0]), float(point.swing_rate[0]) / w1
    times = point.time.values * w1
    rotor = striker.model == "rotor"
    turned = float(point.rotor_angle[-1] + point.rotor_angle[0])  # over the cycle
    period = round(turned / float(point.impact_interval))

    def on_face(u):  # after a plastic law on the face G = 0: G' = 0
        psi, w = u[0], (u[1] if rotor else 1.0)
        return [-beta(psi, striker.k), w, psi, -w / h_of(psi, striker.k)[0]]

    def first_phase(u, side, until=math.inf):
        stretches, end, last = blade_cycle(striker, on_face(u), side, window, period, until)
        return state_at(stretches, times[0])[0], stretches, end, last

    def residual(u, side):
        y = first_phase(u, side, times[0])[0]
        return [y[2] - psi0, y[3] - v0] if rotor else [y[2] - psi0]

    # SciPy's cycle from the law's state that reaches the atlas's first phase, found by a
    # shooting started where a free flight back from that phase meets tau = 0, on the side
    # that gets there
    w_guess = float(point.rotor_speed_ratio) if rotor else 1.0
    back = solve_ivp(lambda t, y: [y[1], *striker.free(y)[:1], y[3], *striker.free(y)[1:]],
                     (times[0], 0.0), [0.0, w_guess, psi0, v0], method="DOP853", rtol=1e-12,
                     atol=1e-13)
    guess = [back.y[2, -1], back.y[1, -1]] if rotor else [back.y[2, -1]]
    shots = []
    for side in (1.0, -1.0):
        with warnings.catch_warnings():  # the other side's shooting need not converge
            warnings.simplefilter("ignore", RuntimeWarning)
            u = fsolve(residual, guess, args=(side,), xtol=1e-13)
        y_first = first_phase(u, side, times[0])[0]
        miss = abs(y_first[2] - psi0) + abs(y_first[3] - v0)
        if miss < 1e-6:  # it reaches the first phase: is it a cycle, its last contact
            cycle = first_phase(u, side)  # on the side of its first?
            if cycle[3] == side:
                shots.append((miss, side, tuple(u), cycle))
    _, side, u, (y_first, stretches, end, last) = min(shots)
    np.testing.assert_allclose(y_first[2:], [psi0, v0], atol=1e-9)
    t_end = stretches[-1][1]
    np.testing.assert_allclose(times[-1] + times[0], t_end, rtol=1e-8)
    # the cycle closes: the last law leaves the state of the first one, faces on
    np.testing.assert_allclose(end[1:], on_face(u)[1:], atol=1e-7)
    for i, tau in enumerate(times):
        y, held = state_at(stretches, tau)
        acc = striker.on_face(y) if held else striker.free(y)
        along, across, _, drive = striker.loads(y, acc, held)
        np.testing.assert_allclose(float(point.swing_angle[i]), y[2], atol=1e-8)
        np.testing.assert_allclose(float(point.swing_rate[i]) / w1, y[3], atol=1e-8)
        np.testing.assert_allclose(float(point.swing_acceleration[i]) / w1 ** 2, acc[1],
                                   atol=1e-8 * max(1.0, abs(acc[1])))
        np.testing.assert_allclose(float(point.hinge_force_along[i]) / force, along,
                                   atol=1e-7 * max(1.0, abs(along)))
        np.testing.assert_allclose(float(point.hinge_force_across[i]) / force, across,
                                   atol=1e-7 * max(1.0, abs(across)))
        np.testing.assert_allclose(float(point.drive_torque[i]) / torque, drive,
                                   atol=1e-7 * max(1.0, abs(drive)))
    return period, stretches


def check_loads(point, striker, stretches):
    """The peaks against a dense search along SciPy's cycle; the drive's work balances the
    impacts' losses (the rigid bodies: the paper's equation is not one)."""
    force, torque = MASS * L2 * OMEGA ** 2, MASS * L2 ** 2 * OMEGA ** 2

    def loads_at(t, held, sol):
        y = sol.sol(t)
        return striker.loads(y, striker.on_face(y) if held else striker.free(y), held)

    span = stretches[-1][1] - stretches[0][0]

    def samples(t0, t1):  # 1000 over the cycle, at least 12 on each stretch
        return max(12, int(1000 * (t1 - t0) / span))

    hinge = max(dense_peak(lambda t: math.hypot(*loads_at(t, held, sol)[:2]), t1,
                           samples(t0, t1), t0) for t0, t1, sol, held in stretches)
    drive = max(dense_peak(lambda t: abs(loads_at(t, held, sol)[3]), t1, samples(t0, t1), t0)
                for t0, t1, sol, held in stretches)
    np.testing.assert_allclose(float(point.hinge_force_peak) / force, hinge, rtol=1e-7)
    np.testing.assert_allclose(float(point.drive_torque_peak) / torque, drive, rtol=1e-7)
    if striker.model != "paper":
        assert abs(float(point.energy_balance_error)) < 1e-7
    assert float(point.hinge_impulse) > 0.0 and np.isfinite(float(point.drive_power_mean))


def test_the_rigid_striker_on_the_blade_against_scipy():
    ds = run_blade("rigid", {"k": [1.0]}, kappa=1.2, tool_window=0.3)
    point = ds.isel(k=0)
    assert str(point.regime.values) == "period_1" and str(point.status.values) == "ok"
    striker = Striker("rigid", 1.0, 4.0, 1.2)
    period, stretches = check_against_scipy(point, striker, 0.3)
    assert period == 1
    check_loads(point, striker, stretches)


@pytest.mark.slow
@pytest.mark.parametrize("model", ["paper", "rigid", "rotor"])
def test_every_model_on_the_blade_against_scipy_at_random_designs(model):
    rng = np.random.default_rng({"paper": 1, "rigid": 2, "rotor": 3}[model])
    checked = periods = 0
    for _ in range(6):
        k, window = float(rng.uniform(0.6, 2.0)), float(rng.uniform(0.15, 0.6))
        xi, kappa = float(rng.uniform(2.0, 6.0)), float(rng.uniform(1.05, 1.5))
        extra = {"xi": xi} if model == "paper" else {"xi": xi, "kappa": kappa}
        rotor = {}
        if model == "rotor":
            rotor = dict(rotor_inertia_ratio=float(rng.uniform(5, 30)),
                         motor_slope=float(rng.uniform(2, 20)), idle_speed=1.0)
        ds = run_blade(model, {"k": [k]}, tool_window=window, **extra, **rotor)
        point = ds.isel(k=0)
        if str(point.status.values) != "ok" or str(point.regime.values) not in ("period_1",
                                                                                "period_n"):
            assert np.isnan(point.hinge_force.values).all()
            continue
        striker = Striker(model, k, xi, kappa if model != "paper" else xi / (1 + xi),
                          rotor.get("rotor_inertia_ratio"), rotor.get("motor_slope"), 1.0)
        period, stretches = check_against_scipy(point, striker, window)
        periods += period > 1
        check_loads(point, striker, stretches)
        checked += 1
    assert checked >= 3 and periods >= 1  # cycles of period 1 and of more

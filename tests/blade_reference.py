"""An independent simulation of the rigid pendulum on the lab-fixed blade at constant rotor
speed, written from the physics with SciPy, for the blade's margins, chatter, slides,
multipliers and attractors (issue 37).

The striker's polar angle G = phi1 + beta(psi) (phi1 = t, the rotor angle) meets the blade
at G = 2 pi n, from below (the working face, side +1) or from above (side -1), where
|psi| <= window; beyond the reach it passes. Free flight psi'' = -kappa k sin psi, by DOP853
at rtol = atol = 1e-12, its first step after a bounce capped at a quarter of the ballistic
return time (else SciPy steps over a short bounce). A contact: Newton's law on G' (the
driven rotor does not move); a bounce leaving slower than SPEED_EPS / R ends the chatter at
its accumulation point (the ballistic tail 2 R v / (|G''| (1 - R))), and a plastic contact
pressed into the face rides it: on the face beta(psi) = level - t, psi' = -1/h, until the
free G'' stops pressing (found by Brent's method on a 400-point scan) or psi reaches
-window (off the edge, past the face); a release whose free path turns back into the face
at third order touches it again at zero speed. A section is a contact after a flight of at least
0.1 rotor rad. None of the integration core is used (only the
kernel's Halton points, to start where its starts do).
"""

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from kernels.impact.attractors import radical_inverse  # the kernel's starts, as stated
from tests.pendulum_twins import beta, h_ratio as h, h_slope, rigid_acceleration

TWO_PI = 2.0 * math.pi
SPEED_EPS = 1e-7
MIN_FLIGHT = 0.1
TIGHT = dict(method="DOP853", rtol=1e-12, atol=1e-12)


class Blade:
    def __init__(self, k, kappa, r, window):
        self.k, self.kappa, self.r, self.window = k, kappa, r, window

    def rhs(self, t, y):
        return [y[1], rigid_acceleration(y[0], self.k, self.kappa)]

    def gap_rate(self, y):
        return 1.0 + h(y[0], self.k) * y[1]

    def free_gap_acceleration(self, y):
        return (h(y[0], self.k) * rigid_acceleration(y[0], self.k, self.kappa)
                + h_slope(y[0], self.k) * y[1] ** 2)

    def free_gap_jerk(self, y):
        """The third derivative of G on the free motion: h'' psi'^3 + 3 h' psi' psi'' +
        h psi3 (h'' by a central difference of h', psi3 the third derivative)."""
        k, psi, v = self.k, y[0], y[1]
        a = rigid_acceleration(psi, k, self.kappa)
        jerk = -self.kappa * k * math.cos(psi) * v
        d = 1e-5
        h2 = (h_slope(psi + d, k) - h_slope(psi - d, k)) / (2 * d)
        return h2 * v ** 3 + 3 * h_slope(psi, k) * v * a + h(psi, k) * jerk

    def striker_speed(self, y):
        k = self.k
        return math.sqrt(k * k + 1 + 2 * k * math.cos(y[0])) * abs(self.gap_rate(y))

    def pressing(self, psi, side):
        """side * G''_free on the face at psi (riding it: psi' = -1/h): > 0 keeps contact."""
        return side * self.free_gap_acceleration((psi, -1.0 / h(psi, self.k)))

    def on_face(self, t, level, near):
        """psi on the face G = level at rotor angle t, the root of beta(psi) = level - t
        next to ``near`` (beta is monotone in psi for |psi| < pi/2 when k > 1)."""
        target = level - t
        f = lambda q: beta(q, self.k) - target
        lo, hi = near - 0.05, near + 0.05
        for _ in range(60):
            if f(lo) * f(hi) <= 0:
                break
            lo, hi = lo - 0.05, hi + 0.05
        return brentq(f, lo, hi, xtol=1e-15)

    # ------------------------------------------------------------------ the pieces

    def flight(self, t, y, up, cap=None, horizon=200 * math.pi):
        """Free flight to the first face met within reach, or escape, or the horizon:
        (kind, t, y, up, side, amplitude) with kind in 'contact', 'escape', 'none', and
        amplitude the largest |psi| on the way (at its ends and turning points)."""
        t0 = t
        amplitude = abs(y[0])
        while True:
            def rising(tt, yy):
                return (tt - up) + beta(yy[0], self.k)

            def falling(tt, yy):
                return (tt - (up - TWO_PI)) + beta(yy[0], self.k)

            def escape(tt, yy):
                return abs(yy[0]) - math.pi

            def turning(tt, yy):
                return yy[1]
            rising.terminal, rising.direction = True, 1.0
            falling.terminal, falling.direction = True, -1.0
            escape.terminal, escape.direction = True, 1.0
            turning.terminal = False
            sol = solve_ivp(self.rhs, (t, t0 + horizon), list(y),
                            events=[rising, falling, escape, turning], first_step=cap,
                            **TIGHT)
            turns = np.reshape(sol.y_events[3], (-1, 2))
            amplitude = max(amplitude, np.max(np.abs(turns[:, 0]), initial=0.0))
            hits = [(sol.t_events[i][0], i, sol.y_events[i][0]) for i in range(3)
                    if sol.t_events[i].size]
            if not hits:
                return "none", sol.t[-1], sol.y[:, -1], up, 0.0, amplitude
            te, i, ye = min(hits, key=lambda x: x[0])
            amplitude = max(amplitude, abs(ye[0]))
            if i == 2:
                return "escape", te, ye, up, 0.0, amplitude
            side = 1.0 if i == 0 else -1.0
            level = up if i == 0 else up - TWO_PI
            if abs(ye[0]) <= self.window:
                return "contact", te, ye, up, side, amplitude
            up += side * TWO_PI  # beyond the blade's reach: passed
            t, y, cap = te, ye, None
            del level

    def slide(self, t, y, level, side):
        """Ride the face from psi_c down towards -window: (t, y, released)."""
        psi_c, end = y[0], -self.window
        grid = np.linspace(psi_c, end, 401)[1:]
        prev = psi_c
        released = False
        for q in grid:
            if self.pressing(q, side) <= 0.0:
                if self.pressing(prev, side) <= 0.0:
                    end = prev
                else:
                    end = brentq(lambda x: self.pressing(x, side), q, prev, xtol=1e-15)
                released = True
                break
            prev = q
        t_end = level - beta(end, self.k)
        return t_end, np.array([end, -1.0 / h(end, self.k)]), released

    # ------------------------------------------------------------- the sequence

    def run(self, t, y, up, side, sections, stop_at_cycle=True, max_period=12,
            max_contacts=20000):
        """From a pre-impact state on a face (G = the face, met from ``side``): the
        contacts in order until ``sections`` sections, or a cycle of the section keys
        (psi, G') repeating to 1e-9. Returns a dict: outcome ('cycle', 'escape', 'none',
        'budget'), period, and per section: key, opening striker speed, rotor angle,
        chatter, contact speeds and edge distances."""
        secs = []
        cap = None
        flight_time = math.inf
        for _ in range(max_contacts):
            level = up if side > 0 else up - TWO_PI
            if flight_time >= MIN_FLIGHT:
                if len(secs) >= sections:
                    return dict(outcome="budget", sections=secs, period=0)
                secs.append(dict(key=(y[0], self.gap_rate(y)), t=t, side=side,
                                 speed=self.striker_speed(y), speeds=[], edges=[],
                                 chatter=False))
                period = _period(secs, max_period) if stop_at_cycle else 0
                if period:
                    return dict(outcome="cycle", sections=secs, period=period)
            sec = secs[-1]
            sec["speeds"].append(self.striker_speed(y))
            sec["edges"].append(self.window - abs(y[0]))
            approach = side * self.gap_rate(y)
            zeno = self.r * abs(approach) < SPEED_EPS if self.r > 0 else \
                abs(approach) < SPEED_EPS
            if zeno and self.r > 0:
                sec["chatter"] = True
                g2 = abs(self.free_gap_acceleration(y))
                if g2 > 0.0:  # else no accumulation point: the law acts at the contact
                    t = t + 2 * self.r * abs(approach) / (g2 * (1 - self.r))
                    psi = self.on_face(t, level, y[0])
                    y = np.array([psi, -1.0 / h(psi, self.k)])
            gap_after = 0.0 if (zeno or self.r == 0) else -self.r * self.gap_rate(y)
            y = np.array([y[0], (gap_after - 1.0) / h(y[0], self.k)])
            cap = None
            if gap_after == 0.0:
                psi = y[0]
                now = self.pressing(psi, side)
                pressed = now > 0 if abs(now) > 1e-9 else self.pressing(psi - 1e-6, side) > 0
                if pressed:
                    t, y, released = self.slide(t, y, level, side)
                    if not released:
                        up += side * TWO_PI  # off the edge: past the face
                    elif side * self.free_gap_jerk(y) > 0.0:
                        # released where the pressing vanishes (G' = G'' = 0), but the free
                        # path turns back into the face at third order: it touches again
                        # at once, at zero speed (a graze no event search can see)
                        sec["speeds"].append(0.0)
                        sec["edges"].append(self.window - abs(y[0]))
            else:
                g2 = abs(self.free_gap_acceleration(y)) + 1e-300
                cap = min(max(0.25 * abs(gap_after) / g2, 1e-14), 0.5)
            t_start = t
            kind, t, y, up, side, amplitude = self.flight(t, y, up, cap)
            sec["amplitude"] = max(sec.get("amplitude", 0.0), amplitude)
            if kind != "contact":
                return dict(outcome=kind, sections=secs, period=0)
            flight_time = t - t_start
        return dict(outcome="contacts", sections=secs, period=0)

    def from_start(self, j, sections):
        """Start j as the kernel's blade states them: 0 at rest on the working face; j > 0
        on it at psi = window (2 x3_j - 1), closing at G' = 2 x2_j (Halton points)."""
        psi = dpsi = 0.0
        if j > 0:
            psi = self.window * (2 * radical_inverse(j, 3) - 1)
            dpsi = (2 * radical_inverse(j, 2) - 1) / h(psi, self.k)
        return self.run(-beta(psi, self.k), np.array([psi, dpsi]), 0.0, 1.0, sections)


def _period(secs, max_period, tol=1e-9):
    keys = np.array([s["key"] for s in secs])
    n = len(keys)
    for p in range(1, max_period + 1):
        if n < 2 * p + 1:
            return 0
        a, b = keys[n - p:], keys[n - 2 * p:n - p]
        if np.all(np.abs(a - b) <= tol * np.maximum(1.0, np.abs(a))):
            return p
    return 0


def cycle_values(result):
    """The steady cycle's values, as the atlas gives them at omega1 = l2 = 1: the mean
    opening impact speed, the rotor angle per section, the slowest over the fastest
    contact, the least edge distance, the largest |psi| (amplitude), and whether it
    chatters."""
    p = result["period"]
    secs = result["sections"][-p - 1:-1]
    last = result["sections"][-1]
    speeds = [v for s in secs for v in s["speeds"]]
    return dict(impact_speed=np.mean([s["speed"] for s in secs]),
                impact_interval=(last["t"] - secs[0]["t"]) / p,
                impact_speed_min_ratio=min(speeds) / max(speeds),
                edge_margin=min(e for s in secs for e in s["edges"]),
                amplitude=max(s["amplitude"] for s in secs),
                chatter=any(s["chatter"] for s in secs), period=p)


def section_map(blade, key, up, side, period):
    """The p-fold section map from a section key (psi, G') on the face ``up`` met from
    ``side``: the key ``period`` sections later."""
    psi, rate = key
    level = up if side > 0 else up - TWO_PI
    t = level - beta(psi, blade.k)
    y = np.array([psi, (rate - 1.0) / h(psi, blade.k)])
    out = blade.run(t, y, up, side, period + 1, stop_at_cycle=False)
    assert out["outcome"] == "budget", out["outcome"]
    return np.array(out["sections"][period]["key"])


def leading_multiplier(blade, result, eps=1e-6):
    """|mu| of the p-fold section map's Jacobian by central differences at the cycle's
    last section."""
    p = result["period"]
    key = np.array(result["sections"][-1]["key"])
    side = result["sections"][-1]["side"]
    jac = np.empty((2, 2))
    for i in range(2):
        step = eps * max(1.0, abs(key[i]))
        plus, minus = key.copy(), key.copy()
        plus[i] += step
        minus[i] -= step
        jac[:, i] = (section_map(blade, plus, 0.0, side, p)
                     - section_map(blade, minus, 0.0, side, p)) / (2 * step)
    return float(np.max(np.abs(np.linalg.eigvals(jac))))

"""SciPy twins of the pendulum systems: each model's vector field in the kernel's state
layout, the blade's geometry, and each tool's event functions, written again with numpy and
integrated by DOP853 at rtol = atol = 1e-13, independent of the integration core. The one
home of the reference systems: the hard-case tests, the model tests
(tests/test_pendulum_models.py) and the blade twin (tests/blade_reference.py) take their
vector fields and geometry from here.

State layouts (as in kernels/pendulum/models.py): the paper and rigid models (psi, psi')
with the rotor angle as the time; the rotor model (phi1, phi1', psi, psi') in time omega1 t.
"""

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

XI = 4.0
TIGHT = dict(method="DOP853", rtol=1e-13, atol=1e-13)


def paper_acceleration(psi, dpsi, k, xi):
    """psi'' of [RP]'s equation (P1-P2)."""
    x = k ** 2 + 1 + 2 * k * math.cos(psi)
    return -k * x / (1 + xi * x) * (dpsi ** 2 + xi) * math.sin(psi)


def rigid_acceleration(psi, k, kappa):
    """psi'' of the rigid pendulum at constant rotor speed (P5)."""
    return -kappa * k * math.sin(psi)


def rotor_mass(psi, xi, kc, j1):
    """The rotor model's mass matrix on (phi1, psi), lengths in l_cm, inertias in J_c."""
    c = math.cos(psi)
    return np.array([[j1 + 1 + xi * (kc * kc + 1 + 2 * kc * c), 1 + xi * (1 + kc * c)],
                     [1 + xi * (1 + kc * c), 1 + xi]])


def rotor_forces(w, psi, dpsi, xi, kc, slope, idle):
    """The rotor model's generalized forces: the motor law and the velocity terms."""
    g = xi * kc * math.sin(psi)
    return np.array([slope * (idle - w) + g * (2 * w * dpsi + dpsi ** 2), -g * w * w])


@dataclass
class Twin:
    """One model with its parameters: p in the kernel's convention, the vector field, the
    rotor angle and speed, the impulse response and Newton's law."""
    model: str
    k: float
    kappa: float = 1.2
    xi: float = XI
    j1: float = 30.0
    slope: float = 5.0
    idle: float = 1.0

    @property
    def driven(self):
        return self.model != "rotor"

    @property
    def k_cm(self):
        return self.k * self.kappa * (1 + 1 / self.xi)

    @property
    def p(self):
        if self.model == "paper":
            return (self.k, self.xi)
        if self.model == "rigid":
            return (self.k, self.kappa)
        return (self.k_cm, self.xi, self.j1, self.slope, self.idle)

    def state(self, psi, dpsi, phi1=0.0, w=None):
        w = self.idle if w is None else w
        return (psi, dpsi) if self.driven else (phi1, w, psi, dpsi)

    def psi(self, y):
        return y[0] if self.driven else y[2]

    def dpsi(self, y):
        return y[1] if self.driven else y[3]

    def rotor_angle(self, t, y):
        return t if self.driven else y[0]

    def rotor_speed(self, y):
        return 1.0 if self.driven else y[1]

    def mass(self, psi):
        return rotor_mass(psi, self.xi, self.k_cm, self.j1)

    def accelerations(self, y):
        """(phi1'', psi'') of the free motion."""
        if self.model == "paper":
            return 0.0, paper_acceleration(y[0], y[1], self.k, self.xi)
        if self.model == "rigid":
            return 0.0, rigid_acceleration(y[0], self.k, self.kappa)
        phi1, w, psi, dpsi = y
        forces = rotor_forces(w, psi, dpsi, self.xi, self.k_cm, self.slope, self.idle)
        return tuple(np.linalg.solve(self.mass(psi), forces))

    def rhs(self, t, y):
        a_phi, a_psi = self.accelerations(y)
        return [y[1], a_psi] if self.driven else [y[1], a_phi, y[3], a_psi]

    def restitute(self, y, jacobian, r):
        """Newton's law v_n+ = -r v_n- along J = (J_phi1, J_psi) through M^-1 J^T (a driven
        rotor does not move: the impulse changes psi' only)."""
        j = np.asarray(jacobian, float)
        x = np.array([0.0, 1.0]) if self.driven else np.linalg.solve(self.mass(self.psi(y)), j)
        v = np.array([self.rotor_speed(y), self.dpsi(y)])
        v = v - (1 + r) * (j @ v) / (j @ x) * x
        return (y[0], v[1]) if self.driven else (y[0], v[0], y[2], v[1])


def beta(psi, k):
    return math.atan2(math.sin(psi), k + math.cos(psi))


def h_ratio(psi, k):
    """h = dbeta/dpsi: the contact point's polar angle over psi."""
    return (1 + k * math.cos(psi)) / (k * k + 1 + 2 * k * math.cos(psi))


def h_slope(psi, k):
    """dh/dpsi."""
    return k * (1 - k * k) * math.sin(psi) / (k * k + 1 + 2 * k * math.cos(psi)) ** 2


def events(twin, tool, data):
    """The tool's event functions in the kernel's order (terminal, with directions)."""
    def make(f, direction):
        f.terminal, f.direction = True, direction
        return f

    if tool == "rotor_stop":
        return [make(lambda t, y: twin.psi(y), 1.0), make(lambda t, y: twin.psi(y) + math.pi,
                                                          -1.0)]
    if tool == "relative_stop":
        stop = data[0]
        return [make(lambda t, y: twin.psi(y) - stop, 1.0),
                make(lambda t, y: twin.psi(y) + math.pi, -1.0)]
    lower, k = data[0], data[2]

    def gap(t, y):
        return twin.rotor_angle(t, y) + beta(twin.psi(y), k)
    return [make(lambda t, y: gap(t, y) - (lower + 2 * math.pi), 1.0),
            make(lambda t, y: gap(t, y) - lower, -1.0),
            make(lambda t, y: abs(twin.psi(y)) - math.pi, 1.0)]


def first_event(twin, tool, t0, y0, data, t_max=60.0, first_step=None):
    """(time, event index, state) of the first event of the free flight that ends it, or
    None; on the blade a face met beyond its reach is passed (the faces move on), as the
    kernel does."""
    t, y, data = t0, list(y0), tuple(data)
    while True:
        sol = solve_ivp(twin.rhs, (t, t0 + t_max), y, events=events(twin, tool, data),
                        first_step=first_step, **TIGHT)
        hits = [(sol.t_events[i][0], i, sol.y_events[i][0]) for i in range(len(sol.t_events))
                if sol.t_events[i].size]
        if not hits:
            return None
        hit = min(hits, key=lambda h: h[0])
        if tool != "lab_window" or hit[1] == 2 or abs(twin.psi(hit[2])) <= data[1]:
            return hit
        t, y, first_step = hit[0], list(hit[2]), None
        lower = data[0] + (2 * math.pi if hit[1] == 0 else -2 * math.pi)
        data = (lower,) + data[1:]


def free_extremum(twin, t0, y0, rate, t_max=60.0):
    """(time, state) where ``rate(t, y)`` first falls through 0: the first maximum of the
    quantity whose rate it is; None if it does not within t_max."""
    def event(t, y):
        return rate(t, y)
    event.terminal, event.direction = True, -1.0
    sol = solve_ivp(twin.rhs, (t0, t0 + t_max), list(y0), events=[event], **TIGHT)
    return (sol.t_events[0][0], sol.y_events[0][0]) if sol.t_events[0].size else None


def chatter_reference(twin, tool, jacobian, t0, y0, data, r, speed_eps=1e-7,
                      max_impacts=1000):
    """Bounce by bounce with SciPy on the face of event 0 until a bounce would leave slower
    than speed_eps (r |v_n| < speed_eps), then the accumulation point by the ballistic tail
    2 r v/(g (1 - r)): (impacts, accumulation time)."""
    t, y = t0, tuple(y0)
    cap = _bounce_cap(twin, np.asarray(jacobian(t, y), float), y)  # a start on the tool too
    for impacts in range(1, max_impacts + 1):
        hit = first_event(twin, tool, t, y, data, first_step=cap)
        assert hit is not None and hit[1] == 0, hit
        t, y = hit[0], tuple(hit[2])
        j = np.asarray(jacobian(t, y), float)
        v_n = j @ [twin.rotor_speed(y), twin.dpsi(y)]
        if r * abs(v_n) < speed_eps:
            a_phi, a_psi = twin.accelerations(y)
            g2 = abs(j @ [a_phi, a_psi] + _jacobian_rate(twin, tool, y, data))
            return impacts, t + 2 * r * abs(v_n) / (g2 * (1 - r))
        y = twin.restitute(y, j, r)
        cap = _bounce_cap(twin, j, y)
    raise AssertionError("no accumulation")


def _jacobian_rate(twin, tool, y, data):
    """J' q' (the gap's acceleration beyond J q''): h' psi'^2 on the blade, 0 on a stop."""
    if tool != "lab_window":
        return 0.0
    k, psi, dpsi = data[2], twin.psi(y), twin.dpsi(y)
    return h_slope(psi, k) * dpsi * dpsi


def _bounce_cap(twin, j, y):
    """SciPy's first step after a bounce, at most a quarter of its ballistic return time:
    else it steps over the bounce (H3/H4)."""
    v_n = j @ [twin.rotor_speed(y), twin.dpsi(y)]
    a_phi, a_psi = twin.accelerations(y)
    g2 = abs(j @ [a_phi, a_psi]) + 1e-300
    return max(0.25 * abs(v_n) / g2, 1e-14) if v_n != 0.0 else None

"""How robust a pendulum design's steady regime is: the multipliers of its cycle's impact map
(carried by the variational equations, the event-time saltation and Newton's law
differentiated), the margins to chatter and to the blade's edge, and the attractors reached
from several starts.

Oracles: central differences of the section map through the same kernels (an independent
method: no tangent, only the map run twice per coordinate), the closed-form multiplier R of
the affine map on the rotor stop, numpy's eigenvalues, and the regime changes the atlas
itself reports (found by bisection here)."""

import math

import numpy as np
import pytest

from kernels.pendulum import systems
from kernels.pendulum.cases import CASE_COLUMNS
from kernels.pendulum.table import MODELS, TOOLS
from kernels.rotary_pendulum import DECLARATION as PENDULUM, REGIMES
from tests import probes
from tests.conftest import kernel_points

STABILITY = ("multiplier_modulus", "multiplier_angle", "stability_margin",
             "impact_speed_min_ratio")
ATTRACTORS = ("attractor_count", "basin_fraction")
CHATTER = REGIMES.index("chatter")


def outputs(*names, tool="lab_window"):
    extra = names + (("edge_margin",) if tool == "lab_window" else ())
    return PENDULUM.default_outputs + extra


def pendulum(method=None, names=STABILITY, **design):
    """The pendulum kernel on points (arrays or scalars), asking for the stability outputs."""
    method = dict(method or {})
    method["outputs"] = outputs(*names, tool=design.get("tool", "rotor_stop"))
    return kernel_points("rotary_pendulum", method, **design)


def leading(matrix):
    """The eigenvalue of largest modulus (the one with argument >= 0 of a complex pair)."""
    values = np.linalg.eigvals(np.atleast_2d(matrix))
    top = values[np.argmax(np.abs(values))]
    return complex(top.real, abs(top.imag))


# ---------------------------------------------------------------- the eigenvalue solver

@pytest.mark.parametrize("d", [1, 2, 3])
def test_leading_multiplier_equals_numpy_on_random_matrices(d):
    rng = np.random.default_rng(160 + d)
    lead = probes.leading_multiplier()
    for _ in range(400):
        a = rng.normal(size=(d, d)) * rng.choice([1e-3, 1.0, 10.0])
        modulus, angle = lead(np.ascontiguousarray(a), d)
        mu = leading(a)
        assert modulus == pytest.approx(abs(mu), rel=1e-10, abs=1e-14)
        if abs(mu) > 1e-8:
            assert angle == pytest.approx(math.atan2(mu.imag, mu.real), abs=1e-7)
    # the hard cases: a double root, a zero matrix, a rotation (|mu| = 1, angle known)
    c, s = math.cos(2.0), math.sin(2.0)
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 0.5]])
    assert lead(rotation[:d, :d].copy(), d) == pytest.approx(
        (1.0, 2.0) if d >= 2 else (abs(c), math.pi), abs=1e-12)
    assert lead(np.zeros((d, d)), d)[0] == pytest.approx(0.0, abs=1e-15)


# ---------------------------------------------------------------- the Jacobian's oracle

#: a random design of each system, drawn where its steady cycles live (the blade: kappa > 1,
#: so the striker swings back after an impact; on the stop kappa > (1 + k)^2/(4 k) for
#: the rigid pendulum to come back at all; restitution small enough not to escape)
DOMAIN = {"rotor_stop": dict(k=(0.5, 2.0), R=(0.0, 0.2), xi=(1.0, 8.0), kappa=(1.2, 2.5)),
          "lab_window": dict(k=(0.5, 2.5), R=(0.001, 0.1), xi=(2.0, 8.0), kappa=(1.05, 1.5),
                             tool_window=(0.1, 0.5))}
SYSTEMS = [("paper", "rotor_stop"), ("rigid", "rotor_stop"), ("rotor", "rotor_stop"),
           ("paper", "lab_window"), ("rigid", "lab_window"), ("rotor", "lab_window")]


def case_of(model, tool, design):
    """The case row (kernels/pendulum/cases.py) of a design of a system: a heavy rotor
    (J1/J_c = 100) on a stiff motor (slope 100) at idle speed 1 unless the design says."""
    values = dict(model=MODELS[model], tool=TOOLS[tool], tool_window=0.0,
                  rotor_inertia_ratio=100.0, motor_slope=100.0, idle_speed=1.0) | design
    return np.array([float(values[name]) for name in CASE_COLUMNS])


def draw(rng, tool, n):
    return {name: rng.uniform(lo, hi, n) for name, (lo, hi) in DOMAIN[tool].items()}


def section_jacobians(model, tool, design, rtol=1e-12, eps=2e-4, transient=600):
    """(ok, period, carried, differenced) of the section map at a design's steady cycle
    (tests/probes.py: the probe's own transient from rest, 600 sections); differenced by
    Richardson's extrapolation of central differences at eps and eps/2 (error O(eps^4);
    not ok where they disagree by more than 25 %: a jump of the map within the step
    shows as a difference that doubles when the step halves):
    plain central differences were 1.4e-6 off at eps = 1e-5 on a blade design whose second
    derivatives are ~3e4, and at eps = 1e-6 the map's own rounding (~1e-11) shows."""
    case = case_of(model, tool, design)
    params = systems.PARAMETERS[model](case)
    data = systems.DATA[tool](case)
    probe = probes.section_jacobian(model, tool)
    settings = probes.settings(rtol=rtol, atol=rtol * 1e-2)
    r = case[CASE_COLUMNS.index("R")]
    ok, period, carried, coarse = probe(params, data, r, settings, transient, eps)
    ok_fine, period_fine, _, fine = probe(params, data, r, settings, transient, eps / 2)
    # a map that jumps within eps of the cycle (a chatter's bounce count, a grazing pass)
    # has no derivative to difference: the two steps then disagree by O(1/eps)
    smooth = np.all(np.abs(fine - coarse) <= 0.25 * np.maximum(1.0, np.abs(fine)))
    return (ok and ok_fine and period == period_fine and smooth, period, carried,
            (4.0 * fine - coarse) / 3.0)


@pytest.mark.slow
@pytest.mark.parametrize("model, tool", SYSTEMS)
def test_multipliers_equal_central_differences_of_the_map_at_random_designs(model, tool):
    """At random designs with a steady cycle (chatter: the next test): the
    kernel's multiplier at its default tolerance (auto, tol 1e-8) and the tangent carried
    at rtol 1e-12 (1e-13 on the blade) both agree to 1e-6 with central differences of the
    section map at the same rtol (Richardson-extrapolated, steps 2e-4 and 1e-4)."""
    rng = np.random.default_rng(16 + SYSTEMS.index((model, tool)))
    n = 40 if tool == "rotor_stop" else 120  # most blade designs escape or chatter
    design = draw(rng, tool, n)
    out, status, _ = pendulum(model=model, tool=tool, **design)
    cycles = [j for j in range(n) if status[j] == "ok" and np.isfinite(
        out["multiplier_modulus"][j]) and out["regime"][j] != CHATTER]
    assert len(cycles) >= 5, f"only {len(cycles)} of {n} random designs have a cycle"
    met = 0
    for j in cycles[:8]:
        one = {name: float(v[j]) for name, v in design.items()}
        # on the blade the oracle runs at rtol 1e-13: the free swings coast in closed form
        # (docs/models.md section 5.5), where a perturbed start may skip a swing more or
        # less, so the integration errors of the differenced runs no longer cancel; a
        # period-6 design's differences were 1.4e-6 off at 1e-12 (2e-8 at 1e-13), while
        # the carried tangent stayed within 1e-7 of its 1e-13 value
        ok, period, carried, differenced = section_jacobians(
            model, tool, one, rtol=1e-13 if tool == "lab_window" else 1e-12)
        assert ok and period >= 1, one
        mu_fd = leading(differenced)
        assert abs(leading(carried) - mu_fd) <= 1e-6 * max(1.0, abs(mu_fd)), one
        mu = out["multiplier_modulus"][j] * np.exp(1j * out["multiplier_angle"][j])
        # auto refines until its estimate meets tol, at most three times: where the
        # multiplier is ill-conditioned (a blade design's moved 1.2e-4 from rtol 1e-10 to
        # 1e-11) it stops short, and its error_estimate says by how much
        bound = max(1e-6, 2.0 * out["error_estimate"][j]) * max(1.0, abs(mu_fd))
        assert abs(mu - mu_fd) <= bound, (one, mu, mu_fd, out["error_estimate"][j])
        met += abs(mu - mu_fd) <= 1e-6 * max(1.0, abs(mu_fd))
        assert out["stability_margin"][j] == 1.0 - out["multiplier_modulus"][j]
        if tool == "rotor_stop" and model != "rotor":
            # the affine map's multiplier is R (P-O6): the kernel reports it in closed form
            assert out["multiplier_modulus"][j] == one["R"]
            assert abs(mu_fd - one["R"]) <= 1e-6
    # within 1e-6 outright at most designs (the rigid blade's large swings past the blade's
    # faces make 2 of its 8 ill-conditioned: estimates 1.41e-5 and 8.70e-6 against errors
    # 1.32e-5 and 8.75e-6)
    assert met >= 0.7 * len(cycles[:8])


#: where the tangent leaves free flight: the rotor model's plastic impacts (R = 0) stick and
#: the striker slides along the blade's face (a flight of the constrained system); with
#: R > 0 a chatter accumulates (the Zeno guard's jump to the accumulation point) and then
#: slides, on the rotor model by integration, at constant rotor speed in closed form (whose
#: exit the face alone decides: the multiplier is 0)
THROUGH_CONTACT = [("rotor", "slide"), ("rotor", "chatter"), ("rigid", "chatter"),
                   ("paper", "chatter")]


@pytest.mark.slow
@pytest.mark.parametrize("model, case", THROUGH_CONTACT)
def test_multipliers_through_a_slide_and_an_accumulated_chatter_equal_central_differences(
        model, case):
    """Every such cycle of random blade designs has a multiplier, and at those where the
    probe's own sequence (60 sections from rest at rtol 1e-12) reaches a cycle the tangent
    carried through the slide's variational equations and its end event, and through the
    accumulation point, agrees with central differences of the section map to 1e-6, and
    the atlas's value too (within twice its error estimate where that is larger). Why the
    probe may not reach a cycle or differences may not exist: a chatter cycle can be one
    rounding from a grazing pass (a driven blade design's drifted into a miss after 74
    sections at rtol 1e-12), and its map can jump within the difference step (a chatter's
    bounce count changes; differences of -4986 against a map that is constant nearby)."""
    rng = np.random.default_rng(1600 + THROUGH_CONTACT.index((model, case)))
    n = 120 if model == "rotor" else 400  # chatter on a driven blade is rarer
    design = draw(rng, "lab_window", n)
    if case == "slide":
        design["R"] = np.zeros(n)
    out, status, _ = pendulum(model=model, tool="lab_window", **design)
    cycle = np.isin(out["regime"], [REGIMES.index(r) for r in ("period_1", "period_n",
                                                                "chatter")])
    chosen = [j for j in range(n) if status[j] == "ok" and cycle[j]
              and (case == "slide" or out["regime"][j] == CHATTER)]
    assert len(chosen) >= 3, f"only {len(chosen)} of {n} random designs"
    assert np.all(np.isfinite(out["multiplier_modulus"][chosen]))
    if model != "rotor":
        assert np.all(out["multiplier_modulus"][chosen] == 0.0)
    compared = 0
    for j in chosen[:8]:
        one = {name: float(v[j]) for name, v in design.items()}
        ok, period, carried, differenced = section_jacobians(model, "lab_window", one,
                                                             transient=60)
        if not ok:
            continue
        compared += 1
        mu_fd = leading(differenced)
        assert abs(leading(carried) - mu_fd) <= 1e-6 * max(1.0, abs(mu_fd)), one
        mu = out["multiplier_modulus"][j] * np.exp(1j * out["multiplier_angle"][j])
        bound = max(1e-6, 2.0 * out["error_estimate"][j]) * max(1.0, abs(mu_fd))
        assert abs(mu - mu_fd) <= bound, (one, mu, mu_fd, out["error_estimate"][j])
    assert compared >= min(5, len(chosen) - 1), compared


def contact_to_accumulate(rng, model):
    """A random contact on the blade's face whose bounce would leave slower than the Zeno
    guard's speed (approach 0.5 SPEED_EPS/R), with a random perturbation that keeps it on
    the face and the largest difference step (<= 1e-8) that keeps the moved approach below
    the guard's threshold: ((t, y, data, p, r, column, eps), (design, psi))."""
    from kernels.impact.impact_map import SPEED_EPS
    design = {name: float(v[0]) for name, v in draw(rng, "lab_window", 1).items()}
    design["R"] = rng.uniform(0.05, 0.5)
    case = case_of(model, "lab_window", design)
    p = systems.PARAMETERS[model](case)
    lower, window, k, level, side = systems.lab_window_data(case)
    r = design["R"]
    psi = rng.uniform(-0.8, 0.8) * window
    w = 1.0 if model != "rotor" else rng.uniform(0.8, 1.2)
    x = k * k + 1.0 + 2.0 * k * math.cos(psi)  # the contact point's radius squared
    h, h_slope = (1.0 + k * math.cos(psi)) / x, k * (1.0 - k * k) * math.sin(psi) / x**2
    approach = 0.5 * SPEED_EPS / r  # closing at G' = approach on the face met rising
    phi1 = -math.atan2(math.sin(psi), k + math.cos(psi))  # on the face G = 0
    t = phi1 if model != "rotor" else 0.0
    y = (psi, (approach - w) / h) if model != "rotor" else (phi1, w, psi, (approach - w) / h)
    data = (lower, window, k, 0.0, 1.0)
    column = rng.normal(size=5)
    column[1] = -h * column[3]  # the moved contact stays on the face
    if model != "rotor":
        column[0], column[2] = column[1], 0.0  # the rotor angle is the time
    # keep the moved approach below the guard's threshold: the jump exists on both sides
    d_approach = column[2] + h * column[4] + h_slope * y[-1] * column[3]
    eps = min(1e-8, 0.25 * approach / max(abs(d_approach), 1e-300))
    return (t, y, data, p, r, column, eps), (design, psi)


@pytest.mark.slow
@pytest.mark.parametrize("model", ["paper", "rigid", "rotor"])
def test_the_jump_to_a_chatters_accumulation_point_is_differentiated(model):
    """A chatter's last bounces contract its perturbations by R each, so through a whole
    cycle the jump's own derivative hardly shows (zeroing the tail's term left the
    cycle test passing): here it is tested alone. At random contacts on the blade's face
    whose bounce would leave slower than the Zeno guard's speed (approach 0.5 SPEED_EPS/R),
    and random perturbations that keep the contact on the face, the carried column equals
    central differences of where the impact map's contact puts the striker after the jump
    and the plastic law, to 1e-5 of the column's size (the tail's time moves by
    2R/((1 - R) g) per unit of approach speed: coefficients up to ~30). The step is at
    most 1e-8 and keeps the moved approach below the threshold; the differences' own
    noise is ~1e-7 at step 1e-8 and 2e-5 at 1e-10 (the face's Newton solve and the
    rotor angle's rounding over a step that small)."""
    rng = np.random.default_rng(1610 + ["paper", "rigid", "rotor"].index(model))
    probe = probes.accumulation(model)
    settings = probes.settings()
    tried = 0
    for _ in range(40):
        (t, y, data, p, r, column, eps), (design, psi) = contact_to_accumulate(rng, model)
        carried, differenced = probe(t, y, data, p, r, settings, column, eps)
        if not np.all(np.isfinite(differenced)):
            continue
        tried += 1
        scale = np.max(np.abs(carried))
        assert np.allclose(carried, differenced, rtol=1e-5, atol=1e-5 * scale), (
            design, psi, carried, differenced)
    assert tried >= 30


# ---------------------------------------------------------------- margins at regime changes

def bisect(inside, lo, hi, rounds=40):
    """The edge between hi (inside(hi) true) and lo (false), as a bracket (lo, hi)."""
    assert inside(hi) and not inside(lo)
    for _ in range(rounds):
        mid = 0.5 * (lo + hi)
        if inside(mid):
            hi = mid
        else:
            lo = mid
    return lo, hi


def follow(model, design, rs, transient, steps, rtol=1e-11):
    """tests/probes.follow on the blade: one cycle followed along R."""
    case = case_of(model, "lab_window", {"R": rs[0]} | design)
    params = systems.PARAMETERS[model](case)
    return probes.follow(model, "lab_window")(
        params, systems.lab_window_data(case), np.asarray(rs, float),
        probes.settings(rtol=rtol, atol=rtol), transient, steps)


#: a rotor-model design on the blade with coexisting cycles (found by following the cycles
#: of a random search's designs along R): from rest at R = 0.011 it settles into a cycle
#: hitting the blade once a turn, near its edge
#: a paper-model blade design whose once-a-cycle blow loses stability by period doubling
#: as R falls: found by a scan of 3000 random blade designs for period_1 cycles with a
#: negative multiplier of modulus > 0.95 far from the blade's edge (edge margin 0.43 rad),
#: then followed in R; most flip-type cycles of the earlier scans along R ended at a
#: border collision or a jump to another attractor before |mu| reached 1
FLIP = dict(model="paper", tool="lab_window", k=2.71573, xi=3.36865, tool_window=0.70681)


@pytest.mark.slow
def test_a_period_doubling_is_where_the_multiplier_reaches_minus_one():
    """Along R, the period_1 pattern's leading multiplier is real and negative (angle pi)
    and its modulus rises as R falls; where its linear trend reaches 1, the regime from
    rest turns period_n (found by bisection on the atlas's regime), and there the period-2
    pattern's own multiplier (of the two-fold map: mu^2 of the flip, angle 0) rises to 1
    from the other side. Near R* the pattern converges like |mu|^n, so max_impacts is
    raised to 20000; within ~5e-4 of R* neither pattern settles to tol 1e-8 in the
    map's rounding (|mu| 0.99: the noise of the adaptive steps is amplified
    1/(1 - |mu|^2)), and the bisection stops there, on the stable side."""
    method = {"max_impacts": 20000}

    def at(r):
        r = np.atleast_1d(r)
        out, _, _ = pendulum(method=method, R=r, **FLIP)
        return out["regime"], out["multiplier_modulus"], out["multiplier_angle"]

    stable = np.linspace(0.165, 0.170, 6)
    regime, modulus, angle = at(stable)
    assert np.all(regime == REGIMES.index("period_1")) and np.all(angle == math.pi)
    assert np.all(np.diff(modulus) < 0.0) and modulus[0] > 0.95  # rises as R falls
    slope, offset = np.polyfit(stable, modulus, 1)
    r_star = (1.0 - offset) / slope  # where the trend reaches |mu| = 1
    lo, hi = bisect(lambda r: at(r)[0][0] == REGIMES.index("period_1"), 0.160, 0.170,
                    rounds=20)
    assert 0.0 <= hi - r_star <= 1e-3, (hi, r_star)
    regime, modulus, angle = at(hi)
    assert modulus[0] > 0.985 and angle[0] == math.pi
    below = r_star - np.array([0.002, 0.001, 0.0005])
    regime, modulus, angle = at(below)
    assert np.all(regime == REGIMES.index("period_n")) and np.all(angle == 0.0)
    assert np.all(np.diff(modulus) > 0.0) and np.all(modulus < 1.0) and modulus[-1] > 0.95


BORDER = dict(k=1.83664, xi=5.96195, kappa=1.43255, tool_window=0.36767)


@pytest.mark.slow
def test_a_border_collision_is_where_edge_margin_reaches_zero():
    """Following the once-a-turn cycle down in R, its impact walks out to the blade's edge:
    edge_margin falls linearly to zero and the cycle ends there (the striker slips past
    the edge and the machine falls into another cycle); the kernel, from rest, reports the
    same cycle and margin where it starts."""
    rs = np.linspace(0.011, 0.007, 81)
    rows = follow("rotor", BORDER, rs, transient=4000, steps=1500)
    turn = np.abs(rows[:, 4] - 2.0 * np.pi) < 1e-6  # one impact a rotor turn
    assert turn[0] and not turn[-1]
    last = int(np.argmin(turn)) - 1
    assert turn[:last + 1].all()
    margin = rows[:last + 1, 3]
    assert (np.diff(margin) < 0).all() and margin[-1] < 0.02 * margin[0]
    # where the margin's line (fit through the last 10 points) reaches zero: the branch's
    # end, to within a step of R (5e-5; it ended 6e-6 before the line's zero)
    slope, intercept = np.polyfit(rs[last - 9:last + 1], margin[-10:], 1)
    edge = -intercept / slope
    step = rs[0] - rs[1]
    assert rs[last + 1] - step <= edge <= rs[last], (rs[last + 1], edge, rs[last])
    out, status, _ = pendulum(model="rotor", tool="lab_window", R=0.011, **BORDER)
    assert status == ["ok"] and out["regime"][0] == 0
    assert out["edge_margin"][0] == pytest.approx(rows[0, 3], abs=1e-7)
    assert out["multiplier_modulus"][0] == pytest.approx(rows[0, 1], abs=1e-6)


#: coexisting attractors: found by the 8-start scan of rotor-model blade designs (k, R,
#: window on a grid); from rest a period-n cycle, and about 11 % of the starts reach another
MULTISTABLE = dict(model="rotor", tool="lab_window", k=1.0, kappa=1.2, R=0.04,
                   tool_window=0.15)


def test_coexisting_attractors_are_counted_and_the_basin_fraction_converges():
    counts, fractions = [], []
    for n in (16, 64, 256):
        out, status, _ = pendulum({"starts": n}, ATTRACTORS, **MULTISTABLE)
        assert status == ["ok"]
        counts.append(out["attractor_count"][0])
        fractions.append(out["basin_fraction"][0])
    assert counts == [2, 2, 2]
    assert abs(fractions[2] - fractions[1]) < 0.02 and abs(fractions[1] - fractions[0]) < 0.05
    assert 0.5 < fractions[2] < 1.0
    # the same design from rest alone: one start, one attractor
    out, _, _ = pendulum({"starts": 1}, ATTRACTORS, **MULTISTABLE)
    assert (out["attractor_count"][0], out["basin_fraction"][0]) == (1, 1.0)


@pytest.mark.parametrize("design", [
    dict(model="rotor", tool="rotor_stop", k=1.0, kappa=1.2, R=0.0),
    dict(model="paper", tool="rotor_stop", k=1.5, R=0.05),
    dict(model="rigid", tool="rotor_stop", k=1.0, kappa=2.5, R=0.1,
         integrator="dopri5"),
])
def test_a_single_attractor_design_has_one_at_every_number_of_starts(design):
    design = dict(design)
    method = {"starts": 0}
    if design.pop("integrator", None):
        method |= {"integrator": "dopri5", "rtol": 1e-10, "atol": 1e-12}
    for n in (1, 4, 16, 64):
        method["starts"] = n
        out, status, _ = pendulum(method, ATTRACTORS, **design)
        assert status == ["ok"]
        assert (out["attractor_count"][0], out["basin_fraction"][0]) == (1, 1.0)


def test_starts_that_escape_count_as_an_attractor_in_closed_form_and_integrated():
    """Near R_crit a fast start throws the pendulum over the top: the closed form and the
    integration core agree on how many of the same starts escape."""
    design = dict(model="paper", tool="rotor_stop", k=2.0, R=0.2)
    closed, _, _ = pendulum({"starts": 32}, ATTRACTORS, **design)
    stepped, _, _ = pendulum({"starts": 32, "integrator": "dopri5", "rtol": 1e-10,
                              "atol": 1e-12}, ATTRACTORS, **design)
    assert closed["attractor_count"][0] == 2 == stepped["attractor_count"][0]
    assert closed["basin_fraction"][0] == stepped["basin_fraction"][0] < 1.0


@pytest.mark.parametrize("starts", [2, 5, 9])
def test_results_do_not_depend_on_chunks_threads_or_asking_with_several_starts(tmp_path,
                                                                               starts):
    """An atlas with several starts and the stability outputs is bit-identical at chunk 3 on
    one thread and chunk 1000 on two, and its regime values equal an atlas without them."""
    import xarray as xr

    from sweep import runner, spec

    text = f'''
mechanism = "rotary_pendulum"
outputs = ["regime", "impact_interval", "multiplier_modulus", "multiplier_angle",
           "stability_margin", "impact_speed_min_ratio", "edge_margin", "attractor_count",
           "basin_fraction"]
[grid]
R = {{start = 0.04, stop = 0.06, num = 5}}
tool_window = [0.15, 0.3]
[fixed]
model = "rotor"
tool = "lab_window"
k = 1.0
kappa = 1.2
[method]
integrator = "dopri5"
rtol = 1e-9
atol = 1e-9
starts = {starts}
'''
    paths = []
    for chunk, workers in ((3, 1), (1000, 2)):
        path = tmp_path / f"c{chunk}.nc"
        runner.run_sweep(spec.parse(text), path, chunk=chunk, progress=False,
                         workers=workers)
        paths.append(path)
    with xr.open_dataset(paths[0]) as a, xr.open_dataset(paths[1]) as b:
        for name in a.data_vars:
            np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)
        assert (a["attractor_count"] >= 1).all() and (a["basin_fraction"] <= 1).all()
        plain = text.replace(f"starts = {starts}", "").replace(
            '"multiplier_modulus", "multiplier_angle",\n           "stability_margin", '
            '"impact_speed_min_ratio", "edge_margin", "attractor_count",\n'
            '           "basin_fraction"', "")
        path = tmp_path / "plain.nc"
        runner.run_sweep(spec.parse(plain), path, chunk=1000, progress=False)
        with xr.open_dataset(path) as c:
            for name in c.data_vars:
                np.testing.assert_array_equal(a[name].values, c[name].values,
                                              err_msg=name)


@pytest.mark.parametrize("lines, key", [
    ('[method]\nstarts = 4', "method.starts"),
    ('outputs = ["edge_margin"]', "outputs: edge_margin"),
    ('[method]\nstarts = 0', "method.starts"),
])
def test_stability_spec_errors_are_one_line_before_any_compute(lines, key):
    from sweep import spec
    from sweep.errors import UserError

    text = 'mechanism = "rotary_pendulum"\n' + lines + '\n[grid]\nk = [1.0, 2.0]\n'
    with pytest.raises(UserError) as err:
        spec.parse(text)
    assert str(err.value).startswith(key) and "\n" not in str(err.value)


def test_stability_outputs_cost_nothing_unless_asked_for():
    """Without them the atlas has none of them, and the kernel runs no tangent: the same
    steps as before (the tangent's steps are not counted among the cycle's)."""
    from sweep import spec

    s = spec.parse('mechanism = "rotary_pendulum"\n[grid]\nk = [1.0, 2.0]\n')
    for name in STABILITY + ATTRACTORS + ("edge_margin",):
        assert name not in s.scalar_outputs
        assert name not in s.method_record.outputs


@pytest.mark.slow
def test_a_chattering_cycle_has_its_slowest_impact_near_zero():
    """impact_speed_min_ratio over random blade designs: where the cycle accumulates a
    chatter, its last bounce is slower than the Zeno guard (SPEED_EPS / R in gap units), so
    the ratio is below 1e-3; every other cycle has a ratio in (0, 1], and one impact a
    cycle on the rotor stop gives exactly 1."""
    from kernels.impact.impact_map import SPEED_EPS

    rng = np.random.default_rng(1616)
    design = draw(rng, "lab_window", 400)
    out, status, _ = pendulum(model="rigid", tool="lab_window", **design)
    ok = np.array(status) == "ok"
    chatter = ok & (out["regime"] == 4)
    assert chatter.sum() >= 5 and (ok & ~chatter).sum() >= 10
    ratio = out["impact_speed_min_ratio"]
    assert (ratio[chatter] < 1e-3).all()
    assert (ratio[chatter] <= 10 * SPEED_EPS / design["R"][chatter]).all()
    assert ((ratio[ok] > 0) & (ratio[ok] <= 1)).all()
    stop, stop_status, _ = pendulum(model="rotor", tool="rotor_stop", k=1.0, kappa=2.0,
                                    R=[0.0, 0.05, 0.1])
    assert stop_status == ["ok"] * 3 and (stop["impact_speed_min_ratio"] == 1.0).all()


@pytest.mark.slow  # DOP853 with the tangent: entry points no fast test compiles
@pytest.mark.parametrize("design", [
    dict(model="rotor", tool="rotor_stop", k=1.0, kappa=1.2, R=0.05),
    dict(model="rotor", tool="lab_window", k=1.0, kappa=1.2, R=0.01, tool_window=0.3),
])
def test_dop853_multipliers_are_dopri5s(design):
    """Issue 40: with DOP853 the tangent's flights are stepped by DOPRI5 at the same rtol
    (DOP853 is not compiled into them); the multipliers of a DOP853 solve at rtol 1e-11
    are those of DOPRI5 at 1e-12 within 1e-7, and so is the impact speed."""
    high, high_status, _ = pendulum({"integrator": "dop853", "rtol": 1e-11, "atol": 1e-13},
                                    (*STABILITY, "impact_speed"), **design)
    low, low_status, _ = pendulum({"integrator": "dopri5", "rtol": 1e-12, "atol": 1e-14},
                                  (*STABILITY, "impact_speed"), **design)
    assert high_status == ["ok"] == low_status
    for name in ("multiplier_modulus", "multiplier_angle", "impact_speed"):
        assert high[name][0] == pytest.approx(low[name][0], rel=1e-7, abs=1e-7), name

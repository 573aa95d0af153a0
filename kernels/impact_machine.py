"""The crank-driven impact machine (``impact_machine``): the impact four-bar of [CR] driven by
a motor through a crank with a flywheel, the crank's own dynamics between blows and the
blow at the special position (docs/machine.md, derived: no paper gives it).

One degree of freedom, the crank angle phi1, between blows: the reduced inertia J(phi1) of
the crank, flywheel, coupler and rocker, a motor law M(omega1), gravity and a conservative
load on the rocker as generalised forces Q(phi1). The revolution between blows is
integrated on the integration core; the blow is the generalised Newton impact at the
node; the steady state is the fixed point of the section map after the blow.

This module is the mechanism's entry point: a design's parameters to the machine's data,
the steady cycle and the outputs by name, and the statuses, mapped once from the outcomes
of the package below (kernels/machine/: declaration, data, dynamics, blow, revolution,
cycle, flywheel, forces).
"""

import math
from collections import namedtuple

import numpy as np
from numba import njit

from kernels import INLINE_OPTIONS, INNER_OPTIONS, KERNEL_OPTIONS
from kernels import kinetostatics as ks
from kernels.block import block_arrays, design_block
from kernels.crank_rocker import S as LINKAGE
from kernels.crank_rocker import TYPE_GENERAL, linkage_point
from kernels.extrema import cell_midpoints
from kernels.fourbar import CHANGE_POINT_C
from kernels.impact.outcomes import Settings as CoreSettings
from kernels.impact.runge_kutta import METHOD_DOPRI5
from kernels.machine.cycle import (CYCLE_ENDED, CYCLE_GAINS_ENERGY, CYCLE_NO_CONVERGENCE,
                                   CYCLE_REVERSES, CYCLE_STEADY, solve, speed_fluctuation)
from kernels.machine.data import Linkage, Loads, Machine, Masses, Motor, no_machine
from kernels.machine.declaration import DECLARATION  # noqa: F401 (the registry's)
from kernels.machine.declaration import (FOR_DELTA, LAW_GENERALIZED, LAW_KINEMATIC, MATERIAL,
                                         F, O, P, S)
from kernels.machine.dynamics import crank_motion, inertia_is_singular, motor_torque
from kernels.machine.flywheel import classical_flywheel, exact_flywheel
from kernels.machine.motor import (MOTOR_FOUND, MOTOR_UNREACHABLE, flywheel_at,
                                   idle_for_speed, with_idle)
from kernels.machine.forces import dynamic_force_peaks
from kernels.machine.revolution import (ANGLE, ENERGY, REV_MAX_STEPS, REV_STALL,
                                        REV_TOO_SLOW, REV_UNDERFLOW, after_blow,
                                        timed_revolution)

#: flywheel_sizing's codes
FLYWHEEL_GIVEN, FLYWHEEL_SIZED, FLYWHEEL_NOT_NEEDED = 0, 1, 2

# ---------------------------------------------------------------- statuses, mapped once

@njit(**INNER_OPTIONS)
def linkage_status(code):
    """The machine's status of a crank_rocker linkage status (anything but ok ends the
    design)."""
    if code == LINKAGE.second_special_position:  # a second node inside the cycle: the
        return S.degenerate  # one-node model does not hold
    if code == LINKAGE.no_impact or code == LINKAGE.no_special_position:
        return S.no_impact  # gamma <= 1, or no change point at all
    if code == LINKAGE.not_assemblable:
        return S.not_assemblable
    if code == LINKAGE.no_real_synthesis:
        return S.no_real_synthesis
    if code == LINKAGE.degenerate:
        return S.degenerate
    if code != LINKAGE.ok:
        return S.nonfinite
    return S.ok


@njit(**INNER_OPTIONS)
def cycle_status(cycle):
    """The status of the search for a steady cycle (cycle.CYCLE_*, and how a revolution
    that did not reach the blow ended)."""
    if cycle.outcome == CYCLE_STEADY:
        return S.ok
    if cycle.outcome == CYCLE_REVERSES:
        return S.reverses
    if cycle.outcome == CYCLE_NO_CONVERGENCE:
        return S.no_convergence
    if cycle.outcome == CYCLE_GAINS_ENERGY:
        return S.gains_energy
    end = cycle.rev.end
    if cycle.outcome != CYCLE_ENDED:
        return S.nonfinite
    if end == REV_STALL:
        return S.stalls
    if end == REV_MAX_STEPS:
        return S.max_steps
    if end == REV_UNDERFLOW:
        return S.step_underflow
    if end == REV_TOO_SLOW:
        return S.too_slow
    return S.nonfinite


# ---------------------------------------------------------------- one design's machine

@njit(**INNER_OPTIONS)
def machine_data(pr, lam0, lam2, lam3, sigma, start, snap, flywheel, tref, wref):
    """The Machine of one design from its parameters (rows P), its synthesised ratios,
    branch and node angle; the flywheel J_f and the reference energy and speed of the
    scaled state given apart (the flywheel is sized by solving again)."""
    l1 = pr[P.crank_length]
    l0, l2, l3 = lam0 * l1, lam2 * l1, lam3 * l1
    p1, q1 = pr[P.s1] * l1, pr[P.q1]
    p2, q2 = pr[P.s2] * l2, pr[P.q2]
    p3, q3 = pr[P.s3] * l3, pr[P.q3]
    m1, m2, m3 = pr[P.m1], pr[P.m2], pr[P.m3]
    ja = pr[P.J1] + m1 * (p1 * p1 + q1 * q1) + flywheel
    jb2 = pr[P.J2] + m2 * (p2 * p2 + q2 * q2)
    jd3 = pr[P.J3] + m3 * (p3 * p3 + q3 * q3)
    kind = float(CHANGE_POINT_C) if start != 0.0 else 0.0
    g, tilt = pr[P.g], pr[P.tilt]
    return Machine(
        linkage=Linkage(l0=l0, l1=l1, l2=l2, l3=l3, sigma=sigma, kind=kind, start=start,
                        snap=snap),
        masses=Masses(m2l1=m2 * l1, p2=p2, q2=q2, jb2=jb2, jd3=jd3, m1=m1, p1=p1, q1=q1,
                      m2=m2, m3=m3, p3=p3, q3=q3),
        loads=Loads(gx=-g * math.sin(tilt), gy=-g * math.cos(tilt), fx=pr[P.load_force_x],
                    fy=pr[P.load_force_y], arm=pr[P.load_arm], offset=pr[P.load_offset],
                    moment=pr[P.load_moment]),
        motor=Motor(law=pr[P.motor_law], stall_torque=pr[P.stall_torque],
                    idle_speed=pr[P.idle_speed]),
        ja=ja, tref=tref, wref=wref)


@njit(**INNER_OPTIONS)
def design_data(pr, snap):
    """A design's linkage: (status, its Machine, the crank's own inertia about A): the
    synthesis of crank_rocker for Rk = -design_restitution (or the given ratios), on the
    impact branch of a positive crank speed; a status other than ok where the linkage is
    not an impact four-bar with one node, or its inertia vanishes."""
    nan = math.nan
    r_design = pr[P.design_restitution]
    if r_design == MATERIAL:
        r_design = pr[P.R]
    if int(pr[P.type]) != TYPE_GENERAL:
        if r_design <= 0.0:  # gamma = 1, lambda0 = 1: B on D at the node
            return S.degenerate, no_machine(), nan
        if not r_design < 1.0:  # gamma = infinity: no linkage
            return S.no_real_synthesis, no_machine(), nan
    lp = linkage_point(int(pr[P.type]), r_design, pr[P.largest_link], pr[P.lambda0],
                       pr[P.lambda2], pr[P.lambda3], int(pr[P.base_root]),
                       pr[P.crank_length], 1.0, 0.0, snap, nan, nan, 0.0)
    status = linkage_status(lp.status)
    if status != S.ok:
        return status, no_machine(), nan
    crank_own = pr[P.J1] + pr[P.m1] * ((pr[P.s1] * pr[P.crank_length]) ** 2 + pr[P.q1] ** 2)
    # a flywheel still to be sized (FOR_DELTA) is none for the singularity test
    m = machine_data(pr, lp.lambda0, lp.lambda2, lp.lambda3, lp.assembly_branch,
                     lp.special_crank_angle, snap, max(pr[P.flywheel_inertia], 0.0), 1.0,
                     1.0)
    if inertia_is_singular(m):
        return S.singular_inertia, m, crank_own
    return S.ok, m, crank_own


@njit(**INNER_OPTIONS)
def linkage_forces_parameters(pr, m):
    """The linkage_forces parameter vector of the machine's linkage (rows of
    kinetostatics.P); speed, acceleration and the load's rocker-frame components are set per
    crank angle (forces.reactions)."""
    lf = np.zeros(len(ks.P))
    lk = m.linkage
    lf[ks.P.l0], lf[ks.P.l1], lf[ks.P.l2], lf[ks.P.l3] = lk.l0, lk.l1, lk.l2, lk.l3
    lf[ks.P.m1], lf[ks.P.m2], lf[ks.P.m3] = pr[P.m1], pr[P.m2], pr[P.m3]
    lf[ks.P.s1], lf[ks.P.s2], lf[ks.P.s3] = pr[P.s1], pr[P.s2], pr[P.s3]
    lf[ks.P.q1], lf[ks.P.q2], lf[ks.P.q3] = pr[P.q1], pr[P.q2], pr[P.q3]
    lf[ks.P.J1], lf[ks.P.J2], lf[ks.P.J3] = pr[P.J1], pr[P.J2], pr[P.J3]
    lf[ks.P.tilt], lf[ks.P.g] = pr[P.tilt], pr[P.g]
    lf[ks.P.external_force_arm] = pr[P.load_arm]
    lf[ks.P.base_motion] = ks.BASE_FIXED
    return lf


# ---------------------------------------------------------------- the outputs of one design

@njit(**INNER_OPTIONS)
def cycle_profiles(w_plus, nd, m, core, angles, prof):
    """The steady cycle from the blow's exit at w_plus, sampled at ``angles`` after the blow
    (ascending, inside the open cycle): crank speed, acceleration, motor and shaft torque,
    each sample reached by the revolution's steps cut to land on it."""
    start = m.linkage.start
    y = after_blow(w_plus, nd, m)
    for j in range(angles.shape[0]):
        reached, y = timed_revolution(y[ANGLE], y, start + angles[j], m, core)
        if not reached:
            return
        w, eps, torque = crank_motion(y[ANGLE], y[ENERGY], m)
        prof[F.crank_speed, j], prof[F.crank_acceleration, j] = w, eps
        prof[F.motor_torque, j], prof[F.shaft_torque, j] = torque, torque - m.ja * eps


@njit(**INNER_OPTIONS)
def finite_or(out, status):
    """``status``, or nonfinite where an output is infinite."""
    for k in range(out.shape[0]):
        if math.isinf(out[k]):
            return S.nonfinite
    return status


@njit(**INNER_OPTIONS)
def steady_outputs(cycle, nd, m, r, law, out):
    """The steady cycle's outputs into ``out``: speeds, impulses, the motor's torque and
    power, the blow's energy, loss and its split, rate, restitution, the energy balance."""
    rev, b = cycle.rev, cycle.blow
    w_plus, w_minus, w_next = cycle.w_plus, rev.w_minus, b.w_plus
    u31m, u31p = nd.u31_before, nd.u31_after
    period = rev.period
    out[O.mean_crank_speed] = 2.0 * math.pi / period
    out[O.speed_fluctuation] = speed_fluctuation(cycle)
    out[O.crank_speed_before_blow] = w_minus
    out[O.crank_speed_after_blow] = w_next
    out[O.crank_speed_jump] = w_next - w_minus
    out[O.tool_impulse] = b.impulse
    out[O.crank_impulse] = m.ja * (w_next - w_minus)
    w_low, w_high = min(rev.w_min, w_plus), max(rev.w_max, w_plus)
    out[O.motor_torque_peak] = max(abs(motor_torque(w_low, m)),
                                   abs(motor_torque(w_high, m)))
    out[O.motor_torque_rms] = math.sqrt(rev.torque_squared / period)
    out[O.motor_power_mean] = rev.motor_work / period
    out[O.blow_energy] = 0.5 * m.masses.jd3 * (u31m * w_minus) ** 2
    out[O.blow_loss] = b.loss
    if law != LAW_KINEMATIC:  # the kinematic law's loss has no split (it may be negative)
        out[O.energy_to_material] = b.tool
        out[O.capture_loss] = b.capture
        out[O.blow_efficiency] = b.tool / rev.motor_work
    out[O.blow_rate] = 60.0 / period
    out[O.cycle_period] = period
    out[O.impact_speed] = abs(u31m * w_minus) * m.linkage.l3
    out[O.restitution_kinematic] = u31p / u31m
    out[O.restitution_mismatch] = u31p / u31m + r
    out[O.reduced_inertia_before], out[O.reduced_inertia_after] = nd.j_before, nd.j_after
    # gravity and the load are conservative: their work over the closed cycle is 0, so
    # the motor's work pays the blow's loss; the integrated load work is left out (the
    # revolution's steps keep W_motor + W_load = T_end - T_start exactly: with it the
    # balance holds whatever the integration error)
    out[O.energy_balance_residual] = (rev.motor_work - b.loss) / b.loss


def design_of(full):
    """One design (kernels/block.py): its status, its outputs written into out and its
    profiles at settings.angles after the blow into prof (NaN where none). ``full``: with
    what a run may ask beyond the steady cycle (the idle speed for a crank speed, a
    flywheel sized for delta, profiles, dynamic force peaks, the flywheels for delta); a
    run that asks none of them compiles without them, a third less (numba prunes the
    branches on the constant)."""

    @njit(**INLINE_OPTIONS)
    def design(i, pr, settings, out, prof):
        r = pr[P.R]
        law = int(pr[P.impact_law])
        revolutions, start_mode, delta = (settings.max_revolutions, settings.start_mode,
                                          settings.delta)
        status, m, crank_own = design_data(pr, settings.geometry_tol)
        if status != S.ok:
            return status
        core = CoreSettings(method=METHOD_DOPRI5, rtol=settings.tol, atol=settings.tol,
                            dt=0.0, max_steps=10 ** 6, horizon=2.0 * math.pi + 1.0)
        flywheel = pr[P.flywheel_inertia]
        sized = flywheel == FOR_DELTA  # the flywheel a delta target asks for: sized first
        if full:
            target = pr[P.omega1]
            if math.isfinite(target):  # the idle speed the mean crank speed asks for
                found, idle = idle_for_speed(m, crank_own, flywheel, sized, r, law, core,
                                             revolutions, start_mode, delta, target)
                if found == MOTOR_UNREACHABLE:
                    return S.unreachable_speed
                if found != MOTOR_FOUND:
                    return S.no_convergence
                m = with_idle(m, idle)
            flywheel = flywheel_at(m, crank_own, flywheel, sized, r, law, core,
                                   revolutions, start_mode, delta)
        out[O.idle_speed] = m.motor.idle_speed
        if not math.isfinite(flywheel):
            return S.no_convergence
        out[O.flywheel_inertia] = flywheel
        out[O.flywheel_sizing] = (FLYWHEEL_GIVEN if not sized else
                                  FLYWHEEL_NOT_NEEDED if flywheel == 0.0 else FLYWHEEL_SIZED)
        cycle, nd, m = solve(m, crank_own, flywheel, r, law, core, revolutions, start_mode)
        out[O.revolutions], out[O.n_steps] = cycle.revolutions, cycle.steps
        status = cycle_status(cycle)
        if status != S.ok:
            return status
        steady_outputs(cycle, nd, m, r, law, out)
        w_plus, period = cycle.w_plus, cycle.rev.period
        if full:  # what a run may ask beyond the steady cycle
            if settings.angles.shape[0]:
                cycle_profiles(w_plus, nd, m, core, settings.angles, prof)
            if settings.peaks:
                peaks = np.empty(ks.N_PEAKS)
                dynamic_force_peaks(w_plus, nd, m, linkage_forces_parameters(pr, m), core,
                                    settings.window, settings.peak_samples, peaks)
                out[O.dynamic_force_peak_A], out[O.dynamic_force_peak_B] = peaks[ks.PEAK_A], \
                    peaks[ks.PEAK_B]
                out[O.dynamic_force_peak_C], out[O.dynamic_force_peak_D] = peaks[ks.PEAK_C], \
                    peaks[ks.PEAK_D]
            if settings.flywheels:
                guess = classical_flywheel(nd, r, m, crank_own, delta, 2.0 * math.pi / period)
                out[O.flywheel_for_delta_classical] = \
                    guess if law == LAW_GENERALIZED else math.nan
                if law == LAW_GENERALIZED and math.isfinite(guess):
                    out[O.flywheel_for_delta] = exact_flywheel(
                        m, crank_own, r, law, core, revolutions, start_mode, delta, guess)
        return finite_or(out, S.ok)

    return design


#: the method's options the block reads, by name (flywheels and peaks: whether those
#: outputs are asked for; angles: the profiles' crank angles after the blow)
Settings = namedtuple("Settings", ["geometry_tol", "tol", "max_revolutions", "start_mode",
                                   "delta", "flywheels", "peaks", "window", "peak_samples",
                                   "angles"])
#: the blocks: each design of it by ``design_of(full)`` (kernels/block.py), cached on disk;
#: the lean one where a run asks nothing beyond the steady cycle
machine_block = design_block(design_of(True), "machine_block", globals(),
                             KERNEL_OPTIONS)
lean_machine_block = design_block(design_of(False), "lean_machine_block",
                                  globals(), KERNEL_OPTIONS)


def needs_full(params, method, angles) -> bool:
    """Whether a run asks anything of the full block: a crank speed to solve the motor's
    idle speed for, a flywheel sized for delta, profiles, dynamic force peaks or the
    flywheels for delta."""
    return bool(np.isfinite(params[P.omega1]).any() or (params[P.flywheel_inertia]
                                                        == FOR_DELTA).any()
                or angles.shape[0] or any(name.startswith("dynamic_force_peak")
                                          or name.startswith("flywheel_for_delta")
                                          for name in method.outputs))


def run(params, method):
    """Entry point: (outputs, status, profiles[n_profiles, n, n_angles])."""
    n = params.shape[1]
    angles = cell_midpoints(method.profile_points, 2.0 * np.pi)
    out, status, prof = block_arrays(DECLARATION, n, angles)
    settings = Settings(
        geometry_tol=float(method.geometry_tol), tol=float(method.tol),
        max_revolutions=int(method.max_revolutions), start_mode=int(method.start),
        delta=float(method.delta_target),
        flywheels=("flywheel_for_delta" in method.outputs
                   or "flywheel_for_delta_classical" in method.outputs),
        peaks=any(name.startswith("dynamic_force_peak") for name in method.outputs),
        window=float(method.special_window), peak_samples=int(method.peak_samples),
        angles=angles)
    block = machine_block if needs_full(params, method, angles) else lean_machine_block
    block(np.ascontiguousarray(params), settings, out, status, prof)
    return out, status, prof

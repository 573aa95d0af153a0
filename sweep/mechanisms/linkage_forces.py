"""Registry entry of the kinetostatics mechanism (seed 001, linkages.md §5)."""

from __future__ import annotations

import math

from kernels import kinetostatics as k
from sweep.errors import UserError
from sweep.mechanisms.common import POSITIVE, assembly_branch, geometry_tol
from sweep.registry import Mechanism, Output, Parameter, register

_POS = POSITIVE
_NONNEG = dict(minimum=0.0)

# defaults: the kinetostatic test mechanism of linkages.md §5.4a (seed 000 Table 1,
# lambda2 = 2.5, R = 0.3, crank 0.1 m, tilt 25 degrees, 30 rad/s)
_L1 = 0.1
_L0, _L2, _L3 = 2.029159519725557 * _L1, 2.5 * _L1, 1.470840480274443 * _L1

PARAMETERS = (
    Parameter("l0", "m", "base length AD (l0)", default=_L0, **_POS),
    Parameter("l1", "m", "crank length AB (l1)", default=_L1, **_POS),
    Parameter("l2", "m", "coupler length BC (l2)", default=_L2, **_POS),
    Parameter("l3", "m", "rocker length DC (l3)", default=_L3, **_POS),
    Parameter("m1", "kg", "crank mass (m1)", default=2.0, **_NONNEG),
    Parameter("m2", "kg", "coupler mass (m2)", default=3.0, **_NONNEG),
    Parameter("m3", "kg", "rocker mass (m3)", default=8.0, **_NONNEG),
    Parameter("s1", "1", "crank centroid along AB, fraction of l1 from A", default=0.5),
    Parameter("s2", "1", "coupler centroid along BC, fraction of l2 from B", default=0.48),
    Parameter("s3", "1", "rocker centroid along DC, fraction of l3 from D",
              default=0.11 / _L3),
    Parameter("q1", "m", "crank centroid offset across the link", default=0.01),
    Parameter("q2", "m", "coupler centroid offset across the link", default=-0.02),
    Parameter("q3", "m", "rocker centroid offset across the link", default=0.015),
    Parameter("J1", "kg m2", "crank centroidal moment of inertia (I_S1)",
              default=2 * 0.1**2 / 12 + 0.001, **_NONNEG),
    Parameter("J2", "kg m2", "coupler centroidal moment of inertia (I_S2)",
              default=3 * 0.25**2 / 12, **_NONNEG),
    Parameter("J3", "kg m2", "rocker centroidal moment of inertia (I_S3)",
              default=8 * 0.15**2 / 12 + 0.02, **_NONNEG),
    Parameter("omega1", "rad s-1", "crank angular velocity (omega1); 0 gives statics",
              default=30.0),
    Parameter("epsilon1", "rad s-2", "crank angular acceleration (epsilon1)", default=0.0),
    Parameter("tilt", "rad", "inclination of the base AD to the horizontal (gamma + psi "
              "of seed 001)", default=math.radians(25.0), minimum=-math.pi, maximum=math.pi),
    Parameter("g", "m s-2", "gravitational acceleration", default=9.81, **_NONNEG),
    assembly_branch(),
    Parameter("external_force", "N", "external force on the rocker, across it "
              "(positive towards increasing phi3)", default=0.0),
    Parameter("external_force_normal", "N", "external force on the rocker, along D->C",
              default=0.0),
    Parameter("external_force_arm", "m", "distance from D along the rocker where the "
              "external force acts", default=0.0),
    Parameter("external_moment", "N m", "external couple on the rocker (counter-clockwise)",
              default=0.0),
    Parameter("base_motion", "1", "fixed base, or the additional rocker's base turning "
              "with the main rocker (GUIM-1)", default="fixed",
              choices={"fixed": k.BASE_FIXED, "rotating": k.BASE_ROTATING}),
    Parameter("base_omega", "rad s-1", "main rocker angular velocity (Omega_b), held over "
              "the cycle", default=0.0),
    Parameter("base_epsilon", "rad s-2", "main rocker angular acceleration (E_b), held "
              "over the cycle", default=0.0),
    Parameter("crank_pivot_x", "m", "crank pivot A relative to the main rocker pivot O, "
              "along the base", default=0.0),
    Parameter("crank_pivot_y", "m", "crank pivot A relative to the main rocker pivot O, "
              "across the base", default=0.0),
)
OUTPUTS = (
    Output("force_peak_A", "N", "peak |F14| at the crank pivot A over a cycle",
           "outside |phi1 - phi1*| < special_window at a special position"),
    Output("force_peak_B", "N", "peak |F21| at the crank pin B over a cycle",
           "outside |phi1 - phi1*| < special_window at a special position"),
    Output("force_peak_C", "N", "peak |F32| at the coupler-rocker joint C over a cycle",
           "outside |phi1 - phi1*| < special_window at a special position"),
    Output("force_peak_D", "N", "peak |F34| at the rocker pivot D over a cycle",
           "outside |phi1 - phi1*| < special_window at a special position"),
    Output("balancing_moment_peak", "N m", "peak |M_b| over a cycle (balancing moment)"),
    Output("balancing_moment_rms", "N m", "RMS of the balancing moment over a cycle"),
    Output("cycle_work", "J", "work of the balancing moment per cycle (integral of M_b "
           "dphi1 along the motion)", "equals the kinetic energy lost at impact for "
           "constant omega1 on the impact branch"),
    Output("assembly_branch", "1", "assembly branch used (sigma)"),
)
PROFILES = (
    Output("F21_n", "N", "crank pin force on the coupler along the coupler (F21 normal)"),
    Output("F21_t", "N", "crank pin force on the coupler across the coupler (F21 tangential)"),
    Output("F34_n", "N", "base force on the rocker along the rocker (F34 normal)"),
    Output("F34_t", "N", "base force on the rocker across the rocker (F34 tangential)"),
    Output("F32_n", "N", "coupler force on the rocker along the rocker (F32 normal)"),
    Output("F32_t", "N", "coupler force on the rocker across the rocker (F32 tangential)"),
    Output("F14_n", "N", "base force on the crank along the crank (F14 normal)"),
    Output("F14_t", "N", "base force on the crank across the crank (F14 tangential)"),
    Output("balancing_moment", "N m", "balancing moment on the crank (M_b, virtual work)"),
)
assert tuple(p.name for p in PARAMETERS) == k.PARAMETERS
assert tuple(o.name for o in OUTPUTS) == k.OUTPUTS
assert tuple(o.name for o in PROFILES) == k.PROFILES

METHOD = {
    "geometry_tol": geometry_tol("the special-position window"),
    "special_window": Parameter("special_window", "rad", "half-width of the window around "
                                "a special position excluded from peaks (delta)",
                                default=0.01, minimum=0.0, maximum=0.5,
                                min_inclusive=False),
    "quadrature_points": Parameter("quadrature_points", "1", "Gauss-Legendre points for the "
                                   "cycle work and RMS", default=200, minimum=2,
                                   maximum=5000, integer=True),
    "peak_samples": Parameter("peak_samples", "1", "crank angles sampled to find each "
                              "peak, which is then refined to the exact maximum",
                              default=361, minimum=3, maximum=10**6, integer=True),
    "profile_points": Parameter("profile_points", "1", "crank angles of the profiles "
                                "(0: no profiles)", default=0, minimum=0, maximum=100000,
                                integer=True),
}
assert tuple(METHOD) == k.METHOD

_BASE_KEYS = ("base_omega", "base_epsilon", "crank_pivot_x", "crank_pivot_y")


def _check(given: dict) -> None:
    motions = given.get("base_motion") or {"fixed"}
    if motions == {"fixed"}:
        for name in _BASE_KEYS:
            if name in given:
                raise UserError(f"{name}: used only with base_motion = \"rotating\"")


register(Mechanism(
    name="linkage_forces",
    title="Kinetostatics of the impact four-bar and GUIM-1's additional rocker (seed 001)",
    parameters=PARAMETERS,
    outputs=OUTPUTS,
    run=k.linkage_forces_run,
    flags=("ok", "not_assemblable", "special_position", "nonfinite", "degenerate",
           "second_special_position", "no_special_position"),
    usable_flags=("special_position", "second_special_position"),
    method=METHOD,
    method_text="Assur-dyad vector route for the reactions (linkages.md §5.3), balancing "
                "moment by virtual work (§5.5), loop closure in factored form (§2.1); "
                "cycle work and RMS by Gauss-Legendre on the open cycle, peaks from a "
                "uniform sample outside the special-position window refined by golden "
                "section",
    check=_check,
    profiles=PROFILES,
    profile_dim=Parameter("crank_angle", "rad", "crank angle (phi1), from A->D"),
    profile_coordinate=lambda method: k.profile_angles(int(method["profile_points"])),
))

assert k.SIGMA_IMPACT == 0.0  # the code sweep.mechanisms.common declares

"""The machine's data: one named record built by keyword, read by name everywhere below
(docs/machine.md §1). Lengths in m, masses in kg, inertias in kg m2, forces in N.

``Machine`` groups what one design fixes:

- ``linkage``: the four-bar on its impact branch (``Linkage``);
- ``masses``: the moving links' masses and centroids, as the reduced inertia and the
  generalised force read them (``Masses``);
- ``loads``: gravity in the base frame and the conservative load on the rocker (``Loads``);
- ``motor``: the motor's law and data (``Motor``);
- ``ja``: J_A, the crank side's inertia about A (the crank's own and the flywheel's);
- ``tref``, ``wref``: the reference kinetic energy and speed that scale the revolution's
  state (set again where the flywheel is sized).
"""

import math
from collections import namedtuple

from numba import njit

from kernels import INNER_OPTIONS

#: lengths l0 (base), l1 (crank), l2 (coupler), l3 (rocker); sigma the assembly branch;
#: kind the change point of the node (fourbar.CHANGE_POINT_C, else 0); start phi1*, the
#: crank angle of the node where the cycle starts; snap the synthesis's geometry tolerance
Linkage = namedtuple("Linkage", ["l0", "l1", "l2", "l3", "sigma", "kind", "start", "snap"])
#: m2 l1 (the coupler's mass times the crank length); p_i, q_i the centroid of link i along
#: and across it [m]; jb2, jd3 the coupler's inertia about B and the rocker's about D; m_i
#: the masses
Masses = namedtuple("Masses", ["m2l1", "p2", "q2", "jb2", "jd3", "m1", "p1", "q1", "m2",
                               "m3", "p3", "q3"])
#: (gx, gy) gravity in the base frame [m s-2]; (fx, fy) the load on the rocker along and
#: across the base, at arm and offset on the rocker; moment a couple on it [N m]
Loads = namedtuple("Loads", ["gx", "gy", "fx", "fy", "arm", "offset", "moment"])
#: law (declaration.MOTOR_*), stall torque M0 [N m], idle speed omega_idle [rad s-1]
Motor = namedtuple("Motor", ["law", "stall_torque", "idle_speed"])
Machine = namedtuple("Machine", ["linkage", "masses", "loads", "motor", "ja", "tref",
                                 "wref"])


@njit(**INNER_OPTIONS)
def no_machine():
    """The data of a design that has no machine (every value NaN)."""
    nan = math.nan
    return Machine(linkage=Linkage(l0=nan, l1=nan, l2=nan, l3=nan, sigma=nan, kind=nan,
                                   start=nan, snap=nan),
                   masses=Masses(m2l1=nan, p2=nan, q2=nan, jb2=nan, jd3=nan, m1=nan,
                                 p1=nan, q1=nan, m2=nan, m3=nan, p3=nan, q3=nan),
                   loads=Loads(gx=nan, gy=nan, fx=nan, fy=nan, arm=nan, offset=nan,
                               moment=nan),
                   motor=Motor(law=nan, stall_torque=nan, idle_speed=nan), ja=nan, tref=nan,
                   wref=nan)


@njit(**INNER_OPTIONS)
def with_flywheel(m, flywheel, crank_own, tref, wref):
    """The machine with another flywheel (J_A = the crank's own inertia + J_f) and
    reference scales of the revolution's state."""
    return Machine(linkage=m.linkage, masses=m.masses, loads=m.loads, motor=m.motor,
                   ja=crank_own + flywheel, tref=tref, wref=wref)

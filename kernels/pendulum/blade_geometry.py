"""The lab-fixed blade's geometry (lab_window, docs/models.md §5.5, H11): the contact point
is at radius rho = sqrt(X), X = k^2 + 1 + 2k cos psi, and at the polar angle G = phi1 +
beta(psi), beta = atan2(sin psi, k + cos psi); h = dbeta/dpsi and its derivatives, the
face's psi for a rotor angle, and the layout of the blade's data.
"""

import math

from numba import njit

from kernels import INNER_OPTIONS, INLINE_OPTIONS

#: the blade's data (lower, window, k, level, side): the lower face's lab angle, the reach,
#: k, the last contact's face level and side (+1 met rising, -1 falling, 0 slid off)
LOWER, WINDOW, K, LEVEL, SIDE = range(5)

@njit(**INLINE_OPTIONS)
def beta(psi, k):
    """Polar angle of the contact point ahead of the rotor arm."""
    return math.atan2(math.sin(psi), k + math.cos(psi))


@njit(**INLINE_OPTIONS)
def h_ratio(psi, k):
    """h = dbeta/dpsi = (1 + k cos psi)/X."""
    return (1.0 + k * math.cos(psi)) / (k * k + 1.0 + 2.0 * k * math.cos(psi))


@njit(**INLINE_OPTIONS)
def h_slope(psi, k):
    """dh/dpsi = k (1 - k^2) sin psi / X^2."""
    x = k * k + 1.0 + 2.0 * k * math.cos(psi)
    return k * (1.0 - k * k) * math.sin(psi) / (x * x)


@njit(**INLINE_OPTIONS)
def h_curvature(psi, k):
    """d2h/dpsi2 = k (1 - k^2) (X cos psi + 4 k sin^2 psi)/X^3."""
    s, c = math.sin(psi), math.cos(psi)
    x = k * k + 1.0 + 2.0 * k * c
    return k * (1.0 - k * k) * (x * c + 4.0 * k * s * s) / (x * x * x)


@njit(**INNER_OPTIONS)
def face_psi(target, psi, k):
    """psi on a face, beta(psi) = target (Newton from psi)."""
    for _ in range(50):
        step = (beta(psi, k) - target) / h_ratio(psi, k)
        psi -= step
        if abs(step) <= 1e-15:
            break
    return psi

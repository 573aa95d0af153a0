"""Numpy's own loop closure for the linkage tests: the two points at distances rp from p and
rq from q (a dyad's free joint in both assemblies), independent of kernels/fourbar.py."""

import math

import numpy as np


def circle_intersections(p, rp, q, rq):
    """Both intersections of the circles (p, rp) and (q, rq); at a tangent, twice the one
    point."""
    d = q - p
    dist = math.hypot(*d)
    a = (rp**2 - rq**2 + dist**2) / (2.0 * dist)
    h = math.sqrt(max(rp**2 - a**2, 0.0))
    mid = p + a * d / dist
    perp = np.array([-d[1], d[0]]) / dist
    return mid + h * perp, mid - h * perp


def pivot_angles(pivot, crank_pin, coupler, rocker):
    """Both angles at ``pivot`` of a rocker of length ``rocker`` whose far end is the
    coupler's length from the crank pin."""
    return [math.atan2(*(c - pivot)[::-1])
            for c in circle_intersections(crank_pin, coupler, pivot, rocker)]

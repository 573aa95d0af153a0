"""Elementwise arithmetic on states held as tuples of floats, for any state size.

A model keeps its own state size (2 for a pendulum at constant rotor speed, 4 with the rotor)
as a tuple: in numba a tuple lives in registers, and a 4-tuple step ran markedly faster than
the same step on a 4-element array. numba has no elementwise tuple arithmetic, so each function
below writes straight-line code for the tuple's length, with the same order of operations as
a hand-written component (``y + h * (a1 k1 + a2 k2)``). The Runge-Kutta stages (``lincomb``,
``weighted``) are typed by one rule and lowered as LLVM instructions in the caller: typed as
numba functions, their n x m products (20 x 12 on DOP853's variational equations) were
typed one by one, the largest share of the stability example's compile. The others are
``overload``s, left to LLVM to inline, not inlined in numba's IR: on the 20-component state
of the variational equations IR inlining made type inference the bulk of the compile, and
the steps run as fast.
Plain-Python versions of the same functions serve tests and callers outside numba.
"""

import math

from numba.core import types
from numba.extending import lower_builtin, overload, type_callable

from kernels import OVERLOAD_OPTIONS


def _compile(name: str, args: str, body: str, prelude: str = ""):
    namespace = {"math": math}
    exec(f"def {name}({args}):\n{prelude}    return {body}\n", namespace)
    return namespace[name]


def _tuple(items: list[str]) -> str:
    return "(" + ", ".join(items) + ("," if len(items) == 1 else "") + ")"


def lincomb(y, h, coefs, ks):
    """y + h (coefs[0] ks[0] + coefs[1] ks[1] + ...), elementwise."""
    return tuple(y[i] + h * sum(c * k[i] for c, k in zip(coefs, ks)) for i in range(len(y)))


def weighted(h, coefs, ks):
    """h (coefs[0] ks[0] + coefs[1] ks[1] + ...), elementwise."""
    return tuple(h * sum(c * k[i] for c, k in zip(coefs, ks)) for i in range(len(ks[0])))


def hermite(s, h, y0, f0, y1, f1):
    """The cubic Hermite interpolant of a step at s in [0, h], from the values and slopes
    at both ends, elementwise."""
    t = s / h
    t2, t3 = t * t, t * t * t
    return tuple((2 * t3 - 3 * t2 + 1) * a + (t3 - 2 * t2 + t) * h * da
                 + (-2 * t3 + 3 * t2) * b + (t3 - t2) * h * db
                 for a, da, b, db in zip(y0, f0, y1, f1))


def hermite_slope(s, h, y0, f0, y1, f1):
    """The slope of the cubic Hermite interpolant at s, elementwise."""
    t = s / h
    return tuple((6 * t * t - 6 * t) * a / h + (3 * t * t - 4 * t + 1) * da
                 + (-6 * t * t + 6 * t) * b / h + (3 * t * t - 2 * t) * db
                 for a, da, b, db in zip(y0, f0, y1, f1))


def error_norm(err, scales):
    """The RMS of err over scales: sqrt(mean((err_i / scale_i)^2))."""
    return (sum((e / c) ** 2 for e, c in zip(err, scales)) / len(err)) ** 0.5


def relative_scales(y0, y1, rtol, atol):
    """The usual error scale of each component: atol + rtol max(|y0|, |y1|)."""
    return tuple(atol + rtol * max(abs(a), abs(b)) for a, b in zip(y0, y1))


def from_row(like, row, offset):
    """A tuple as long as ``like`` of row[offset], row[offset + 1], ..."""
    return tuple(row[offset + i] for i in range(len(like)))


def _length(tup):
    return tup.count if isinstance(tup, types.UniTuple) else len(tup.types)


def _of_numbers(tup, n=None) -> bool:
    """Whether a numba type is a tuple of real numbers (n of them where given)."""
    return (isinstance(tup, types.BaseTuple) and (n is None or _length(tup) == n)
            and all(isinstance(t, (types.Float, types.Integer)) for t in tup.types))


def _combination_type(h, coefs, ks, y=None):
    """The type of lincomb (with y) or weighted: n floats, for states ks (and y) of n
    numbers each and one coefficient per state; None (numba then says no match) else."""
    if not (isinstance(h, types.Number) and _of_numbers(coefs)
            and isinstance(ks, types.BaseTuple) and 0 < _length(ks) == _length(coefs)):
        return None
    n = _length(ks.types[0])
    if not all(_of_numbers(k, n) for k in ks.types) or not (y is None or _of_numbers(y, n)):
        return None
    return types.UniTuple(types.float64, n)


@type_callable(lincomb)
def _type_lincomb(context):
    def typer(y, h, coefs, ks):
        return _combination_type(h, coefs, ks, y)
    return typer


@type_callable(weighted)
def _type_weighted(context):
    def typer(h, coefs, ks):
        return _combination_type(h, coefs, ks)
    return typer


@lower_builtin(lincomb, types.BaseTuple, types.Number, types.BaseTuple, types.BaseTuple)
@lower_builtin(weighted, types.Number, types.BaseTuple, types.BaseTuple)
def _lower_combination(context, builder, sig, args):
    """lincomb or weighted (by the count of its arguments) as LLVM instructions in the
    caller, in the order of the written sum: y[i] + h * ((c0 k0[i] + c1 k1[i]) + ...)."""
    *state, (h_type, h), (coefs_type, coefs), (ks_type, ks) = zip(sig.args, args)
    f8 = types.float64

    def element(value, tuple_type, i):
        return context.cast(builder, builder.extract_value(value, i), tuple_type.types[i], f8)

    h = context.cast(builder, h, h_type, f8)
    terms = [(element(coefs, coefs_type, j), builder.extract_value(ks, j), ks_type.types[j])
             for j in range(_length(coefs_type))]
    out = []
    for i in range(_length(sig.return_type)):
        total = None
        for c, k, k_type in terms:
            product = builder.fmul(c, element(k, k_type, i))
            total = product if total is None else builder.fadd(total, product)
        value = builder.fmul(h, total)
        for y_type, y in state:  # lincomb's y: none for weighted
            value = builder.fadd(element(y, y_type, i), value)
        out.append(value)
    return context.make_tuple(builder, sig.return_type, out)


@overload(from_row, jit_options=OVERLOAD_OPTIONS)
def _from_row(like, row, offset):
    return _compile("from_row", "like, row, offset",
                    _tuple([f"row[offset + {i}]" for i in range(_length(like))]))


_HERMITE_WEIGHTS = ("    t = s / h\n    t2, t3 = t * t, t * t * t\n"
                    "    w0, w1 = 2 * t3 - 3 * t2 + 1, t3 - 2 * t2 + t\n"
                    "    w2, w3 = -2 * t3 + 3 * t2, t3 - t2\n")
_SLOPE_WEIGHTS = ("    t = s / h\n"
                  "    w0, w1 = 6 * t * t - 6 * t, 3 * t * t - 4 * t + 1\n"
                  "    w2, w3 = -6 * t * t + 6 * t, 3 * t * t - 2 * t\n")


def _cubic(name: str, weights: str, term: str):
    """The overload of a cubic Hermite expression: its four weights at s, then ``term`` of
    each component i."""
    def implementation(s, h, y0, f0, y1, f1):
        return _compile(name, "s, h, y0, f0, y1, f1",
                        _tuple([term.format(i=i) for i in range(_length(y0))]), weights)
    return implementation


overload(hermite, jit_options=OVERLOAD_OPTIONS)(_cubic(
    "hermite", _HERMITE_WEIGHTS,
    "(w0 * y0[{i}] + w1 * h * f0[{i}] + w2 * y1[{i}] + w3 * h * f1[{i}])"))
overload(hermite_slope, jit_options=OVERLOAD_OPTIONS)(_cubic(
    "hermite_slope", _SLOPE_WEIGHTS,
    "(w0 * y0[{i}] / h + w1 * f0[{i}] + w2 * y1[{i}] / h + w3 * f1[{i}])"))


@overload(relative_scales, jit_options=OVERLOAD_OPTIONS)
def _relative_scales(y0, y1, rtol, atol):
    n = _length(y0)
    return _compile("relative_scales", "y0, y1, rtol, atol",
                    _tuple([f"atol + rtol * max(abs(y0[{i}]), abs(y1[{i}]))"
                            for i in range(n)]))


@overload(error_norm, jit_options=OVERLOAD_OPTIONS)
def _error_norm(err, scales):
    n = _length(err)
    total = " + ".join(f"(err[{i}] / scales[{i}]) ** 2" for i in range(n))
    return _compile("error_norm", "err, scales", f"math.sqrt({1.0 / n!r} * ({total}))")

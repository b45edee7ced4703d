"""Compiled (numba) tabulated traction ``mu(nu, r_g)``: the law of
`empact.variator.traction.TabulatedTraction` for the nonlinear model's kernel (private).

The table is encoded by `TabulatedTraction.encode` into a flat float vector that the kernel
appends to its parameter vector ``p`` (its offset in ``p`` is ``base``)::

    [n_r, r_1 .. r_n, start_1 .. start_n, nu_lo, nu_hi,
     (n, nu_1 .. nu_n, mu_1 .. mu_n, d_1 .. d_n, o_1 .. o_(n-1)) per curve]

with the ratios ``r_i`` [-] (not their logarithms: the table is linear in ``r_g``), each
curve's start as an offset from the beginning of the table, the slips every curve covers
(``TabulatedTraction.nu_range``), and per curve the knots ``nu``
[-], the values ``mu`` [-] and the knot slopes ``d = d mu / d nu`` [-] that
`scipy.interpolate.PchipInterpolator` computed when the table was loaded, and the curve's
segments ordered by their larger knot value, largest first (``o``: the peak search visits
only the segments that can hold the peak).  Between two knots
the curve is scipy's cubic Hermite polynomial (the same coefficients, formed as
`scipy.interpolate.CubicHermiteSpline` forms them); outside its knots a curve is held at its
end value (slope 0: the model is only valid inside ``TabulatedTraction.nu_range``, where it
equals ``TabulatedTraction.mu``).  Between the curves: linear in ``r_g``, held constant
outside the tabulated ratios.

``mu_max(r_g)``, the denominator of the torque ratio ``tau = mu / mu_max``, is the true peak
of the interpolated curve at that ratio over the slips every curve covers
(``TabulatedTraction.nu_range``, where the model is valid): the largest value of
the piecewise-cubic blend ``(1 - w) mu_i + w mu_(i+1)``, found exactly (the blend's
stationary points on each interval between the union of both curves' knots, a quadratic's
roots, and the interval ends; PCHIP is monotone on every segment, so a segment whose knot
values stay below a value already found cannot hold the peak and is not searched).  Its
slope in ``r_g`` follows from the envelope theorem: ``d mu_max / d w = mu_(i+1)(nu*) -
mu_i(nu*)`` at the peak's slip ``nu*``.  For the analytic magic formula ``mu_max`` is its
coefficient ``D(r_g)``, the same definition (the formula's peak).

Every function takes real or complex ``nu`` / ``r_g`` where the kernel's complex step needs
it (branches on the real part; a knot counts to the segment on its left), and the ``_d``
functions return the partial derivatives the forward mode needs, on the same branches.
"""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _coefficients(p, start, j):
    """``(x_j, c0, c1, c2, c3)``: segment `j` of the curve at ``p[start:]`` as the polynomial
    ``((c0 s + c1) s + c2) s + c3`` in ``s = nu - x_j`` (scipy's CubicHermiteSpline
    coefficients from the knot values and slopes)."""
    n = int(p[start])
    x0 = p[start + 1 + j]
    x1 = p[start + 2 + j]
    y0 = p[start + 1 + n + j]
    y1 = p[start + 2 + n + j]
    d0 = p[start + 1 + 2 * n + j]
    d1 = p[start + 2 + 2 * n + j]
    dx = x1 - x0
    slope = (y1 - y0) / dx
    t = (d0 + d1 - 2.0 * slope) / dx
    return x0, t / dx, (slope - d0) / dx - t, d0, y0


@njit(cache=True)
def _segment(xr, p, start):
    """The segment of the curve at ``p[start:]`` holding the real slip `xr`: ``j`` with
    ``nu_j < xr <= nu_(j+1)`` (the first segment from ``nu_0`` on), ``-1`` below the first
    knot, ``n - 1`` above the last."""
    n = int(p[start])
    if xr < p[start + 1]:
        return -1
    if xr > p[start + n]:
        return n - 1
    if xr <= p[start + 2]:
        return 0
    lo, hi = 1, n - 1  # bisection: nu_lo < xr <= nu_hi
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if p[start + 1 + mid] < xr:
            lo = mid
        else:
            hi = mid
    return lo


@njit(cache=True)
def _curve(x, p, start):
    """One tabulated curve at slip `x` (real or complex), held constant outside its knots."""
    n = int(p[start])
    j = _segment(x.real, p, start)
    if j < 0:
        return p[start + 1 + n] + 0.0 * x
    if j == n - 1:
        return p[start + 2 * n] + 0.0 * x
    x0, c0, c1, c2, c3 = _coefficients(p, start, j)
    s = x - x0
    return ((c0 * s + c1) * s + c2) * s + c3


@njit(cache=True)
def _curve_d(x, p, start):
    """`_curve` at real `x` and its slope ``d mu / d nu``."""
    n = int(p[start])
    j = _segment(x, p, start)
    if j < 0:
        return p[start + 1 + n], 0.0
    if j == n - 1:
        return p[start + 2 * n], 0.0
    x0, c0, c1, c2, c3 = _coefficients(p, start, j)
    s = x - x0
    return ((c0 * s + c1) * s + c2) * s + c3, (3.0 * c0 * s + 2.0 * c1) * s + c2


@njit(cache=True)
def _bracket(rr, p, base):
    """``(i, k)``: the curves at ``p[base:]`` that a real ratio `rr` lies between (``i == k``
    outside the tabulated ratios or for one curve; a tabulated ratio counts to the interval on
    its left)."""
    n_r = int(p[base])
    if n_r == 1 or rr <= p[base + 1]:
        return 0, 0
    for i in range(n_r - 1):
        if rr <= p[base + 2 + i]:
            return i, i + 1
    return n_r - 1, n_r - 1


@njit(cache=True)
def _start(p, base, i):
    """Offset in ``p`` of curve `i` of the table at ``p[base:]``."""
    return base + int(p[base + 1 + int(p[base]) + i])


@njit(cache=True)
def _nu_range(p, base):
    """``(nu_lo, nu_hi)``: the slips every curve of the table at ``p[base:]`` covers."""
    n_r = int(p[base])
    return p[base + 1 + 2 * n_r], p[base + 2 + 2 * n_r]


@njit(cache=True)
def table_mu(nu, r_g, p, base):
    """Tabulated traction coefficient ``mu(nu, r_g)`` [-] (real or complex arguments)."""
    i, k = _bracket(r_g.real, p, base)
    c0 = _curve(nu, p, _start(p, base, i))
    if i == k:
        return c0 + 0.0 * r_g
    r0 = p[base + 1 + i]
    w = (r_g - r0) / (p[base + 1 + k] - r0)
    return c0 + w * (_curve(nu, p, _start(p, base, k)) - c0)


@njit(cache=True)
def table_mu_d(nu, r_g, p, base):
    """``(mu, d mu / d nu, d mu / d ln r_g)``: `table_mu` at real arguments and its partials."""
    i, k = _bracket(r_g, p, base)
    c0, s0 = _curve_d(nu, p, _start(p, base, i))
    if i == k:
        return c0, s0, 0.0
    r0 = p[base + 1 + i]
    dr = p[base + 1 + k] - r0
    w = (r_g - r0) / dr
    c1, s1 = _curve_d(nu, p, _start(p, base, k))
    return c0 + w * (c1 - c0), s0 + w * (s1 - s0), (c1 - c0) * r_g / dr


@njit(cache=True)
def _blend_at(x, w, p, sa, ja, sb, jb):
    """``(1 - w) mu_a + w mu_b`` and its slope at real `x`, the curves at ``p[sa:]``,
    ``p[sb:]`` on their segments `ja`, `jb`, written as the kernel evaluates the blend."""
    xa, a0, a1, a2, a3 = _coefficients(p, sa, ja)
    xb, b0, b1, b2, b3 = _coefficients(p, sb, jb)
    s = x - xa
    t = x - xb
    va = ((a0 * s + a1) * s + a2) * s + a3
    vb = ((b0 * t + b1) * t + b2) * t + b3
    da = (3.0 * a0 * s + 2.0 * a1) * s + a2
    db = (3.0 * b0 * t + 2.0 * b1) * t + b2
    return va + w * (vb - va), da + w * (db - da)


@njit(cache=True)
def _interval_peak(a, b, w, p, sa, ja, sb, jb):
    """``(value, nu)``: the largest value of the blend ``(1 - w) mu_a + w mu_b`` on ``[a, b]``,
    where the curves stay on their segments `ja`, `jb`: the blend is one cubic there, so its
    largest value is at an end or at a root of its derivative, a quadratic whose coefficients
    follow from the derivative at the ends and the middle (exact for a quadratic).  The first
    of equal values wins."""
    L = b - a
    best, g0 = _blend_at(a, w, p, sa, ja, sb, jb)
    best_x = a
    _, gm = _blend_at(a + 0.5 * L, w, p, sa, ja, sb, jb)
    vb, g1 = _blend_at(b, w, p, sa, ja, sb, jb)
    if vb > best:
        best, best_x = vb, b
    # g(z) = q2 z^2 + q1 z + q0 on z = nu - a in [0, L] through g0, gm, g1
    q0 = g0
    q2 = 2.0 * (g1 - 2.0 * gm + g0) / (L * L)
    q1 = (g1 - g0) / L - q2 * L
    z1 = -1.0
    z2 = -1.0
    if q2 == 0.0:
        if q1 != 0.0:
            z1 = -q0 / q1
    else:
        disc = q1 * q1 - 4.0 * q2 * q0
        if disc >= 0.0:
            qq = -0.5 * (q1 + np.copysign(np.sqrt(disc), q1))
            z1 = qq / q2
            if qq != 0.0:
                z2 = q0 / qq
    for z in (z1, z2):
        if 0.0 < z < L:
            v, _ = _blend_at(a + z, w, p, sa, ja, sb, jb)
            if v > best:
                best, best_x = v, a + z
    return best, best_x


@njit(cache=True)
def _bound(w, p, sa, ja, sb, jb):
    """An upper bound of the blend on the segments `ja`, `jb`: PCHIP is monotone on every
    segment (shape-preserving), so each curve stays between its segment's knot values."""
    na = int(p[sa])
    nb = int(p[sb])
    ya = max(p[sa + 1 + na + ja], p[sa + 2 + na + ja])
    yb = max(p[sb + 1 + nb + jb], p[sb + 2 + nb + jb])
    return (1.0 - w) * ya + w * yb


@njit(cache=True)
def _peak(w, p, sa, sb, lo, hi):
    """``(nu*, mu_a(nu*), mu_b(nu*))``: the slip of the largest value of the blend
    ``(1 - w) mu_a + w mu_b`` (real `w` in [0, 1]) on ``[lo, hi]`` (slips both curves
    cover), and the two curves' values there.

    The blend is one cubic on each interval between the union of both curves' knots
    (`_interval_peak` finds its largest value exactly).  At the peak ``nu*`` the blend is at
    most the larger of the two curves' segment maxima there (each is its larger knot value:
    PCHIP is monotone on a segment), so the peak lies on a segment of either curve whose
    larger knot value, blended with the other curve's largest, exceeds the best value found:
    each curve's segments are visited largest first (the encoded order) until that bound
    falls to it, and only the intervals whose bound (`_bound`) exceeds it are searched - a
    few near the peak, whatever the number of knots.  (A value equal to the best found is
    not searched again: of equal largest values the one found first is kept.)"""
    best, _ = _blend_at(lo, w, p, sa, max(_segment(lo, p, sa), 0), sb,
                        max(_segment(lo, p, sb), 0))
    best_x = lo
    for s in (sa, sb):  # a high first value: the blend at each curve's highest knot
        n = int(p[s])
        j = int(p[s + 1 + 3 * n])
        k = j if p[s + 1 + n + j] >= p[s + 2 + n + j] else j + 1
        x = p[s + 1 + k]
        if lo <= x <= hi:
            v, _ = _blend_at(x, w, p, sa, max(_segment(x, p, sa), 0), sb,
                             max(_segment(x, p, sb), 0))
            if v > best:
                best, best_x = v, x
    for which in range(2):
        s, so = (sa, sb) if which == 0 else (sb, sa)
        n = int(p[s])
        no = int(p[so])
        jo = int(p[so + 1 + 3 * no])
        top_o = max(p[so + 1 + no + jo], p[so + 2 + no + jo])  # the other curve's largest
        ws, wo = (1.0 - w, w) if which == 0 else (w, 1.0 - w)
        for r in range(n - 1):
            j = int(p[s + 1 + 3 * n + r])
            if ws * max(p[s + 1 + n + j], p[s + 2 + n + j]) + wo * top_o <= best:
                break  # no point of this segment, nor of a later (lower) one, is higher
            x0 = max(p[s + 1 + j], lo)
            x1 = min(p[s + 2 + j], hi)
            if not x0 < x1:
                continue
            jo = max(_segment(x0, p, so), 0)
            a = x0
            while a < x1:
                # [a, b]: this curve on segment j, the other on jo throughout
                while jo < no - 2 and p[so + 2 + jo] <= a:
                    jo += 1
                b = min(p[so + 2 + jo], x1)
                ja, jb = (j, jo) if which == 0 else (jo, j)
                if _bound(w, p, sa, ja, sb, jb) > best:
                    v, x = _interval_peak(a, b, w, p, sa, ja, sb, jb)
                    if v > best or (v == best and x < best_x):
                        best, best_x = v, x
                a = b
    va = _curve(best_x, p, sa)
    vb = _curve(best_x, p, sb)
    return best_x, va, vb


@njit(cache=True)
def table_peak(r_g, p, base):
    """``(nu*, mu_max, d mu_max / d ln r_g)`` at the real ratio `r_g`: the slip [-] of the
    interpolated curve's peak, the peak [-] and its slope (envelope theorem)."""
    i, k = _bracket(r_g, p, base)
    sa = _start(p, base, i)
    lo, hi = _nu_range(p, base)
    if i == k:
        x, va, _ = _peak(0.0, p, sa, sa, lo, hi)
        return x, va, 0.0
    r0 = p[base + 1 + i]
    dr = p[base + 1 + k] - r0
    w = (r_g - r0) / dr
    x, va, vb = _peak(w, p, sa, _start(p, base, k), lo, hi)
    return x, va + w * (vb - va), (vb - va) * r_g / dr


@njit(cache=True)
def table_mu_max(r_g, p, base):
    """``mu_max(r_g)`` [-] (real or complex `r_g`): the peak of the interpolated curve at
    ``r_g.real``, continued analytically in `r_g` (the peak's slip held, exact to first
    order by the envelope theorem)."""
    i, k = _bracket(r_g.real, p, base)
    sa = _start(p, base, i)
    lo, hi = _nu_range(p, base)
    if i == k:
        x, va, _ = _peak(0.0, p, sa, sa, lo, hi)
        return va + 0.0 * r_g
    r0 = p[base + 1 + i]
    w = (r_g - r0) / (p[base + 1 + k] - r0)
    x, va, vb = _peak(w.real, p, sa, _start(p, base, k), lo, hi)
    return va + w * (vb - va)


@njit(cache=True)
def table_many(nu, r_g, p, base, mu, dmu, peak_nu, peak_mu):
    """For 1-D arrays: ``mu[k], dmu[k]`` at ``(nu[k], r_g[k])`` and the peak
    ``peak_nu[k], peak_mu[k]`` at ``r_g[k]`` (`TabulatedTraction.mu_max` and the tests)."""
    for k in range(r_g.shape[0]):
        m, s, _ = table_mu_d(nu[k], r_g[k], p, base)
        mu[k] = m
        dmu[k] = s
        x, v, _ = table_peak(r_g[k], p, base)
        peak_nu[k] = x
        peak_mu[k] = v

r"""Roots of many small real polynomials at once, with a certificate per polynomial (private).

`polyroots(coeffs)` solves ``N`` real polynomials of one degree ``n`` (rows of `coeffs`,
highest power first, as `numpy.roots`) in one compiled loop (numba ``@njit(cache=True,
nogil=True)``; callers may run chunks in threads).  Per polynomial:

1. Exact zero roots: trailing zero coefficients are roots at exactly 0 (deflated).
2. Scaling ``s = sigma t`` with ``sigma = |a_0 / a_n|^(1/n)`` (geometric mean of the root
   moduli) and division by the leading coefficient: a monic polynomial whose roots have
   geometric-mean modulus 1 (the slip model's roots span ~0.1 to ~1e5 rad/s).
3. Start: Bini's Newton-polygon start - for each edge of the upper convex hull of
   ``(k, log|b_k|)`` as many points as the edge is long, on a circle of the edge's radius
   (rotated, so no point is real and no two circles line up).
4. Aberth-Ehrlich iteration (simultaneous, Gauss-Seidel) until every correction is below
   ``4 eps |z|`` or `MAX_ITER` sweeps, then one Newton step per root (polish).
5. Certificate (Braess-Hadeler inclusion): for a monic polynomial the disks
   ``D(z_i, n |W_i|)`` with the Weierstrass corrections ``W_i = p(z_i) / prod_{j != i}
   (z_i - z_j)`` contain all roots and every connected component of ``m`` disks contains
   exactly ``m`` roots.  ``|p(z_i)|`` is bounded above by its computed value plus the Horner
   rounding bound ``4 n eps sum |b_k| |z_i|^k``.  A polynomial is *converged* when the disks
   are pairwise disjoint (each holds exactly one root) and every radius is at most
   ``rtol |z_i|``: every returned root is then within ``rtol`` relative of a true root.
   A root whose disk touches the real axis is made exactly real when the mirrored disk meets
   no other disk (the conjugate root must then be the same root); otherwise the polynomial
   is not converged.  Repeated or nearly repeated roots (overlapping disks) are never
   certified.

Not converged polynomials keep their (uncertified) approximations and ``converged = False``:
the caller must treat them otherwise (`empact.slip.stability_map` recomputes them with
`numpy.linalg.eigvals` and counts them).
"""
from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

#: Aberth sweeps before giving up (quadratic/cubic convergence needs ~10 from the start).
MAX_ITER = 60
#: Default certified relative accuracy of every root.
RTOL = 1e-11

_EPS = np.finfo(float).eps


@njit(cache=True, nogil=True)
def _start(b, n, out, logs, hull):  # pragma: no cover - compiled
    """Newton-polygon start points for the monic, scaled polynomial ``b`` (descending)."""
    # points (k, log|coefficient of t^k|), k = 0..n; coefficient of t^k is b[n - k]
    for k in range(n + 1):
        a = abs(b[n - k])
        logs[k] = np.log(a) if a > 0 else -np.inf
    h = 0
    for k in range(n + 1):
        if logs[k] == -np.inf:
            continue
        while h >= 2:
            i0, i1 = hull[h - 2], hull[h - 1]
            # drop i1 if it lies on or below the segment i0 -> k (upper hull)
            if (logs[i1] - logs[i0]) * (k - i0) <= (logs[k] - logs[i0]) * (i1 - i0):
                h -= 1
            else:
                break
        hull[h] = k
        h += 1
    m = 0
    for e in range(h - 1):
        k0, k1 = hull[e], hull[e + 1]
        d = k1 - k0
        u = np.exp((logs[k0] - logs[k1]) / d)
        for j in range(d):
            ang = 2.0 * np.pi * j / d + 2.0 * np.pi * (e + 1) / (n + 1) + 0.4
            out[m] = u * complex(np.cos(ang), np.sin(ang))
            m += 1


@njit(cache=True, nogil=True, inline="always")
def _inv(d):  # pragma: no cover - compiled
    """``1 / d`` without the overflow-safe (slow) complex division; inf/nan for ``d = 0``."""
    a, b = d.real, d.imag
    m = a * a + b * b
    return complex(a / m, -b / m)


@njit(cache=True, nogil=True)
def _horner(b, n, z):  # pragma: no cover - compiled
    p = complex(b[0])
    dp = 0j
    for k in range(1, n + 1):
        dp = dp * z + p
        p = p * z + b[k]
    return p, dp


@njit(cache=True, nogil=True)
def _solve_one(c, rtol, roots, b, babs, z, r, logs, hull):  # pragma: no cover - compiled
    """Roots of one real polynomial `c` (descending, c[0] != 0) into `roots`; certified?"""
    deg = c.shape[0] - 1
    if not np.isfinite(c[0]) or c[0] == 0.0:
        for i in range(deg):
            roots[i] = np.nan
        return False
    nz = 0
    while nz < deg and c[deg - nz] == 0.0:
        nz += 1
    n = deg - nz
    for i in range(nz):
        roots[n + i] = 0j
    if n == 0:
        return True
    sigma = (abs(c[n] / c[0])) ** (1.0 / n)
    sk = 1.0
    for k in range(n + 1):  # coefficient of t^(n-k): c[k] sigma^(n-k) / (c[0] sigma^n)
        b[k] = c[k] / c[0] * sk
        babs[k] = abs(b[k])
        sk /= sigma
    for k in range(n + 1):
        if not np.isfinite(b[k]):
            for i in range(n):
                roots[i] = np.nan
            return False
    _start(b, n, z, logs, hull)
    small = 4.0 * 2.220446049250313e-16
    for _ in range(MAX_ITER):
        done = True
        for i in range(n):
            p, dp = _horner(b, n, z[i])
            if p == 0:
                continue
            ratio = p * _inv(dp)
            s = 0j
            for j in range(n):
                if j != i:
                    s += _inv(z[i] - z[j])
            w = ratio * _inv(1.0 - ratio * s)
            if not (np.isfinite(w.real) and np.isfinite(w.imag)):
                continue
            z[i] -= w
            if abs(w) > small * abs(z[i]):
                done = False
        if done:
            break
    for i in range(n):  # Newton polish
        p, dp = _horner(b, n, z[i])
        if dp != 0:
            step = p / dp
            if np.isfinite(step.real) and np.isfinite(step.imag):
                z[i] -= step
    # Braess-Hadeler inclusion disks
    gamma = 4.0 * (n + 1) * 2.220446049250313e-16
    ok = True
    for i in range(n):
        p, _ = _horner(b, n, z[i])
        az = abs(z[i])
        bound = babs[0]
        for k in range(1, n + 1):
            bound = bound * az + babs[k]
        prod = 1.0
        for j in range(n):
            if j != i:
                prod *= abs(z[i] - z[j])
        if not (prod > 0 and np.isfinite(prod)):
            ok = False
            r[i] = np.inf
        else:
            r[i] = n * (abs(p) + gamma * bound) / prod * (1.0 + gamma)
        if not (r[i] <= rtol * az):
            ok = False
    if ok:
        for i in range(n):
            for j in range(i + 1, n):
                if not (abs(z[i] - z[j]) > r[i] + r[j]):
                    ok = False
    if ok:
        for i in range(n):
            if abs(z[i].imag) <= r[i]:
                zc = z[i].conjugate()
                for j in range(n):
                    if j != i and not (abs(zc - z[j]) > r[i] + r[j]):
                        ok = False
                if ok:
                    z[i] = complex(z[i].real, 0.0)
    for i in range(n):
        roots[i] = z[i] * sigma
    return ok


@njit(cache=True, nogil=True)
def _solve_many(c, rtol, roots, ok):  # pragma: no cover - compiled
    n = c.shape[1] - 1
    b = np.empty(n + 1)
    babs = np.empty(n + 1)
    z = np.empty(n, np.complex128)
    r = np.empty(n)
    logs = np.empty(n + 1)
    hull = np.empty(n + 1, np.int64)
    for k in range(c.shape[0]):
        ok[k] = _solve_one(c[k], rtol, roots[k], b, babs, z, r, logs, hull)


def polyroots(coeffs: ArrayLike, rtol: float = RTOL) \
        -> tuple[NDArray[np.complex128], NDArray[np.bool_]]:
    """Roots of real polynomials, rows of `coeffs` (shape (N, n + 1), highest power first).

    Returns
    -------
    roots : shape (N, n), in no particular order (exact zero roots last)
    converged : shape (N,); True where every root is certified within `rtol` relative of a
        distinct true root (module docstring).  Rows with ``converged = False`` (repeated or
        clustered roots, non-finite or zero leading coefficients) hold uncertified values.
    """
    c = np.ascontiguousarray(np.atleast_2d(np.asarray(coeffs, float)))
    if c.ndim != 2 or c.shape[1] < 2:
        raise ValueError(f"coeffs: need shape (N, n + 1) with n >= 1, got {c.shape}")
    roots = np.empty((c.shape[0], c.shape[1] - 1), np.complex128)
    ok = np.empty(c.shape[0], np.bool_)
    _solve_many(c, float(rtol), roots, ok)
    return roots, ok


def warm_up() -> None:
    """Compile (or load from the cache) the kernels."""
    polyroots(np.array([[1.0, 3.0, 2.0]]))

"""Compiled (numba) measured loss map: the law of `empact.variator.losses.LossMap` for the
nonlinear model's kernel (private).

The map is encoded by `LossMap.encode` into a flat float vector that the kernel appends to
its parameter vector ``p`` (its offset in ``p`` is ``base``)::

    [n_r, n_w, n_T, n_F, ln r_g (n_r), omega_in (n_w), T_in (n_T), F_s (n_F),
     T_loss (n_r n_w n_T n_F, C order)]

The torque loss ``L(T_in; ln r_g, omega, F_s)`` is multilinear on the grid, held constant
outside it (a knot counts to the segment on its left, the complex step's branch, as
`empact.variator._laws.knots_at`).  The kernel knows the belt's torque on the primary
``T_pb``, not the input torque: the primary carries ``T_in = T_pb + sg L(T_in)`` (``sg`` the
smooth sign of its speed), and its loss torque is ``Lambda = sg L(T_in)``.  At fixed ratio,
speed and force ``L`` is piecewise linear in ``T_in`` with the torque knots as breakpoints
(the blend of the eight neighbouring lines), so the fixed point is solved exactly: the
segment where ``g_j = T_j - sg L_j`` brackets ``T_pb`` (``g`` increases, `LossMap` checks
``|dL/dT_in| < 1``), then one linear solve.  Its partials follow from the implicit
function::

    dLambda = (L dsg + sg s dT_pb + sg L_x dx) / (1 - sg s)

with ``s`` the segment's slope in ``T_in`` and ``L_x`` the slopes in ``x = ln r_g, omega,
F_s`` at fixed ``T_in``.  `table_loss` takes real or complex arguments (the complex step);
`table_loss_d` returns the value and its partials (real, the forward mode), on the same
branches.
"""
from __future__ import annotations

from numba import njit


@njit(cache=True, inline="always")
def _axis(x, p, k0, n):
    """``(j, t, dt/dx)``: the segment ``j`` of `x` on the `n` knots ``p[k0:k0 + n]``, its
    weight ``t`` in [0, 1] (real or complex) and the weight's slope (0 outside the knots,
    where the map is held constant)."""
    if n == 1 or x.real <= p[k0]:
        return 0, 0.0 * x, 0.0
    for j in range(n - 1):
        if x.real <= p[k0 + j + 1]:
            run = p[k0 + j + 1] - p[k0 + j]
            return j, (x - p[k0 + j]) / run, 1.0 / run
    return n - 2, 1.0 + 0.0 * x, 0.0


@njit(cache=True, inline="always")
def _blend(p, v0, nr, nw, nT, nF, ir, iw, iF, tr, tw, tF, j):
    """``(L, dL/dtr, dL/dtw, dL/dtF)``: the map at torque knot `j`, blended linearly over the
    ratio, speed and force cells ``(ir, iw, iF)`` with weights ``tr, tw, tF``."""
    r1 = min(ir + 1, nr - 1)
    w1 = min(iw + 1, nw - 1)
    f1 = min(iF + 1, nF - 1)
    # the four lines along F_s at the corners (ratio, speed): their values and rises
    c00 = v0 + ((ir * nw + iw) * nT + j) * nF
    c01 = v0 + ((ir * nw + w1) * nT + j) * nF
    c10 = v0 + ((r1 * nw + iw) * nT + j) * nF
    c11 = v0 + ((r1 * nw + w1) * nT + j) * nF
    d00 = p[c00 + f1] - p[c00 + iF]
    d01 = p[c01 + f1] - p[c01 + iF]
    d10 = p[c10 + f1] - p[c10 + iF]
    d11 = p[c11 + f1] - p[c11 + iF]
    A00 = p[c00 + iF] + tF * d00
    A01 = p[c01 + iF] + tF * d01
    A10 = p[c10 + iF] + tF * d10
    A11 = p[c11 + iF] + tF * d11
    B0 = A00 + tw * (A01 - A00)
    B1 = A10 + tw * (A11 - A10)
    L = B0 + tr * (B1 - B0)
    L_tr = B1 - B0
    L_tw = (1.0 - tr) * (A01 - A00) + tr * (A11 - A10)
    L_tF = ((1.0 - tr) * ((1.0 - tw) * d00 + tw * d01)
            + tr * ((1.0 - tw) * d10 + tw * d11))
    return L, L_tr, L_tw, L_tF


@njit(cache=True, inline="always")
def _locate(lr, w, F, p, base):
    """The map's sizes, the offsets of its torque knots and values, and the cells and
    weights of the point (with the weights' slopes)."""
    nr = int(p[base])
    nw = int(p[base + 1])
    nT = int(p[base + 2])
    nF = int(p[base + 3])
    kr = base + 4
    kw = kr + nr
    kT = kw + nw
    kF = kT + nT
    v0 = kF + nF
    ir, tr, sr = _axis(lr, p, kr, nr)
    iw, tw, sw = _axis(w, p, kw, nw)
    iF, tF, sF = _axis(F, p, kF, nF)
    return nr, nw, nT, nF, kT, v0, ir, iw, iF, tr, tw, tF, sr, sw, sF


@njit(cache=True, inline="always")
def _segment(T_pb, sg, p, nr, nw, nT, nF, kT, v0, ir, iw, iF, tr, tw, tF):
    """``(j, k)``: the torque segment holding the solution of ``T_in = T_pb + sg L(T_in)``:
    ``k = 0`` below the first knot, ``k = 2`` above the last, else ``k = 1`` and
    ``g_j < T_pb <= g_(j+1)``; and the blended values at ``j`` and ``j + 1``."""
    L0 = _blend(p, v0, nr, nw, nT, nF, ir, iw, iF, tr, tw, tF, 0)[0]
    if T_pb.real <= (p[kT] - sg * L0).real:
        return 0, 0, L0, L0
    for j in range(nT - 1):
        L1 = _blend(p, v0, nr, nw, nT, nF, ir, iw, iF, tr, tw, tF, j + 1)[0]
        if T_pb.real <= (p[kT + j + 1] - sg * L1).real:
            return j, 1, L0, L1
        L0 = L1
    return nT - 1, 2, L0, L0


@njit(cache=True)
def table_loss(T_pb, lr, w, F, sg, p, base):
    """``sg L(T_in)`` [N m]: the loss torque on the primary where the belt takes `T_pb` from
    it, at log-ratio `lr`, primary speed `w` [rad/s] and clamping force `F` [N], the map
    encoded at ``p[base:]`` (module notes); real or complex."""
    nr, nw, nT, nF, kT, v0, ir, iw, iF, tr, tw, tF, _, _, _ = _locate(lr, w, F, p, base)
    j, k, L0, L1 = _segment(T_pb, sg, p, nr, nw, nT, nF, kT, v0, ir, iw, iF, tr, tw, tF)
    if k != 1:
        return sg * L0
    Tj = p[kT + j]
    s = (L1 - L0) / (p[kT + j + 1] - Tj)
    T_in = Tj + (T_pb - (Tj - sg * L0)) / (1.0 - sg * s)
    return sg * (L0 + s * (T_in - Tj))


@njit(cache=True)
def table_loss_d(T_pb, lr, w, F, sg, p, base):
    """``(Lambda, dLambda/dT_pb, dLambda/dlr, dLambda/dw, dLambda/dF, dLambda/dsg)``:
    `table_loss` and its partials (real; module notes)."""
    nr, nw, nT, nF, kT, v0, ir, iw, iF, tr, tw, tF, sr, sw, sF = _locate(lr, w, F, p, base)
    j, k, _, _ = _segment(T_pb, sg, p, nr, nw, nT, nF, kT, v0, ir, iw, iF, tr, tw, tF)
    L0, a_r, a_w, a_F = _blend(p, v0, nr, nw, nT, nF, ir, iw, iF, tr, tw, tF, j)
    s = 0.0
    L = L0
    if k == 1:
        L1, b_r, b_w, b_F = _blend(p, v0, nr, nw, nT, nF, ir, iw, iF, tr, tw, tF, j + 1)
        Tj = p[kT + j]
        dT = p[kT + j + 1] - Tj
        s = (L1 - L0) / dT
        T_in = Tj + (T_pb - (Tj - sg * L0)) / (1.0 - sg * s)
        th = (T_in - Tj) / dT
        L = L0 + s * (T_in - Tj)
        a_r = (1.0 - th) * a_r + th * b_r
        a_w = (1.0 - th) * a_w + th * b_w
        a_F = (1.0 - th) * a_F + th * b_F
    q = 1.0 / (1.0 - sg * s)
    return (sg * L, sg * s * q, sg * a_r * sr * q, sg * a_w * sw * q, sg * a_F * sF * q,
            L * q)

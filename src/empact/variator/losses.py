"""The pushbelt variator's losses beside the slip: clamping, load and drag (the ``[losses]``
block).

The kernel (`empact.nonlinear._kernel._losses`) applies them as torques on the pulley shafts,
each opposing its shaft's rotation (smooth sign ``tanh(omega / coulomb_omega)``, as the
model's Coulomb terms)::

    primary:    T_var_p = r_g T_b + T_clamp + T_load + T_drag(omega_p)
    secondary:  T_var_s = T_b - T_drag(omega_s)

    T_clamp = lambda_F F_s R_p                    (power lambda_F F_s v_b, v_b = R_p omega_p)
    T_load  = k_T |r_g T_b|                       (|T| ~ T tanh(T / T_smooth))
    T_drag(omega) = c_v omega + c_q omega^2 sg(omega)     (on each shaft at its own speed)

so that ``P_var_in - P_var_out = P_slip + P_clamp + P_load + P_drag`` with the shaft powers
``P_var_in = T_var_p omega_p`` and ``P_var_out = T_var_s omega_s`` (outputs ``P_loss_*``,
``P_var_in``, ``P_var_out`` of `empact.nonlinear`; `empact.nonlinear.VARIATOR_LOSSES`).

Forms and sources.  The loss mechanisms are those of Akehurst, Vaughan, Parker & Simner,
Proc. IMechE D 218 (2004), Parts 1-3: band-set and segment friction and band-band sliding
(Part 1), pulley deflection and misalignment, i.e. the belt's radial motion in the wrap
(Part 2), and belt-pulley slip (Part 3; the kernel's slip power).  Micklem et al., Proc.
IMechE D 210 (1996): the belt's torque loss, the pump and the slip lead the losses, and
"much lower pulley clamping pressures" are the remedy, i.e. a torque loss growing with the
clamping force.  Narita & Priest, Proc. IMechE J 221 (2007) (a production unit at secondary
clamping 10.5-34.6 kN): efficiency falls at low load (a load-independent torque: clamping
and drag) and towards overdrive.  van der Meulen et al. (extremum seeking of the variator's
efficiency): efficiency over clamping force has an interior maximum, where the falling slip
power meets the rising clamping loss.  The clamping term is written as a sliding power at the
belt speed: at given input torque and torque ratio ``F_s R_p = T_in cos(beta) / (2 tau
mu_max)``, so its share of the input torque does not depend on the radii but grows with the
clamping reserve and where mu_max is low (overdrive, Fig. 10).

The coefficients are estimates (no published coefficient of these forms could be read): the
bands of ``data/parameter_sources.toml`` state their basis.

A measured map replaces the analytic terms (clamping, load, drag) when given: `LossMap`, read
by `load_loss_map` from a CSV over ratio, input speed, input torque and clamping force
(``[losses] table = "map.csv"`` in a parameter file, ``--loss-map`` on the command line,
``ModelOptions(loss_map=...)``); the slip stays the traction law's.
"""
from __future__ import annotations

import csv
import os
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._columns import column_name, load_records
from .._io import check_input, read_input_text
from .._section import Section, param
from ..errors import ParameterError
from ._tables import interp_knots, knot_segments

__all__ = ["LossParams", "LossMap", "load_loss_map", "MAP_AXES"]


@dataclass(frozen=True)
class LossParams(Section):
    """The variator's losses beside the slip (``[losses]``; every key has a default).

    Attributes
    ----------
    lambda_F : float
        Clamping loss [-]: ``T_clamp = lambda_F F_s R_p`` on the primary, the sliding power
        ``lambda_F F_s v_b`` at the belt speed (default 3e-3: 0.17 N m per kN of clamping at
        r_g 1; estimate).
    k_T : float
        Load loss [-]: ``T_load = k_T |r_g T_b|`` on the primary, a fraction of the input
        torque (default 0.01; estimate).
    c_v : float
        Viscous drag of each pulley shaft [N m s/rad] (default 5e-4: 0.15 N m at 300 rad/s;
        estimate).
    c_q : float
        Quadratic (churning) drag of each pulley shaft [N m s^2/rad^2] (default 1e-6: 0.09 N m
        at 300 rad/s; estimate).
    T_smooth : float
        Torque scale of the smooth ``|T| ~ T tanh(T / T_smooth)`` of the load loss [N m]
        (default 1; a regularisation: the Jacobian exists at zero torque).
    """

    _name = "losses"

    lambda_F: float = param("-", "clamping loss: T_clamp = lambda_F F_s R_p on the primary "
                            "(band and segment friction, sheave deflection; sliding power "
                            "lambda_F F_s v_b)", 0.0, 0.1, lo_open=False, default=3e-3)
    k_T: float = param("-", "load loss: T_load = k_T |r_g T_b| on the primary (torque-"
                       "dependent belt loss)", 0.0, 0.2, lo_open=False, default=0.01)
    c_v: float = param("N m s/rad", "viscous drag of each pulley shaft (spin loss: bearings, "
                       "seals)", 0.0, 0.1, lo_open=False, default=5e-4)
    c_q: float = param("N m s^2/rad^2", "quadratic drag of each pulley shaft (spin loss: oil "
                       "churning)", 0.0, 1e-3, lo_open=False, default=1e-6)
    T_smooth: float = param("N m", "torque scale of the load loss's smooth |T| (a "
                            "regularisation)", 0.0, 100.0, default=1.0)


#: the loss map's axes, in its order (the CSV's columns beside the loss)
MAP_AXES = ("r_g", "omega_in", "T_in", "F_s")
#: each axis' unit and the quantity a CSV header unit must be (`load_loss_map`)
_AXIS_UNITS = {"r_g": ("-", "dimensionless"), "omega_in": ("rad/s", "angular speed"),
               "T_in": ("N m", "torque"), "F_s": ("N", "force"),
               "T_loss": ("N m", "torque"), "efficiency": ("-", "dimensionless")}


@dataclass(frozen=True, eq=False)
class LossMap:
    """A measured torque-loss map of the variator: the torque it loses beside the slip,
    ``T_loss(r_g, omega_in, T_in, F_s)`` [N m] at the primary, on a full tensor grid of ratio,
    input speed, input torque and secondary clamping force, in place of the analytic
    clamping, load and drag terms of `LossParams` (`load_loss_map`, ``[losses] table``).

    What a test rig measures: at each set ratio, speed, input torque and clamping force the
    input and output torques and speeds, so the torque loss ``T_loss = T_in - T_out / i``
    referred to the geometric ratio ``i`` (`r_g` of the paper: ``omega_s = r_g omega_p``
    without slip), the speed loss (the slip) apart.  The model keeps the slip as the
    traction law's (its ``P_loss_slip``) and takes the rest from the map: on the primary
    shaft a loss torque ``T_loss`` at the input torque ``T_in = r_g T_b + T_loss`` the
    primary carries (solved exactly on the interpolant, `torque_loss_at_belt`), none on the
    secondary (its drag is in the map, referred to the primary), so that the variator's
    torque efficiency is ``1 - T_loss / T_in`` and its efficiency ``(1 - T_loss / T_in)
    (1 - nu)``.

    Interpolation: multilinear in ``(ln r_g, omega_in, T_in, F_s)`` (linear along each axis
    between neighbouring grid values, held constant outside the grid), the rule of the other
    measured maps (`empact.variator._tables`); the compiled law is
    `empact.variator._loss_table`, the same numbers.  The loss opposes the primary's
    rotation (the kernel's smooth sign ``tanh(omega_p / coulomb_omega)``).

    Parameters
    ----------
    r_g, omega_in, T_in, F_s : array_like, shapes (n_r,), (n_w,), (n_T,), (n_F,)
        The grid's axes, each strictly increasing: ratios [-] > 0, input speeds [rad/s] >= 0,
        input torques [N m], secondary clamping forces [N] > 0 (one value: the map is
        constant along that axis).
    T_loss : array_like, shape (n_r, n_w, n_T, n_F)
        The torque loss at the primary [N m], >= 0, rising by less than the input torque
        along every line of the torque axis (``|d T_loss / d T_in| < 1``: the output torque
        rises with the input torque, and the input torque the belt needs is unique).
    source : str
        Where the map came from (used in messages).

    Examples
    --------
    >>> import numpy as np
    >>> m = LossMap(r_g=[0.5, 2.0], omega_in=[100.0, 400.0], T_in=[0.0, 200.0],
    ...             F_s=[5e3, 30e3], T_loss=np.full((2, 2, 2, 2), 2.0))
    >>> float(m.efficiency(1.0, 300.0, 100.0, 1e4))      # [-] torque efficiency
    0.98
    """

    r_g: NDArray[np.float64]
    omega_in: NDArray[np.float64]
    T_in: NDArray[np.float64]
    F_s: NDArray[np.float64]
    T_loss: NDArray[np.float64]
    source: str = "loss map"

    def __post_init__(self) -> None:
        src = self.source
        axes = {}
        for name in MAP_AXES:
            try:
                a = np.asarray(getattr(self, name), float).ravel()
            except (TypeError, ValueError):
                raise ParameterError(f"{src}: {name} must be a list of numbers") from None
            if a.size == 0:
                raise ParameterError(f"{src}: no values of {name}")
            bad = np.flatnonzero(~np.isfinite(a))
            if bad.size:
                raise ParameterError(f"{src}: {name} = {a[bad[0]]!r}: must be finite")
            step = np.flatnonzero(np.diff(a) <= 0)
            if step.size:
                i = int(step[0]) + 1
                raise ParameterError(f"{src}: {name} must increase strictly, but {a[i]:g} "
                                     f"follows {a[i - 1]:g}")
            unit = _AXIS_UNITS[name][0]
            if name in ("r_g", "F_s") and a[0] <= 0:
                raise ParameterError(f"{src}: {name} = {a[0]:g}: must be > 0 [{unit}]")
            if name == "omega_in" and a[0] < 0:
                raise ParameterError(f"{src}: omega_in = {a[0]:g}: must be >= 0 [rad/s] "
                                     "(the map is mirrored in speed)")
            axes[name] = a
        shape = tuple(a.size for a in axes.values())
        try:
            L = np.asarray(self.T_loss, float)
        except (TypeError, ValueError):
            raise ParameterError(f"{src}: T_loss must be an array of numbers") from None
        if L.shape != shape:
            raise ParameterError(f"{src}: T_loss has shape {L.shape}, the grid "
                                 f"(r_g, omega_in, T_in, F_s) {shape}")
        for check, what in ((~np.isfinite(L), "must be finite"),
                            (~(L >= 0), "must be >= 0 [N m] (a loss)")):
            where = np.argwhere(check)
            if where.size:
                raise ParameterError(f"{src}: T_loss = {L[tuple(where[0])]:g} at "
                                     f"{self._point(axes, where[0])}: {what}")
        if shape[2] > 1:
            slope = np.diff(L, axis=2) / np.diff(axes["T_in"])[None, None, :, None]
            steep = np.argwhere(~(np.abs(slope) < 1.0))
            if steep.size:
                k = tuple(int(v) for v in steep[0])
                at = self._point(axes, steep[0], skip="T_in")
                T = axes["T_in"]
                raise ParameterError(
                    f"{src}: T_loss changes by {slope[k]:.4g} N m per N m of input torque "
                    f"between T_in = {T[k[2]]:g} and {T[k[2] + 1]:g} N m at {at}: "
                    "|dT_loss/dT_in| must be < 1 (the output torque must rise with the input "
                    "torque)")
        for name, a in axes.items():
            a.setflags(write=False)
            object.__setattr__(self, name, a)
        L = L.copy()
        L.setflags(write=False)
        object.__setattr__(self, "T_loss", L)

    @staticmethod
    def _point(axes: dict[str, NDArray], idx, skip: str = "") -> str:
        units = {"r_g": "", "omega_in": " rad/s", "T_in": " N m", "F_s": " N"}
        return ", ".join(f"{n} = {axes[n][int(i)]:g}{units[n]}"
                         for n, i in zip(MAP_AXES, idx) if n != skip)

    def __hash__(self) -> int:  # arrays are not hashable: hash the contents
        return hash(tuple(getattr(self, n).tobytes() for n in MAP_AXES + ("T_loss",)))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, LossMap) and all(
            np.array_equal(getattr(self, n), getattr(other, n))
            for n in MAP_AXES + ("T_loss",))

    def torque_loss(self, r_g: ArrayLike, omega_in: ArrayLike, T_in: ArrayLike,
                    F_s: ArrayLike) -> NDArray[np.float64]:
        """The map's torque loss [N m] at the primary (multilinear, held constant outside).

        Parameters
        ----------
        r_g : array_like
            Ratios [-].
        omega_in : array_like
            Input (primary) speeds [rad/s].
        T_in : array_like
            Input torques at the primary [N m].
        F_s : array_like
            Secondary clamping forces [N] (all four broadcast).

        Returns
        -------
        ndarray
            ``T_loss`` [N m], the broadcast shape.
        """
        r, w, T, F = np.broadcast_arrays(*(np.asarray(v, float)
                                           for v in (r_g, omega_in, T_in, F_s)))
        lines = self._lines(r, w, F)                      # (n_T,) + shape
        Tk = self.T_in
        i, j = knot_segments(T, Tk)
        return interp_knots(T, Tk, lines, (i, j))

    def efficiency(self, r_g: ArrayLike, omega_in: ArrayLike, T_in: ArrayLike,
                   F_s: ArrayLike) -> NDArray[np.float64]:
        """The torque efficiency ``1 - T_loss / T_in`` [-] (the slip's speed loss apart).

        Parameters
        ----------
        r_g, omega_in, T_in, F_s : array_like
            As `torque_loss` (`T_in` [N m] nonzero).

        Returns
        -------
        ndarray
            The torque efficiency [-], the broadcast shape.
        """
        T = np.asarray(T_in, float)
        return 1.0 - self.torque_loss(r_g, omega_in, T_in, F_s) / T

    def torque_loss_at_belt(self, r_g: ArrayLike, omega_in: ArrayLike, T_pb: ArrayLike,
                            F_s: ArrayLike, sign: ArrayLike = 1.0) -> NDArray[np.float64]:
        """The loss torque ``sign T_loss(r_g, omega_in, T_in, F_s)`` [N m] at the input torque
        ``T_in = T_pb + sign T_loss`` the primary carries when the belt takes `T_pb` from it:
        the kernel's law (`empact.variator._loss_table.table_loss`), solved exactly on the
        interpolant (piecewise linear in ``T_in``).

        Parameters
        ----------
        r_g, omega_in, F_s : array_like
            Ratios [-], primary speeds [rad/s], clamping forces [N].
        T_pb : array_like
            The belt's torque on the primary [N m] (``r_g T_b``).
        sign : array_like, optional
            The smooth sign of the primary's speed (the kernel's ``tanh(omega_p /
            coulomb_omega)``; default 1), in [-1, 1].

        Returns
        -------
        ndarray
            The loss torque on the primary [N m], the broadcast shape.
        """
        r, w, b, F, sg = np.broadcast_arrays(*(np.asarray(v, float)
                                               for v in (r_g, omega_in, T_pb, F_s, sign)))
        Lk = self._lines(r, w, F)                         # L_j at every torque knot
        Tk = self.T_in.reshape((-1,) + (1,) * r.ndim)
        g = Tk - sg * Lk                                  # increasing in j
        idx = np.sum(g < b, axis=0)                       # b <= g_0: 0; b > g_last: n_T
        n = Tk.shape[0]
        lo = np.clip(idx - 1, 0, max(n - 2, 0))
        hi = np.minimum(lo + 1, n - 1)
        take = lambda a, k: np.take_along_axis(a, k[None], 0)[0]  # noqa: E731
        L0, L1 = take(Lk, lo), take(Lk, hi)
        T0 = self.T_in[lo]
        dT = self.T_in[hi] - T0
        with np.errstate(invalid="ignore", divide="ignore"):
            s = np.where(dT > 0, (L1 - L0) / np.where(dT > 0, dT, 1.0), 0.0)
            T_in = T0 + (b - take(g, lo)) / (1.0 - sg * s)
            inside = L0 + s * (T_in - T0)
        L = np.where(idx == 0, take(Lk, np.zeros_like(idx)),
                     np.where(idx >= n, take(Lk, np.full_like(idx, n - 1)), inside))
        return sg * L

    def _lines(self, r: NDArray, w: NDArray, F: NDArray) -> NDArray[np.float64]:
        """The map blended over ratio, speed and force at the points, one value per torque
        knot: shape ``(n_T,) + r.shape``."""
        L = np.moveaxis(self.T_loss, 2, 0)                # (n_T, n_r, n_w, n_F)
        out = np.empty((L.shape[0],) + r.shape)
        for j in range(L.shape[0]):
            vals = L[j]
            # along F_s, then omega_in, then ln r_g: `interp_knots` on each axis
            along_F = np.stack([np.stack([interp_knots(F, self.F_s, vals[a, b])
                                          for b in range(vals.shape[1])])
                                for a in range(vals.shape[0])])       # (n_r, n_w) + shape
            along_w = np.stack([interp_knots(w, self.omega_in, along_F[a])
                                for a in range(vals.shape[0])])      # (n_r,) + shape
            out[j] = interp_knots(np.log(r), np.log(self.r_g), along_w)
        return out

    def encode(self) -> NDArray[np.float64]:
        """Flat encoding for the compiled model (`empact.variator._loss_table`)::

            [n_r, n_w, n_T, n_F, ln r_g (n_r), omega_in (n_w), T_in (n_T), F_s (n_F),
             T_loss (n_r n_w n_T n_F, C order)]
        """
        return np.concatenate([[float(len(self.r_g)), float(len(self.omega_in)),
                                float(len(self.T_in)), float(len(self.F_s))],
                               np.log(self.r_g), self.omega_in, self.T_in, self.F_s,
                               self.T_loss.ravel()])

    def to_csv(self) -> str:
        """The map as the CSV `load_loss_map` reads (columns ``r_g [-], omega_in [rad/s],
        T_in [N m], F_s [N], T_loss [N m]``, one row per grid point, 17 significant
        digits).

        Returns
        -------
        str
            The CSV text.
        """
        cells = [f"{n} [{_AXIS_UNITS[n][0]}]" for n in MAP_AXES + ("T_loss",)]
        rows = [",".join(cells)]
        for idx in np.ndindex(self.T_loss.shape):
            vals = [getattr(self, n)[i] for n, i in zip(MAP_AXES, idx)] + [self.T_loss[idx]]
            rows.append(",".join(f"{v:.17g}" for v in vals))
        return "\n".join(rows) + "\n"


def load_loss_map(path: str | os.PathLike[str]) -> LossMap:
    """Read a measured loss map: a ``.csv`` file with the columns ``r_g``, ``omega_in``,
    ``T_in``, ``F_s`` and either ``T_loss`` (the torque loss at the primary [N m]) or
    ``efficiency`` (the torque efficiency ``1 - T_loss / T_in`` [-], at input torques > 0),
    one row per point of a full tensor grid (every combination of the four columns' values
    exactly once, rows in any order), as a test rig measures it: the rig sets ratio, speed,
    input torque and clamping force and records each combination.  Scattered points are
    refused (a missing combination is an error): a grid interpolates without a
    triangulation's arbitrary choices, and the compiled law reproduces it to rounding.

    A header cell may carry its unit in brackets (``omega_in [rpm]``, ``T_in [N m]``, ``F_s
    [N]``, ``efficiency [-]``), converted to SI as in `empact.identification.load_records`
    (`~empact.identification.records.HEADER_UNITS`); without one a column is SI.  ``#``
    lines before the header are comments.

    Parameters
    ----------
    path : str or path-like
        The CSV file.

    Returns
    -------
    LossMap
        The map (efficiency converted to ``T_loss = (1 - efficiency) T_in``); its
        ``source`` is `path`.

    Raises
    ------
    ParameterError
        One line naming the file and what is wrong: a missing or unreadable file, a column
        missing, unknown or given twice, a value that is not a finite number, a grid point
        missing or given twice, or a map `LossMap` refuses.
    """
    p = check_input(path, "loss map")
    if p.suffix.lower() != ".csv":
        raise ParameterError(f"{p}: a loss map must be .csv, not {p.suffix or 'no suffix'!r}")
    text = read_input_text(p, "loss map")
    lines = [ln for ln in text.splitlines() if ln.strip()]
    while lines and lines[0].lstrip().startswith("#"):
        lines.pop(0)
    header = [column_name(h) for h in next(csv.reader(lines[:1]), [])]
    values = [n for n in ("T_loss", "efficiency") if n in header]
    if len(values) != 1:
        raise ParameterError(f"{p}: header {','.join(header)!r} must name the columns "
                             f"{', '.join(MAP_AXES)} and one of T_loss [N m], efficiency [-]")
    extra = [h for h in header if h not in MAP_AXES + tuple(values)]
    if extra:
        raise ParameterError(f"{p}: unknown column {extra[0]!r} (a loss map has the columns "
                             f"{', '.join(MAP_AXES)} and T_loss or efficiency)")
    names = MAP_AXES + (values[0],)
    cols = load_records(p, names, min_rows=1,
                        quantities={n: _AXIS_UNITS[n][1] for n in names})
    axes = {n: np.unique(cols[n]) for n in MAP_AXES}
    shape = tuple(a.size for a in axes.values())
    grid = np.full(shape, np.nan)
    seen: dict[tuple[int, ...], int] = {}
    for row in range(cols["r_g"].size):
        idx = tuple(int(np.searchsorted(axes[n], cols[n][row])) for n in MAP_AXES)
        if idx in seen:
            raise ParameterError(f"{p}: data rows {seen[idx] + 1} and {row + 1} give the same "
                                 f"grid point ({LossMap._point(axes, idx)})")
        seen[idx] = row
        v = cols[values[0]][row]
        if values[0] == "efficiency":
            T = cols["T_in"][row]
            if not T > 0:
                raise ParameterError(f"{p}, data row {row + 1}: T_in = {T:g} N m: an "
                                     "efficiency map needs input torques > 0 (give T_loss "
                                     "at zero torque)")
            if not 0 < v <= 1:
                raise ParameterError(f"{p}, data row {row + 1}: efficiency = {v:g}: allowed "
                                     "range is (0, 1] [-]")
            v = (1.0 - v) * T
        grid[idx] = v
    if len(seen) != grid.size:
        missing = np.argwhere(np.isnan(grid))[0]
        dims = " x ".join(map(str, shape))
        raise ParameterError(f"{p}: not a full grid: {len(seen)} rows for {dims} = {grid.size} "
                             f"points of r_g, omega_in, T_in, F_s; no row at "
                             f"{LossMap._point(axes, missing)}")
    return LossMap(**axes, T_loss=grid, source=str(p))

"""Plant families: the exactly linearised machine over a grid of operating points, and its
interpolation between them (an LPV model).

A family holds, at every grid point, the plant of `empact.nonlinear.linearization.plant`: the
servo torques ``T_mp, T_ms`` and the load input (``T_l``, or ``omega_l_ref`` with a
speed-controlled load) as the disturbance, to ``r_g, nu, nu_r``, in the same physical state
coordinates at every point (deviations from each point's trim).  It is built in one batch:
`empact.nonlinear.equilibrium.trim_grid` trims all points at once and one compiled loop
(`empact.nonlinear._batch.linearize_batch`) linearises them exactly (forward mode).

Operating variables (axes, any subset, in this order): ``r_g`` [-], ``nu`` [-] or ``tau``
[-] (the slip, or the torque ratio ``mu / mu_max``), ``F_s`` [N], ``omega_p`` [rad/s], ``T_l``
[N m].  The trim needs two of the slip, ``F_s``, ``T_l`` (an `~empact.params.OperatingPoint`):
two given state the pair; one given changes that variable of the base point (default
``params.operating``; ``nu`` and ``tau`` replace each other); what is not given comes from the
base point.

`PlantFamily.at` interpolates A, B, C, D multilinearly between the grid points, in ``ln r_g``,
``ln nu`` (``nu`` when the slip axis reaches zero or below), ``ln F_s``, ``ln omega_p`` and
``T_l``.  Entries of the state matrices vary smoothly
with the operating point, so the interpolated model's frequency response follows the exact one
where the grid is dense enough (`tests/test_control.py` states the density).

Export (`save_family`): ``.npz``, JSON and ``.mat``.  In MATLAB::

    s = load('family.mat');
    sys = ss(s.A, s.B, s.C, s.D, 'InputName', cellstr(s.inputs), ...
             'OutputName', cellstr(s.outputs), 'StateName', cellstr(s.states));
    sys.SamplingGrid = struct('r_g', s.grid_r_g, 'nu', s.grid_nu);  % the family's axes

``s.A`` is ``n x n x N1 x N2 ...`` (one page per grid point, axes in ``s.axes``); ``grid_<name>``
are ``ndgrid`` arrays of the operating variables.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from .._deprecate import warn_renamed
from .._io import atomic_write_text
from .._lazy import lazy_module
from .._results import Result
from .._validate import check_choice, check_values
from ..errors import ParameterError
from ..export import jsonable, read_npz, write_arrays
from ..lti import channel_zeros
from ..nonlinear.equilibrium import trim_cruise, trim_grid
from ..nonlinear.linearization import (
    BENCH_OPTIONS,
    PLANT_INPUTS,
    PLANT_OUTPUTS,
    Plant,
    disturbance_input,
    linearize_many,
    plant_options,
)
from ..nonlinear.model import INPUT_UNITS, OUTPUT_UNITS, STATE_UNITS, EmpactModel, nonlinear_model
from ..params import OperatingPoint, Params, check_one_slip
from ..sweep import SweepOptions, plan_chunks, run_chunks

interpolate = lazy_module("scipy.interpolate")

__all__ = ["VARIABLES", "PlantFamily", "FamilyRoots", "plant_family", "save_family",
           "load_family", "BENCH_OPTIONS", "DESIGN_GRID", "ISSUE21_GRID", "LOOP_FAMILY_OUTPUTS",
           "design_family"]

#: operating variables of a family: unit, and whether it is interpolated in its logarithm
#: (when all its grid values are positive: the plant depends on the slip through the slope of
#: the traction curve, which varies roughly with ln nu)
VARIABLES = {"r_g": ("-", True), "nu": ("-", True), "tau": ("-", True), "F_s": ("N", True),
             "omega_p": ("rad/s", True), "T_l": ("N m", False)}

#: most points of one family
MAX_POINTS = 1_000_000

#: the default design family of the shipped controllers and of ``empact control design``:
#: ratio (7, geometric 0.43-2.25: where the machine runs, LOW to OD) x torque ratio (0.8-0.95:
#: set-points with a 5-20 % torque reserve on the traction curve) x clamping force (3-32 kN:
#: light-load cruising up to the secondary servo's limit; issue 33: the loop must be stable
#: wherever it runs) at ``params.operating``'s speed
DESIGN_GRID: dict[str, Any] = {"r_g": np.geomspace(0.43, 2.25, 7),
                               "tau": np.array([0.8, 0.9, 0.95]),
                               "F_s": np.array([3e3, 5e3, 8e3, 16e3, 32e3])}
#: the design family of issue 21 (ratio 0.5-2, clamping 8-32 kN), the one the shipped
#: H-infinity design (``data/control/hinf.json``) was made on (its record's ``family_axes``)
ISSUE21_GRID: dict[str, Any] = {"r_g": np.geomspace(0.5, 2.0, 7),
                                "tau": np.array([0.8, 0.9, 0.95]),
                                "F_s": np.array([8e3, 16e3, 32e3])}

#: the outputs a family needs for the loop model (`empact.control.loop.family_loops`): the
#: plant's, what the loop law measures (`empact.control.law.RAW_SIGNALS`; the observer's
#: wheel speed and the car's engine torque at the secondary besides) and what the loop model
#: predicts (`empact.control.loop.PERFORMANCE`)
LOOP_FAMILY_OUTPUTS = ("r_g", "nu", "nu_r", "omega_p", "omega_s", "T_ds", "omega_mp",
                       "omega_ms", "T_l_act", "F_s", "tau", "omega_l", "T_d_sec")


@dataclass(frozen=True, eq=False)
class PlantFamily:
    """Exact plants on a grid of operating points.

    Attributes
    ----------
    axes : dict name -> array
        The grid's axes (operating variables that vary), in `VARIABLES` order, SI.
    fixed : dict name -> float
        The operating variables held (those not on an axis and used by the trim).
    A, B, C, D : arrays, shapes ``grid + (n, n)``, ``grid + (n, m)``, ``grid + (p, n)``,
        ``grid + (p, m)``, with ``grid = tuple(len(v) for v in axes.values())``
    states, inputs, outputs : tuple of str
    operating : dict name -> array of shape ``grid``
        Every operating variable at every point (``r_g, nu, F_s, omega_p, T_l``), solved ones
        included.
    ok : bool array, shape ``grid``
        Points that trimmed (the others hold NaN and a `reason`).
    reason : array of str, shape ``grid``
    options : dict
        The model options: drive, load, damping, kinematics, shift law, and each tabulated
        law given (``thrust_ratio``, ``creep_map``, ``traction``, ``loss_map``; `to_dict`
        and the saved file name it by its source file, which `nonlinear_model` reads back).
    """

    axes: dict[str, NDArray[np.float64]]
    fixed: dict[str, float]
    A: NDArray[np.float64]
    B: NDArray[np.float64]
    C: NDArray[np.float64]
    D: NDArray[np.float64]
    states: tuple[str, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    operating: dict[str, NDArray[np.float64]]
    ok: NDArray[np.bool_]
    reason: NDArray[np.object_]
    options: dict[str, Any] = field(default_factory=dict)
    _interp: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def shape(self) -> tuple[int, ...]:
        """The grid's shape."""
        return self.ok.shape

    @property
    def log_axes(self) -> tuple[str, ...]:
        """Axes interpolated in their logarithm."""
        return tuple(n for n, g in self.axes.items() if VARIABLES[n][1] and np.all(g > 0))

    @property
    def size(self) -> int:
        """Number of grid points."""
        return int(self.ok.size)

    def _index(self, index: tuple[int, ...] | int) -> tuple[int, ...]:
        idx = tuple(int(i) for i in np.unravel_index(index, self.shape)) \
            if isinstance(index, (int, np.integer)) else tuple(index)
        if not self.ok[idx]:
            raise ParameterError(f"grid point {idx}: not trimmed ({self.reason[idx]})")
        return idx

    def plant(self, index: tuple[int, ...] | int) -> Plant:
        """The plant at one grid point (a `Plant`, as `empact.nonlinear.linearization.plant`
        returns; its ``state_space()`` is the named `control.StateSpace`).

        Parameters
        ----------
        index : int or tuple of int
            The grid point: one index per axis (an int for a one-axis family).
        """
        idx = self._index(index)
        return Plant(self.A[idx], self.B[idx], self.C[idx], self.D[idx],
                     inputs=tuple(self.inputs), outputs=tuple(self.outputs),
                     states=tuple(self.states),
                     name="plant_" + "_".join(f"{k}_{self.operating[k][idx]:.4g}"
                                              for k in self.axes),
                     operating={k: float(v[idx]) for k, v in self.operating.items()})

    def _matrices(self, point: dict[str, float]) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        if set(point) != set(self.axes):
            raise ParameterError(f"give the family's axes {', '.join(self.axes)}; got "
                                 f"{', '.join(point) or 'none'}")
        if not np.all(self.ok):
            raise ParameterError("the family has points that did not trim: interpolation "
                                 "needs every grid point")
        q = []
        for name, grid in self.axes.items():
            v = float(check_values(name, point[name], float(grid.min()), float(grid.max()),
                                   unit=VARIABLES[name][0], note="the family's grid"))
            q.append(np.log(v) if name in self.log_axes else v)
        out = []
        for key, M in (("A", self.A), ("B", self.B), ("C", self.C), ("D", self.D)):
            f = self._interp.get(key)
            if f is None:
                coords = [np.log(g) if n in self.log_axes else g for n, g in self.axes.items()]
                f = interpolate.RegularGridInterpolator(
                    coords, M.reshape(self.shape + (-1,)), method="linear")
                self._interp[key] = f
            out.append(f(np.array(q)[None])[0].reshape(M.shape[len(self.shape):]))
        return tuple(out)

    def interpolate(self, **point: float) -> Plant:
        """The plant interpolated multilinearly at an off-grid point, given by the family's
        axis variables (``r_g=...``, ...), each inside its axis' range (a `Plant`).

        Parameters
        ----------
        **point : float
            A value for each axis variable of the family (``r_g=...``, ...), in its SI unit,
            inside the axis' range.
        """
        A, B, C, D = self._matrices(point)
        return Plant(A, B, C, D, inputs=tuple(self.inputs), outputs=tuple(self.outputs),
                     states=tuple(self.states), name="plant_interpolated",
                     operating={k: float(v) for k, v in point.items()})

    def at(self, **point: float) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """Deprecated: `interpolate` (returns a `Plant`); this gives its (A, B, C, D).

        Parameters
        ----------
        **point : float
            As `interpolate`'s.
        """
        warn_renamed("PlantFamily.at", "PlantFamily.interpolate (a Plant)")
        return self._matrices(point)

    def interpolated_plant(self, **point: float):
        """Deprecated: ``interpolate(...).state_space()``.

        Parameters
        ----------
        **point : float
            As `interpolate`'s.
        """
        warn_renamed("PlantFamily.interpolated_plant",
                     "PlantFamily.interpolate(...).state_space()")
        return self.interpolate(**point).system

    def roots(self, f_max_hz: float = 60.0) -> "FamilyRoots":
        """The poles and the zeros of ``T_mp -> r_g`` and ``T_ms -> nu`` of every trimmed
        plant, those of magnitude below `f_max_hz`.

        Parameters
        ----------
        f_max_hz : float
            Poles and zeros of magnitude above ``2 pi f_max_hz`` [rad/s] are left out [Hz].

        Returns
        -------
        FamilyRoots
            Per trimmed point (in grid order): its ratio, poles and channel zeros [rad/s].
        """
        w_max = 2 * np.pi * f_max_hz
        r_g, poles = [], []
        zeros: dict[str, list[NDArray[np.complex128]]] = {c: [] for c in FamilyRoots.CHANNELS}
        for k in range(self.size):
            idx = np.unravel_index(k, self.shape)
            if not self.ok[idx]:
                continue
            r_g.append(float(self.operating["r_g"][idx]))
            p = np.linalg.eigvals(self.A[idx])
            poles.append(p[np.abs(p) < w_max])
            plant = self.plant(tuple(int(i) for i in idx))
            for c in FamilyRoots.CHANNELS:
                inp, out = c.split("->")
                zeros[c].append(channel_zeros(plant, inp, out, max_abs=w_max))
        return FamilyRoots(np.array(r_g), tuple(poles),
                           {c: tuple(z) for c, z in zeros.items()}, float(f_max_hz))

    def to_dict(self) -> dict[str, Any]:
        """The family as plain JSON types (the export layout of `_layout`, as `save_family`
        writes it to JSON: arrays as nested lists, NaN as None).

        Returns
        -------
        dict
            ``A``, ``B``, ``C``, ``D``, the names and their units, ``axis_<name>``,
            ``grid_<name>``, ``operating_<name>``, ``ok``, ``reason``, ``fixed``,
            ``options``.
        """
        return jsonable(self._layout())

    def _layout(self) -> dict[str, Any]:
        """Arrays and names (the export layout: `save_family` writes it)."""
        grids = np.meshgrid(*self.axes.values(), indexing="ij") if self.axes else []
        d: dict[str, Any] = {
            "A": self.A, "B": self.B, "C": self.C, "D": self.D,
            "states": list(self.states), "inputs": list(self.inputs),
            "outputs": list(self.outputs), "axes": list(self.axes),
            "control_inputs": list(PLANT_INPUTS), "disturbance_inputs": [self.inputs[-1]],
            "ok": self.ok, "reason": self.reason.tolist(),
            "states_units": [STATE_UNITS[s] for s in self.states],
            "inputs_units": [INPUT_UNITS[s] for s in self.inputs],
            "outputs_units": [OUTPUT_UNITS[s] for s in self.outputs],
            "options": {k: getattr(v, "source", v) for k, v in self.options.items()}}
        for name, values in self.axes.items():
            d[f"axis_{name}"] = values
        for name, g in zip(self.axes, grids):
            d[f"grid_{name}"] = g
        for name, values in self.operating.items():
            d[f"operating_{name}"] = values
        d["fixed"] = dict(self.fixed)
        return d


@dataclass(frozen=True, eq=False)
class FamilyRoots(Result):
    """The poles and channel zeros of every trimmed plant of a family (`PlantFamily.roots`).

    Attributes
    ----------
    r_g : ndarray, shape (n,)
        The ratio [-] of each trimmed point (grid order).
    poles : tuple of ndarray
        Each point's poles [rad/s] below the bound (complex, shapes vary).
    zeros : dict str -> tuple of ndarray
        Per channel (`CHANNELS`, ``"T_mp->r_g"``, ``"T_ms->nu"``) each point's finite
        zeros [rad/s] below the bound.
    f_max_hz : float
        The bound on the magnitude [Hz].
    """

    #: the channels whose zeros are taken (input->output)
    CHANNELS = ("T_mp->r_g", "T_ms->nu")

    r_g: NDArray[np.float64]
    poles: tuple[NDArray[np.complex128], ...]
    zeros: dict[str, tuple[NDArray[np.complex128], ...]]
    f_max_hz: float


def _axis(name: str, value) -> NDArray[np.float64]:
    unit = VARIABLES[name][0]
    arr = check_values(name, value, unit=unit)
    return np.atleast_1d(np.asarray(arr, float)).ravel()


def plant_family(params: Params, *, r_g=None, nu=None, tau=None, F_s=None, omega_p=None,
                 T_l=None, base: OperatingPoint | None = None,
                 model: EmpactModel | None = None, sweep: SweepOptions | None = None,
                 outputs: Sequence[str] | None = None, cruise: bool = False,
                 **options) -> PlantFamily:
    """Trim and exactly linearise the machine on a grid of operating points.

    Parameters
    ----------
    params : Params
    r_g, nu, tau, F_s, omega_p, T_l : float or 1-D array, optional
        Operating variables (SI); arrays become the grid's axes.  See the module notes for
        which two of the slip (nu or tau), F_s, T_l the trim uses.
    base : OperatingPoint, optional
        The point whose variables fill in what is not given (default ``params.operating``).
    model : EmpactModel, optional
        A built model with torque servo inputs (then `options` must be empty).
    sweep : SweepOptions, optional
        Where the points are computed (`empact.sweep`: in process by default, or on Dask);
        the result is bitwise the same.
    outputs : sequence of str, optional
        The model outputs kept (default ``r_g, nu, nu_r``; `empact.control.loop` adds what
        the loop law measures).
    cruise : bool
        The car at steady cruise on a level road (the vehicle driveline,
        `empact.nonlinear.equilibrium.trim_cruise`): the road load sets ``T_l``, so give one
        of the slip and ``F_s`` (or let the base point's slip stand); default False: two of
        them, the load beyond the road's held by the input ``T_l`` (a grade, the brakes).
    **options
        `empact.nonlinear.model.ModelOptions` fields (default `BENCH_OPTIONS`, the test bench,
        or with ``driveline = "vehicle"`` the car's: the same defaults as
        `empact.nonlinear.linearization.plant`, `plant_options`).

    Returns
    -------
    PlantFamily
        The plants on the grid (``family.shape``: one axis per array argument, in the order
        ``r_g, nu, tau, F_s, omega_p, T_l``), each with inputs ``T_mp, T_ms, T_l`` [N m] and
        outputs ``r_g, nu, nu_r`` [-]; ``family.plant(index)`` is one `Plant`.

    Examples
    --------
    >>> import empact
    >>> family = empact.plant_family(empact.load_params(), r_g=[0.5, 1.0, 2.0],
    ...                              tau=[0.85, 0.95])
    >>> family.shape, list(family.axes)
    ((3, 2), ['r_g', 'tau'])
    >>> family.plant((1, 0)).outputs
    ('r_g', 'nu', 'nu_r')
    """
    if model is None:
        model = nonlinear_model(params, **plant_options(options))
    elif options:
        raise ValueError("give either model or options, not both")
    if "T_mp" not in model.inputs:
        raise ParameterError("a plant family needs the servo torques as inputs "
                             "(ratio_control = false)")
    given = {"r_g": r_g, "nu": nu, "tau": tau, "F_s": F_s, "omega_p": omega_p, "T_l": T_l}
    base = params.operating if base is None else base
    pair = [k for k in ("nu", "tau", "F_s", "T_l") if given[k] is not None]
    check_one_slip("nu" in pair, "tau" in pair)
    if cruise:
        return _cruise_family(params, model, given, pair, base, sweep, outputs)
    if len(pair) > 2:
        raise ParameterError("give at most two of nu (or tau), F_s, T_l (the trim solves the "
                             "third)")
    first: dict[str, float | None] = {k: float(np.ravel(np.asarray(given[k], float))[0])
                                      for k in pair}
    if len(pair) == 2:
        first.update({k: None for k in ("nu", "tau", "F_s", "T_l") if k not in pair})
    elif len(pair) == 1 and pair[0] in ("F_s", "T_l") and getattr(base, pair[0]) is None:
        raise ParameterError(f"{pair[0]} given with a base point given by "
                             f"{' and '.join(base.given)}: give the second variable too")
    point = base.replace(**first)
    values = {}
    for name in ("r_g", "omega_p") + point.given:
        v = given[name] if given[name] is not None else getattr(point, name)
        values[name] = _axis(name, v)
    return _family(model, point.given, values, sweep, outputs)


def _cruise_family(params: Params, model: EmpactModel, given: dict[str, Any],
                   pair: list[str], base: OperatingPoint, sweep: SweepOptions | None,
                   outputs: Sequence[str] | None) -> PlantFamily:
    """`plant_family` at the car's steady cruise (``cruise``): one of the slip and ``F_s``
    (given, else the base point's slip), the road load's ``T_l``."""
    if not model.vehicle:
        raise ParameterError("cruise: the road load needs the vehicle driveline "
                             "(driveline = 'vehicle')")
    if "T_l" in pair or len(pair) > 1:
        raise ParameterError("cruise: give one of nu (or tau), F_s; the road load sets T_l")
    if not pair:
        slip = [k for k in ("nu", "tau") if getattr(base, k) is not None]
        if not slip:
            raise ParameterError("cruise: give nu, tau or F_s (the base point has no slip)")
        pair = slip
    values = {name: _axis(name, given[name] if given[name] is not None
                          else getattr(base, name)) for name in ("r_g", "omega_p", pair[0])}
    return _family(model, ("cruise", pair[0]), values, sweep, outputs)


def _family(model: EmpactModel, pair: tuple[str, ...], values: dict[str, NDArray],
            sweep: SweepOptions | None, outputs: Sequence[str] | None) -> PlantFamily:
    """Trim and linearise the grid of `values` (the axes: arrays of more than one value)
    with the trim's `pair` (``("cruise", name)``: `trim_cruise` given `name`)."""
    axes = {n: values[n] for n in VARIABLES if n in values and values[n].size > 1}
    fixed = {n: float(values[n][0]) for n in values if values[n].size == 1}
    shape = tuple(len(v) for v in axes.values())
    n_pts = int(np.prod(shape)) if shape else 1
    if n_pts > MAX_POINTS:
        raise ParameterError(f"{n_pts} grid points; at most {MAX_POINTS}")
    mesh = dict(zip(axes, np.meshgrid(*axes.values(), indexing="ij"))) if axes else {}
    flat = {n: (mesh[n].ravel() if n in mesh else np.full(n_pts, fixed[n])) for n in values}
    tasks = [(model, pair, {k: v[s] for k, v in flat.items()})
             for s in plan_chunks(n_pts, SECONDS_PER_POINT, sweep)]
    parts = run_chunks(_linearise_points, tasks, sweep, desc="plant family")
    res = {k: np.concatenate([part[k] for part in parts]) for k in parts[0]}
    A, B, C, D = res["A"], res["B"], res["C"], res["D"]
    inputs = PLANT_INPUTS + (disturbance_input(model),)
    ii = [model.input_index(k) for k in inputs]
    outputs = PLANT_OUTPUTS if outputs is None else tuple(outputs)
    oo = [model.output_index(k) for k in outputs]
    grid = shape if shape else ()
    n = model.n
    op_all = {k: res[k] for k in ("r_g", "nu", "F_s", "omega_p", "T_l", "tau")}
    return PlantFamily(
        axes=axes, fixed=fixed,
        A=A.reshape(grid + (n, n)), B=B[:, :, ii].reshape(grid + (n, len(ii))),
        C=C[:, oo].reshape(grid + (len(oo), n)),
        D=D[:, oo][:, :, ii].reshape(grid + (len(oo), len(ii))),
        states=model.states, inputs=inputs, outputs=outputs,
        operating={k: v.reshape(grid) for k, v in op_all.items()},
        ok=res["ok"].reshape(grid), reason=res["reason"].reshape(grid),
        options=_family_options(model.options))


#: the model options a family records (and a design rebuilds its model from); the tabulated
#: laws only when given
_FAMILY_OPTIONS = ("driveline", "drive", "load", "damping", "kinematics", "shift_law")
_TABLE_OPTIONS = ("thrust_ratio", "creep_map", "traction", "loss_map")


def _family_options(options) -> dict[str, Any]:
    """The options of `_FAMILY_OPTIONS`, and each tabulated law that is given."""
    out = {k: getattr(options, k) for k in _FAMILY_OPTIONS}
    out.update({k: getattr(options, k) for k in _TABLE_OPTIONS
                if getattr(options, k) is not None})
    return out


def design_family(params: Params, **options) -> "PlantFamily":
    """The design family (`DESIGN_GRID`, with `LOOP_FAMILY_OUTPUTS`) on a parameter set;
    `options` as `plant_family`'s.

    Parameters
    ----------
    params : Params
        The parameter set (its ``operating`` point gives the primary speed and the base).
    **options
        Further keywords of `plant_family` other than the grid's axes and ``outputs``
        (``base``, ``model``, ``sweep``, ``omega_p``, or
        `empact.nonlinear.model.ModelOptions` fields).

    Returns
    -------
    PlantFamily
        Shape (7, 3, 5) over ``r_g`` [-] x ``tau`` [-] x ``F_s`` [N] (an ``omega_p`` array
        adds its axis), inputs ``T_mp, T_ms`` [N m] and the load input, outputs
        `LOOP_FAMILY_OUTPUTS`.
    """
    return plant_family(params, **DESIGN_GRID, outputs=LOOP_FAMILY_OUTPUTS, **options)


#: measured cost of one point (trim + linearisation), for sizing chunks [s]
SECONDS_PER_POINT = 4e-5


def _linearise_points(task) -> dict[str, Any]:
    """Trim and linearise the points of one chunk (`run_chunks` task: model, the trim pair,
    flat arrays of the operating variables).  Each point's result depends on that point only
    (per-point convergence in `trim_grid`; one compiled loop here), so chunking does not
    change a bit."""
    model, pair, flat = task
    if pair[0] == "cruise":
        tg = trim_cruise(model, flat["r_g"], flat["omega_p"], **{pair[1]: flat[pair[1]]})
    else:
        tg = trim_grid(model, flat["r_g"], flat["omega_p"], **{k: flat[k] for k in pair})
    N, n, ny = tg.r_g.size, model.n, len(model.outputs)
    A = np.full((N, n, n), np.nan)
    B = np.full((N, n, 4), np.nan)
    C = np.full((N, ny, n), np.nan)
    D = np.full((N, ny, 4), np.nan)
    g = np.flatnonzero(tg.ok)
    if g.size:  # linearise the points that trimmed, in one compiled loop
        A[g], B[g], C[g], D[g] = linearize_many(model, tg.x[g], tg.u[g], tg.r_g[g], tg.nu[g])
    return {"A": A, "B": B, "C": C, "D": D, "r_g": tg.r_g, "omega_p": tg.omega_p,
            "nu": tg.nu, "F_s": tg.F_s, "T_l": tg.T_l, "tau": tg.tau, "ok": tg.ok,
            "reason": np.array(tg.reason, dtype=object)}


def save_family(family: PlantFamily, path: str | os.PathLike[str], fmt: str | None = None
                ) -> Path:
    """Write a family atomically as ``.npz``, JSON or ``.mat`` (see the module notes).

    Parameters
    ----------
    family : PlantFamily
        The family to write.
    path : str or path-like
        The destination file.
    fmt : {"npz", "json", "mat"}, optional
        The format (default: from the suffix of `path`); only ``.npz`` reads back
        (`load_family`).

    Returns
    -------
    Path
        The file written (`path`).

    Raises
    ------
    ParameterError
        For a format (or suffix) that is none of the three.
    """
    fmt = check_choice("format", fmt or Path(path).suffix.lstrip(".").lower(),
                       ("npz", "json", "mat"))
    data = family._layout()
    if fmt == "json":
        doc = {"schema": {"name": "empact.plants", "version": 1}, **data}
        atomic_write_text(path, json.dumps(jsonable(doc)) + "\n")
        return Path(path)
    flat: dict[str, Any] = {}
    for k, v in data.items():
        if isinstance(v, Mapping):
            for n, x in v.items():
                flat[f"{k}_{n}"] = x
        elif isinstance(v, list) and (not v or isinstance(v[0], str)):
            flat[k] = np.array(v, dtype=object if fmt == "mat" else str)
        else:
            flat[k] = np.asarray(v)
    if fmt == "mat":  # MATLAB: n x n x N1 x N2 ... (one page per grid point)
        nd = len(family.shape)
        for key in ("A", "B", "C", "D"):
            flat[key] = np.moveaxis(flat[key], (nd, nd + 1), (0, 1))
    return write_arrays(path, flat, fmt)


def load_family(path: str | os.PathLike[str]) -> PlantFamily:
    """Read a family written by `save_family` as ``.npz`` (one-line errors for a file that is
    not one).

    Parameters
    ----------
    path : str or path-like
        A ``.npz`` file of `save_family` (or ``empact plants --out FILE.npz``).

    Returns
    -------
    PlantFamily
        The family as written: axes, fixed variables, the A, B, C, D arrays (shapes
        ``grid + (n, n)``, ``grid + (n, m)``, ``grid + (q, n)``, ``grid + (q, m)``), names,
        operating variables, trim status and model options.

    Raises
    ------
    ParameterError
        For a file that is not ``.npz``, not readable, or not a consistent plant family.
    """
    p = Path(path)
    hint = "write one with `empact plants --out FILE.npz`"
    if p.suffix.lower() != ".npz":
        raise ParameterError(f"{p}: a plant family is read from .npz, not "
                             f"{p.suffix or 'no suffix'!r} ({hint})")
    z = read_npz(p, "plant family", ("axes", "A", "B", "C", "D", "states", "inputs",
                                     "outputs", "ok", "reason"), hint)
    names = [str(a) for a in z["axes"]]
    missing = [f"axis_{n}" for n in names if f"axis_{n}" not in z]
    if missing:
        raise ParameterError(f"{p}: not a plant family (no {', '.join(missing)} in the "
                             f"archive; {hint})")
    grid = tuple(len(z[f"axis_{n}"]) for n in names)
    n, m, q = len(z["states"]), len(z["inputs"]), len(z["outputs"])
    for key, shape in (("ok", grid), ("A", grid + (n, n)), ("B", grid + (n, m)),
                       ("C", grid + (q, n)), ("D", grid + (q, m))):
        if z[key].shape != shape:
            raise ParameterError(f"{p}: not a plant family ({key} has shape "
                                 f"{z[key].shape}, expected {shape} for the grid {grid} of "
                                 f"{n} states, {m} inputs, {q} outputs)")
    for key in ("A", "B", "C", "D", *(f"axis_{n}" for n in names)):
        arr = np.asarray(z[key])
        if arr.dtype.kind not in "iuf":
            raise ParameterError(f"{p}: not a plant family ({key} holds no numbers; {hint})")
        ok = z["ok"].astype(bool)
        bad = ~np.isfinite(arr) if key.startswith("axis_") else \
            ~np.isfinite(arr).reshape(ok.shape + (-1,)).all(axis=-1) & ok
        if bad.any():
            where = np.argwhere(bad)[0]
            raise ParameterError(f"{p}: {key} holds a value that is not finite (NaN or "
                                 f"infinite) at grid index {tuple(int(i) for i in where)}; "
                                 "not a usable plant family")
    axes = {n: z[f"axis_{n}"] for n in names}
    fixed = {k[len("fixed_"):]: float(z[k]) for k in z if k.startswith("fixed_")}
    return PlantFamily(axes=axes, fixed=fixed, A=z["A"], B=z["B"], C=z["C"], D=z["D"],
                       states=tuple(map(str, z["states"])), inputs=tuple(map(str, z["inputs"])),
                       outputs=tuple(map(str, z["outputs"])),
                       operating={n: z[f"operating_{n}"] for n in VARIABLES
                                  if f"operating_{n}" in z},
                       ok=z["ok"].astype(bool), reason=np.array(z["reason"], dtype=object),
                       options={k[len("options_"):]: str(z[k]) for k in z
                                if k.startswith("options_")})

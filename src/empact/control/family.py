"""Plant families: the exactly linearised machine over a grid of operating points, and its
interpolation between them (an LPV model).

A family holds, at every grid point, the plant of `empact.nonlinear.linearization.plant`: the
servo torques ``T_mp, T_ms`` and the load input (``T_l``, or ``omega_l_ref`` with a
speed-controlled load) as the disturbance, to ``r_g, nu, nu_r``, in the same physical state
coordinates at every point (deviations from each point's trim).  It is built in one batch:
`empact.nonlinear.equilibrium.trim_grid` trims all points at once and one compiled loop
(`empact.nonlinear._kernel.linearize_batch`) linearises them by the complex step.

Operating variables (axes, any subset, in this order): ``r_g`` [-], ``nu`` [-], ``F_s`` [N],
``omega_p`` [rad/s], ``T_l`` [N m].  The trim needs two of ``nu``, ``F_s``, ``T_l``: with a
load given it uses ``(F_s, T_l)``, or ``(nu, T_l)`` when the slip is given and the clamping
force is not; otherwise ``(nu, F_s)``; what is not given comes from ``params.operating``.

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
from types import SimpleNamespace
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from numpy.typing import NDArray

from .._io import atomic_write_text
from .._lazy import lazy_module
from .._validate import check_choice, check_values
from ..errors import ParameterError
from ..export import jsonable, write_arrays
from ..lti import statespace
from ..nonlinear import _kernel as K
from ..nonlinear.equilibrium import trim_grid
from ..nonlinear.linearization import PLANT_INPUTS, PLANT_OUTPUTS, disturbance_input
from ..nonlinear.model import (INPUT_UNITS, OUTPUT_UNITS, STATE_UNITS, EmpactModel,
                               nonlinear_model)
from ..params import Params
from ..sweep import SweepOptions, plan_chunks, run_chunks

interpolate = lazy_module("scipy.interpolate")

__all__ = ["VARIABLES", "PlantFamily", "plant_family", "save_family", "load_family",
           "BENCH_OPTIONS"]

#: operating variables of a family: unit, and whether it is interpolated in its logarithm
#: (when all its grid values are positive: the plant depends on the slip through the slope of
#: the traction curve, which varies roughly with ln nu)
VARIABLES = {"r_g": ("-", True), "nu": ("-", True), "F_s": ("N", True),
             "omega_p": ("rad/s", True), "T_l": ("N m", False)}

#: model options of a plant family by default: the test bench of the paper's Sec. 3 and 4
#: (speed-controlled drive motor, torque-controlled load motor)
BENCH_OPTIONS = {"drive": "speed", "load": "torque"}

#: most points of one family
MAX_POINTS = 1_000_000


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
        The model options.
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

    def plant(self, index: tuple[int, ...] | int):
        """The plant at one grid point as a named `control.StateSpace`."""
        idx = np.unravel_index(index, self.shape) if isinstance(index, (int, np.integer)) \
            else tuple(index)
        if not self.ok[idx]:
            raise ParameterError(f"grid point {idx}: not trimmed ({self.reason[idx]})")
        return statespace(self.A[idx], self.B[idx], self.C[idx], self.D[idx],
                          states=self.states, inputs=self.inputs, outputs=self.outputs,
                          name="plant_" + "_".join(f"{k}_{self.operating[k][idx]:.4g}"
                                                   for k in self.axes))

    def at(self, **point: float) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """``(A, B, C, D)`` interpolated multilinearly at an off-grid point, given by the
        family's axis variables (``r_g=...``, ...), each inside its axis' range."""
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

    def interpolated_plant(self, **point: float):
        """`at` as a named `control.StateSpace`."""
        A, B, C, D = self.at(**point)
        return statespace(A, B, C, D, states=self.states, inputs=self.inputs,
                          outputs=self.outputs, name="plant_interpolated")

    def to_dict(self) -> dict[str, Any]:
        """Plain arrays and names (the export layout)."""
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
            "options": dict(self.options)}
        for name, values in self.axes.items():
            d[f"axis_{name}"] = values
        for name, g in zip(self.axes, grids):
            d[f"grid_{name}"] = g
        for name, values in self.operating.items():
            d[f"operating_{name}"] = values
        d["fixed"] = dict(self.fixed)
        return d


def _axis(name: str, value) -> NDArray[np.float64]:
    unit = VARIABLES[name][0]
    arr = check_values(name, value, unit=unit)
    return np.atleast_1d(np.asarray(arr, float)).ravel()


def plant_family(params: Params, *, r_g=None, nu=None, F_s=None, omega_p=None, T_l=None,
                 model: EmpactModel | None = None, sweep: SweepOptions | None = None,
                 **options) -> PlantFamily:
    """Trim and exactly linearise the machine on a grid of operating points.

    Parameters
    ----------
    params : Params
    r_g, nu, F_s, omega_p, T_l : float or 1-D array, optional
        Operating variables (SI); arrays become the grid's axes.  See the module notes for
        which two of nu, F_s, T_l the trim uses; the rest come from ``params.operating``.
    model : EmpactModel, optional
        A built model with torque servo inputs (then `options` must be empty).
    sweep : SweepOptions, optional
        Where the points are computed (`empact.sweep`: in process by default, or on Dask);
        the result is bitwise the same.
    **options
        `empact.nonlinear.model.ModelOptions` fields (default `BENCH_OPTIONS`).

    Returns
    -------
    PlantFamily
    """
    if model is None:
        model = nonlinear_model(params, **{**BENCH_OPTIONS, **options})
    elif options:
        raise ValueError("give either model or options, not both")
    if "T_mp" not in model.inputs:
        raise ParameterError("a plant family needs the servo torques as inputs "
                             "(ratio_control = false)")
    given = {"r_g": r_g, "nu": nu, "F_s": F_s, "omega_p": omega_p, "T_l": T_l}
    if all(given[k] is not None for k in ("nu", "F_s", "T_l")):
        raise ParameterError("give at most two of nu, F_s, T_l (the trim solves the third)")
    if given["T_l"] is not None:
        pair = ("nu", "T_l") if given["nu"] is not None and given["F_s"] is None \
            else ("F_s", "T_l")
    else:
        pair = ("nu", "F_s")
    op = params.operating
    values = {}
    for name in ("r_g", "omega_p") + pair:
        v = given[name] if given[name] is not None else getattr(op, name)
        values[name] = _axis(name, v)
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
    tg = SimpleNamespace(**{k: res[k] for k in ("r_g", "omega_p", "nu", "F_s", "T_l", "ok")},
                         reason=tuple(res["reason"].tolist()))
    n = model.n
    # nu_r at each point's own ratio: d nu_r = d nu - (1 - nu0) d r_g / r_g0
    w = ((1 - tg.nu) / tg.r_g)[:, None]
    C[:, K.Y_NUR] = C[:, K.Y_NU] - w * C[:, K.Y_RG]
    D[:, K.Y_NUR] = D[:, K.Y_NU] - w * D[:, K.Y_RG]
    inputs = PLANT_INPUTS + (disturbance_input(model),)
    ii = [model.inputs.index(k) for k in inputs]
    oo = [model.outputs.index(k) for k in PLANT_OUTPUTS]
    grid = shape if shape else ()
    op_all = {"r_g": tg.r_g, "nu": tg.nu, "F_s": tg.F_s, "omega_p": tg.omega_p, "T_l": tg.T_l}
    return PlantFamily(
        axes=axes, fixed=fixed,
        A=A.reshape(grid + (n, n)), B=B[:, :, ii].reshape(grid + (n, len(ii))),
        C=C[:, oo].reshape(grid + (len(oo), n)),
        D=D[:, oo][:, :, ii].reshape(grid + (len(oo), len(ii))),
        states=model.states, inputs=inputs, outputs=PLANT_OUTPUTS,
        operating={k: v.reshape(grid) for k, v in op_all.items()},
        ok=tg.ok.reshape(grid), reason=np.array(tg.reason, dtype=object).reshape(grid),
        options={k: getattr(model.options, k) for k in ("drive", "load", "damping",
                                                        "kinematics", "shift_law")})


#: measured cost of one point (trim + linearisation), for sizing chunks [s]
SECONDS_PER_POINT = 4e-5


def _linearise_points(task) -> dict[str, NDArray]:
    """Trim and linearise the points of one chunk (`run_chunks` task: model, the trim pair,
    flat arrays of the operating variables).  Each point's result depends on that point only
    (per-point convergence in `trim_grid`; one compiled loop here), so chunking does not
    change a bit."""
    model, pair, flat = task
    tg = trim_grid(model, flat["r_g"], flat["omega_p"], **{k: flat[k] for k in pair})
    N, n, m_all = tg.r_g.size, model.n, 4
    A = np.full((N, n, n), np.nan)
    B = np.full((N, n, m_all), np.nan)
    C = np.full((N, K.NY, n), np.nan)
    D = np.full((N, K.NY, m_all), np.nan)
    g = np.flatnonzero(tg.ok)
    if g.size:  # linearise the points that trimmed, in one compiled loop
        Ag, Bg = np.empty((g.size, n, n)), np.empty((g.size, n, m_all))
        Cg, Dg = np.empty((g.size, K.NY, n)), np.empty((g.size, K.NY, m_all))
        K.linearize_batch(np.ascontiguousarray(tg.x[g]), np.ascontiguousarray(tg.u[g]),
                          model.p, model.ix, np.empty((g.size, n)), Ag, Bg, Cg, Dg)
        A[g], B[g], C[g], D[g] = Ag, Bg, Cg, Dg
    return {"A": A, "B": B, "C": C, "D": D, "r_g": tg.r_g, "omega_p": tg.omega_p,
            "nu": tg.nu, "F_s": tg.F_s, "T_l": tg.T_l, "ok": tg.ok,
            "reason": np.array(tg.reason, dtype=object)}


def save_family(family: PlantFamily, path: str | os.PathLike[str], fmt: str | None = None
                ) -> Path:
    """Write a family atomically as ``.npz``, JSON or ``.mat`` (see the module notes)."""
    fmt = check_choice("format", fmt or Path(path).suffix.lstrip(".").lower(),
                       ("npz", "json", "mat"))
    data = family.to_dict()
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
    """Read a family written by `save_family` as ``.npz``."""
    p = Path(path)
    if p.suffix.lower() != ".npz":
        raise ParameterError(f"{p}: a plant family is read from .npz (save_family)")
    try:
        z = np.load(p, allow_pickle=False)
    except (OSError, ValueError) as exc:
        raise ParameterError(f"{p}: not a plant family ({exc})") from None
    names = [str(a) for a in z["axes"]]
    axes = {n: z[f"axis_{n}"] for n in names}
    fixed = {k[len("fixed_"):]: float(z[k]) for k in z.files if k.startswith("fixed_")}
    return PlantFamily(axes=axes, fixed=fixed, A=z["A"], B=z["B"], C=z["C"], D=z["D"],
                       states=tuple(map(str, z["states"])), inputs=tuple(map(str, z["inputs"])),
                       outputs=tuple(map(str, z["outputs"])),
                       operating={n: z[f"operating_{n}"] for n in VARIABLES},
                       ok=z["ok"], reason=np.array(z["reason"], dtype=object),
                       options={k[len("options_"):]: str(z[k]) for k in z.files
                                if k.startswith("options_")})


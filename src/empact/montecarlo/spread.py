"""Parameter spread: distributions of parameters, read from TOML and sampled reproducibly.

A spread file has one table per parameter, keyed by the parameter's dotted name (any value
of a parameter file, the operating point included)::

    [spread."actuation.k_w"]
    distribution = "normal"      # normal | uniform | lognormal
    rel_std = 0.05               # or std = 2.4 [unit of the parameter]; mean defaults to
    lower = 40.0                 #   the parameter's value; optional bounds truncate
    upper = 55.0

    [spread."traction.D_med"]
    distribution = "uniform"
    lower = 0.09
    upper = 0.11

    [spread."driveline.k_ds"]
    distribution = "lognormal"   # ln X ~ N(ln median, sigma^2)
    sigma = 0.1                  # median defaults to the parameter's value
    upper = 60.0

Variables of a closed-loop scenario rather than of the parameter set are named
``scenario.*`` (`SCENARIO_VARIABLES`): the initial operating point's clamping force, torque
ratio, ratio and speed (``scenario.initial.F_s``, ``.tau``, ``.r_g``, ``.omega_p``) and the
load-step size (``scenario.load_step``, a fraction of the torque capacity).  Their nominal
value is the scenario's; each is checked as the scenario file's own value is (`apply_scenario`:
the operating point's ranges, the variator's ratio range, the load step's [-1, 2]) when the
spread is loaded, before any run.

The magic formula's peak slip at each of its ratios is a variable of its own
(``traction.peak_slip_low``, ``_med``, ``_od`` [-], `PEAK_SLIP_VARIABLES`; its nominal value
the parameter set's curve's): a run's ``B`` at that ratio is the one that puts the peak at the
drawn slip with the run's ``C`` and ``E`` (`stiffness_for_peak_slip`), so that a spread can
vary the peak slip by a stated band and the shape factor ``C`` on its own (drawing ``B`` and
``C`` independently moves the peak slip by both).  A spread gives ``B`` or the peak slip at a
ratio, not both.

Sampling is by inverse transform of the (truncated) distribution, one uniform number per
parameter and run: run ``i`` draws from its own stream ``SeedSequence(seed, spawn_key=(i,))``,
so a run's sample depends on the seed and its index only, never on how the runs are chunked
or on the number of workers.
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, fields, replace
from typing import Any, Mapping, Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import brentq
from scipy.special import ndtr, ndtri

from .._validate import check_number, fmt
from ..errors import ParameterError
from ..params import Params, read_toml
from ..variator.geometry import check_ratio
from ..variator.traction import MAGIC_NU_MAX, traction_from_params

__all__ = ["Distribution", "Spread", "load_spread", "spread_from_dict", "DISTRIBUTIONS",
           "SCENARIO_VARIABLES", "PEAK_SLIP_VARIABLES", "apply_scenario", "peak_slip",
           "stiffness_for_peak_slip", "resolve_peak_slips"]

DISTRIBUTIONS = ("normal", "uniform", "lognormal")

#: the keys each distribution accepts (besides ``distribution``)
_KEYS = {"normal": ("mean", "std", "rel_std", "lower", "upper"),
         "uniform": ("lower", "upper"),
         "lognormal": ("median", "sigma", "lower", "upper")}

#: spread variables of a closed-loop scenario (not of the parameter set) -> unit
SCENARIO_VARIABLES = {"scenario.initial.F_s": "N", "scenario.initial.tau": "-",
                      "scenario.initial.r_g": "-", "scenario.initial.omega_p": "rad/s",
                      "scenario.load_step": "-"}


def apply_scenario(scenario: Any, values: Mapping[str, float], params: Params) -> Any:
    """A copy of a closed-loop scenario with `values` of `SCENARIO_VARIABLES`, validated as
    the scenario file's own values are.

    Parameters
    ----------
    scenario : empact.nonlinear.scenario.Scenario
        The nominal scenario.
    values : mapping str -> float
        ``scenario.*`` names (`SCENARIO_VARIABLES`) -> values (SI; fractions).
    params : Params
        The machine (its variator's ratio range).

    Returns
    -------
    Scenario
        The scenario with the new initial point and load step.

    Raises
    ------
    ParameterError
        One line naming the variable, its value and what is allowed.
    """
    if not values:
        return scenario
    init = {f.name: getattr(scenario.initial, f.name) for f in fields(scenario.initial)}
    load_step = scenario.load_step
    for name, x in values.items():
        key = name.removeprefix("scenario.")
        if key == "load_step":
            if scenario.load_step is None:
                raise ParameterError(f"{name}: the scenario {scenario.name!r} has no load "
                                     "step (scenario.load_step) to vary")
            load_step = check_number(name, x, -1.0, 2.0,
                                     note="a fraction of the torque capacity")
        else:
            field_ = key.removeprefix("initial.")
            if init.get(field_) is None:
                raise ParameterError(f"{name}: the scenario {scenario.name!r} does not give "
                                     f"initial.{field_} (its operating point is given by "
                                     "other variables)")
            init[field_] = float(x)
    try:
        initial = type(scenario.initial)(**init)
    except ParameterError as exc:
        raise ParameterError(f"scenario.initial: {exc}") from None
    if "scenario.initial.r_g" in values:
        check_ratio(initial.r_g, params.variator, "scenario.initial.r_g")
    if "scenario.initial.F_s" in values and not initial.F_s > 0:
        raise ParameterError(f"scenario.initial.F_s = {fmt(initial.F_s)}: a clamping force "
                             "is > 0 [N]")
    return replace(scenario, initial=initial, load_step=load_step)


#: spread variables of the magic formula's peak slip [-] -> the ratio's suffix
PEAK_SLIP_VARIABLES = {f"traction.peak_slip_{k}": k for k in ("low", "med", "od")}


def _peak_argument(C: float, E: float) -> float:
    """``x = B nu_peak`` of the magic formula: where ``C atan(x - E (x - atan x)) = pi/2``,
    i.e. ``(1 - E) x + E atan x = tan(pi / (2 C))`` (monotone in ``x`` for ``E < 1``)."""
    if not 1.0 < C <= 2.0:
        raise ParameterError(f"traction C = {fmt(C)}: the magic formula has a peak only for "
                             "C in (1, 2]")
    t = math.tan(math.pi / (2.0 * C))
    if E == 0.0:
        return t
    if E >= 1.0:
        raise ParameterError(f"traction E = {fmt(E)}: the peak slip is defined for E < 1")
    hi = t / (1.0 - E) + 2.0 * abs(E) + 1.0  # f(hi) >= t: (1-E) hi + E atan(hi) > t
    return float(brentq(lambda x: (1.0 - E) * x + E * math.atan(x) - t, 0.0, hi,
                        xtol=1e-15, rtol=1e-15))


def peak_slip(B: float, C: float, E: float = 0.0) -> float:
    """The slip [-] at the magic formula's peak, ``x / B`` (``x`` where ``C atan(x - E (x -
    atan x)) = pi / 2``).

    Parameters
    ----------
    B, C, E : float
        The formula's stiffness [-], shape (in (1, 2]) [-] and curvature (< 1) [-] factors.

    Returns
    -------
    float
        The peak's slip [-].
    """
    return _peak_argument(C, E) / B


def stiffness_for_peak_slip(nu_peak: float, C: float, E: float = 0.0) -> float:
    """The stiffness factor ``B`` [-] that puts the magic formula's peak at the slip
    `nu_peak` [-] with shape `C` and curvature `E` (`peak_slip`'s inverse in ``B``).

    Parameters
    ----------
    nu_peak : float
        The peak's slip [-], in (0, `MAGIC_NU_MAX`) (the slips the formula is used at).
    C, E : float
        The formula's shape (in (1, 2]) and curvature (< 1) factors [-].

    Returns
    -------
    float
        The stiffness factor ``B`` [-].
    """
    if not 0 < nu_peak < MAGIC_NU_MAX:
        raise ParameterError(f"traction peak slip = {fmt(nu_peak)}: a peak slip is in (0, "
                             f"{fmt(MAGIC_NU_MAX)}) [-], the slips the magic formula is used at")
    return _peak_argument(C, E) / nu_peak


def resolve_peak_slips(values: Mapping[str, float], params: Params) -> dict[str, float]:
    """`values` (dotted names -> values) with each ``traction.peak_slip_*``
    (`PEAK_SLIP_VARIABLES`) replaced by the stiffness ``traction.B_*`` that puts the peak
    there with the ratio's ``C`` and ``E`` (`values`' where given, else `params`').

    Parameters
    ----------
    values : mapping str -> float
        One run's parameter values by dotted name.
    params : Params
        The nominal set (``C`` and ``E`` where `values` does not give them).

    Returns
    -------
    dict of str to float
        The values `Params.from_dotted` takes.
    """
    out = {k: v for k, v in values.items() if k not in PEAK_SLIP_VARIABLES}
    for name, k in PEAK_SLIP_VARIABLES.items():
        if name in values:
            C = values.get(f"traction.C_{k}", params.get(f"traction.C_{k}"))
            E = values.get(f"traction.E_{k}", params.get(f"traction.E_{k}"))
            out[f"traction.B_{k}"] = stiffness_for_peak_slip(values[name], C, E)
    return out


#: a truncation keeping less probability than this is refused (bounds far in a tail)
_MIN_MASS = 1e-9


@dataclass(frozen=True)
class Distribution:
    """One parameter's distribution.

    Attributes
    ----------
    name : dotted parameter name, e.g. ``"actuation.k_w"``
    kind : "normal", "uniform" or "lognormal"
    loc : mean (normal), median (lognormal) or lower bound (uniform) [unit of the parameter]
    scale : standard deviation (normal) [unit], sigma of ``ln X`` (lognormal) [-], or the
        upper bound (uniform) [unit]
    lower, upper : truncation bounds [unit] (infinite when not given)
    """

    name: str
    kind: str
    loc: float
    scale: float
    lower: float = -math.inf
    upper: float = math.inf

    def _cdf_bounds(self) -> tuple[float, float]:
        if self.kind == "normal":
            z = lambda x: (x - self.loc) / self.scale  # noqa: E731
        else:  # lognormal
            z = lambda x: ((math.log(x) if x > 0 else -math.inf) - math.log(self.loc)) \
                / self.scale  # noqa: E731
        return float(ndtr(z(self.lower))), float(ndtr(z(self.upper)))

    def ppf(self, u: NDArray[np.float64]) -> NDArray[np.float64]:
        """Inverse CDF of the truncated distribution at `u` in (0, 1) (any shape).

        Parameters
        ----------
        u : ndarray
            Probabilities in (0, 1), any shape.
        """
        u = np.asarray(u, float)
        if self.kind == "uniform":
            return self.loc + u * (self.scale - self.loc)
        lo, hi = self._cdf_bounds()
        z = ndtri(lo + u * (hi - lo))
        x = self.loc + self.scale * z if self.kind == "normal" \
            else self.loc * np.exp(self.scale * z)
        return np.clip(x, self.lower, self.upper)  # rounding at a bound only

    def describe(self) -> str:
        """One line, e.g. ``normal(mean 47.3, std 2.36) in [40, 55]``."""
        if self.kind == "uniform":
            return f"uniform on [{fmt(self.loc)}, {fmt(self.scale)}]"
        head = (f"normal(mean {fmt(self.loc)}, std {fmt(self.scale)})" if self.kind == "normal"
                else f"lognormal(median {fmt(self.loc)}, sigma {fmt(self.scale)})")
        if math.isinf(self.lower) and math.isinf(self.upper):
            return head
        return f"{head} in [{fmt(self.lower)}, {fmt(self.upper)}]"


@dataclass(frozen=True)
class Spread:
    """The distributions of a Monte Carlo study, in file order.

    Attributes
    ----------
    distributions : tuple of Distribution
        One per spread parameter, in file order.
    source : str
        The spread file it was read from (empty if built in code), for messages.
    """

    distributions: tuple[Distribution, ...]
    source: str = ""

    @property
    def names(self) -> tuple[str, ...]:
        """The dotted parameter names."""
        return tuple(d.name for d in self.distributions)

    def split(self, row: Sequence[float] | NDArray[np.float64]
              ) -> tuple[dict[str, float], dict[str, float]]:
        """One run's values as (parameters by dotted name, ``scenario.*`` variables).

        Parameters
        ----------
        row : sequence of float
            The run's values, in the order of `names`.
        """
        values = dict(zip(self.names, (float(x) for x in row)))
        scen = {k: v for k, v in values.items() if k.startswith("scenario.")}
        return {k: v for k, v in values.items() if k not in scen}, scen

    def sample(self, seed: int, runs: Sequence[int] | NDArray[np.int64]) -> NDArray[np.float64]:
        """The parameter values of runs `runs` (indices), shape ``(len(runs), n_parameters)``.

        Run ``i`` uses the stream ``SeedSequence(seed, spawn_key=(i,))``: its values do not
        depend on which other runs are drawn with it.

        Parameters
        ----------
        seed : int
            The study's seed.
        runs : sequence of int
            Run indices.
        """
        runs = np.asarray(runs, dtype=np.int64).ravel()
        k = len(self.distributions)
        u = np.empty((runs.size, k))
        for j, i in enumerate(runs):
            rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(int(i),)))
            u[j] = rng.random(k)
        return np.column_stack([d.ppf(u[:, c]) for c, d in enumerate(self.distributions)]) \
            if k else u


def _distribution(name: str, table: Any, params: Params, src: str,
                  scenario: Any = None) -> Distribution:
    where = f"{src}: spread.{name!r}" if src else f"spread.{name!r}"
    if not isinstance(table, Mapping):
        raise ParameterError(f"{where} must be a table with a distribution, not {table!r}")
    if name.startswith("scenario."):
        if name not in SCENARIO_VARIABLES:
            raise ParameterError(f"{where}: unknown scenario variable {name!r} (choose from "
                                 f"{', '.join(SCENARIO_VARIABLES)})")
        if scenario is None:
            raise ParameterError(f"{where}: {name} is a variable of a closed-loop scenario; "
                                 "it needs --analysis closed-loop with a scenario")
        key = name.removeprefix("scenario.")
        nominal = scenario.load_step if key == "load_step" \
            else getattr(scenario.initial, key.removeprefix("initial."))
        if nominal is None:
            raise ParameterError(f"{where}: the scenario {scenario.name!r} does not give "
                                 f"{key}; it cannot be varied")
    elif name in PEAK_SLIP_VARIABLES:
        k = PEAK_SLIP_VARIABLES[name]
        if params.traction_table is not None:
            raise ParameterError(f"{where}: {name} is a variable of the magic formula; the "
                                 "parameter set's traction is a table "
                                 f"({params.traction_table_file}), which a spread does not vary")
        nominal = peak_slip(*(params.get(f"traction.{c}_{k}") for c in "BCE"))
    else:
        try:
            nominal = params.get(name, unset_ok=True)
        except ParameterError:
            raise ParameterError(f"{where}: unknown parameter {name!r} (use a dotted name of "
                                 "a parameter file, e.g. 'actuation.k_w')") from None
    if nominal is None and table.get("distribution") in DISTRIBUTIONS and not (
            {"mean", "median", "lower"} & set(table) and "rel_std" not in table):
        raise ParameterError(f"{where}: {name} is not set in this parameter set (the "
                             "operating point is given by other variables): give the "
                             "distribution's mean, median or bounds explicitly")
    kind = table.get("distribution")
    if kind not in DISTRIBUTIONS:
        raise ParameterError(f"{where}: distribution = {kind!r}; choose one of "
                             f"{', '.join(DISTRIBUTIONS)}")
    extra = sorted(set(table) - {"distribution", *_KEYS[kind]})
    if extra:
        raise ParameterError(f"{where}: unknown key {extra[0]!r} for a {kind} distribution "
                             f"(allowed: {', '.join(_KEYS[kind])})")
    v = {k: check_number(k, table[k], where=where) for k in table if k != "distribution"}
    lower, upper = v.get("lower", -math.inf), v.get("upper", math.inf)
    if kind == "uniform":
        if "lower" not in v or "upper" not in v:
            raise ParameterError(f"{where}: a uniform distribution needs lower and upper")
        loc, scale = lower, upper
    elif kind == "normal":
        mean = v.get("mean", nominal)
        if mean is None:
            raise ParameterError(f"{where}: a normal distribution of {name} needs its mean (the "
                                 "parameter set does not give the variable)")
        loc = mean
        if ("std" in v) == ("rel_std" in v):
            raise ParameterError(f"{where}: give one of std or rel_std")
        scale = v["std"] if "std" in v else v["rel_std"] * abs(loc)
        check_number("std", scale, 0.0, lo_open=True, where=where)
    else:
        loc = check_number("median", v.get("median", nominal), 0.0, lo_open=True, where=where)
        if "sigma" not in v:
            raise ParameterError(f"{where}: a lognormal distribution needs sigma (the standard "
                                 "deviation of ln X)")
        scale = check_number("sigma", v["sigma"], 0.0, lo_open=True, where=where)
        if "lower" in v and lower < 0:
            raise ParameterError(f"{where}: lower = {fmt(lower)} is negative; a log-normal "
                                 "value is positive")
    if not lower < upper:
        raise ParameterError(f"{where}: lower = {fmt(lower)} must be below upper = "
                             f"{fmt(upper)}")
    d = Distribution(name, kind, float(loc), float(scale), lower, upper)
    if kind != "uniform":
        lo, hi = d._cdf_bounds()
        if hi - lo < _MIN_MASS:
            raise ParameterError(f"{where}: the bounds [{fmt(lower)}, {fmt(upper)}] keep "
                                 f"no probability of {d.describe().split(' in ')[0]}")
    _check_reachable(d, params, where, scenario)
    return d


#: quantiles at which a distribution is tried against the parameter's allowed values
_PROBES = np.linspace(0.0005, 0.9995, 41)


def _check_reachable(d: Distribution, params: Params, where: str, scenario: Any = None) -> None:
    """Refuse a distribution whose values (41 quantiles, 0.05 % to 99.95 %) the parameter
    set refuses wholly (every run of the study would fail) or for the most part (more than
    half of the probes: most runs would fail, found only after they ran)."""
    why, refused = "", 0
    for x in d.ppf(_PROBES):
        try:
            if d.name.startswith("scenario."):
                apply_scenario(scenario, {d.name: float(x)}, params)
                continue
            p = params.from_dotted(resolve_peak_slips({d.name: float(x)}, params))
            nu = p.operating.nu
            if d.name == "operating.nu" and nu is not None:
                lo, hi = traction_from_params(p).nu_range
                if not lo <= nu <= hi:
                    raise ParameterError(f"{d.name} = {fmt(nu)}: outside the valid slip range "
                                         f"[{fmt(lo)}, {fmt(hi)}] of the traction curve")
        except ParameterError as exc:
            why, refused = why or str(exc), refused + 1
    if 2 * refused <= len(_PROBES):
        return
    m = re.search(r"= \S+: (.*)$", why)
    if refused == len(_PROBES):
        raise ParameterError(f"{where}: {d.describe()} lies wholly outside the values "
                             f"{d.name} may take ({m.group(1) if m else why}); every run "
                             "would fail")
    share = 100 * refused / len(_PROBES)
    raise ParameterError(f"{where}: {d.describe()} lies for the most part ({share:.0f} % of "
                         f"its quantiles) outside the values {d.name} may take "
                         f"({m.group(1) if m else why}); most runs would fail (narrow it or "
                         "bound it with lower and upper)")


def spread_from_dict(data: Mapping[str, Any], params: Params, source: str = "",
                     scenario: Any = None) -> Spread:
    """Validate a parsed spread document against a parameter set (names, distributions).

    Parameters
    ----------
    data : mapping
        A parsed spread document: a ``spread`` table of one table per parameter, keyed by
        its dotted name (``[spread."actuation.k_w"]`` or ``[spread.actuation.k_w]``).
    params : Params
        The nominal set (defines each parameter's value and allowed range).
    source : str
        The file it came from (named in the messages).
    scenario : Scenario, optional
        The closed-loop scenario of the study: ``scenario.*`` variables
        (`SCENARIO_VARIABLES`) take their nominal value from it and are checked against it.

    Returns
    -------
    Spread
        The distributions by dotted name, in document order.

    Raises
    ------
    ParameterError
        One line naming the file and parameter: an unknown table, key, parameter or
        distribution, a parameter given twice, bad bounds, or a distribution whose values the
        parameter set never accepts.
    """
    where = source or "spread"
    extra = sorted(set(data) - {"spread"})
    if extra:
        raise ParameterError(f"{where}: unknown table or key {extra[0]!r} (a spread file has "
                             "only [spread.\"section.name\"] tables)")
    tables = data.get("spread")
    if not isinstance(tables, Mapping) or not tables:
        raise ParameterError(f"{where}: no [spread.\"section.name\"] table; give at least one "
                             "parameter's distribution")
    flat: dict[str, Any] = {}

    def collect(prefix: str, node: Mapping[str, Any]) -> None:
        # [spread."actuation.k_w"] and [spread.actuation.k_w] are the same parameter
        for key, value in node.items():
            name = f"{prefix}.{key}" if prefix else key
            if isinstance(value, Mapping) and "distribution" not in value:
                collect(name, value)
            else:
                if name in flat:
                    raise ParameterError(f"{where}: parameter {name!r} given twice")
                flat[name] = value

    collect("", tables)
    both = [n for n, k in PEAK_SLIP_VARIABLES.items() if n in flat and f"traction.B_{k}" in flat]
    if both:
        k = PEAK_SLIP_VARIABLES[both[0]]
        raise ParameterError(f"{where}: {both[0]} and traction.B_{k} both given; the peak slip "
                             f"sets B_{k} (with C_{k} and E_{k}): give one of them")
    return Spread(tuple(_distribution(n, t, params, source, scenario)
                        for n, t in flat.items()), source=source)


def load_spread(path: str | os.PathLike[str], params: Params, scenario: Any = None) -> Spread:
    """Read and validate a spread TOML file; errors are one line naming file and parameter.

    Parameters
    ----------
    path : str or path-like
        A spread TOML file: one ``[spread."section.key"]`` table per parameter.
    params : Params
        The nominal set (defines each parameter's value and allowed range).
    scenario : Scenario, optional
        The closed-loop scenario (for ``scenario.*`` variables, `SCENARIO_VARIABLES`).

    Returns
    -------
    Spread
        The distributions by dotted name; ``names`` in file order.
    """
    return spread_from_dict(read_toml(path, "spread"), params, str(path), scenario)

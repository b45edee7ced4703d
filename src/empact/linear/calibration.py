"""Calibration: fit chosen parameters to target eigenfrequencies (bounded least squares).

A targets file (TOML) names the free parameters, optional ties, and lists the targets::

    free = ["driveline.J_p", "driveline.k_tc", "actuation.k_tp"]   # dotted parameter names
    kinematics = "equal-translation"   # default for actuation targets (optional)

    [ties]                             # parameters that follow a free one (optional)
    "actuation.k_ts" = "actuation.k_tp"

    [[target]]
    model = "driveline"        # "actuation" or "driveline"
    ratio = 1.0                # geometric ratio r_g
    mode = 2                   # 1-based, counting rigid-body modes (the paper's numbering)
    frequency_hz = 4.14
    source = "paper Table 2"   # optional
    weight = 1.0               # optional

    [[target]]
    model = "driveline"
    uncoupled = "primary"      # belt removed: "primary" or "secondary" side
    frequency_hz = 24.6

    [[target]]
    model = "actuation"
    kinematics = "paper-sec2.1"   # this target's actuation rows (stiffnesses [paper_sec21])
    ratio = 1.0
    mode = 2
    frequency_hz = 10.7

The fit works on the logarithm of each free parameter (all are positive), bounded by the
parameter's allowed range, and minimises ``sum weight * (f_model / f_target - 1)^2``.
"""
from __future__ import annotations

import math
from dataclasses import MISSING, dataclass, field, fields
from typing import Any, Sequence

import numpy as np

from .._lazy import lazy_module
from .._results import Result
from .._validate import check_number
from ..errors import ParameterError
from ..params import _SECTIONS, DampingLevel, Params, read_toml
from .actuation import KINEMATICS, actuation_model
from .driveline import driveline_model, uncoupled_frequencies

#: `calibrate`'s solver, imported when it runs (not by every command that imports the linear
#: models: scipy.optimize is a third of `empact modes`' start-up)
optimize = lazy_module("scipy.optimize")

__all__ = ["Target", "CalibrationResult", "load_targets", "calibrate", "model_frequencies"]

MODELS = ("actuation", "driveline")


@dataclass(frozen=True)
class Target:
    """One target eigenfrequency.

    Attributes
    ----------
    model : "actuation" or "driveline"
    frequency_hz : target frequency [Hz]
    ratio : geometric ratio r_g (mode targets)
    mode : 1-based mode number including rigid-body modes (mode targets)
    uncoupled : "primary" or "secondary" (driveline with the belt removed)
    weight : weight of the squared relative residual
    source : where the number comes from
    kinematics : actuation rows, "equal-translation" (the machine, stiffnesses
        ``[actuation]``) or "paper-sec2.1" (stiffnesses ``[paper_sec21]``)
    """

    model: str
    frequency_hz: float
    ratio: float | None = None
    mode: int | None = None
    uncoupled: str | None = None
    weight: float = 1.0
    source: str = ""
    kinematics: str = "equal-translation"

    @property
    def label(self) -> str:
        """Short description, e.g. ``driveline r_g=1 mode 2``."""
        if self.uncoupled:
            return f"{self.model} uncoupled {self.uncoupled}"
        kin = f" ({self.kinematics})" if self.model == "actuation" else ""
        return f"{self.model}{kin} r_g={self.ratio:g} mode {self.mode}"


@dataclass(frozen=True)
class CalibrationResult(Result):
    """Result of `calibrate`.

    Attributes
    ----------
    params : the calibrated parameter set
    targets : the targets
    achieved_hz : model frequencies at the solution [Hz], shape (n_targets,)
    relative_error : ``achieved / target - 1``, shape (n_targets,)
    free : names of the fitted parameters
    initial, final : their values before and after
    success, message : from the optimiser
    ties : ``{dependent: free}``, parameters set equal to a fitted one
    """

    params: Params
    targets: tuple[Target, ...]
    achieved_hz: np.ndarray
    relative_error: np.ndarray
    free: tuple[str, ...]
    initial: np.ndarray
    final: np.ndarray
    success: bool
    message: str
    ties: dict[str, str] = field(default_factory=dict)


def _field_meta(dotted: str) -> dict[str, Any]:
    parts = dotted.split(".")
    kind = DampingLevel if parts[0] == "damping" and len(parts) == 3 else _SECTIONS.get(parts[0])
    for f in fields(kind) if kind is not None else ():
        if f.name == parts[-1] and "unit" in f.metadata:
            return dict(f.metadata)
    raise ParameterError(f"free parameter {dotted!r}: not a parameter name (use section.key, "
                         "e.g. driveline.k_tc)")


def _check_target(raw: dict[str, Any], where: str) -> Target:
    allowed = {f.name for f in fields(Target)}
    unknown = set(raw) - allowed
    if unknown:
        raise ParameterError(f"{where}: unknown key {sorted(unknown)[0]!r} (allowed: "
                             f"{', '.join(sorted(allowed))})")
    required = [f.name for f in fields(Target) if f.default is MISSING]
    missing = [k for k in required if k not in raw]
    if missing:
        raise ParameterError(f"{where}: missing {', '.join(missing)} (each target needs "
                             f"{', '.join(required)})")
    t = Target(**raw)
    if t.model not in MODELS:
        raise ParameterError(f"{where}: model = {t.model!r}: must be one of {', '.join(MODELS)}")
    if t.kinematics not in KINEMATICS:
        raise ParameterError(f"{where}: kinematics = {t.kinematics!r}: must be one of "
                             f"{', '.join(KINEMATICS)}")
    check_number("frequency_hz", t.frequency_hz, 0.0, 1e6, lo_open=True, unit="Hz",
                 where=where)
    if t.uncoupled is not None:
        if t.model != "driveline" or t.uncoupled not in ("primary", "secondary"):
            raise ParameterError(f"{where}: uncoupled = {t.uncoupled!r}: only for the driveline, "
                                 "'primary' or 'secondary'")
    elif not (isinstance(t.mode, int) and t.mode >= 1 and isinstance(t.ratio, (int, float))):
        raise ParameterError(f"{where}: a mode target needs ratio (a number) and mode "
                             f"(integer >= 1), got ratio = {t.ratio!r}, mode = {t.mode!r}")
    if not isinstance(t.weight, (int, float)) or not t.weight > 0:
        raise ParameterError(f"{where}: weight = {t.weight!r}: must be > 0")
    return t


def load_targets(path: str, kinematics: str | None = None,
                 ties: dict[str, str] | None = None) \
        -> tuple[tuple[Target, ...], tuple[str, ...], dict[str, str]]:
    """Read a targets file; returns ``(targets, free, ties)``.  Errors name the entry and key.

    `kinematics` (if given) is the default for actuation targets that do not name theirs
    (over the file's own ``kinematics``); `ties` are added to the file's ``[ties]``.

    Parameters
    ----------
    path : str
        The targets file (TOML, the module notes' layout).
    kinematics : {"equal-translation", "paper-sec2.1"}, optional
        Default actuation rows of the targets that name none (default: the file's
        ``kinematics``, else ``"equal-translation"``).
    ties : dict str -> str, optional
        ``{dependent: free}`` dotted parameter names, added to (and overriding) the file's
        ``[ties]``.

    Returns
    -------
    targets : tuple of Target
        The ``[[target]]`` tables, checked, in file order.
    free : tuple of str
        Dotted names of the parameters to fit (the file's ``free``).
    ties : dict str -> str
        ``{dependent: free}``, the file's ties with `ties` added.

    Raises
    ------
    ParameterError
        One line naming the file, the entry and the key that is wrong.
    """
    data = read_toml(path, "targets")
    unknown = set(data) - {"free", "target", "ties", "kinematics"}
    if unknown:
        raise ParameterError(f"{path}: unknown key {sorted(unknown)[0]!r} (allowed: free, "
                             "kinematics, ties, target)")
    free = data.get("free")
    if free is None:
        raise ParameterError(f"{path}: missing free (the list of parameters to fit, e.g. "
                             "free = [\"driveline.k_tc\"])")
    if not isinstance(free, list) or not free or not all(isinstance(x, str) for x in free):
        raise ParameterError(f"{path}: free = {free!r}: must be a non-empty list of parameter "
                             "names")
    for name in free:
        _field_meta(name)
    default_kin = kinematics if kinematics is not None else data.get("kinematics",
                                                                      "equal-translation")
    if default_kin not in KINEMATICS:
        raise ParameterError(f"{path}: kinematics = {default_kin!r}: must be one of "
                             f"{', '.join(KINEMATICS)}")
    raw_ties = data.get("ties", {})
    if not isinstance(raw_ties, dict):
        raise ParameterError(f"{path}: ties must be a table of \"dependent\" = \"free\" names")
    all_ties = {**raw_ties, **(ties or {})}
    check_ties(all_ties, free, str(path))
    raw = data.get("target")
    if not isinstance(raw, list) or not raw:
        raise ParameterError(f"{path}: needs at least one [[target]] table")
    targets = tuple(_check_target({"kinematics": default_kin, **dict(t)},
                                  f"{path}: target {i + 1}") for i, t in enumerate(raw))
    return targets, tuple(free), dict(all_ties)


def check_ties(ties: dict[str, str], free: Sequence[str], where: str = "ties") -> None:
    """Each tie ``dependent = source``: both parameter names of the same unit, the source
    fitted (in `free`), the dependent not."""
    for dep, src in ties.items():
        if not isinstance(src, str):
            raise ParameterError(f"{where}: tie {dep!r} = {src!r}: the source must be a "
                                 "parameter name")
        m_dep, m_src = _field_meta(dep), _field_meta(src)
        if src not in free:
            raise ParameterError(f"{where}: tie {dep} = {src}: {src} is not a free parameter "
                                 f"(free: {', '.join(free)})")
        if dep in free:
            raise ParameterError(f"{where}: tie {dep} = {src}: {dep} is free; a tied "
                                 "parameter follows its source and cannot be fitted too")
        if m_dep["unit"] != m_src["unit"]:
            raise ParameterError(f"{where}: tie {dep} = {src}: units differ "
                                 f"({m_dep['unit']} vs {m_src['unit']})")


def model_frequencies(params: Params, targets: Sequence[Target]) -> np.ndarray:
    """The model's frequency for every target [Hz], shape (n_targets,).

    Parameters
    ----------
    params : Params
        The parameter set the models are built from.
    targets : sequence of Target
        Mode targets (model, ratio, mode, kinematics) or uncoupled driveline targets
        (`uncoupled_frequencies`).

    Returns
    -------
    ndarray, shape (n_targets,)
        The model's frequency of each target's mode [Hz] (mode numbers count rigid-body
        modes, at 0 Hz).

    Raises
    ------
    ParameterError
        When a target's mode number exceeds its model's number of modes.
    """
    cache: dict[tuple[str, float, str], np.ndarray] = {}
    out = np.empty(len(targets))
    for i, t in enumerate(targets):
        if t.uncoupled:
            out[i] = uncoupled_frequencies(params)[t.uncoupled]
            continue
        assert t.ratio is not None and t.mode is not None  # a mode target (FrequencyTarget)
        key = (t.model, float(t.ratio), t.kinematics)
        if key not in cache:
            lm = actuation_model(params, t.ratio, kinematics=t.kinematics) \
                if t.model == "actuation" else driveline_model(params, t.ratio)
            cache[key] = lm.modes().frequencies_hz
        f = cache[key]
        if t.mode > len(f):
            raise ParameterError(f"target {t.label}: the {t.model} model has {len(f)} modes")
        out[i] = f[t.mode - 1]
    return out


def calibrate(params: Params, targets: Sequence[Target], free: Sequence[str],
              ties: dict[str, str] | None = None) -> CalibrationResult:
    """Fit the `free` parameters of `params` to the target frequencies.

    Bounded least squares (`scipy.optimize.least_squares`, trust-region reflective) on the
    logarithms of the free parameters; bounds are the parameters' allowed ranges.  `ties`
    ``{dependent: source}`` set a parameter equal to a free one throughout (e.g.
    ``{"actuation.k_ts": "actuation.k_tp"}``).

    Parameters
    ----------
    params : Params
        The starting parameter set.
    targets : sequence of Target
        Target eigenfrequencies [Hz] by model, ratio and mode (`load_targets`).
    free : sequence of str
        Dotted names of the fitted parameters (``"actuation.k_w"``).
    ties : dict, optional
        ``{dependent: source}`` dotted names held equal.

    Returns
    -------
    CalibrationResult
        ``params`` (the fitted set), ``achieved_hz`` and ``relative_error`` per target,
        ``initial`` and ``final`` values of the free parameters, ``success`` and ``message``.
    """
    targets, free, ties = tuple(targets), tuple(free), dict(ties or {})
    check_ties(ties, free)
    x0 = np.log([params.get(name) for name in free])
    lo, hi = [], []
    for name in free:
        meta = _field_meta(name)
        lo.append(math.log(meta["lo"]) if meta["lo"] > 0 else -np.inf)
        hi.append(math.log(meta["hi"]) if math.isfinite(meta["hi"]) else np.inf)
    f_t = np.array([t.frequency_hz for t in targets])
    w = np.sqrt([t.weight for t in targets])

    def build(x: np.ndarray) -> Params:
        values = dict(zip(free, np.exp(x)))
        values.update({dep: values[src] for dep, src in ties.items()})
        return params.from_dotted(values)

    def residual(x: np.ndarray) -> np.ndarray:
        return w * (model_frequencies(build(x), targets) / f_t - 1)

    sol = optimize.least_squares(residual, x0, bounds=(lo, hi), x_scale=1.0, xtol=1e-12, ftol=1e-12,
                        gtol=1e-12, max_nfev=2000)
    fitted = build(sol.x)
    achieved = model_frequencies(fitted, targets)
    return CalibrationResult(params=fitted, targets=targets, achieved_hz=achieved,
                             relative_error=achieved / f_t - 1, free=free,
                             initial=np.exp(x0), final=np.exp(sol.x), success=bool(sol.success),
                             message=str(sol.message), ties=ties)

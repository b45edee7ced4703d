"""Frozen, validated model parameters, loaded from and saved to TOML.

A parameter set has one section per concept::

    [variator]          belt and pulley geometry (eqs. 4-6 of the paper)
    [actuation]         inertias, ratios and stiffnesses of the actuation (Fig. 3)
    [damping.none]      damping levels of the actuation model (Fig. 6)
    [damping.moderate]
    [damping.large]
    [driveline]         inertias and stiffnesses of the test-bench driveline (Fig. 7)
    [traction]          traction curve mu(nu, r_g) (Fig. 10); ``table = "curves.csv"``:
                        measured curves instead (path relative to the file)
    [shift]             creep-mode shifting of the belt (Carbone et al. 2007; Ide et al.)
    [thrust_ratio]      torque-dependent equilibrium thrust ratio kappa(tau, r_g)
    [paper_sec21]       stiffnesses of the paper's Sec. 2.1 kinematics (the published variant)
    [servo]             torque and speed limits of the servo drives, their motor constants,
                        drives and transmissions (`empact.hardware`)
    [hydraulic]         a hydraulic actuation of the same variator, the reference to compare
                        with (`empact.hardware`, billed by `empact.actuation_energy`)
    [losses]            the variator's losses beside the slip: clamping, load, drag
                        (`empact.variator.losses`); ``table = "map.csv"``: a measured
                        loss map instead (path relative to the file)
    [sensors]           the closed loop's instruments: delay, encoders, noise
    [vehicle]           the car around the CVT: mass, wheels, final drive, road load
                        (`empact.vehicle`)
    [engine]            the engine: full load, Willans-line fuel, operating line, fuel
                        (`empact.engine`)
    [operating]         the default operating point (r_g, nu, F_s, omega_p), used by every
                        analysis that is not given one (slip model, trim, plants, NMP, Fig. 2)

All values are SI (radians, metres, kilograms, seconds).  The shipped set
(`default_params`) is the result of ``empact calibrate`` on the paper's
eigenfrequencies; a user file may give any subset of keys, the rest are taken
from the shipped set.  Every value is checked on construction: a bad value
raises `ParameterError` whose message names the field, the value and the
allowed range.
"""
from __future__ import annotations

import os
import tomllib
from dataclasses import asdict, dataclass, field, fields
from importlib import resources
from typing import Any, Literal, Mapping, overload

import tomli_w

from ._io import atomic_write_text, parse_toml
from ._section import Section, param
from ._validate import check_choice, check_number
from .engine import EngineParams
from .errors import ParameterError
from .hardware import HydraulicParams, SensorParams, ServoLimits
from .operating import (
    OPERATING_VARIABLES,
    OperatingPoint,
    ResolvedPoint,
    check_clamping,
    check_one_slip,
)
from .variator.geometry import VariatorParams, ratio_range
from .variator.losses import LossMap, LossParams, load_loss_map
from .variator.shift_law import ShiftParams
from .variator.thrust_ratio import ThrustRatioParams
from .variator.traction import TabulatedTraction, TractionParams, load_traction
from .vehicle import VehicleParams

__all__ = [
    "ParameterError", "VariatorParams", "ActuationParams", "DampingLevel", "DampingParams",
    "DrivelineParams", "TractionParams", "ShiftParams", "ThrustRatioParams", "Sec21Stiffness",
    "OperatingPoint", "ResolvedPoint", "HydraulicParams", "Params", "default_params",
    "load_params", "save_params", "dumps_params", "read_toml", "DAMPING_LEVELS",
    "OPERATING_VARIABLES", "LossParams", "ParameterInfo", "describe_parameters",
    "parameter_sources",
    "check_clamping", "check_one_slip",
]

DAMPING_LEVELS = ("none", "moderate", "large")

@dataclass(frozen=True)
class ActuationParams(Section):
    """Linear actuation model (paper Sec. 2.1, Fig. 3).

    Attributes
    ----------
    J_mp : float
        Primary servo inertia (rotor and worm), coordinate q1 [kg m^2].
    J_ms : float
        Secondary servo inertia (rotor and chain sprocket), coordinate q2 [kg m^2].
    J_sp : float
        Primary sun gear with screw (ring, carrier and planets lumped), q3 [kg m^2].
    J_ss : float
        Secondary sun gear with screw input, q4 [kg m^2].
    m_p, m_s : float
        Primary and secondary moving sheaves with screw output, q5 and q6 [kg].
    i_w : float
        Worm ratio (servo turns per ring turn) [-].
    i_c : float
        Chain ratio (servo turns per ring turn) [-].
    i_e : float
        Ring to sun ratio of the epicyclic sets (the paper: 2) [-].
    s : float
        Screw pitch (translation per radian) [m/rad].
    k_w, k_c : float
        Worm stiffness (spring 1) and chain stiffness (spring 2) [N m/rad].
    k_belt : float
        Longitudinal pushbelt stiffness (spring 3) [N/m]: against a change of the belt's
        running length by the sheaves' axial positions; the actuation model's belt and the
        nonlinear model's belt element (`DrivelineParams.k_belt` is the belt as a
        torque-carrying chain).
    k_tp, k_ts : float
        Primary and secondary thrust bearing stiffnesses (springs 4 and 5) [N/m].
    """

    _name = "actuation"
    J_mp: float = param("kg m^2", "primary servo inertia (rotor and worm), coordinate q1",
                        1e-8, 1.0)
    J_ms: float = param("kg m^2", "secondary servo inertia (rotor and chain sprocket), "
                     "coordinate q2", 1e-8, 1.0)
    J_sp: float = param("kg m^2", "primary sun gear with screw, ring/carrier/planets lumped, q3",
                     1e-7, 10.0)
    J_ss: float = param("kg m^2", "secondary sun gear with screw input, q4", 1e-7, 10.0)
    m_p: float = param("kg", "primary moving sheave with screw output, q5", 0.01, 100.0)
    m_s: float = param("kg", "secondary moving sheave with screw output, q6", 0.01, 100.0)
    i_w: float = param("-", "worm ratio (servo turns per ring turn)", 0.1, 1000.0)
    i_c: float = param("-", "chain ratio (servo turns per ring turn)", 0.01, 100.0)
    i_e: float = param("-", "ring to sun ratio of the epicyclic sets (the paper: 2)", 1.0, 10.0)
    s: float = param("m/rad", "screw pitch (translation per radian)", 1e-7, 1e-2)
    k_w: float = param("N m/rad", "worm stiffness (spring 1)", 1e-3, 1e8)
    k_c: float = param("N m/rad", "chain stiffness (spring 2)", 1e-3, 1e8)
    k_belt: float = param("N/m", "longitudinal pushbelt stiffness against a change of its "
                          "running length by the sheaves' axial positions (spring 3): the "
                          "actuation model's belt and the nonlinear model's belt element "
                          "(clamping and ratio); not driveline.k_belt, the belt as a "
                          "torque-carrying chain", 1e2, 1e11)
    k_tp: float = param("N/m", "primary thrust bearing stiffness (spring 4)", 1e4, 1e12)
    k_ts: float = param("N/m", "secondary thrust bearing stiffness (spring 5)", 1e4, 1e12)


@dataclass(frozen=True)
class DampingLevel(Section):
    """One damping level of the actuation model (Fig. 6).

    Attributes
    ----------
    alpha : float
        Proportional spring damping, ``C_spring = alpha K`` [s].
    c_mp, c_ms : float
        Viscous friction of the primary and secondary servos [N m s/rad].
    c_sp, c_ss : float
        Viscous friction of the primary and secondary screws [N m s/rad].
    c_shafai : float
        Shafai pulley damping coefficient [N/m]: the pulley damping is ``c_pulley =
        c_shafai / |omega|`` [N s/m] at pulley speed ``omega``.
    """

    _name = "damping"
    alpha: float = param("s", "proportional spring damping, C_spring = alpha K", 0.0, 0.1,
                      lo_open=False)
    c_mp: float = param("N m s/rad", "viscous friction of the primary servo", 0.0, 100.0,
                     lo_open=False)
    c_ms: float = param("N m s/rad", "viscous friction of the secondary servo", 0.0, 100.0,
                     lo_open=False)
    c_sp: float = param("N m s/rad", "viscous friction of the primary screw", 0.0, 1e4,
                     lo_open=False)
    c_ss: float = param("N m s/rad", "viscous friction of the secondary screw", 0.0, 1e4,
                     lo_open=False)
    c_shafai: float = param("N/m", "Shafai pulley damping: c_pulley = c_shafai / |omega| [N s/m]",
                         0.0, 1e10, lo_open=False)


@dataclass(frozen=True)
class DampingParams:
    """The three damping levels of Fig. 6 and the pulley speed for Shafai's model.

    Attributes
    ----------
    none, moderate, large : DampingLevel
        The damping levels ``[damping.none]``, ``[damping.moderate]`` and
        ``[damping.large]`` (`DAMPING_LEVELS`).
    omega_pulley : float
        Pulley speed of Shafai's damping model in the linear actuation model [rad/s], in
        (0, 2000].
    """

    none: DampingLevel
    moderate: DampingLevel
    large: DampingLevel
    omega_pulley: float = 300.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "omega_pulley",
                           check_number("damping.omega_pulley", self.omega_pulley, 0.0, 2000.0,
                                        lo_open=True, unit="rad/s"))

    def level(self, name: str) -> DampingLevel:
        """The damping level called `name` (one of ``DAMPING_LEVELS``).

        Parameters
        ----------
        name : str
            One of ``DAMPING_LEVELS``.
        """
        return getattr(self, check_choice("damping", name, DAMPING_LEVELS))


@dataclass(frozen=True)
class DrivelineParams(Section):
    """Test-bench driveline (paper Sec. 2.2, Fig. 7).

    Attributes
    ----------
    J_d : float
        Drive motor inertia, q1 [kg m^2].
    J_p : float
        Primary pulley with torque converter, q2 [kg m^2].
    J_s : float
        Secondary pulley, q3 [kg m^2].
    J_l : float
        Load motor inertia, q4 [kg m^2].
    k_tc : float
        Torque converter lock-up clutch stiffness [N m/rad].
    k_belt : float
        Pushbelt stiffness as a torque-carrying chain element, on the elongation ``R_p q2 -
        R_s q3`` [N/m]: the linear driveline model's belt, and the nonlinear model's only
        with ``belt="locked"`` (no slip, in place of traction); the nonlinear model's belt
        element is `ActuationParams.k_belt`.
    k_ds : float
        Driveshaft stiffness [N m/rad].
    """

    _name = "driveline"
    J_d: float = param("kg m^2", "drive motor inertia, q1", 1e-6, 1e3)
    J_p: float = param("kg m^2", "primary pulley with torque converter, q2", 1e-6, 1e2)
    J_s: float = param("kg m^2", "secondary pulley, q3", 1e-6, 1e2)
    J_l: float = param("kg m^2", "load motor inertia, q4", 1e-6, 1e3)
    k_tc: float = param("N m/rad", "torque converter lock-up clutch stiffness", 1e-2, 1e8)
    k_belt: float = param("N/m", "pushbelt stiffness as a torque-carrying chain element "
                          "(elongation R_p q2 - R_s q3): the linear driveline model's belt, "
                          "and the nonlinear model's only with belt = \"locked\" (no slip, "
                          "in place of traction); not actuation.k_belt, the nonlinear model's "
                          "belt element", 1e2, 1e11)
    k_ds: float = param("N m/rad", "driveshaft stiffness", 1e-2, 1e8)


@dataclass(frozen=True)
class Sec21Stiffness(Section):
    """Stiffnesses of the actuation model with the paper's Sec. 2.1 kinematics as published
    (kinematics ``"paper-sec2.1"``), calibrated to Table 1 on its own: the overlay that
    `empact.linear.actuation.actuation_model` and the nonlinear model use for that variant.

    Attributes
    ----------
    k_w, k_c : float
        Worm stiffness (spring 1) and chain stiffness (spring 2) [N m/rad].
    k_belt : float
        Longitudinal pushbelt stiffness (spring 3) [N/m].
    k_tp, k_ts : float
        Primary and secondary thrust bearing stiffnesses (springs 4 and 5) [N/m].
    """

    _name = "paper_sec21"
    k_w: float = param("N m/rad", "worm stiffness (spring 1)", 1e-3, 1e8)
    k_c: float = param("N m/rad", "chain stiffness (spring 2)", 1e-3, 1e8)
    k_belt: float = param("N/m", "longitudinal pushbelt stiffness (spring 3) of the Sec. 2.1 "
                          "rows (--kinematics paper-sec2.1): in place of actuation.k_belt "
                          "there, in the actuation and the nonlinear model", 1e2, 1e11)
    k_tp: float = param("N/m", "primary thrust bearing stiffness (spring 4)", 1e4, 1e12)
    k_ts: float = param("N/m", "secondary thrust bearing stiffness (spring 5)", 1e4, 1e12)



_SECTIONS = {
    "variator": VariatorParams, "actuation": ActuationParams, "driveline": DrivelineParams,
    "traction": TractionParams, "shift": ShiftParams, "thrust_ratio": ThrustRatioParams,
    "paper_sec21": Sec21Stiffness, "servo": ServoLimits, "sensors": SensorParams,
    "hydraulic": HydraulicParams, "losses": LossParams, "operating": OperatingPoint,
    "vehicle": VehicleParams, "engine": EngineParams,
}
#: sections whose every key has a default (a file may leave them out)
_OPTIONAL_SECTIONS = ("servo", "sensors", "hydraulic", "losses", "vehicle", "engine")


@dataclass(frozen=True)
class Params:
    """A complete, validated parameter set.  Immutable: `from_dotted` returns a changed copy.

    Attributes
    ----------
    variator, actuation, damping, driveline, traction, shift : Section
        The frozen, validated blocks of the parameter file's tables (``[variator]``, ...;
        SI units, each field's unit and range in ``empact params show --describe``).
    thrust_ratio, paper_sec21, servo, sensors, losses : Section
        The same, for the ``[thrust_ratio]``, ``[paper_sec21]``, ``[servo]``, ``[sensors]``
        and ``[losses]`` tables.
    hydraulic : HydraulicParams
        The hydraulic reference actuation (``[hydraulic]``; every key has a default).
    vehicle, engine : VehicleParams, EngineParams
        The car and its engine (``[vehicle]``, ``[engine]``; every key has a default), for
        the drive cycle (`empact.drive_cycle`).
    operating : OperatingPoint
        The default operating point (``[operating]``).
    traction_table_file : str or None
        The file of measured traction curves the parameter file names (``[traction] table =
        "curves.csv"``, resolved relative to that file by `load_params`), or None: the
        analytic curve of ``[traction]``.  What `to_dict` writes back as ``traction.table``.
    traction_table : TabulatedTraction or None
        Those curves, loaded and validated once (from `traction_table_file` when not given):
        the nonlinear model's default traction (`empact.nonlinear.nonlinear_model`; an
        explicit ``traction`` option wins).  Not compared: two sets are equal when they name
        the same file.
    loss_map_file : str or None
        The file of a measured loss map the parameter file names (``[losses] table =
        "map.csv"``, resolved relative to that file by `load_params`), or None: the analytic
        losses of ``[losses]``.  What `to_dict` writes back as ``losses.table``.
    loss_map : LossMap or None
        That map, loaded and validated once (`empact.variator.losses.load_loss_map`): the
        nonlinear model's default losses (an explicit ``loss_map`` option wins).  Not
        compared, as `traction_table`.
    """

    variator: VariatorParams
    actuation: ActuationParams
    damping: DampingParams
    driveline: DrivelineParams
    traction: TractionParams
    shift: ShiftParams
    thrust_ratio: ThrustRatioParams
    paper_sec21: Sec21Stiffness
    servo: ServoLimits
    sensors: SensorParams
    losses: LossParams
    operating: OperatingPoint
    hydraulic: HydraulicParams = HydraulicParams()
    vehicle: VehicleParams = VehicleParams()
    engine: EngineParams = EngineParams()
    traction_table_file: str | None = None
    traction_table: TabulatedTraction | None = field(default=None, compare=False, repr=False)
    loss_map_file: str | None = None
    loss_map: LossMap | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        self._load_table("traction_table", "traction", load_traction, TabulatedTraction,
                         "a traction table (a string: .csv or .toml")
        self._load_table("loss_map", "losses", load_loss_map, LossMap,
                         "a loss map (a string: .csv")
        if self.shift.k_D * self.shift.F_ref >= 0.9:
            raise ParameterError(
                f"shift.k_D = {self.shift.k_D:g}: with F_ref = {self.shift.F_ref:g} N the "
                f"deformation D would vanish at low clamping force; need k_D F_ref < 0.9")
        lo, hi = ratio_range(self.variator)
        if not lo <= self.operating.r_g <= hi:
            raise ParameterError(
                f"operating.r_g = {self.operating.r_g!r}: outside the geometric ratio range "
                f"[{lo:.4g}, {hi:.4g}] of this variator")

    def _load_table(self, name: str, section: str, load: Any, kind: Any, what: str) -> None:
        """Check the file of a measured table (``[section] table``) and load it once into the
        field `name` (its file in ``name_file``): the traction curves, the loss map."""
        file: Any = getattr(self, f"{name}_file")
        table: Any = getattr(self, name)
        if table is not None and not isinstance(table, kind):
            raise ParameterError(f"{name} = {table!r}: must be a {kind.__name__} "
                                 f"({load.__module__}.{load.__name__})")
        if file is None:
            if table is not None:  # given as an object: its source names it
                object.__setattr__(self, f"{name}_file", table.source)
            return
        if not isinstance(file, (str, os.PathLike)):
            raise ParameterError(f"{section}.table = {file!r}: must be the path of {what}, "
                                 "relative to the parameter file)")
        object.__setattr__(self, f"{name}_file", os.fspath(file))
        if table is None:
            try:
                object.__setattr__(self, name, load(file))
            except ParameterError as exc:  # (its message starts with the path: said once)
                why = str(exc).removeprefix(f"{os.path.normpath(file)}: ")
                raise ParameterError(f"{section}.table = {os.fspath(file)!r}: {why}") from None

    # -- conversion -----------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Nested plain dictionary, as written to TOML (variables of the operating point that
        are not given are left out; a measured traction table as its file,
        ``traction.table``, a measured loss map as ``losses.table``)."""
        d = {f.name: asdict(getattr(self, f.name)) for f in fields(self)
             if not f.name.startswith(("traction_table", "loss_map"))}
        d["operating"] = self.operating.to_dict()
        if self.traction_table_file is not None:
            d["traction"]["table"] = self.traction_table_file
        if self.loss_map_file is not None:
            d["losses"]["table"] = self.loss_map_file
        return d

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], base: "Params | None" = None,
                  source: str = "parameters") -> "Params":
        """Build from a nested mapping; keys not given are taken from `base`.

        Parameters
        ----------
        data : mapping
            Sections (``"actuation"``, ...) to mappings of keys to values (SI units).
        base : Params, optional
            The set that gives the keys `data` leaves out (default none: `data` gives every
            section and key without a default).
        source : str, optional
            What the messages call `data` (e.g. the file's name; default ``"parameters"``).

        Raises
        ------
        ParameterError
            For an unknown section or key, a wrong type or a value out of range.
        """
        merged = base.to_dict() if base is not None else {}
        op_base = dict(merged.get("operating", {}))
        _merge(merged, data, source, _schema())
        _merge_operating(merged, op_base, data.get("operating", {}))
        try:
            damping = merged["damping"]
            levels = {name: DampingLevel(**damping[name]) for name in DAMPING_LEVELS}
            for name in _OPTIONAL_SECTIONS:  # every key has a default
                merged.setdefault(name, {})
            file = merged["traction"].pop("table", None)
            map_file = merged["losses"].pop("table", None)
            # the base's tables are reused, not read again, while the files stay the same
            table = base.traction_table if base is not None \
                and file == base.traction_table_file else None
            loss_map = base.loss_map if base is not None \
                and map_file == base.loss_map_file else None
            sections = {name: kind(**merged[name]) for name, kind in _SECTIONS.items()}
            return cls(damping=DampingParams(**levels, omega_pulley=damping["omega_pulley"]),
                       **sections, traction_table_file=file, traction_table=table,
                       loss_map_file=map_file, loss_map=loss_map)
        except KeyError as exc:
            raise ParameterError(f"{source}: missing section or key {exc.args[0]!r}") from None
        except TypeError as exc:  # missing fields of a section
            raise ParameterError(f"{source}: {exc}") from None
        except ParameterError as exc:  # name the file in every message
            raise ParameterError(f"{source}: {exc}") from None

    def from_dotted(self, values: Mapping[str, float]) -> "Params":
        """A copy with values changed by dotted name, e.g. ``{"damping.large.alpha": 1e-3}``.

        Parameters
        ----------
        values : mapping of str to float
            Dotted names (``"section.key"`` or ``"damping.level.key"``) to new values (SI).
        """
        nested: dict[str, Any] = {}
        for name, value in values.items():
            node = nested
            *path, last = name.split(".")
            for part in path:
                node = node.setdefault(part, {})
            node[last] = value
        return Params.from_dict(nested, base=self)

    @overload
    def get(self, dotted: str, *, unset_ok: Literal[False] = False) -> float: ...

    @overload
    def get(self, dotted: str, *, unset_ok: bool) -> float | None: ...

    def get(self, dotted: str, *, unset_ok: bool = False) -> float | None:
        """The value of a dotted name such as ``"actuation.k_w"`` (with `unset_ok`, None for
        an operating-point variable the set does not give, e.g. ``operating.nu`` of a point
        given by its torque ratio).

        Parameters
        ----------
        dotted : str
            A dotted parameter name.
        unset_ok : bool, optional
            Return None for an operating-point variable the set does not give, instead of
            raising (default False).
        """
        node: Any = self
        for part in dotted.split("."):
            if not hasattr(node, part) or part.startswith("_"):
                raise ParameterError(f"unknown parameter {dotted!r}")
            node = getattr(node, part)
        if node is None:
            if unset_ok:
                return None
            raise ParameterError(f"parameter {dotted!r} is not set in this parameter set")
        if not isinstance(node, float):
            raise ParameterError(f"parameter {dotted!r} is a section, not a value")
        return node

    def unit(self, dotted: str) -> str:
        """The unit of a dotted parameter name, e.g. ``"N m/rad"`` for ``"actuation.k_w"``.

        Parameters
        ----------
        dotted : str
            A dotted parameter name.
        """
        self.get(dotted, unset_ok=True)
        *path, last = dotted.split(".")
        node: Any = self
        for part in path:
            node = getattr(node, part)
        meta = {f.name: f.metadata for f in fields(node)}[last]
        return str(meta.get("unit", ""))


def _merge_operating(merged: dict[str, Any], base: Mapping[str, Any],
                     given: Mapping[str, Any]) -> None:
    """The ``[operating]`` table of a file over the base set's: a file that names two of the
    variables ``nu`` (or ``tau``), ``F_s``, ``T_l`` states its own point; one that names one
    of them changes that one (``nu`` and ``tau`` replace each other), as
    `OperatingPoint.replace` does."""
    if not isinstance(given, Mapping):
        return
    pair = [k for k in ("nu", "F_s", "T_l", "tau") if k in given]
    if not pair:
        return
    table = {k: v for k, v in merged["operating"].items()
             if k not in ("nu", "F_s", "T_l", "tau")}
    if len(pair) == 1:
        table.update({k: v for k, v in base.items() if k in ("nu", "F_s", "T_l", "tau")})
        if pair[0] in ("nu", "tau"):
            table.pop("tau" if pair[0] == "nu" else "nu", None)
    table.update({k: given[k] for k in pair})
    merged["operating"] = table


def _schema() -> dict[str, Any]:
    """Nested dict of the allowed keys (values None) of a parameter file."""
    names = lambda kind: {f.name: None for f in fields(kind)}  # noqa: E731
    schema: dict[str, Any] = {name: names(kind) for name, kind in _SECTIONS.items()}
    schema["traction"]["table"] = None  # a file of measured curves (`Params.traction_table`)
    schema["losses"]["table"] = None  # a measured loss map (`Params.loss_map`)
    schema["damping"] = {"omega_pulley": None,
                         **{lvl: names(DampingLevel) for lvl in DAMPING_LEVELS}}
    return schema


def _merge(into: dict[str, Any], data: Mapping[str, Any], where: str,
           schema: Mapping[str, Any], path: str = "") -> None:
    """Recursively merge `data` into `into`, refusing keys and tables not in `schema`."""
    for key, value in data.items():
        name = f"{path}.{key}" if path else key
        if key not in schema:
            raise ParameterError(f"{where}: unknown key {name!r} (allowed here: "
                                 f"{', '.join(schema)})")
        if isinstance(schema[key], Mapping):
            if not isinstance(value, Mapping):
                raise ParameterError(f"{where}: {name!r} must be a table, not {value!r}")
            _merge(into.setdefault(key, {}), value, where, schema[key], name)
        elif isinstance(value, Mapping):
            raise ParameterError(f"{where}: {name!r} must be a value, not a table")
        else:
            into[key] = value


def read_toml(path: str | os.PathLike[str], what: str = "parameter") -> dict[str, Any]:
    """Parse a TOML file; a missing file or bad syntax is a one-line `ParameterError`.

    Parameters
    ----------
    path : str or path-like
        The TOML file to read.
    what : str
        What the file is, for the error messages (``"no such parameter file"``).

    Returns
    -------
    dict
        The parsed tables and values (nested dicts, as `tomllib.load` returns them).

    Raises
    ------
    ParameterError
        When the file is missing, a folder, a FIFO or device, too large, not UTF-8, not valid
        TOML, nested too deep or unreadable (`empact._io.parse_toml`).
    """
    return parse_toml(path, what)


_DEFAULT: Params | None = None


def default_params() -> Params:
    """The shipped parameter set (``empact/data/default.toml``), calibrated to the paper.

    Returns
    -------
    Params
        The shipped set (cached: every call returns the same frozen object).
    """
    global _DEFAULT
    if _DEFAULT is None:
        text = resources.files("empact.data").joinpath("default.toml").read_text()
        _DEFAULT = Params.from_dict(tomllib.loads(text), source="default.toml")
    return _DEFAULT


@dataclass(frozen=True)
class ParameterInfo:
    """What `describe_parameters` says of one parameter.

    Attributes
    ----------
    name : dotted name (``"traction.B_med"``)
    unit : SI unit
    allowed : the interval a value must lie in (validation)
    doc : what it is
    value : the shipped value
    band : ``(lo, hi)``, the plausible band of the shipped value (a value outside it is
        allowed but not physically credible for a pushbelt CVT and its test bench)
    source : where the shipped value comes from, or the stated rationale for it
    """

    name: str
    unit: str
    allowed: str
    doc: str
    value: float | None
    band: tuple[float, float]
    source: str


def parameter_sources() -> dict[str, dict[str, Any]]:
    """Source and plausible band of every shipped parameter (``data/parameter_sources.toml``):
    dotted name -> ``{"source": str, "band": [lo, hi]}``.

    Returns
    -------
    dict
        Dotted parameter name (``"traction.B_med"``) -> ``{"source": str, "band": [lo,
        hi]}``, the band in the parameter's SI unit.
    """
    text = resources.files("empact.data").joinpath("parameter_sources.toml").read_text()
    return dict(tomllib.loads(text))


def describe_parameters(params: Params | None = None) -> list[ParameterInfo]:
    """Every parameter of a set (default: the shipped one) with its unit, allowed interval,
    meaning, value, plausible band and source, in file order.

    Parameters
    ----------
    params : Params, optional
        The parameter set whose values are shown (default: `default_params`).

    Returns
    -------
    list of ParameterInfo
        One entry per parameter, in the order of the parameter file's tables; the band is
        ``(nan, nan)`` and the source empty for a parameter without an entry in
        `parameter_sources`.
    """
    params = default_params() if params is None else params
    sources = parameter_sources()
    out = []
    blocks: list[tuple[str, Any]] = []
    for name in ("variator", "actuation", "damping", "driveline", "traction", "shift",
                 "thrust_ratio", "paper_sec21", "servo", "sensors", "hydraulic", "losses",
                 "operating", "vehicle", "engine"):
        block = getattr(params, name)
        if name == "damping":
            blocks += [(f"damping.{lvl}", getattr(block, lvl)) for lvl in DAMPING_LEVELS]
            blocks.append(("damping", block))
        else:
            blocks.append((name, block))
    for prefix, block in blocks:
        if isinstance(block, DampingParams):
            rows = [("omega_pulley", "rad/s", "(0, 2000]", "pulley speed of Shafai's model "
                     "in the linear actuation model (Fig. 6)")]
        else:
            rows = type(block).describe()
        for key, unit, allowed, doc in rows:
            dotted = f"{prefix}.{key}"
            info = sources.get(dotted, {})
            lo, hi = (float(v) for v in info.get("band", (float("nan"), float("nan"))))
            band = (lo, hi)
            out.append(ParameterInfo(dotted, unit, allowed, doc, getattr(block, key),
                                     band, str(info.get("source", ""))))
    return out


def load_params(path: str | os.PathLike[str] | None = None) -> Params:
    """Load a TOML parameter file over the shipped defaults.

    Parameters
    ----------
    path : str or path-like, optional
        A TOML parameter file with any subset of the shipped keys (``[section] key = value``,
        SI units); the other keys keep their shipped values. `None`: the shipped set.
        ``[traction] table = "curves.csv"`` names measured traction curves (a path relative
        to this file; `Params.traction_table`), ``[losses] table = "map.csv"`` a measured
        loss map (`Params.loss_map`).

    Returns
    -------
    Params
        The frozen, validated parameter set.

    Raises
    ------
    ParameterError
        One line naming the file, the bad field, its value and the allowed range.

    Examples
    --------
    >>> import empact
    >>> params = empact.load_params()
    >>> params.operating.r_g, params.operating.F_s, params.operating.tau   # [-], [N], [-]
    (1.0, 10000.0, 0.9)
    """
    if path is None:
        return default_params()
    data = read_toml(path)
    for name in ("traction", "losses"):
        section = data.get(name)
        if isinstance(section, dict) and isinstance(section.get("table"), str):
            section["table"] = os.path.abspath(os.path.join(os.path.dirname(path),
                                                            section["table"]))
    return Params.from_dict(data, base=default_params(), source=str(path))


def dumps_params(params: Params, header: str = "") -> str:
    """TOML text of a parameter set, with an optional comment header.

    Parameters
    ----------
    params : Params
        The parameter set (every key, SI units; only the given operating-point variables).
    header : str
        Comment lines put at the top of the text (each prefixed with ``#``).

    Returns
    -------
    str
        The TOML text, as `save_params` writes it and `load_params` reads it back.
    """
    lines = "".join(f"# {line}\n" for line in header.splitlines())
    return lines + tomli_w.dumps(params.to_dict())


def save_params(params: Params, path: str | os.PathLike[str], header: str = "") -> None:
    """Write a parameter set to TOML atomically (temporary file, then rename).

    Parameters
    ----------
    params : Params
        The parameter set to write (every key, SI units).
    path : str or path-like
        The TOML file written.
    header : str
        Comment lines written at the top of the file (without ``#``).
    """
    atomic_write_text(path, dumps_params(params, header))

"""Frozen, validated model parameters, loaded from and saved to TOML.

A parameter set has one section per concept::

    [variator]          belt and pulley geometry (eqs. 4-6 of the paper)
    [actuation]         inertias, ratios and stiffnesses of the actuation (Fig. 3)
    [damping.none]      damping levels of the actuation model (Fig. 6)
    [damping.moderate]
    [damping.large]
    [driveline]         inertias and stiffnesses of the test-bench driveline (Fig. 7)
    [traction]          traction curve mu(nu, r_g) (Fig. 10)
    [shift]             creep-mode shifting of the belt (Carbone et al. 2007; Ide et al.)
    [thrust_ratio]      torque-dependent equilibrium thrust ratio kappa(tau, r_g)
    [paper_sec21]       stiffnesses of the paper's Sec. 2.1 kinematics (the published variant)
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

import math
import os
import tomllib
from dataclasses import asdict, dataclass, field, fields, replace
from importlib import resources
from typing import Any, Mapping

import tomli_w

from ._io import atomic_write_text
from ._validate import check_choice, check_number, interval
from .errors import ParameterError
from .geometry import ratio_range

__all__ = [
    "ParameterError", "VariatorParams", "ActuationParams", "DampingLevel", "DampingParams",
    "DrivelineParams", "TractionParams", "ShiftParams", "ThrustRatioParams", "Sec21Stiffness",
    "OperatingPoint", "Params", "default_params",
    "load_params", "save_params", "dumps_params", "read_toml", "DAMPING_LEVELS",
    "OPERATING_VARIABLES",
]

DAMPING_LEVELS = ("none", "moderate", "large")


def _p(unit: str, doc: str, lo: float = 0.0, hi: float = math.inf, *, lo_open: bool = True,
       hi_open: bool = False, note: str = "") -> Any:
    """Field spec: a float with unit, description and an allowed interval."""
    return field(metadata=dict(unit=unit, doc=doc, lo=lo, hi=hi, lo_open=lo_open,
                               hi_open=hi_open, note=note))


def _interval(meta: Mapping[str, Any]) -> str:
    return interval(meta["lo"], meta["hi"], lo_open=meta["lo_open"], hi_open=meta["hi_open"])


class _Section:
    """Mixin: range-checks every float field after construction (`empact._validate`)."""

    _name = "section"

    def __post_init__(self) -> None:
        for f in fields(self):  # type: ignore[arg-type]
            meta = f.metadata
            if "unit" not in meta:
                continue
            value = check_number(f"{self._name}.{f.name}", getattr(self, f.name), meta["lo"],
                                 meta["hi"], lo_open=meta["lo_open"], hi_open=meta["hi_open"],
                                 unit=meta["unit"], note=meta["note"])
            object.__setattr__(self, f.name, value)

    @classmethod
    def describe(cls) -> list[tuple[str, str, str, str]]:
        """(name, unit, allowed interval, description) for every field."""
        return [(f.name, f.metadata["unit"], _interval(f.metadata), f.metadata["doc"])
                for f in fields(cls) if "unit" in f.metadata]  # type: ignore[arg-type]


@dataclass(frozen=True)
class VariatorParams(_Section):
    """Pushbelt variator geometry (paper eqs. 4-6)."""

    _name = "variator"
    a: float = _p("m", "centre distance between the pulley shafts", 0.02, 1.0)
    beta: float = _p("rad", "pulley wedge angle (half the V angle; pushbelts: about 11 deg)",
                     math.radians(1), math.radians(30), lo_open=False)
    L_belt: float = _p("m", "belt length (running circumference)", 0.1, 5.0)
    R_min: float = _p("m", "smallest running radius; also R0, the radius at zero sheave "
                           "translation", 0.002, 0.5)
    R_max: float = _p("m", "largest running radius", 0.002, 0.5)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.R_max <= self.R_min:
            raise ParameterError(
                f"variator.R_max = {self.R_max!r}: must exceed variator.R_min = {self.R_min!r} [m]")
        # The belt must fit: at r_g = 1 both radii are (L - 2a) / (2 pi).
        R_med = (self.L_belt - 2 * self.a) / (2 * math.pi)
        if not self.R_min < R_med < self.R_max:
            raise ParameterError(
                f"variator.L_belt = {self.L_belt!r}: gives the medium-ratio radius {R_med:.4g} m, "
                f"which must lie in (R_min, R_max) = ({self.R_min:g}, {self.R_max:g}) m")


@dataclass(frozen=True)
class ActuationParams(_Section):
    """Linear actuation model (paper Sec. 2.1, Fig. 3)."""

    _name = "actuation"
    J_mp: float = _p("kg m^2", "primary servo inertia (rotor and worm), coordinate q1", 1e-8, 1.0)
    J_ms: float = _p("kg m^2", "secondary servo inertia (rotor and chain sprocket), "
                     "coordinate q2", 1e-8, 1.0)
    J_sp: float = _p("kg m^2", "primary sun gear with screw, ring/carrier/planets lumped, q3",
                     1e-7, 10.0)
    J_ss: float = _p("kg m^2", "secondary sun gear with screw input, q4", 1e-7, 10.0)
    m_p: float = _p("kg", "primary moving sheave with screw output, q5", 0.01, 100.0)
    m_s: float = _p("kg", "secondary moving sheave with screw output, q6", 0.01, 100.0)
    i_w: float = _p("-", "worm ratio (servo turns per ring turn)", 0.1, 1000.0)
    i_c: float = _p("-", "chain ratio (servo turns per ring turn)", 0.01, 100.0)
    i_e: float = _p("-", "ring to sun ratio of the epicyclic sets (the paper: 2)", 1.0, 10.0)
    s: float = _p("m/rad", "screw pitch (translation per radian)", 1e-7, 1e-2)
    k_w: float = _p("N m/rad", "worm stiffness (spring 1)", 1e-3, 1e8)
    k_c: float = _p("N m/rad", "chain stiffness (spring 2)", 1e-3, 1e8)
    k_belt: float = _p("N/m", "longitudinal pushbelt stiffness (spring 3)", 1e2, 1e11)
    k_tp: float = _p("N/m", "primary thrust bearing stiffness (spring 4)", 1e4, 1e12)
    k_ts: float = _p("N/m", "secondary thrust bearing stiffness (spring 5)", 1e4, 1e12)


@dataclass(frozen=True)
class DampingLevel(_Section):
    """One damping level of the actuation model (Fig. 6)."""

    _name = "damping"
    alpha: float = _p("s", "proportional spring damping, C_spring = alpha K", 0.0, 0.1,
                      lo_open=False)
    c_mp: float = _p("N m s/rad", "viscous friction of the primary servo", 0.0, 100.0,
                     lo_open=False)
    c_ms: float = _p("N m s/rad", "viscous friction of the secondary servo", 0.0, 100.0,
                     lo_open=False)
    c_sp: float = _p("N m s/rad", "viscous friction of the primary screw", 0.0, 1e4,
                     lo_open=False)
    c_ss: float = _p("N m s/rad", "viscous friction of the secondary screw", 0.0, 1e4,
                     lo_open=False)
    c_shafai: float = _p("N/m", "Shafai pulley damping: c_pulley = c_shafai / |omega| [N s/m]",
                         0.0, 1e10, lo_open=False)


@dataclass(frozen=True)
class DampingParams:
    """The three damping levels of Fig. 6 and the pulley speed for Shafai's model."""

    none: DampingLevel
    moderate: DampingLevel
    large: DampingLevel
    omega_pulley: float = 300.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "omega_pulley",
                           check_number("damping.omega_pulley", self.omega_pulley, 0.0, 2000.0,
                                        lo_open=True, unit="rad/s"))

    def level(self, name: str) -> DampingLevel:
        """The damping level called `name` (one of ``DAMPING_LEVELS``)."""
        return getattr(self, check_choice("damping", name, DAMPING_LEVELS))


@dataclass(frozen=True)
class DrivelineParams(_Section):
    """Test-bench driveline (paper Sec. 2.2, Fig. 7)."""

    _name = "driveline"
    J_d: float = _p("kg m^2", "drive motor inertia, q1", 1e-6, 1e3)
    J_p: float = _p("kg m^2", "primary pulley with torque converter, q2", 1e-6, 1e2)
    J_s: float = _p("kg m^2", "secondary pulley, q3", 1e-6, 1e2)
    J_l: float = _p("kg m^2", "load motor inertia, q4", 1e-6, 1e3)
    k_tc: float = _p("N m/rad", "torque converter lock-up clutch stiffness", 1e-2, 1e8)
    k_belt: float = _p("N/m", "pushbelt stiffness as a chain element (elongation R_p q2 - R_s "
                              "q3)", 1e2, 1e11)
    k_ds: float = _p("N m/rad", "driveshaft stiffness", 1e-2, 1e8)


@dataclass(frozen=True)
class TractionParams(_Section):
    """Analytic traction curve mu(nu, r_g) (Fig. 10), a Pacejka-type magic formula.

    ``mu = D sin(C arctan(B nu - E (B nu - arctan(B nu))))``; B, C, D, E are given at the
    LOW, MED and OD ratios and interpolated linearly in log(r_g) in between (held
    constant outside).
    """

    _name = "traction"
    r_low: float = _p("-", "LOW ratio where the *_low coefficients hold", 0.05, 20.0)
    r_med: float = _p("-", "MED ratio where the *_med coefficients hold", 0.05, 20.0)
    r_od: float = _p("-", "OD ratio where the *_od coefficients hold", 0.05, 20.0)
    B_low: float = _p("-", "stiffness factor at LOW", 1.0, 1e6)
    B_med: float = _p("-", "stiffness factor at MED", 1.0, 1e6)
    B_od: float = _p("-", "stiffness factor at OD", 1.0, 1e6)
    C_low: float = _p("-", "shape factor at LOW", 1.0, 2.0, lo_open=False)
    C_med: float = _p("-", "shape factor at MED", 1.0, 2.0, lo_open=False)
    C_od: float = _p("-", "shape factor at OD", 1.0, 2.0, lo_open=False)
    D_low: float = _p("-", "peak traction coefficient at LOW", 0.0, 1.0)
    D_med: float = _p("-", "peak traction coefficient at MED", 0.0, 1.0)
    D_od: float = _p("-", "peak traction coefficient at OD", 0.0, 1.0)
    E_low: float = _p("-", "curvature factor at LOW", -10.0, 1.0, lo_open=False)
    E_med: float = _p("-", "curvature factor at MED", -10.0, 1.0, lo_open=False)
    E_od: float = _p("-", "curvature factor at OD", -10.0, 1.0, lo_open=False)

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.r_low < self.r_med < self.r_od:
            raise ParameterError(
                f"traction.r_med = {self.r_med!r}: must lie strictly between r_low = "
                f"{self.r_low!r} and r_od = {self.r_od!r}")


@dataclass(frozen=True)
class ShiftParams(_Section):
    """Creep-mode shifting of the pushbelt: the belt's resistance to a ratio change.

    Carbone, Mangialardi, Bonsen, Tursi, Veenhuizen, "CVT dynamics: theory and experiments",
    Mechanism and Machine Theory 42 (2007) 409-428: in creep mode the ratio rate is
    proportional to the primary speed and linear in the log of the ratio of the actual to the
    equilibrium thrust ratio::

        dr_g/dt = |omega_p| K_c [ln(F_p / F_s) - ln kappa*(tau, r_g)]
        K_c = gain D(F_s) (1 + cos^2 beta) / sin(2 beta) r_g (R_p / a) (a1 + a2 ln^2 r_g)
        D(F_s) = D_ref (1 + k_D (F_s - F_ref))

    D is the amplitude of the pulley deformation that lets the belt creep radially (rigid
    pulleys: no creep).  The coefficients are a third party's reconstruction of the paper's
    fits (eng-tools.dev, "How does a CVT actually change ratio?", its Eqs. 23 and 49 and the
    calculator's a1, a2 fitted to the paper's Fig. 13); the paper's own tables could not be
    read, so the magnitude is uncertain by about a factor 10 (hence `gain`).  The test rig of
    the paper covered r_g = 0.6-1.8, F_s = 20-30 kN, 1000-2000 rpm.
    """

    _name = "shift"
    D_ref: float = _p("rad", "pulley deformation amplitude at F_ref (Carbone 2007, "
                             "reconstructed: 1e-3)", 0.0, 5e-3)
    F_ref: float = _p("N", "clamping force of D_ref (Carbone 2007: 20 kN)", 1e3, 1e6)
    k_D: float = _p("1/N", "growth of D with the clamping force (Carbone 2007, "
                           "reconstructed: 2e-5, i.e. 2 % per kN)", 0.0, 1e-4, lo_open=False)
    a1: float = _p("-", "ratio dependence g(r) = r q (a1 + a2 ln^2 r), constant term "
                        "(reconstructed fit: 0.21)", 0.0, 5.0)
    a2: float = _p("-", "ratio dependence, quadratic term (reconstructed fit: 0.08)", 0.0, 5.0,
                   lo_open=False)
    gain: float = _p("-", "overall factor on the creep rate: 1 is the published magnitude; "
                          "the reconstruction is uncertain by about 10x", 0.1, 50.0,
                     lo_open=False)
    omega_0: float = _p("rad/s", "speed below which creep fades (regularisation at "
                                 "standstill: no shifting without rotation)", 0.01, 10.0)
    xi_sat: float = _p("-", "saturation of the log thrust-ratio error (slip mode beyond "
                            "it; no published threshold)", 0.3, 3.0, lo_open=False)


@dataclass(frozen=True)
class ThrustRatioParams(_Section):
    """Torque-dependent equilibrium thrust ratio ``kappa* = F_p* / F_s`` (analytic default).

    ``ln kappa*(tau, r_g) = p0 ln kappa_geo(r_g) + (b0 - b1 ln r_g) tau`` with the torque ratio
    ``tau = T_b cos(beta) / (2 mu_max F_s R_s)`` (1 at the traction limit) and the geometric
    thrust ratio of the elastic belt ``kappa_geo = (pi + 2 phi) / (pi - 2 phi)`` (virtual
    work; Carbone's frictionless limit): with ``p0 = 1`` it agrees exactly at zero torque.
    Shaped like published pushbelt curves (rising with torque, faster at LOW, flat or falling
    at OD); the values are estimates, no measured map could be read: a tabulated map (CSV or
    TOML, `empact.thrust_ratio.load_thrust_ratio`) replaces it.
    """

    _name = "thrust_ratio"
    p0: float = _p("-", "steepness of the zero-torque curve relative to kappa_geo", 0.5, 2.0,
                   lo_open=False)
    b0: float = _p("-", "d ln kappa* / d tau at r_g = 1", 0.0, 1.5, lo_open=False)
    b1: float = _p("-", "how much faster ln kappa* rises with tau at LOW than at OD", -1.0, 2.0)


@dataclass(frozen=True)
class Sec21Stiffness(_Section):
    """Stiffnesses of the actuation model with the paper's Sec. 2.1 kinematics as published
    (kinematics ``"paper-sec2.1"``), calibrated to Table 1 on its own: the overlay that
    `empact.linear.actuation.actuation_model` and the nonlinear model use for that variant."""

    _name = "paper_sec21"
    k_w: float = _p("N m/rad", "worm stiffness (spring 1)", 1e-3, 1e8)
    k_c: float = _p("N m/rad", "chain stiffness (spring 2)", 1e-3, 1e8)
    k_belt: float = _p("N/m", "longitudinal pushbelt stiffness (spring 3)", 1e2, 1e11)
    k_tp: float = _p("N/m", "primary thrust bearing stiffness (spring 4)", 1e4, 1e12)
    k_ts: float = _p("N/m", "secondary thrust bearing stiffness (spring 5)", 1e4, 1e12)


#: Operating-point variables: unit and description (names as in the paper).
OPERATING_VARIABLES = {"r_g": ("-", "geometric ratio R_p / R_s"),
                       "nu": ("-", "slip (fraction, 0.01 is 1 %)"),
                       "F_s": ("N", "secondary clamping force"),
                       "omega_p": ("rad/s", "primary pulley speed")}


@dataclass(frozen=True)
class OperatingPoint(_Section):
    """An operating point of the variator (names as in the paper), validated on construction.

    The one operating-point type of empact: the ``[operating]`` table of a parameter file, the
    point of the slip model and the trim request of the nonlinear model.

    Attributes
    ----------
    r_g : geometric ratio ``R_p / R_s`` [-], > 0 (checked against the variator where used)
    nu : slip [-] (a fraction: 0.01 is 1 %), in (-1, 1)
    F_s : secondary clamping force [N], >= 0
    omega_p : primary pulley speed [rad/s], > 0 (eq. 2 is undefined at standstill)
    """

    _name = "operating"
    r_g: float = _p("-", OPERATING_VARIABLES["r_g"][1])
    nu: float = _p("-", OPERATING_VARIABLES["nu"][1], -1.0, 1.0, hi_open=True)
    F_s: float = _p("N", OPERATING_VARIABLES["F_s"][1], lo_open=False)
    omega_p: float = _p("rad/s", OPERATING_VARIABLES["omega_p"][1],
                        note="the slip nu = 1 - omega_s / (r_g omega_p) of eq. 2 is undefined "
                             "at standstill")

    @property
    def omega_s(self) -> float:
        """Secondary speed ``r_g (1 - nu) omega_p`` [rad/s] (eq. 2 solved for omega_s)."""
        return self.r_g * (1 - self.nu) * self.omega_p

    @classmethod
    def from_params(cls, params: "Params", **changes: float) -> "OperatingPoint":
        """The ``[operating]`` point of a parameter set, with keyword `changes`."""
        return params.operating.replace(**changes)

    def replace(self, **changes: float) -> "OperatingPoint":
        """A copy with some variables changed (validated)."""
        unknown = set(changes) - set(OPERATING_VARIABLES)
        if unknown:
            raise ParameterError(f"unknown operating-point variable {sorted(unknown)[0]!r}: "
                                 f"choose from {', '.join(OPERATING_VARIABLES)}")
        return replace(self, **changes)

    def as_dict(self) -> dict[str, float]:
        """``{"r_g": ..., "nu": ..., "F_s": ..., "omega_p": ...}`` (SI)."""
        return dict(r_g=self.r_g, nu=self.nu, F_s=self.F_s, omega_p=self.omega_p)


_SECTIONS = {
    "variator": VariatorParams, "actuation": ActuationParams, "driveline": DrivelineParams,
    "traction": TractionParams, "shift": ShiftParams, "thrust_ratio": ThrustRatioParams,
    "paper_sec21": Sec21Stiffness, "operating": OperatingPoint,
}


@dataclass(frozen=True)
class Params:
    """A complete, validated parameter set.  Immutable: `from_dotted` returns a changed copy."""

    variator: VariatorParams
    actuation: ActuationParams
    damping: DampingParams
    driveline: DrivelineParams
    traction: TractionParams
    shift: ShiftParams
    thrust_ratio: ThrustRatioParams
    paper_sec21: Sec21Stiffness
    operating: OperatingPoint

    def __post_init__(self) -> None:
        if self.shift.k_D * self.shift.F_ref >= 0.9:
            raise ParameterError(
                f"shift.k_D = {self.shift.k_D:g}: with F_ref = {self.shift.F_ref:g} N the "
                f"deformation D would vanish at low clamping force; need k_D F_ref < 0.9")
        lo, hi = ratio_range(self.variator)
        if not lo <= self.operating.r_g <= hi:
            raise ParameterError(
                f"operating.r_g = {self.operating.r_g!r}: outside the geometric ratio range "
                f"[{lo:.4g}, {hi:.4g}] of this variator")

    # -- conversion -----------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Nested plain dictionary, as written to TOML."""
        return asdict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], base: "Params | None" = None,
                  source: str = "parameters") -> "Params":
        """Build from a nested mapping; keys not given are taken from `base`.

        Raises
        ------
        ParameterError
            For an unknown section or key, a wrong type or a value out of range.
        """
        merged = base.to_dict() if base is not None else {}
        _merge(merged, data, source, _schema())
        try:
            damping = merged["damping"]
            levels = {name: DampingLevel(**damping[name]) for name in DAMPING_LEVELS}
            sections = {name: kind(**merged[name]) for name, kind in _SECTIONS.items()}
            return cls(damping=DampingParams(**levels, omega_pulley=damping["omega_pulley"]),
                       **sections)
        except KeyError as exc:
            raise ParameterError(f"{source}: missing section or key {exc.args[0]!r}") from None
        except TypeError as exc:  # missing fields of a section
            raise ParameterError(f"{source}: {exc}") from None
        except ParameterError as exc:  # name the file in every message
            raise ParameterError(f"{source}: {exc}") from None

    def from_dotted(self, values: Mapping[str, float]) -> "Params":
        """A copy with values changed by dotted name, e.g. ``{"damping.large.alpha": 1e-3}``."""
        nested: dict[str, Any] = {}
        for name, value in values.items():
            node = nested
            *path, last = name.split(".")
            for part in path:
                node = node.setdefault(part, {})
            node[last] = value
        return Params.from_dict(nested, base=self)

    def get(self, dotted: str) -> float:
        """The value of a dotted name such as ``"actuation.k_w"``."""
        node: Any = self
        for part in dotted.split("."):
            if not hasattr(node, part) or part.startswith("_"):
                raise ParameterError(f"unknown parameter {dotted!r}")
            node = getattr(node, part)
        if not isinstance(node, float):
            raise ParameterError(f"parameter {dotted!r} is a section, not a value")
        return node

    def unit(self, dotted: str) -> str:
        """The unit of a dotted parameter name, e.g. ``"N m/rad"`` for ``"actuation.k_w"``."""
        self.get(dotted)
        *path, last = dotted.split(".")
        node: Any = self
        for part in path:
            node = getattr(node, part)
        meta = {f.name: f.metadata for f in fields(node)}[last]
        return str(meta.get("unit", ""))


def _schema() -> dict[str, Any]:
    """Nested dict of the allowed keys (values None) of a parameter file."""
    names = lambda kind: {f.name: None for f in fields(kind)}  # noqa: E731
    schema: dict[str, Any] = {name: names(kind) for name, kind in _SECTIONS.items()}
    schema["damping"] = {"omega_pulley": None, **{lvl: names(DampingLevel) for lvl in DAMPING_LEVELS}}
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
    """Parse a TOML file; a missing file or bad syntax is a one-line `ParameterError`."""
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ParameterError(f"{path}: no such {what} file") from None
    except IsADirectoryError:
        raise ParameterError(f"{path}: is a folder, not a {what} file") from None
    except UnicodeDecodeError:
        raise ParameterError(f"{path}: not a text file (TOML must be UTF-8)") from None
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"{path}: not valid TOML ({exc})") from None
    except OSError as exc:
        raise ParameterError(f"{path}: cannot be read ({exc.strerror})") from None


_DEFAULT: Params | None = None


def default_params() -> Params:
    """The shipped parameter set (``empact/data/default.toml``), calibrated to the paper."""
    global _DEFAULT
    if _DEFAULT is None:
        text = resources.files("empact.data").joinpath("default.toml").read_text()
        _DEFAULT = Params.from_dict(tomllib.loads(text), source="default.toml")
    return _DEFAULT


def load_params(path: str | os.PathLike[str] | None = None) -> Params:
    """Load a TOML parameter file over the shipped defaults (`None`: the defaults)."""
    if path is None:
        return default_params()
    return Params.from_dict(read_toml(path), base=default_params(), source=str(path))


def dumps_params(params: Params, header: str = "") -> str:
    """TOML text of a parameter set, with an optional comment header."""
    lines = "".join(f"# {line}\n" for line in header.splitlines())
    return lines + tomli_w.dumps(params.to_dict())


def save_params(params: Params, path: str | os.PathLike[str], header: str = "") -> None:
    """Write a parameter set to TOML atomically (temporary file, then rename)."""
    atomic_write_text(path, dumps_params(params, header))

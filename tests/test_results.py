"""The result contract (issue 31 item 5): every public result class has ``to_dict`` (plain
JSON types, SI, complex as [re, im], NaN as None) and, where it is a table, ``to_pandas``
with pandas optional.  Each class is built cheaply from small made-up arrays (the contract
is about the form, not the numbers), and a census of the public dataclasses makes a new
result class without ``to_dict`` (or without a builder here) fail."""
from __future__ import annotations

import dataclasses
import importlib
import json
import pkgutil
import sys
import warnings

import numpy as np
import pytest

import empact
from empact._results import TableResult
from empact._section import Section
from empact.actuation_energy import ActuationEnergy, Transmissions
from empact.control.closed_loop import ClosedLoopResult, TargetCheck, resolve_controller
from empact.control.family import FamilyRoots, PlantFamily
from empact.control.loop import DiskMarginMap, LoopModel, LoopPrediction, LoopShapes
from empact.control.robustness import RobustnessMap
from empact.control.shifting import ShiftEnvelope
from empact.control.tune import TuneResult
from empact.cycles import Cycle
from empact.drive_cycle import CycleResult, quasi_static_cycle
from empact.dynamic_cycle import DynamicCycleResult, DynamicRun
from empact.efficiency import EfficiencyMap
from empact.experiments.plant_id import PlantIdentification, StepExperiment
from empact.experiments.rig import RigRecord, RigSettings
from empact.identification.frf_estimation import FRFEstimate
from empact.identification.realization import RealizationResult
from empact.linear.calibration import CalibrationResult, Target
from empact.linear.lumped import Modes
from empact.lti import FrequencyResponse, RootLocus
from empact.montecarlo.cycle import CycleStudy
from empact.montecarlo.spread import Distribution, Spread
from empact.montecarlo.study import MonteCarloResult
from empact.nonlinear.equilibrium import TrimGrid, TrimResult
from empact.nonlinear.linearization import Plant
from empact.nonlinear.nmp import BeltLengthChange, NmpResult
from empact.nonlinear.scenario import example_path, load_scenario
from empact.nonlinear.simulation import SimulationResult
from empact.params import OperatingPoint, default_params
from empact.slip.coupling import BeltLinearisation
from empact.slip.loci import BeltRootLocus, PoleSweep, ZeroLocus
from empact.slip.stability import StabilityMap
from empact.variator.geometry import VariatorState
from empact.variator.thrust_ratio import RatioStabilityMap

RNG = np.random.default_rng(31)


def _r(*shape):
    return RNG.standard_normal(shape)


def _c(*shape):
    return _r(*shape) + 1j * _r(*shape)


OP = OperatingPoint(r_g=1.0, nu=0.01, F_s=1e4, omega_p=300.0)


def _trim():
    return TrimResult(None, _r(6), _r(4), 1.0, 0.01, 1e4, 1.2e4, 300.0, 290.0, 50.0, 5.0,
                      50.0, 0.3, 2.0, 0.08, 1e-12, tau=0.9, request=OP)


def _sim():
    t = np.linspace(0, 1, 5)
    y = _r(5, 2)
    y[2, 1] = np.nan  # a run's NaN is written as None
    return SimulationResult(t, _r(5, 3), y, _r(5, 2), ("a", "b", "c"), ("nu", "r_g"),
                            ("T_mp", "T_ms"), True, "completed", "s", {"steps": 4})


def _controller():
    return resolve_controller("shipped:pi")


def _family():
    ok = np.array([True, False])
    return PlantFamily({"r_g": np.array([0.5, 2.0])}, {"F_s": 1e4}, _r(2, 3, 3), _r(2, 3, 2),
                       _r(2, 1, 3), np.zeros((2, 1, 2)), ("theta_mp", "theta_ms", "theta_sp"),
                       ("T_mp", "T_ms"),
                       ("r_g",), {"r_g": np.array([0.5, 2.0])}, ok,
                       np.array(["", "did not trim"], dtype=object))


def _rig():
    return RigRecord(np.linspace(0, 1, 4), {"T_mp": _r(4), "nu": _r(4)}, RigSettings(),
                     _trim(), True, "completed")


def _realization():
    return RealizationResult(_r(2, 2), _r(2, 1), _r(1, 2), _r(1, 1), _r(2, 2), _r(2, 1), 1e-3,
                             ("T_mp",), ("r_g",), np.abs(_r(4)), 2, np.abs(_r(1)),
                             _r(10, 1, 1))


#: class -> builder of a small instance, and the fields (or keys) whose arrays round-trip
def _efficiency_map():
    n = 2
    f = {k: _r(n) for k in ("T_in", "omega_in", "r_g", "F_s", "F_p", "tau", "nu", "T_mp",
                            "T_ms", "P_in", "P_out", "efficiency", "total_efficiency")}
    names = [f"{t}_{s}" for s in ("mp", "ms") for t in ("mechanical", "gear", "copper",
                                                         "drive")]
    return EfficiencyMap(strategy=("slip", "slip"), losses={"P_loss_slip": _r(n)},
                         actuation={k: _r(n) for k in names}, ok=np.array([True, False]),
                         reason=("", "no trim"), strategies=("slip",),
                         axes={"T_in": np.array([50.0]), "omega_in": np.array([300.0]),
                               "r_g": np.array([0.5, 1.0])}, **f)


def _cycle():
    return Cycle("t", np.array([0.0, 1.0, 2.0, 3.0]), np.array([0.0, 2.0, 3.0, 0.0]),
                 ("a", "a", "b", "b"))


def _tune_result():
    summary = {"disk_margin": 0.6, "gain_margin_db": 5.0, "phase_margin_deg": 30.0,
               "ms": {"ratio": 1.8, "slip": 1.7}, "ms_above_2": {"ratio": 0, "slip": 0},
               "bandwidth_hz": {"ratio": 0.5, "slip": 1.0}, "spectral_radius": 0.99,
               "all_stable": True, "worst_point": {"r_g": 2.0, "tau": 0.8, "F_s": 8e3}}
    return TuneResult("disk-margin", ("kp_ratio",), {"kp_ratio": 1.5}, _r(4), summary,
                      summary, {"ratio": 0.4, "slip": 0.9}, 2.0, 0.6, 4, 1.0, 0, True, "ok")


def _dynamic_cycle():
    from empact.dynamic_cycle import dynamic_cycle
    trace = Cycle("d", np.arange(3.0), np.array([5.0, 5.5, 6.0]), ("a", "a", "b"))
    return dynamic_cycle(default_params(), trace, strategies=("hydraulic-sf1.3", "slip"))


def _cycle_study():
    from empact.montecarlo.cycle import CycleStudy
    return CycleStudy("c", False, ("vehicle.mass",), _r(2, 1), ("slip",),
                      {"slip": _r(2)}, {"slip": _r(2)}, {"slip": np.array([False, True])}, 0)


BUILDERS = {
    TuneResult: (_tune_result, ("history",)),
    DynamicCycleResult: (_dynamic_cycle, ("stretches",)),
    DynamicRun: (lambda: _dynamic_cycle().runs["slip"], ("t", "signals")),
    CycleStudy: (_cycle_study, ("values", "fuel_g")),
    Cycle: (_cycle, ("t", "v")),
    CycleResult: (lambda: quasi_static_cycle(default_params(), _cycle(),
                                             strategies=("hydraulic-sf1.3", "slip")), ()),
    SimulationResult: (_sim, ("t", "x", "y", "u")),
    EfficiencyMap: (_efficiency_map, ("axes", "strategies")),
    Transmissions: (lambda: Transmissions((0.8, 0.7), (0.9, 0.8), 0.02, (0.7, 0.5),
                                          (0.8, 0.6), False, 0.05), ("worm", "primary")),
    ActuationEnergy: (lambda: ActuationEnergy(1.0, {"copper_ms": 10.0}, {"pump": 100.0},
                                              {"pump": 100.0}, {"mp": 0.1, "ms": 8.0},
                                              {"mp": 1.0, "ms": 5.0}, False),
                      ("energy", "hydraulic")),
    TrimResult: (_trim, ("r_g", "F_s", "tau")),
    ClosedLoopResult: (lambda: ClosedLoopResult(
        _sim(), {"r_g": np.ones(5), "nu": np.full(5, 0.01)}, _trim(),
        load_scenario(example_path("slip-load-step-r1")), _controller(),
        {"slip_error": 0.001, "ratio_rate": float("nan"), "macro_slip": False}),
        ("references",)),
    TargetCheck: (lambda: TargetCheck("peak_slip_error", 0.004, (-np.inf, 0.006), True), ()),
    LoopPrediction: (lambda: LoopPrediction(np.arange(3.0), {"nu": _r(3), "r_g": _r(3)}),
                     ("t", "signals")),
    LoopShapes: (lambda: LoopShapes(np.array([0.1, 1.0]), _c(3, 2, 2)), ("f_hz", "gains")),
    DiskMarginMap: (lambda: DiskMarginMap({"r_g": np.array([0.5, 1.0]), "tau": np.ones(3)},
                                          _r(2, 3), _r(2, 3), _r(2, 3)),
                    ("alpha", "input", "output")),
    LoopModel: (lambda: LoopModel(*(_r(2, 2) for _ in range(11)), controller=_controller(),
                                  mask=np.ones(2), dt=1e-3, disturbances=("T_l",),
                                  outputs=("r_g", "nu"), y0=np.zeros(2)), ("Aa", "mask")),
    FamilyRoots: (lambda: FamilyRoots(np.array([1.0, 2.0]), (_c(3), _c(1)),
                                      {"T_mp->r_g": (_c(2), _c(0)), "T_ms->nu": (_c(1), _c(1))},
                                      60.0), ("r_g",)),
    PlantFamily: (_family, ("A", "B", "C")),
    RobustnessMap: (lambda: RobustnessMap(_r(2, 3), _r(2, 3), _r(2, 3), _r(2, 3), _r(4)),
                    ("max_real_pole", "disk_margin", "omega")),
    ShiftEnvelope: (lambda: ShiftEnvelope(np.array([0.5, 1.0]), _r(2),
                                          np.array(["primary", "secondary"], dtype=object),
                                          _r(2), _r(2), 300.0, 50.0, 0.9),
                    ("r_g", "rate", "F_s", "T_mp")),
    FrequencyResponse: (lambda: FrequencyResponse(np.array([1.0, 2.0, 3.0]), _c(2, 1, 3),
                                                  ("T_mp",), ("r_g", "nu")), ("omega", "H")),
    RootLocus: (lambda: RootLocus(np.array([0.0, 1.0]), _c(2, 3)), ("parameter", "poles")),
    FRFEstimate: (lambda: FRFEstimate(np.array([0.0, 1.0, 2.0]), _c(1, 2, 3), _r(1, 2, 3),
                                      _r(1, 3), "H1", ("T_mp", "T_ms"), ("nu",), 8),
                  ("omega", "H", "coherence", "multiple_coherence")),
    RealizationResult: (_realization, ("A", "B", "singular_values", "step_model")),
    StabilityMap: (lambda: StabilityMap("nu", "r_g", np.array([0.01, 0.02]),
                                        np.array([0.5, 1.0, 2.0]), OP, _r(2, 3), _r(2, 3),
                                        1e-9), ("x", "y", "max_real", "min_damping")),
    PoleSweep: (lambda: PoleSweep("nu", np.array([0.01, 0.02]), OP, _c(2, 4), _r(2), _r(2)),
                ("values", "poles", "c_b", "dmu")),
    BeltRootLocus: (lambda: BeltRootLocus(1.0, 0.01, RootLocus(np.array([0.0, 1.0]), _c(2, 3)),
                                          _c(3), _c(3), np.abs(_r(2)), np.abs(_r(2))),
                    ("start", "stop", "uncoupled_hz")),
    ZeroLocus: (lambda: ZeroLocus(np.array([0.5, 1.0]), OP, _c(2, 3), np.array([0, 1]),
                                  _c(2, 2)), ("r_g", "zeros", "n_origin")),
    BeltLinearisation: (lambda: BeltLinearisation(OP, 0.05, 0.05, 0.08, 2.0, 10.0, 1.0, 0.01,
                                                  0.3), ("R_p", "c_b")),
    RatioStabilityMap: (lambda: RatioStabilityMap(np.array([0.5, 0.9]), np.array([1.0, 2.0]),
                                                  _r(2, 2), ((0.9, 1.0),)), ("tau", "S")),
    VariatorState: (lambda: VariatorState(*(_r(3) for _ in range(10))), ("r_g", "L")),
    TrimGrid: (lambda: TrimGrid(None, _r(2, 6), _r(2, 4), *(_r(2) for _ in range(5)),
                                np.array([True, False]), ("", "no trim")), ("x", "u", "r_g")),
    NmpResult: (lambda: NmpResult(
        np.array([0.5, 1.0]), (_c(2), _c(1)), (_c(1), _c(0)), np.array([1, 0]),
        np.array([1, 0]), "nu", BeltLengthChange(np.array([0.5, 1.0]), _r(2), _r(2), 1e-3,
                                                 _r(2), _r(2)), {"nu": 0.01}, 100.0),
        ("r_g", "n_rhp")),
    BeltLengthChange: (lambda: BeltLengthChange(np.array([0.5, 1.0]), _r(2), _r(2), 1e-3,
                                                _r(2), _r(2)), ("r_g", "phi", "dL_exact")),
    Modes: (lambda: Modes("actuation", ("a", "b"), ("k",), np.array([0.0, 60.0]), _r(2, 2),
                          _r(1, 2), _r(2, 2), _r(1, 2), 1, np.eye(2), np.eye(2)),
            ("omega", "shapes", "mass_matrix")),
    CalibrationResult: (lambda: CalibrationResult(
        empact.load_params(), (Target("actuation", 10.7, ratio=1.0),), np.array([10.7]),
        np.array([1e-6]), ("k",), np.array([1.0]), np.array([1.1]), True, "converged"),
        ("achieved_hz", "final")),
    RigRecord: (_rig, ("t", "signals")),
    StepExperiment: (lambda: StepExperiment(np.arange(4.0), np.zeros((4, 2)), np.ones(2),
                                            _trim()), ("t", "steps", "amplitudes")),
    PlantIdentification: (lambda: PlantIdentification(
        StepExperiment(np.arange(4.0), np.zeros((4, 2)), np.ones(2), _trim()),
        _realization(), empact.load_params(), OP), ()),
    MonteCarloResult: (lambda: MonteCarloResult(
        "slip", 0, Spread((Distribution("mu_0", "normal", 0.09, 0.005),)), _r(3, 1),
        ("max_real",), {"mu_0": "-", "max_real": "1/s"}, np.array([[1.0], [np.nan], [2.0]]),
        np.array([True, False, True]), ("", "trim: failed", "")), ("samples",)),
    Plant: (lambda: Plant(_r(2, 2), _r(2, 1), _r(1, 2), _r(1, 1), ("T_mp",), ("r_g",),
                          ("x1", "x2"), operating={"r_g": 1.0}, trim=_trim()), ("A", "D")),
}

#: public dataclasses that are not results (inputs, settings, models, laws), with why
NOT_RESULTS = {
    "empact.control.controller.Controller": "a controller (its file: to_dict/save)",
    "empact.control.controller.Schedule": "a controller's gain schedule",
    "empact.control.designs.ControllerType": "a registry entry (a design function by name)",
    "empact.control.driver.Driver": "settings of the driver model (its gains and lag)",
    "empact.control.law.LoopConfig": "settings of the loop law",
    "empact.control.tune.TuneOptions": "settings of the tuner (recorded in its design record)",
    "empact.experiments.rig.RigSettings": "settings of a rig experiment",
    "empact.fmu.FmuConfig": "settings of an FMU export (its input)",
    "empact.fmu.FmuVariable": "an entry of an FMU's model description",
    "empact.hardware.SensorParams": "a parameter section",
    "empact.hardware.ServoLimits": "a parameter section",
    "empact.linear.calibration.Target": "a calibration target (input)",
    "empact.linear.lumped.LumpedModel": "a model",
    "empact.montecarlo.analyses.AnalysisContext": "settings of an analysis",
    "empact.montecarlo.spread.Distribution": "an input distribution",
    "empact.montecarlo.spread.Spread": "an input spread",
    "empact.nonlinear.model.EmpactModel": "a model",
    "empact.nonlinear.options.ModelOptions": "model settings",
    "empact.nonlinear.controller_spec.ControllerSpec": "a scenario's [controller] table",
    "empact.nonlinear.scenario.Scenario": "a scenario (input)",
    "empact.params.Params": "the parameter set (to_dict: its TOML layout)",
    "empact.params.DampingParams": "a parameter section",
    "empact.variator.shift_law.CreepDamping": "a law (creep damping)",
    "empact.variator.losses.LossMap": "a law (a measured loss map; its file: to_csv)",
    "empact.variator.shift_law.CreepMap": "a law (tabulated creep)",
    "empact.variator.thrust_ratio.AnalyticThrustRatio": "a law",
    "empact.variator.thrust_ratio.TabulatedThrustRatio": "a law (table)",
    "empact.variator.traction.AnalyticTraction": "a law",
    "empact.variator.traction.MagicFormulaTraction": "a law",
    "empact.variator.traction.TabulatedTraction": "a law (table)",
    "empact.variator.traction.TractionCurves": "a law's measured curves (input)",
    "empact.params.ParameterInfo": "a parameter's documentation",
    "empact.slip.model.SlipModel": "a model",
    "empact.sweep.SweepOptions": "settings of a sweep",
}

#: packages whose dataclasses are the command line's and the report's own (they hold the
#: results above for a page or a figure)
NOT_API = ("empact.cli", "empact.report", "empact.reproduction", "empact.plotting")


def _public_dataclasses():
    found = {}
    for info in pkgutil.walk_packages(empact.__path__, "empact."):
        name = info.name
        if any(p.startswith("_") for p in name.split(".")[1:]) or name.startswith(NOT_API):
            continue
        with warnings.catch_warnings():  # the deprecated shim modules re-export
            warnings.simplefilter("ignore", DeprecationWarning)
            mod = importlib.import_module(name)
        for n in getattr(mod, "__all__", ()):
            c = getattr(mod, n, None)
            if isinstance(c, type) and dataclasses.is_dataclass(c) \
                    and c.__module__.startswith("empact."):
                found[f"{c.__module__}.{c.__qualname__}"] = c
    return found


def test_every_public_result_class_has_the_contract():
    """A census of the public modules' dataclasses: each is a result with ``to_dict`` and a
    builder above, or named in `NOT_RESULTS` with the reason."""
    found = _public_dataclasses()
    # parameter sections are inputs (their to_dict is the TOML layout)
    results = {k: c for k, c in found.items()
               if k not in NOT_RESULTS and not issubclass(c, Section)}
    missing = sorted(k for k, c in results.items() if not callable(getattr(c, "to_dict", None)))
    assert missing == [], f"public result classes without to_dict: {missing}"
    unbuilt = sorted(k for k, c in results.items() if c not in BUILDERS)
    assert unbuilt == [], f"result classes without a builder in tests/test_results.py: {unbuilt}"
    stale = sorted(k for k in NOT_RESULTS if k not in found)
    assert stale == [], f"NOT_RESULTS names classes that are not public: {stale}"


def _same(got, want):
    """`got` (from JSON) equals the array `want`: complex as [re, im] pairs, NaN as None."""
    want = np.asarray(want)
    if np.iscomplexobj(want):
        pairs = np.array(got, dtype=float).reshape(want.shape + (2,))
        return np.array_equal(pairs[..., 0] + 1j * pairs[..., 1], want)
    if want.dtype.kind == "f":
        back = np.array([np.nan if v is None else v for v in np.ravel(np.array(got, object))],
                        dtype=float).reshape(want.shape)
        return np.array_equal(back, want, equal_nan=True)
    return np.array_equal(np.array(got, dtype=want.dtype), want)


@pytest.mark.parametrize("cls", list(BUILDERS), ids=lambda c: c.__name__)
def test_to_dict_is_json_and_round_trips(cls):
    """``to_dict`` gives only JSON types (``json.dumps(allow_nan=False)`` accepts it), no
    display units (no key ending ``_pp``, ``_percent`` or ``_kn``), and its main arrays read
    back equal (bitwise: no unit conversion, SI as the fields hold them)."""
    build, arrays = BUILDERS[cls]
    obj = build()
    d = obj.to_dict()
    text = json.dumps(d, allow_nan=False)
    assert json.loads(text) == d

    def keys(o):
        if isinstance(o, dict):
            for k, v in o.items():
                yield k
                yield from keys(v)
        elif isinstance(o, list):
            for v in o:
                yield from keys(v)

    assert not [k for k in keys(d) if k.endswith(("_pp", "_percent", "_kn"))]
    for name in arrays:
        want = getattr(obj, name)
        if isinstance(want, dict):
            assert set(d[name]) == set(want), name
            for k, v in want.items():
                assert _same(d[name][k], v), (name, k)
        else:
            assert _same(d[name], want), name


def test_closed_loop_result_writes_its_run_and_metrics():
    """A closed-loop result: the simulation nested as its own ``to_dict``, the scenario by
    name, the metrics as fractions (NaN as None), the law left out."""
    obj = BUILDERS[ClosedLoopResult][0]()
    d = obj.to_dict()
    assert d["scenario"] == "slip-load-step-r1" and "law" not in d
    assert d["result"] == obj.result.to_dict()
    assert d["metrics"] == {"slip_error": 0.001, "ratio_rate": None, "macro_slip": False}
    assert d["op"]["tau"] == 0.9


TABLES = [c for c in BUILDERS if issubclass(c, TableResult)] + [SimulationResult]


@pytest.mark.parametrize("cls", TABLES, ids=lambda c: c.__name__)
def test_to_pandas_gets_one_column_per_quantity(cls, monkeypatch):
    """A table's ``to_pandas`` hands pandas one 1-D column per quantity, all of one length
    (pandas stood in for by a stub that keeps the columns: it is optional here)."""
    import types

    stub = types.ModuleType("pandas")
    stub.DataFrame = lambda columns: columns  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "pandas", stub)
    columns = BUILDERS[cls][0]().to_pandas()
    lengths = {k: np.shape(v) for k, v in columns.items()}
    assert len(set(lengths.values())) == 1 and len(next(iter(lengths.values()))) == 1, lengths


def test_to_pandas_without_pandas_is_one_clear_error(monkeypatch):
    """Without pandas: an ImportError naming the method and the way out."""
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas raises ImportError
    with pytest.raises(ImportError, match=r"^SimulationResult.to_pandas needs pandas "
                                          r"\(pip install pandas\)"):
        _sim().to_pandas()


def test_simulation_table_is_time_outputs_inputs(monkeypatch):
    """`SimulationResult.to_pandas`: ``t`` [s], every output, every input (SI, bitwise)."""
    import types

    stub = types.ModuleType("pandas")
    stub.DataFrame = lambda columns: columns  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "pandas", stub)
    res = _sim()
    columns = res.to_pandas()
    assert list(columns) == ["t", "nu", "r_g", "T_mp", "T_ms"]
    assert np.array_equal(columns["nu"], res.y[:, 0], equal_nan=True)
    assert np.array_equal(columns["T_ms"], res.u[:, 1])


def test_rig_csv_is_built_on_the_table_columns():
    """`RigRecord.to_csv` writes the columns `to_pandas` has (time, then the signals)."""
    rec = _rig()
    rows = [r for r in rec.to_csv().splitlines() if not r.startswith("#")]
    assert rows[0] == "time [s],T_mp [N m],nu [-]"
    assert [float(v) for v in rows[2].split(",")] == pytest.approx(
        [rec.t[1], rec.signals["T_mp"][1], rec.signals["nu"][1]], rel=1e-8)  # %.9g written

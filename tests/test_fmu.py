"""The machine as an FMU (`empact.fmu`, ``empact fmu export``), checked with FMPy.

Two FMUs are built once for the module: the open-loop machine of the shipped scenario
``servo-torque-steps`` and the closed loop of ``slip-load-step-r1`` with the shipped PI.
Each runs through FMPy at a 1 ms communication step with the scenario's inputs sampled at
the communication points, against the native simulator:

* open loop against `simulate` with a sampled controller of 1 ms that holds (the native run
  on the FMU's communication grid: the integrator restarts at every point in both; measured
  bitwise on r_g and nu, 2.5e-16 relative on F_s), and against ``empact simulate``'s own
  run, whose integrator stops only at its chunks (7.7e-6 relative on nu: the integrator's
  tolerance, rtol = 1e-4);
* closed loop against ``empact control simulate`` (the law samples at 1 kHz, so its grid
  is the FMU's: 1.5e-14 relative measured).
"""
from __future__ import annotations

import json
import zipfile

import numpy as np
import pytest
from click.testing import CliRunner
from numpy.testing import assert_allclose

import empact
from empact.cli import main
from empact.control.closed_loop import control_example_path, run_closed_loop
from empact.errors import ParameterError
from empact.nonlinear.scenario import example_path, load_scenario
from empact.nonlinear.simulation import (
    Stepper,
    _inputs_at,
    _signal_table,
    run_scenario,
    scenario_model,
    scenario_signals,
    simulate,
)

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")
from fmpy.fmi2 import FMU2Slave  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from empact.fmu import CoSimulation, FmuConfig, export_fmu  # noqa: E402

DT = 1e-3  # the communication step [s]
SIGNALS = ("r_g", "nu", "F_s")
PI = str(control_example_path("slip-load-step-r1").parent / "pi.json")


def _setup(name, params):
    sc = load_scenario(example_path(name) if name != "slip-load-step-r1"
                       else control_example_path(name))
    model, op = scenario_model(sc, params)
    return sc, model, op, scenario_signals(sc, model, op)


def _point(sc):
    i = sc.initial
    return empact.OperatingPoint(**{k: getattr(i, k) for k in ("r_g", "omega_p") + i.given})


def _inputs(sc, model, op, signals, names):
    """The scenario's inputs at the communication points (right-continuous: a step at a
    point applies from it), as FMPy's input table."""
    sig_t, sig_v, sig_n, _ = _signal_table(model, signals, op.u, sc.duration)
    t = np.arange(int(round(sc.duration / DT)) + 1) * DT
    u = _inputs_at(t, sig_t, sig_v, sig_n)
    table = np.zeros(t.size, dtype=[("time", float)] + [(n, float) for n in names])
    table["time"] = t
    for n in names:
        table[n] = u[:, model.inputs.index(n)]
    return table


class _Hold:
    """A sampled controller that commands nothing: `simulate` restarts its integrator at
    every sample, as the FMU at every communication point."""

    dt = DT
    measured = ("r_g",)
    commands: tuple[str, ...] = ()

    def step(self, t, measured):
        return np.zeros(0)


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    params = empact.load_params()
    folder = tmp_path_factory.mktemp("fmu")
    out = {}
    sc, *_ = _setup("servo-torque-steps", params)
    options = {k: getattr(sc.options, k) for k in ("drive", "load", "damping")}
    out["open"] = export_fmu(folder / "open.fmu", params, options=options, point=_point(sc),
                             method=sc.method, rtol=sc.rtol, max_step=sc.max_step)
    sc, *_ = _setup("slip-load-step-r1", params)
    options = {k: getattr(sc.options, k) for k in ("drive", "load", "damping")}
    out["closed"] = export_fmu(folder / "closed.fmu", params, options=options,
                               point=_point(sc), controller=PI, rate=sc.controller.rate,
                               method=sc.method, rtol=sc.rtol, max_step=sc.max_step)
    return out


def test_fmus_validate_with_units_and_ranges(fmus):
    for path in fmus.values():
        assert validate_fmu(str(path)) == []
    md = fmpy.read_model_description(str(fmus["closed"]))
    v = {x.name: x for x in md.modelVariables}
    # the parameter blocks' metadata: J_p [kg m^2] in (0, inf), nu_0 ... (empact._section)
    params = empact.load_params()
    assert v["driveline.J_p"].unit == params.unit("driveline.J_p")
    assert v["driveline.J_p"].causality == "parameter"
    assert float(v["driveline.J_p"].start) == params.driveline.J_p
    assert float(v["initial.tau"].max) == 1.0 and float(v["initial.tau"].min) == -1.0
    assert {u.name for u in md.unitDefinitions} >= {"N", "N m", "rad/s"}
    ins = [x.name for x in md.modelVariables if x.causality == "input"]
    assert ins == ["r_g_ref", "tau_ref", "omega_d_ref", "T_l"]
    outs = {x.name for x in md.modelVariables if x.causality == "output"}
    assert outs >= {"r_g", "nu", "nu_r", "F_s", "omega_p", "omega_s", "omega_mp",
                    "omega_ms", "T_mp", "T_ms", "P_diss"}
    md = fmpy.read_model_description(str(fmus["open"]))
    ins = [x.name for x in md.modelVariables if x.causality == "input"]
    assert ins == ["T_mp", "T_ms", "omega_d_ref", "T_l"]
    assert md.coSimulation.canGetAndSetFMUstate
    with zipfile.ZipFile(fmus["open"]) as z:  # the FMU carries its configuration
        spec = json.loads(z.read("resources/empact_fmu.json"))
    assert spec["solver"]["method"] == "rodas5p" and not spec["controller"]


def test_open_loop_scenario_through_fmpy_matches_the_native_run(fmus):
    params = empact.load_params()
    sc, model, op, signals = _setup("servo-torque-steps", params)
    table = _inputs(sc, model, op, signals, model.inputs)
    res = fmpy.simulate_fmu(str(fmus["open"]), start_time=0.0, stop_time=sc.duration,
                            step_size=DT, output_interval=DT, input=table,
                            output=list(SIGNALS))
    grid = simulate(model, op.x, signals, sc.duration, u0=op.u, controller=_Hold(),
                    sample_rate=1 / DT, rtol=sc.rtol, max_step=sc.max_step,
                    omega_min=sc.omega_min, max_steps=sc.max_steps, method=sc.method)
    native = run_scenario(sc, params)
    assert len(res) == len(grid.t) == int(round(sc.duration / DT)) + 1
    step = int(round(sc.sample_rate * DT))  # the scenario samples at 2 kHz
    for s in SIGNALS:
        # the same integrator on the same grid (measured: 0 on r_g and nu, 2.5e-16 on F_s)
        assert_allclose(res[s], grid.output(s), rtol=1e-6, atol=0, err_msg=s)
        # empact simulate's run, which the integrator steps across the points: within its
        # tolerance (rtol = 1e-4; measured 1.6e-8 on r_g, 7.7e-6 on nu, 1.9e-6 on F_s)
        assert_allclose(res[s], native.output(s)[::step], rtol=1e-4, atol=0, err_msg=s)


def test_closed_loop_load_step_through_fmpy_matches_control_simulate(fmus):
    params = empact.load_params()
    sc, model, op, signals = _setup("slip-load-step-r1", params)
    table = _inputs(sc, model, op, signals, model.inputs[2:])  # references held at start
    res = fmpy.simulate_fmu(str(fmus["closed"]), start_time=0.0, stop_time=sc.duration,
                            step_size=DT, output_interval=DT, input=table,
                            output=list(SIGNALS) + ["T_mp", "T_ms"])
    native = run_closed_loop(sc, params).result
    assert len(res) == len(native.t)
    # the law's samples are the communication points (measured: 1.5e-14 relative on nu)
    for s in SIGNALS + ("T_mp", "T_ms"):
        assert_allclose(res[s], native.output(s), rtol=1e-6, atol=0, err_msg=s)
    assert np.ptp(res["F_s"]) > 1e3  # the step moved the clamping (a test that can fail)


def _slave(path, tmp_path, stop):
    md = fmpy.read_model_description(str(path))
    folder = fmpy.extract(str(path), str(tmp_path / path.stem))
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=folder,
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="x")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0, stopTime=stop)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    refs = {v.name: v.valueReference for v in md.modelVariables}
    return fmu, refs


@pytest.mark.parametrize("kind", ["open", "closed"])
def test_state_get_set_and_serialise_round_trip_bitwise(fmus, tmp_path, kind):
    fmu, refs = _slave(fmus[kind], tmp_path, 0.1)
    vr = [refs[s] for s in SIGNALS]
    u = refs["T_l"]
    T_l = fmu.getReal([u])[0]

    def run(t0, n):
        out = []
        for k in range(n):
            fmu.setReal([u], [T_l + (20.0 if k >= 5 else 0.0)])  # a load step in the run
            fmu.doStep(currentCommunicationPoint=t0 + k * DT, communicationStepSize=DT)
            out.append(fmu.getReal(vr))
        return np.array(out)

    run(0.0, 10)
    state = fmu.getFMUState()
    blob = fmu.serializeFMUState(state)
    first = run(0.01, 20)
    fmu.setFMUState(state)
    again = run(0.01, 20)
    fmu.setFMUState(fmu.deSerializeFMUstate(blob))
    third = run(0.01, 20)
    assert np.array_equal(first, again) and np.array_equal(first, third)
    assert not np.array_equal(first[0], first[-1])  # the state moved
    fmu.freeFMUState(state)
    fmu.terminate()
    fmu.freeInstance()


def test_any_communication_step(fmus):
    """0.25 ms and 2.5 ms steps (not the law's sample period) reach the same state as 1 ms
    within the integrator's tolerance (restarts in other places: measured below 1e-6)."""
    res = [fmpy.simulate_fmu(str(fmus["closed"]), stop_time=0.05, step_size=h,
                             output_interval=h, output=list(SIGNALS))[-1]
           for h in (DT, DT / 4, 2.5 * DT)]
    for s in SIGNALS:
        assert_allclose([r[s] for r in res[1:]], res[0][s], rtol=1e-5, atol=0)


def test_a_changed_parameter_is_validated_and_trimmed(fmus, tmp_path):
    base = fmpy.simulate_fmu(str(fmus["open"]), stop_time=0.01, output=["F_s"])
    res = fmpy.simulate_fmu(str(fmus["open"]), stop_time=0.01, output=["F_s"],
                            start_values={"initial.F_s": 12000.0})
    assert_allclose(res["F_s"][0], 12000.0, rtol=1e-6)  # the trim's clamping force
    assert_allclose(base["F_s"][0], 10000.0, rtol=1e-6)
    with pytest.raises(Exception, match="(?i)initializationmode"):
        fmpy.simulate_fmu(str(fmus["open"]), stop_time=0.01,
                          start_values={"driveline.J_p": -1.0})


def test_stepper_snapshot_and_config_errors():
    params = empact.load_params()
    model = empact.nonlinear_model(params, drive="speed")
    op = empact.trim(model, params.operating)
    st = Stepper(model, op.x, op.u)
    with pytest.raises(ValueError, match="before the current time"):
        st.advance(-1.0)
    with pytest.raises(ParameterError, match="model option 'belt'"):
        FmuConfig(params, {"belt": "locked"})
    with pytest.raises(ParameterError, match="method"):
        CoSimulation(FmuConfig(params, {}, method="euler"))


def test_export_bad_input_is_one_line_and_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    bad = tmp_path / "bad.toml"
    bad.write_text("[driveline]\nJ_p = -1.0\n")
    cases = [
        (["--params", str(bad)], "J_p"),
        (["--rate", "0", "--controller", PI], "rate"),
        (["--controller", "missing.json"], "missing.json"),
        (["--thrust-ratio", "map.csv"], "map.csv"),
        (["--tau", "1.5"], "--tau"),
        (["--method", "euler"], "euler"),
    ]
    for args, match in cases:
        res = CliRunner().invoke(main, ["fmu", "export", "--out", "m.fmu", *args])
        assert res.exit_code == 2, res.output
        line = res.output.strip()
        assert line.startswith("error:") and "\n" not in line and match in line, line
    res = CliRunner().invoke(main, ["fmu", "export", "--out", "m.txt"])
    assert res.exit_code == 2 and ".fmu" in res.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


def test_a_measured_traction_table_travels_in_the_fmu(tmp_path):
    """``--traction curves.csv``: the FMU carries the table, and its unit starts from the
    trim of the model on that table (bitwise the native trim)."""
    from empact.variator.traction import load_traction, traction_from_params

    params = empact.load_params()
    magic = traction_from_params(params)  # the shipped curve sampled, as a measured table
    nu = np.concatenate([[0.0], np.linspace(0.002, 0.2, 100)])
    rows = [f"{r:g},{n:.10g},{float(magic.mu(n, r)):.12g}" for r in (0.5, 1.0, 2.0)
            for n in nu]
    csv = tmp_path / "curves.csv"
    csv.write_text("r_g,nu,mu\n" + "\n".join(rows) + "\n")
    table = load_traction(csv)
    res = CliRunner().invoke(main, ["fmu", "export", "--out", str(tmp_path / "t.fmu"),
                                       "--traction", str(csv)])
    assert res.exit_code == 0, res.output
    folder = tmp_path / "x"
    with zipfile.ZipFile(tmp_path / "t.fmu") as z:
        z.extractall(folder)
        assert z.read("resources/traction.csv") == csv.read_bytes()
    unit = CoSimulation.from_folder(folder / "resources")
    assert unit.model.options.traction is not None
    point = params.operating
    model = empact.nonlinear_model(params, drive="speed", traction=table,
                                   reference_ratio=point.r_g)
    assert np.array_equal(unit.op.x, empact.trim(model, point).x)

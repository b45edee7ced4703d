"""The dynamic drive cycle (issue 34, items 2, 4 and 6): the driver in the compiled loop, the
launch model's stretches, the energies' bookkeeping and closure, the JSON contract.

A short trace above the launch speed (accelerate, cruise, brake: 30 s) keeps it quick; the
WLTC 3b run itself is the report's (`empact.reproduction.drive_cycle`) and the benchmark's
(`bench/bench_dynamic_cycle.py`)."""
import numpy as np
import pytest

from empact.control.driver import Driver
from empact.cycles import Cycle
from empact.drive_cycle import TERMS, quasi_static_cycle
from empact.dynamic_cycle import (
    DynamicCycleResult,
    driving_stretches,
    dynamic_cycle,
    launch_speed,
)
from empact.engine import full_load_torque
from empact.errors import ParameterError


def _trace():
    """4 m/s, up to 14 m/s along a half cosine in 10 s (up to 1.6 m/s^2), held, down to
    4 m/s likewise: 30 s at 1 Hz, two phases."""
    t = np.arange(31.0)
    ramp = lambda x: 5.0 * (1 - np.cos(np.pi * np.clip(x, 0.0, 10.0) / 10.0))  # noqa: E731
    v = 4.0 + ramp(t) - ramp(t - 20.0)
    phase = tuple("up" if x < 15 else "down" for x in t)
    return Cycle("test", t, v, phase)


@pytest.fixture(scope="module")
def run(params):
    return dynamic_cycle(params, _trace(), strategies=("hydraulic-sf1.3", "slip"))


def test_stretches_and_launch_speed(params):
    """The launch speed is LOW at omega_drive (11.2 km/h for the shipped car); the stretches
    are the runs of samples at or above it, two samples at least."""
    assert 3.6 * launch_speed(params) == pytest.approx(11.2, abs=0.05)
    v = np.array([0.0, 2.0, 5.0, 6.0, 1.0, 5.0, 0.0, 4.0, 4.0, 4.0])
    c = Cycle("c", np.arange(v.size, dtype=float), v, ("all",) * v.size)
    assert driving_stretches(c, 3.12) == [(2, 3), (7, 9)]


def test_run_follows_the_trace_without_macro_slip_or_slack(params, run):
    """Every stretch runs to its end; the car follows the trace within the WLTP's 2 km/h;
    no belt slack; macro slip is the slip reserve's sign, and the safety-factor clamping
    does not macro-slip (on this trace's tip-out at 9 s it reached the peak, -0.50 pp, while
    it followed the engine's torque down at once; it holds it now,
    `empact.dynamic_cycle.clamping_release`: +1.47 pp).  The slip loop reaches it there
    (-0.15 pp, measured; its feedforward follows the torque estimate down; a finding, not
    excluded: the tip-out of this trace, 1.6 m/s^2 ended within 5 s, is harsher than
    WLTC 3b's, where its reserve stays at or above 0.34 pp).  The engine at most at its
    full-load torque (1e-3 of it: the torque is held over a sample period while the speed
    moves the curve)."""
    for s, r in run.runs.items():
        assert r.complete, r.messages
        assert r.speed_error_max_kmh < 2.0, s
        assert r.macro_slip == (r.slip_reserve < 0), s
        if s != "slip":
            assert not r.macro_slip, (s, r.slip_reserve)
        assert not r.belt_slack and r.min_clamping_force > 0, s
        sig = r.signals
        full = full_load_torque(params.engine, sig["omega_d"])
        assert np.all(sig["T_d_act"] <= full * (1 + 1e-3))


def test_energy_closes_on_the_run(run):
    """Over the run: engine work + the servos' mechanical work = the load's work (road, final
    drive, brakes) + the dissipated power + the change of stored energy, to 1e-3 of the
    engine work (the trapezoid rule on the 100 Hz outputs); the load's work is its named
    terms (road, final drive, brakes: 1e-9)."""
    for s, r in run.runs.items():
        sig, t = r.signals, r.t
        w = np.zeros_like(t)
        dt = np.diff(t)
        w[:-1] += dt / 2
        w[1:] += dt / 2
        engine = np.sum(w * sig["T_d_act"] * sig["omega_d"])
        servo = np.sum(w * (sig["T_mp_act"] * sig["omega_mp"] + sig["T_ms_act"]
                            * sig["omega_ms"]))
        load = np.sum(w * sig["T_l_act"] * sig["omega_l"])
        named = np.sum(w * (sig["P_road"] + sig["P_loss_fd"]
                            + sig["T_l_brake"] * sig["omega_l"]))
        assert load == pytest.approx(named, rel=1e-9)
        diss = np.sum(w * sig["P_diss"])
        dE = sig["E"][-1] - sig["E"][0]
        assert engine + servo == pytest.approx(load + diss + dE, rel=1e-3), s


def test_energies_add_up_and_json_keys(run):
    """The cycle's energies are the dynamic stretches' plus the quasi-static rest (here none:
    the trace is above the launch speed), by phase they add up to the cycle's; the JSON has
    the issue's keys."""
    d = run.to_dict()
    for k in ("cycle", "distance_m", "duration_s", "wheel_energy_J", "launch_model",
              "strategies"):
        assert k in d
    for s, r in run.runs.items():
        e = d["strategies"][s]
        for k in ("energy_J", "fuel_g", "speed_error_max_kmh", "macro_slip", "belt_slack"):
            assert k in e
        for k in TERMS + ("brakes",):
            assert r.energy_J[k] == pytest.approx(r.dynamic_J[k], rel=1e-12, abs=1e-9)
            by_phase = sum(p[k] for p in r.phases.values())
            assert by_phase == pytest.approx(r.energy_J[k], rel=1e-9, abs=1e-6)
        assert r.fuel_g == pytest.approx(sum(p["fuel_g"] for p in r.phases.values()),
                                         rel=1e-9)
    # the hydraulic strategy's actuation is its pump, the slip strategy's its servos
    h, sl = run.runs["hydraulic-sf1.3"].energy_J, run.runs["slip"].energy_J
    assert h["pump"] > 0 and h["servo_electrical"] == 0
    assert sl["pump"] == 0 and sl["servo_electrical"] > 0
    assert d["strategies"]["slip"]["saving"] is not None


def test_quasi_static_rest_counts_below_the_launch_speed(params):
    """A trace that starts and ends at rest: the dynamic stretch is the part at or above
    the launch speed; the cycle's energies are its plus the quasi-static samples' of the
    rest, interval by interval (the launch clutch's energy is only the quasi-static's)."""
    t = np.arange(26.0)
    v = np.interp(t, [0.0, 2.0, 8.0, 16.0, 22.0, 25.0], [0.0, 0.0, 8.0, 8.0, 0.0, 0.0])
    c = Cycle("stop-go", t, v, ("all",) * t.size)
    qs = quasi_static_cycle(params, c, strategies=("slip",))
    res = dynamic_cycle(params, c, strategies=("slip",), quasi_static=qs)
    (a, b), = res.stretches
    assert v[int(a)] >= launch_speed(params) > v[int(a) - 1]
    r = res.runs["slip"]
    assert r.complete
    assert r.energy_J["launch"] > 0 and r.dynamic_J["launch"] == 0
    rest = {k: r.energy_J[k] - r.dynamic_J[k] for k in TERMS}
    cov = (t[:-1] >= a) & (t[1:] <= b)
    w = np.zeros_like(t)
    dt = np.where(~cov, np.diff(t), 0.0)
    w[:-1] += dt / 2
    w[1:] += dt / 2
    for k in TERMS:
        assert rest[k] == pytest.approx(float(np.sum(w * qs.power["slip"][k])), rel=1e-12,
                                        abs=1e-9)


def test_compiled_loop_equals_the_python_path(params):
    """The driver and the law in the compiled loop (`run_samples_driven`) give bitwise the
    outputs of the simulator's Python loop stepping the same law (`DrivenLaw.step`)."""
    from empact.control.closed_loop import resolve_controller
    from empact.control.driver import DrivenLaw
    from empact.control.law import LoopConfig
    from empact.dynamic_cycle import LOOPS
    from empact.nonlinear.equilibrium import trim
    from empact.nonlinear.model import nonlinear_model
    from empact.nonlinear.simulation import simulate
    from empact.operating import CruisePoint

    model = nonlinear_model(params, driveline="vehicle")
    op = trim(model, CruisePoint(r_g=0.8, omega_p=150.0, F_s=5000.0))
    point = {k: getattr(op, k) for k in ("r_g", "nu", "omega_p", "T_l", "F_s", "T_d")}
    tk = np.array([0.0, 1.0, 2.0])
    refs = {"r_g": np.column_stack([tk, [0.8, 0.9, 1.0]]),
            "tau": np.column_stack([tk, [0.9, 0.9, 0.9]])}
    v0 = op.omega_s * model.constants.vehicle_gear
    trace = np.column_stack([tk, [v0, v0 + 1.0, v0 + 1.5]])

    def law():
        return DrivenLaw(resolve_controller("shipped:pi"), model, point, op.u[:2],
                         LoopConfig.of(params, **LOOPS["feedback"]), refs, 2.0, Driver(),
                         trace)

    class Stepped:  # the law without its compiled loop: the simulator steps it
        def __init__(self, inner):
            self.inner = inner
            self.dt, self.measured, self.commands = inner.dt, inner.measured, inner.commands

        def step(self, t, measured):
            return self.inner.step(t, measured)

    a = simulate(model, op.x, {}, 2.0, u0=op.u, controller=law(), sample_rate=100.0)
    b = simulate(model, op.x, {}, 2.0, u0=op.u, controller=Stepped(law()), sample_rate=100.0)
    assert a.complete and b.complete
    assert np.array_equal(a.y, b.y) and np.array_equal(a.u, b.u)
    assert np.ptp(a.output("T_d_act")) > 1.0  # the driver moved the engine


def test_bad_arguments(params):
    """Unknown strategies and rates are refused before any work."""
    with pytest.raises(ParameterError, match="strategy"):
        dynamic_cycle(params, _trace(), strategies=("sf2",))
    with pytest.raises(ParameterError, match="output_rate"):
        dynamic_cycle(params, _trace(), output_rate=0.0)
    with pytest.raises(ParameterError, match="bandwidth_hz"):
        Driver(bandwidth_hz=0.0)
    assert isinstance(DynamicCycleResult, type)


def test_cycle_monte_carlo_forked_equals_in_process(params):
    """The cycle Monte Carlo on the sweep layer: 4 quasi-static runs of a short trace over a
    spread of the car's mass and road load; two forked workers give bitwise the in-process
    table; a heavier car burns more (the runs' fuel rises with the mass at equal road load,
    checked by rank on the reference strategy); a scenario variable is refused."""
    from empact.montecarlo.cycle import cycle_monte_carlo
    from empact.montecarlo.spread import spread_from_dict
    from empact.sweep import SweepOptions

    spread = spread_from_dict({"spread": {
        "vehicle.mass": {"distribution": "uniform", "lower": 1100.0, "upper": 1600.0}}},
        params)
    trace = _trace()
    one = cycle_monte_carlo(params, spread, 4, cycle=trace,
                            strategies=("hydraulic-sf1.3", "slip"), seed=3)
    two = cycle_monte_carlo(params, spread, 4, cycle=trace,
                            strategies=("hydraulic-sf1.3", "slip"), seed=3,
                            sweep=SweepOptions(workers=2))
    for s in one.strategies:
        assert np.array_equal(one.fuel_g[s], two.fuel_g[s])
    assert np.array_equal(one.values, two.values)
    m = one.values[:, 0]
    f = one.fuel_g["hydraulic-sf1.3"]
    assert np.array_equal(np.argsort(m), np.argsort(f))
    assert np.all(one.saving["hydraulic-sf1.3"] == 0.0)
    assert set(one._columns()) >= {"vehicle.mass", "fuel_g.slip", "saving.slip"}
    bad = spread_from_dict({"spread": {"scenario.initial.F_s": {
        "distribution": "uniform", "lower": 5e3, "upper": 6e3}}}, params,
        scenario=_scenario(params))
    with pytest.raises(ParameterError, match="no scenario"):
        cycle_monte_carlo(params, bad, 2, cycle=trace)


def _scenario(params):
    from empact.control.closed_loop import control_example_path
    from empact.nonlinear.scenario import load_scenario
    return load_scenario(control_example_path("slip-load-step-r1"))


def test_cli_dynamic_json_and_plot(tmp_path):
    """``empact cycle --dynamic --json`` on a short trace: the issue's keys (with the
    dynamic checks) under schema and units; ``--plot`` writes the five-panel figure."""
    import json

    from click.testing import CliRunner

    from empact.cli import main

    f = tmp_path / "t.csv"
    f.write_text("time [s],speed [km/h]\n0,0\n1,6\n2,12\n3,16\n4,18\n5,18\n6,14\n7,6\n8,0\n")
    png = tmp_path / "c.png"
    res = CliRunner().invoke(main, ["cycle", "--cycle", str(f), "--dynamic", "--json",
                                    "--strategies", "hydraulic-sf1.3,slip", "--plot",
                                    str(png)])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    for key in ("schema", "units", "cycle", "distance_m", "duration_s", "wheel_energy_J",
                "launch_model", "strategies"):
        assert key in doc
    for d in doc["strategies"].values():
        for k in ("energy_J", "fuel_g", "speed_error_max_kmh", "macro_slip", "belt_slack"):
            assert k in d
        assert set(TERMS) <= set(d["energy_J"])
    assert png.stat().st_size > 0

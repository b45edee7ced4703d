"""Drive cycles (`empact.cycles`), the car and engine (`empact.vehicle`, `empact.engine`) and
the quasi-static cycle (`empact.drive_cycle`, `empact cycle`)."""
from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from click.testing import CliRunner
from numpy.testing import assert_allclose

from empact.cli import main
from empact.control.family import DESIGN_GRID
from empact.cycles import Cycle, load_cycle, parse_trace, read_trace
from empact.drive_cycle import RATIO_LIMITS, STRATEGIES, TERMS, quasi_static_cycle
from empact.engine import EngineParams, fuel_rate, full_load_torque, operating_speed
from empact.errors import ParameterError
from empact.params import default_params
from empact.plotting import plot_drive_cycle
from empact.vehicle import VehicleParams, road_load, wheel_force


def test_wltc3b_invariants():
    """UN GTR 15 Annex 1 (and the JRC wltp package's 'checksum'): 1801 samples at 1 Hz,
    23.266 km, 131.3 km/h, sum of the samples 83 758.6 km/h; phases 589/433/455/323 s."""
    c = load_cycle("wltc3b")
    assert c.t.size == 1801
    assert_allclose(np.diff(c.t), 1.0, rtol=0, atol=0)
    kmh = 3.6 * c.v
    assert_allclose(kmh.sum(), 83758.6, rtol=1e-12)
    assert_allclose(kmh.max(), 131.3, rtol=1e-12)
    # the trapezoid and sum/3600 agree: the trace starts and ends at rest
    assert_allclose(c.distance, 23266.0, atol=0.5)
    assert_allclose(kmh.sum() / 3.6, c.distance, rtol=1e-12)
    assert c.phases == ("Low", "Medium", "High", "Extra-high")
    counts = [c.phase.count(p) for p in c.phases]
    assert counts == [590, 433, 455, 323]


def test_nedc_invariants():
    """UNECE R83 (as the JRC wltp tables give it): 1180 samples (t = 0..1179 s), 11.013 km,
    120 km/h; ECE 781 samples (4 x 195 s), EUDC 399."""
    c = load_cycle("nedc")
    assert c.t.size == 1180 and c.t[0] == 0 and c.t[-1] == 1179
    assert_allclose(c.distance, 11013.0, atol=0.5)
    assert_allclose(3.6 * c.v.max(), 120.0, rtol=1e-12)
    assert [c.phase.count(p) for p in c.phases] == [781, 399]


def test_ftp75_built_from_the_udds():
    """40 CFR 86 App. I: FTP-75 is 1874 s of driving, 11.04 mi = 17.77 km, 56.7 mph top
    speed; the hot phase repeats the UDDS's first 505 s."""
    c = load_cycle("ftp75")
    assert c.t.size == 1875 and c.duration == 1874
    assert_allclose(c.distance, 11.04 * 1609.344, atol=10.0)
    assert_allclose(c.v.max() / 0.44704, 56.7, atol=0.05)
    hot = np.array([p == "hot-transient" for p in c.phase])
    assert_allclose(c.v[hot], c.v[1:506], rtol=0, atol=0)


def test_trace_validation_one_line_per_error(tmp_path):
    f = tmp_path / "trace.csv"
    f.write_text("# mine\ntime [s],speed [m/s]\n0,0\n1,2.5\n2,1\n")
    c = read_trace(f)
    assert_allclose(c.v, [0, 2.5, 1], rtol=0, atol=0)
    assert c.phases == ("all",)
    with pytest.raises(ParameterError) as exc:
        parse_trace("time [s],speed [km/h]\n0,0\n1,-3\n1,5\n2,nan\n", "t.csv")
    lines = str(exc.value).splitlines()
    assert len(lines) == 3
    assert "data row 2: speed = -3" in lines[0]
    assert "time = 1 s: must increase" in lines[1]
    assert "speed = nan" in lines[2]
    with pytest.raises(ParameterError, match="need the columns 'time"):
        parse_trace("t,v\n0,0\n", "t.csv")
    with pytest.raises(ParameterError, match="cycle = 'wltc'"):
        load_cycle("wltc")


def test_road_load_closed_form():
    """At constant speed the wheel force is the coast-down polynomial (the wltp example
    car's 100 N + 0.5 N/(km/h) + 0.04 N/(km/h)^2), and with a grade m g sin(grade)."""
    veh = VehicleParams()
    v = np.array([0.0, 10.0, 100 / 3.6])
    F = wheel_force(veh, v, 0.0)
    assert_allclose(F, [0.0, 100 + 1.8 * 10 + 0.5184 * 100, 100 + 50 + 400], rtol=1e-12)
    hill = VehicleParams(grade=0.05)
    assert_allclose(road_load(hill, 0.0) - road_load(veh, 0.0),
                    1300 * 9.80665 * math.sin(0.05), rtol=1e-12)


def test_operating_line_is_the_lowest_speed_with_the_reserve():
    eng = EngineParams()
    P = np.array([0.0, 5e3, 20e3, 50e3])
    w = operating_speed(eng, P)
    assert w[0] == eng.omega_drive and w[1] == eng.omega_drive  # 5 kW: below the 1200 rpm line
    line = eng.load_max * full_load_torque(eng, w) * w
    assert np.all(line[2:] >= P[2:] * (1 - 1e-12))
    below = w[2:] - 1e-6
    assert np.all(eng.load_max * full_load_torque(eng, below) * below < P[2:])
    # Willans: fuel power (T + T0) omega / e, LHV 43 MJ/kg (closed form)
    T0 = 1.5e5 * 1.6e-3 / (4 * math.pi)
    assert_allclose(fuel_rate(eng, 50.0, 200.0), (50 + T0) * 200 / 0.4 / 43e6, rtol=1e-12)


def test_ratio_limits_are_the_design_grid():
    r = DESIGN_GRID["r_g"]
    assert RATIO_LIMITS == (min(r), max(r))


@pytest.fixture(scope="module")
def short_run():
    """The first 120 s of WLTC 3b: rest, launch, accelerations, braking, a stop."""
    c = load_cycle("wltc3b")
    trace = Cycle(name="wltc3b-120s", t=c.t[:121], v=c.v[:121], phase=c.phase[:121])
    return quasi_static_cycle(default_params(), trace, strategies=tuple(STRATEGIES))


def test_energy_closes_per_strategy(short_run):
    """The engine's brake power (its sum of terms) equals, independently, the primary torque
    (variator input over primary speed) at the engine's speed plus the actuation; the
    final drive's loss is P_w (1/eta_fd - 1) where the car draws (the speed iteration met
    the wheels' speed); the variator's terms sum to its input less its output."""
    r = short_run
    eta = default_params().vehicle.eta_fd
    trac = (r.v > 0) & (r.P_wheel > 0)
    assert trac.sum() > 30
    for s in STRATEGIES:
        P = r.power[s]
        var = sum(P[k] for k in ("slip", "clamp", "load", "drag"))
        assert_allclose(var, P["variator_in"] - P["variator_out"], rtol=1e-9, atol=1e-9)
        assert_allclose(P["final_drive"][trac], r.P_wheel[trac] * (1 / eta - 1), rtol=1e-9)
        crank = P["engine"] - P["actuation"] - P["alternator"]
        wheel = np.where(trac, r.P_wheel, 0.0)
        assert_allclose(crank, wheel + P["final_drive"] + P["launch"] + var, rtol=1e-9,
                        atol=1e-9)
        d = r.summary(s)
        total = d["wheel_energy_J"] + sum(d["energy_J"][k] for k in TERMS)
        assert_allclose(total, d["engine_J"], rtol=1e-9)
        phases = [r.summary(s, p)["fuel_g"] for p in r.cycle.phases]
        assert_allclose(sum(phases), d["fuel_g"], rtol=1e-12)


def test_strategies_bill_their_actuation(short_run):
    r = short_run
    assert np.all(r.power["hydraulic-sf1.3"]["alternator"] == 0)
    assert np.all(r.power["hydraulic-sf1.3"]["servo_electrical"] == 0)
    assert np.all(r.power["sf1.3"]["pump"] == 0)
    assert np.all(r.power["sf1.3"]["alternator"] > 0)
    # the same clamping law, other actuation: the variator's losses are the same
    assert_allclose(r.power["sf1.3"]["clamp"], r.power["hydraulic-sf1.3"]["clamp"], rtol=1e-12)
    assert np.all(r.F_s["sf1.3"] >= 3000.0 * (1 - 1e-9))
    assert_allclose(r.F_s["slip"], r.F_s["hydraulic-slip"], rtol=1e-12)
    assert np.all(r.power["hydraulic-slip"]["alternator"] == 0)


def test_cli_json_keys_and_bad_input(tmp_path):
    f = tmp_path / "t.csv"
    f.write_text("time [s],speed [km/h]\n0,0\n1,5\n2,10\n3,12\n4,12\n5,8\n6,0\n")
    res = CliRunner().invoke(main, ["cycle", "--cycle", str(f), "--json",
                                    "--strategies", "hydraulic-sf1.3,slip"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    for key in ("schema", "units", "cycle", "distance_m", "duration_s", "wheel_energy_J",
                "strategies"):
        assert key in doc
    assert set(doc["strategies"]) == {"hydraulic-sf1.3", "slip"}
    for d in doc["strategies"].values():
        assert set(d["energy_J"]) == set(TERMS) and d["fuel_g"] > 0
    assert doc["strategies"]["hydraulic-sf1.3"]["saving"] == 0
    bad = tmp_path / "bad.csv"
    bad.write_text("time [s],speed [km/h]\n0,0\n0,1\n")
    for args, match in ((["--cycle", "wltc"], "--cycle 'wltc': not a shipped cycle"),
                        (["--cycle", str(bad)], "time = 0 s: must increase"),
                        (["--cycle", "nedc", "--strategies", "hydraulic"], "--strategies")):
        res = CliRunner().invoke(main, ["cycle", *args])
        assert res.exit_code == 2
        err = res.stderr.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("error:") and match in err[0]


def test_operating_rules_hold(short_run):
    """The ratio stays in the design range, the engine never below its driving speed while
    the car moves (the launch clutch slips below 11.2 km/h in LOW), at rest the variator
    stands (no losses) while its actuation holds the floor clamping."""
    r = short_run
    eng = default_params().engine
    moving = r.v > 0
    rest = ~moving
    assert rest.sum() > 5
    for s in STRATEGIES:
        rg = r.r_g[s][moving]
        assert np.all((rg >= RATIO_LIMITS[0]) & (rg <= RATIO_LIMITS[1]))
        assert np.all(r.omega_e[s][moving] >= eng.omega_drive * (1 - 1e-12))
        assert_allclose(r.omega_e[s][rest], eng.omega_idle, rtol=1e-12)
        P = r.power[s]
        assert np.all(P["variator_in"][rest] == 0) and np.all(P["launch"][rest] == 0)
        assert np.all(P["actuation"][rest] > 0)
        launch = P["launch"] > 0
        # the launch clutch slips only at LOW
        assert launch.any() and np.all(r.r_g[s][launch] == RATIO_LIMITS[0])


def test_plot_draws_the_four_panels(short_run):
    p = plot_drive_cycle(short_run)
    assert p.axes.shape == (4, 1)
    assert len(p.artists) == 1 + 3 * len(short_run.strategies)


def test_a_trace_header_unit_is_converted_or_refused():
    """A trace's header units go through the one table of the CSV readers
    (`empact._columns`): ``time [ms]``, ``[min]`` and ``speed [mph]`` give the trace of
    ``time [s]``, ``speed [km/h]`` (1 mph = 1.609344 km/h exactly), an unknown unit or a
    speed without one is one line (`time [ms]` was refused as a missing column)."""
    rows = [(0, 0.0), (60, 36.0), (120, 72.0), (180, 0.0)]
    ref = parse_trace("time [s],speed [km/h]\n" + "".join(f"{t},{v}\n" for t, v in rows), "s")
    for header, ft, fv in (("time [ms],speed [km/h]", 1e3, 1.0),
                           ("time [min],speed [km/h]", 1 / 60, 1.0),
                           ("time [s],speed [mph]", 1.0, 1 / 1.609344)):
        c = parse_trace(header + "\n" + "".join(f"{t * ft!r},{v * fv!r}\n" for t, v in rows),
                        "x")
        np.testing.assert_allclose(c.t, ref.t, rtol=1e-14, atol=0)
        np.testing.assert_allclose(c.v, ref.v, rtol=1e-14, atol=0)
    for header, match in (("time [s],speed [knots]", "unit [knots], which empact does not"),
                          ("time [s],speed", "column 'speed' has no unit")):
        with pytest.raises(ParameterError, match=re.escape(match)):
            parse_trace(header + "\n0,0\n1,1\n", "x")

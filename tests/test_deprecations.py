"""The names of empact 0.1 that issues 19-24 renamed keep working until empact 0.3.0, each
through the one helper (`empact._deprecate.warn_renamed`) with a DeprecationWarning that names
its replacement and the release that removes it, gives the same result as the new name, and is
left out of its module's ``__all__``."""
import importlib
import sys
import warnings

import numpy as np
import pytest

import empact
from empact import OperatingPoint
from empact._deprecate import REMOVAL, deprecation_message, warn_renamed
from empact.control.family import plant_family
from empact.control.pi import pi_controller
from empact.nonlinear.equilibrium import trim
from empact.nonlinear.linearization import plant, trim_point
from empact.nonlinear.model import ModelOptions, nonlinear_model
from empact.params import default_params

P = default_params()


def test_the_helper_names_the_replacement_and_the_removal():
    assert REMOVAL == "0.3.0"
    assert deprecation_message("old_name", "new_name") == (
        "old_name is deprecated and will be removed in empact 0.3.0; use new_name")
    with pytest.warns(DeprecationWarning) as rec:
        warn_renamed("a", "b", removal="9.9.0")
    assert str(rec[0].message) == "a is deprecated and will be removed in empact 9.9.0; use b"
    # stacklevel counts from the deprecated function's caller: the warning points here
    def deprecated():
        warn_renamed("deprecated()", "fresh()")
    with pytest.warns(DeprecationWarning) as rec:
        deprecated()
    assert rec[0].filename == __file__


def test_no_hand_written_deprecation_warning_is_left():
    """Every DeprecationWarning of empact goes through the helper (one wording, one removal)."""
    pkg = importlib.import_module("empact").__path__[0]
    from pathlib import Path
    hand = [f"{p.name}:{i}" for p in Path(pkg).rglob("*.py") if p.name != "_deprecate.py"
            for i, line in enumerate(p.read_text().splitlines(), 1)
            if "DeprecationWarning," in line or "warnings.warn(" in line and "deprecat" in line]
    assert hand == []


@pytest.mark.parametrize("old, new", [
    ("empact.geometry", "empact.variator.geometry"),
    ("empact.traction", "empact.variator.traction"),
    ("empact.shift_law", "empact.variator.shift_law"),
    ("empact.thrust_ratio", "empact.variator.thrust_ratio")])
def test_old_module_paths_warn_and_re_export(old, new):
    assert empact.DEPRECATED_MODULES[old] == new
    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning) as rec:
        mod = importlib.import_module(old)
    assert str(rec[0].message) == deprecation_message(old, new)
    assert f"removed in empact {REMOVAL}" in mod.__doc__ and new in mod.__doc__
    assert all(getattr(mod, n) is getattr(importlib.import_module(new), n)
               for n in importlib.import_module(new).__all__)


def _family():
    return plant_family(P, r_g=np.array([0.8, 1.2]))


def _frf():
    from empact.linear.actuation import actuation_model
    return actuation_model(P, 1.0).frequency_response(2 * np.pi * np.logspace(0, 2, 20),
                                                      ["T_mp"], ["theta_mp"])


def _plot_bode_axes():
    from empact.plotting import plot_bode
    a = plot_bode([_frf()], [("theta_mp", "T_mp")])
    return plot_bode([_frf()], [("theta_mp", "T_mp")], axes=a.axes)


def _trim_old():
    return trim(nonlinear_model(P), 1.0, 300.0, nu=0.004, F_s=1e4)


#: each deprecated name or form of the API: a call that uses it, and the replacement its
#: warning must name
CASES = {
    "OperatingPoint.as_dict": (lambda: P.operating.as_dict(), "to_dict"),
    "TrimResult.as_dict": (lambda: trim(nonlinear_model(P), P.operating).as_dict(), "to_dict"),
    "Claim.as_dict": (lambda: __import__("empact.reproduction.claims", fromlist=["Claim"]).Claim(
        key="k", source="s", claim="x", computed="y", shown=True).as_dict(), "to_dict"),
    "trim(model, r_g, omega_p, nu=, F_s=, T_l=)": (_trim_old, "trim(model, op)"),
    "trim_point(model, op)": (lambda: trim_point(nonlinear_model(P), P.operating),
                              "trim(model, op)"),
    "unpacking plant() as (system, trim)": (lambda: tuple(plant(P)), ".state_space() and .trim"),
    "Controller.statespace": (lambda: pi_controller([1.0, 1.0], [0.1, 0.1],
                                                    [10.0, 10.0]).statespace(), "state_space"),
    "linearise_belt": (lambda: __import__("empact.slip.coupling", fromlist=["x"])
                       .linearise_belt(P), "linearize_belt"),
    "ModelOptions.drive_bandwidth": (lambda: ModelOptions(drive_bandwidth=3.0),
                                     "drive_bandwidth_hz"),
    "ModelOptions.load_bandwidth": (lambda: ModelOptions(load_bandwidth=3.0),
                                    "load_bandwidth_hz"),
    "ModelOptions.ratio_bandwidth": (lambda: ModelOptions.from_mapping({"ratio_bandwidth": 1.5}),
                                     "ratio_bandwidth_hz"),
    "RigSettings.band": (lambda: __import__("empact.experiments.rig", fromlist=["x"])
                         .RigSettings(band=(1.0, 50.0)), "band_hz"),
    "nmp_analysis(f_max=)": (lambda: __import__("empact.nonlinear.nmp", fromlist=["x"])
                             .nmp_analysis(P, [1.0], f_max=50.0), "f_max_hz"),
    "NmpResult.f_max": (lambda: __import__("empact.nonlinear.nmp", fromlist=["x"])
                        .nmp_analysis(P, [1.0], f_max_hz=50.0).f_max, "f_max_hz"),
    "PlantFamily.at": (lambda: _family().at(r_g=1.0), "PlantFamily.interpolate"),
    "PlantFamily.interpolated_plant": (lambda: _family().interpolated_plant(r_g=1.0),
                                       "PlantFamily.interpolate(...).state_space()"),
    "residualize(f_keep=)": (lambda: __import__("empact.control.hinf", fromlist=["x"])
                             .residualize(np.diag([-1.0, -1e4]), np.ones((2, 1)),
                                          np.ones((1, 2)), np.zeros((1, 1)), f_keep=100.0),
                             "f_keep_hz"),
    "design_hinf(f_keep=)": (lambda: __import__("empact.control.hinf", fromlist=["x"])
                             .design_hinf(_family(), f_keep=100.0), "f_keep_hz"),
    "load_control_scenario": (lambda: empact.load_control_scenario(
        __import__("empact.control.closed_loop", fromlist=["x"])
        .control_example_path("slip-load-step-r1")), "load_scenario"),
    "empact.control.closed_loop.ControlScenario": (
        lambda: __import__("empact.control.closed_loop", fromlist=["x"]).ControlScenario,
        "empact.nonlinear.scenario.Scenario"),
    "plot_bode(axes=...)": (_plot_bode_axes, "ax="),
}


@pytest.mark.parametrize("old", sorted(CASES))
def test_each_deprecated_name_warns_with_its_replacement_and_removal(old):
    call, new = CASES[old]
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        call()
    messages = [str(w.message) for w in rec if issubclass(w.category, DeprecationWarning)
                and str(w.message).startswith(f"{old} is deprecated")]
    assert len(messages) == 1, [str(w.message) for w in rec]
    assert messages[0].startswith(deprecation_message(old, new)), messages[0]


def test_deprecated_names_are_importable_but_not_public():
    """Out of every ``__all__`` (so out of the API pages and ``import *``), still importable."""
    import empact.control.closed_loop as closed_loop
    import empact.nonlinear as nonlinear
    import empact.nonlinear.linearization as linearization
    import empact.slip as slip
    import empact.slip.coupling as coupling
    for module, name in [(slip, "linearise_belt"), (coupling, "linearise_belt"),
                         (nonlinear, "trim_point"), (linearization, "trim_point"),
                         (closed_loop, "load_control_scenario"),
                         (closed_loop, "ControlScenario"), (empact, "load_control_scenario")]:
        assert name not in module.__all__, (module.__name__, name)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            assert callable(getattr(module, name)), (module.__name__, name)
    assert set(empact.DEPRECATED_NAMES) <= set(dir(empact))


def test_renamed_callables_agree_with_their_replacements():
    m = nonlinear_model(P)
    op = OperatingPoint(r_g=1.0, nu=0.004, F_s=1e4, omega_p=300.0)
    ref = trim(m, op)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        assert np.array_equal(trim(m, 1.0, 300.0, nu=0.004, F_s=1e4).x, ref.x)
        assert np.array_equal(trim_point(m, op).x, ref.x)
        assert op.as_dict() == op.to_dict()
        assert ref.as_dict() == ref.to_dict()
        pl = plant(P)
        sys_, trimmed = pl
        assert sys_ is pl.state_space() and trimmed is pl.trim
        c = pi_controller([1.0, 1.0], [0.1, 0.1], [10.0, 10.0])
        assert np.array_equal(c.statespace().A, c.state_space().A)
        from empact.slip.coupling import linearise_belt, linearize_belt
        assert linearise_belt(P).c_b == linearize_belt(P).c_b
        assert ModelOptions(drive_bandwidth=3.0).drive_bandwidth_hz == 3.0
        assert ModelOptions.from_mapping({"ratio_bandwidth": 1.5}).ratio_bandwidth_hz == 1.5
        from empact.experiments.rig import RigSettings
        assert RigSettings(band=(1.0, 50.0)).band_hz == (1.0, 50.0)
        from empact.nonlinear.nmp import nmp_analysis
        res = nmp_analysis(P, [1.0], f_max=50.0)
        assert res.f_max == res.f_max_hz == 50.0
        fam = _family()
        assert np.array_equal(fam.at(r_g=1.0)[0], fam.interpolate(r_g=1.0).A)
        from empact.control.closed_loop import ControlScenario
        from empact.nonlinear.scenario import Scenario
        assert ControlScenario is Scenario
        from empact.plotting import plot_bode
        a = plot_bode([_frf()], [("theta_mp", "T_mp")])
        b = plot_bode([_frf()], [("theta_mp", "T_mp")], axes=a.axes)
        assert b.figure is a.figure

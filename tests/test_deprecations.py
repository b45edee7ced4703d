"""The names of empact 0.1 that issue 19 renamed keep working for one release, each with a
DeprecationWarning that names its replacement, and give the same result."""
import importlib
import sys

import numpy as np
import pytest

from empact import OperatingPoint
from empact.control.family import plant_family
from empact.control.pi import pi_controller
from empact.nonlinear.equilibrium import trim
from empact.nonlinear.linearization import plant, trim_point
from empact.nonlinear.model import ModelOptions, nonlinear_model
from empact.params import default_params

P = default_params()


@pytest.mark.parametrize("old, new", [
    ("empact.geometry", "empact.variator.geometry"),
    ("empact.traction", "empact.variator.traction"),
    ("empact.shift_law", "empact.variator.shift_law"),
    ("empact.thrust_ratio", "empact.variator.thrust_ratio")])
def test_old_module_paths_warn_and_re_export(old, new):
    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match=new.replace(".", r"\.")):
        mod = importlib.import_module(old)
    assert all(getattr(mod, n) is getattr(importlib.import_module(new), n)
               for n in importlib.import_module(new).__all__)


def test_renamed_callables_warn_and_agree():
    m = nonlinear_model(P)
    op = OperatingPoint(r_g=1.0, nu=0.004, F_s=1e4, omega_p=300.0)
    ref = trim(m, op)
    with pytest.warns(DeprecationWarning, match="pass an OperatingPoint"):
        old = trim(m, 1.0, 300.0, nu=0.004, F_s=1e4)
    assert np.array_equal(old.x, ref.x)
    with pytest.warns(DeprecationWarning, match=r"use trim\(model, op\)"):
        assert np.array_equal(trim_point(m, op).x, ref.x)
    with pytest.warns(DeprecationWarning, match="use to_dict"):
        assert op.as_dict() == op.to_dict()
    with pytest.warns(DeprecationWarning, match="use to_dict"):
        assert ref.as_dict() == ref.to_dict()
    pl = plant(P)
    with pytest.warns(DeprecationWarning, match=r"use \.state_space\(\) and \.trim"):
        sys_, trimmed = pl
    assert sys_ is pl.state_space() and trimmed is pl.trim
    c = pi_controller([1.0, 1.0], [0.1, 0.1], [10.0, 10.0])
    with pytest.warns(DeprecationWarning, match="use state_space"):
        assert np.array_equal(c.statespace().A, c.state_space().A)
    from empact.slip.coupling import linearise_belt, linearize_belt
    with pytest.warns(DeprecationWarning, match="use linearize_belt"):
        assert linearise_belt(P).c_b == linearize_belt(P).c_b


def test_renamed_options_and_fields_warn():
    with pytest.warns(DeprecationWarning, match="use drive_bandwidth_hz"):
        o = ModelOptions(drive_bandwidth=3.0)
    assert o.drive_bandwidth_hz == 3.0
    with pytest.warns(DeprecationWarning, match="use ratio_bandwidth_hz"):
        o = ModelOptions.from_mapping({"ratio_bandwidth": 1.5})
    assert o.ratio_bandwidth_hz == 1.5
    from empact.experiments.rig import RigSettings
    with pytest.warns(DeprecationWarning, match="use band_hz"):
        assert RigSettings(band=(1.0, 50.0)).band_hz == (1.0, 50.0)
    from empact.nonlinear.nmp import nmp_analysis
    with pytest.warns(DeprecationWarning, match="use f_max_hz"):
        res = nmp_analysis(P, [1.0], f_max=50.0)
    with pytest.warns(DeprecationWarning, match="use f_max_hz"):
        assert res.f_max == res.f_max_hz == 50.0
    fam = plant_family(P, r_g=np.array([0.8, 1.2]))
    with pytest.warns(DeprecationWarning, match="use PlantFamily.interpolate"):
        A = fam.at(r_g=1.0)[0]
    assert np.array_equal(A, fam.interpolate(r_g=1.0).A)
    from empact.linear.actuation import actuation_model
    from empact.plotting import plot_bode
    frf = actuation_model(P, 1.0).frequency_response(2 * np.pi * np.logspace(0, 2, 20),
                                                     ["T_mp"], ["theta_mp"])
    a = plot_bode([frf], [("theta_mp", "T_mp")])
    with pytest.warns(DeprecationWarning, match="use ax="):
        b = plot_bode([frf], [("theta_mp", "T_mp")], axes=a.axes)
    assert b.figure is a.figure

"""Parameter files: loading, saving, validation (issue 2, item 2)."""
import math
import re

import pytest

from empact.params import ParameterError, load_params, save_params


def write(tmp_path, text, name="p.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_round_trip(tmp_path, params):
    path = tmp_path / "out.toml"
    save_params(params, path)
    assert load_params(path) == params  # exact: floats are written with repr precision


def test_partial_file_overrides_defaults(tmp_path, params):
    loaded = load_params(write(tmp_path, "[driveline]\nJ_d = 0.2\n"))
    assert loaded.driveline.J_d == 0.2
    assert loaded.actuation == params.actuation


@pytest.mark.parametrize("text, match", [
    ("[driveline]\nJ_p = -0.01\n", r"p.toml: driveline\.J_p = -0\.01: allowed range is "
                                   r"\(1e-06, 100\] \[kg m\^2\]"),
    ("[operating]\nr_g = 5.0\n", r"operating\.r_g = 5\.0: outside the geometric ratio range"),
    ("[driveline]\nJ_x = 1.0\n", r"unknown key 'driveline\.J_x'"),
    ("[gearbox]\nk = 1.0\n", r"unknown key 'gearbox'"),
    ("[driveline]\nJ_p = \"heavy\"\n", r"driveline\.J_p = 'heavy': must be a number"),
    ("[driveline]\nJ_p = true\n", r"driveline\.J_p = true: must be a number"),
    ("[variator]\nbeta = 1.2\n", r"variator\.beta = 1\.2: allowed range is \[0\.0174533, "
                                 r"0\.523599\] \[rad\]"),
    ("[traction]\nD_med = 1.5\n", r"traction\.D_med = 1\.5"),
    ("driveline = 3\n", r"'driveline' must be a table"),
    ("[driveline\n", r"not valid TOML"),
])
def test_bad_values_are_refused(tmp_path, text, match):
    with pytest.raises(ParameterError, match=match):
        load_params(write(tmp_path, text))


def test_variator_consistency(tmp_path):
    with pytest.raises(ParameterError, match="R_max"):
        load_params(write(tmp_path, "[variator]\nR_min = 0.09\n"))





@pytest.mark.parametrize("text, match", [
    ('free = ["driveline.k_zz"]\n[[target]]\nmodel="driveline"\nuncoupled="primary"\n'
     'frequency_hz=1.0\n', "not a parameter name"),
    ('free = ["driveline.k_tc"]\n[[target]]\nmodel="gearbox"\nratio=1.0\nmode=2\n'
     'frequency_hz=1.0\n', "model = 'gearbox'"),
    ('free = ["driveline.k_tc"]\n[[target]]\nmodel="driveline"\nratio=1.0\nmode=0\n'
     'frequency_hz=1.0\n', "mode"),
    ('free = ["driveline.k_tc"]\n[[target]]\nmodel="driveline"\nratio=1.0\nmode=2\n'
     'frequency_hz=-1.0\n', "frequency_hz = -1: allowed range is \\(0, 1e\\+06\\] \\[Hz\\]"),
])
def test_bad_targets_are_refused(tmp_path, text, match):
    from empact.linear.calibration import load_targets

    with pytest.raises(ParameterError, match=match):
        load_targets(str(write(tmp_path, text, "t.toml")))


def test_describe_lists_every_field_with_unit_interval_and_text(params):
    """`describe` has one row per field, in field order, each with a unit, the allowed
    interval the validator uses and a description (the old version asserted
    ``not math.isnan(0)`` over the rows, which could not fail)."""
    from dataclasses import fields

    section = type(params.driveline)
    rows = section.describe()
    assert [r[0] for r in rows] == [f.name for f in fields(section)]
    assert rows[0][:3] == ("J_d", "kg m^2", "(1e-06, 1000]")
    assert all(unit and re.fullmatch(r"[(\[].+, .+[)\]]", interval) and text
               for _, unit, interval, text in rows), rows


def test_every_shipped_parameter_has_a_source_and_a_plausible_band():
    """Issue 20: `params show --describe` gives every shipped value its source (or rationale)
    and a plausible band; the value lies in its band and the band inside the allowed range."""

    from empact.params import describe_parameters

    infos = [p for p in describe_parameters() if p.value is not None]
    assert len(infos) > 80
    for p in infos:
        assert p.source, p.name
        lo, hi = p.band
        assert lo <= p.value <= hi, (p.name, p.value, p.band)
        a_lo, a_hi = (float(x.strip("[]() ")) for x in p.allowed.split(","))
        assert a_lo <= lo and hi <= a_hi, (p.name, p.band, p.allowed)
        assert math.isfinite(lo) and math.isfinite(hi)

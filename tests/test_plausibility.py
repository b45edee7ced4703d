"""Physical plausibility of parameter files (`empact.plausibility`), and a seeded fuzzer of
mutated parameter files: no crash, and every accepted file defines finite models with the
expected rigid-body modes."""
import math
import tomllib

import numpy as np
import pytest
import tomli_w

from empact.errors import ParameterError
from empact.linear.actuation import actuation_model
from empact.linear.driveline import driveline_model
from empact.params import dumps_params, load_params
from empact.plausibility import EXPECTED_RIGID_MODES, check_plausible
from empact.slip import slip_model
from empact.variator.geometry import ratio_range

N_FUZZ = 600


def _leaves(d, prefix=()):
    for k, v in d.items():
        if isinstance(v, dict):
            yield from _leaves(v, prefix + (k,))
        else:
            yield prefix + (k,)


def _mutate(rng, base: dict) -> str:
    """One mutated parameter file (TOML text, or raw bytes-like garbage as text)."""
    doc = {k: (dict(v) if not isinstance(v, dict) else
               {kk: (dict(vv) if isinstance(vv, dict) else vv) for kk, vv in v.items()})
           for k, v in base.items()}
    keys = list(_leaves(doc))
    for _ in range(rng.integers(1, 4)):
        path = keys[rng.integers(len(keys))]
        node = doc
        for p in path[:-1]:
            node = node[p]
        old = node.get(path[-1], 1.0)  # (an earlier mutation may have removed it: kind 12)
        if isinstance(old, bool) or not isinstance(old, (int, float)):
            old = 1.0  # (an earlier mutation of this file made it text, a list, a table)
        kind = rng.integers(14)
        if kind == 0:
            new = float(old) * 10.0 ** rng.integers(-15, 16)      # scaled by decades
        elif kind == 1:
            new = -abs(float(old)) - 1e-3                          # negative
        elif kind == 2:
            new = 0.0
        elif kind == 3:
            new = float(10.0 ** rng.uniform(-300, 300))           # anything positive
        elif kind == 4:
            new = "abc"
        elif kind == 5:
            new = bool(rng.integers(2))
        elif kind == 6:
            new = int("9" * int(rng.integers(20, 500)))           # an integer too large
        elif kind == 7:
            new = [1.0, 2.0]
        elif kind == 8:
            new = {"x": 1.0}
        elif kind == 9:
            new = float(old) * rng.uniform(0.5, 1.5)               # plausible change
        elif kind == 10:
            new = float(rng.choice([math.inf, -math.inf, math.nan]))
        elif kind == 11:
            node[f"unknown_{rng.integers(100)}"] = 1.0
            continue
        elif kind == 12:  # the operating point by torque ratio or load (issue 10's options)
            op = doc.setdefault("operating", {})
            op[str(rng.choice(["tau", "T_l"]))] = float(rng.choice(
                [rng.uniform(-2, 2), rng.uniform(-500, 500), 0.9, 60.0, math.nan]))
            if rng.integers(2):
                op.pop(str(rng.choice(["nu", "F_s"])), None)
            continue
        else:  # a number written as text
            new = str(old)
        node[path[-1]] = new
    try:
        text = tomli_w.dumps(doc)
    except (TypeError, ValueError):  # nan / inf: write TOML by hand
        text = tomli_w.dumps({k: v for k, v in doc.items() if k != "operating"}) + \
            "\n[operating]\nnu = nan\n"
    edit = rng.integers(12)
    if edit == 0:  # as a spreadsheet or Windows editor saves it (accepted or one line)
        text = "\ufeff" + text
    elif edit == 1:
        text = text.replace("\n", "\r\n")
    elif edit == 2:  # truncated
        text = text[:int(rng.integers(1, max(2, len(text))))]
    return text


def _models_sound(params) -> None:
    """What every accepted file must give: finite linear models with exactly their expected
    rigid-body modes and finite positive elastic frequencies over the ratio range (five ratios,
    more than the validation itself looks at), and a finite slip model at the operating
    point."""
    lo, hi = ratio_range(params.variator)
    assert np.all(np.isfinite(slip_model(params).A))
    for r in np.geomspace(lo, hi, 5):
        for name, build in (("actuation", actuation_model), ("driveline", driveline_model)):
            lm = build(params, r)
            assert np.all(np.isfinite(lm.M)) and np.all(np.isfinite(lm.K)), (name, r)
            m = lm.modes()
            assert m.n_rigid == EXPECTED_RIGID_MODES[name], (name, r, m.frequencies_hz)
            f = m.frequencies_hz[m.n_rigid:]
            assert np.all(np.isfinite(f) & (f > 0)), (name, r, f)


def test_fuzzed_parameter_files(tmp_path):
    rng = np.random.default_rng(20261122)
    base = tomllib.loads(dumps_params(load_params()))
    accepted = refused = 0
    for k in range(N_FUZZ):
        path = tmp_path / f"f{k}.toml"
        text = _mutate(rng, base)
        path.write_text(text)
        try:
            params = check_plausible(load_params(path), str(path))
        except ParameterError as exc:
            msg = str(exc)
            assert "\n" not in msg and msg.startswith(str(path)), msg  # one line, names file
            refused += 1
            continue
        accepted += 1
        _models_sound(params)
    # a seeded fuzzer must exercise both outcomes
    assert accepted > 30 and refused > 200, (accepted, refused)


def test_shipped_set_is_plausible(params):
    assert check_plausible(params) is params
    _models_sound(params)


@pytest.mark.parametrize("text, match", [
    ("[operating]\nnu = 0.5\n", r"operating.nu = 0.5: outside the valid slip range"),
    ("[operating]\nF_s = 0.0\n", r"operating.F_s = 0: allowed range is \(0, inf\)"),
])
def test_operating_point_must_be_usable(tmp_path, text, match):
    path = tmp_path / "p.toml"
    path.write_text(text)
    with pytest.raises(ParameterError, match=match):
        check_plausible(load_params(path), str(path))


def test_span_beyond_double_precision_names_the_keys(params):
    # inside every key's own range, but together 17 decades apart: extra rigid-body modes
    bad = params.from_dotted({"actuation.k_tp": 1e12, "actuation.k_ts": 1e12,
                              "actuation.k_w": 2e-3, "actuation.k_c": 2e-3,
                              "actuation.J_mp": 1.0, "actuation.J_ms": 1.0,
                              "actuation.m_p": 0.02, "actuation.m_s": 0.02})
    with pytest.raises(ParameterError, match=r"rigid-body modes, expected 1.*largest "
                                             r"actuation.k_tp"):
        check_plausible(bad, "x.toml")


@pytest.mark.parametrize("text", ["[operating]\nr_g = 1.0\nnu = 0.004\nT_l = 60.0\n"
                                  "omega_p = 300.0\n", "[operating]\ntau = 0.9\nT_l = 60.0\n"])
def test_a_point_given_by_torque_ratio_or_load_is_checked(tmp_path, text):
    """Found by the fuzzer (issue 22): a file whose [operating] point is given by a load (or a
    torque ratio and a load) crashed the check and the slip model (None compared with 0);
    its slip and clamping force are solved first."""
    path = tmp_path / "p.toml"
    path.write_text(text)
    params = check_plausible(load_params(path), str(path))
    assert params.operating.F_s is None
    _models_sound(params)  # the slip model at the resolved point

"""The one checker of values and options (`empact._validate`): message format."""
import math

import numpy as np
import pytest

from empact._validate import check_bool, check_choice, check_int, check_number, check_values, fmt
from empact.errors import ParameterError


@pytest.mark.parametrize("call, match", [
    (lambda: check_number("k_w", -1.0, 0.0, lo_open=True, unit="N m/rad"),
     r"^k_w = -1: allowed range is \(0, inf\) \[N m/rad\]$"),
    (lambda: check_number("beta", 2.0, 0.0, 0.785, lo_open=True, unit="rad", where="p.toml"),
     r"^p.toml: beta = 2: allowed range is \(0, 0.785\] \[rad\]$"),
    (lambda: check_number("x", "abc"), r"^x = 'abc': must be a number in \(-inf, inf\)$"),
    (lambda: check_number("x", True), r"^x = true: must be a number"),
    (lambda: check_number("x", math.nan), r"^x = nan: must be a finite number in"),
    (lambda: check_number("x", 10**400), r"^x = 10000000\.\.\.\(401 digits\): too large"),
    (lambda: check_number("w", 0.0, 0.0, lo_open=True, note="why"),
     r"^w = 0: allowed range is \(0, inf\) \(why\)$"),
    (lambda: check_values("nu", [0.1, 2.0, 3.0], -1, 1), r"^nu = 2: allowed range is \[-1, 1\]$"),
    (lambda: check_int("--n", 2.5, 2), r"^--n = 2.5: must be a whole number in \[2, inf\)$"),
    (lambda: check_choice("method", "H3", ("H1", "H2")), r"^method = 'H3': must be one of H1, H2$"),
    (lambda: check_bool("ratio_control", 1), r"^ratio_control = 1: must be true or false$"),
])
def test_one_line_messages(call, match):
    with pytest.raises(ParameterError, match=match):
        call()


def test_values_pass_through():
    assert check_number("x", np.float64(0.499), 0, 1) == 0.499
    assert fmt(np.float64(0.499)) == "0.499"  # never np.float64(0.499)
    assert check_int("n", 1e3, 1) == 1000
    assert check_values("v", [1, 2], 0).tolist() == [1.0, 2.0]

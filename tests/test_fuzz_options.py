"""A seeded fuzzer of command-line options (the companion of the parameter-file fuzzer in
`test_plausibility`): every numeric, list and choice option of the commands, the operating
point options added since issue 10 (--tau, --load-torque, --drive, --load) included, gets
hostile values (NaN, infinities, huge, empty, empty list items, wrong separators, text).
Whatever the value, a command ends with exit status 0 (the value was fine), 1 (the run did
not succeed) or 2 with one ``error:`` line naming the option, no internals, and nothing
written."""
import os

import numpy as np
import pytest
from click.testing import CliRunner
from test_cli import LEAKS, PROGRESS

from empact.cli import main

#: command (cheap with any acceptable value) -> the options fuzzed
TARGETS = {
    ("modes", "driveline"): ["--ratio"],
    ("modes", "actuation"): ["--ratio", "--kinematics"],
    ("frf", "actuation", "--n", "5"): ["--ratio", "--fmin", "--fmax", "--speed", "--clamp",
                                       "--damping", "--input", "--output"],
    ("slip", "poles"): ["--ratio", "--slip", "--clamp", "--speed"],
    ("slip", "statespace"): ["--ratio", "--slip", "--clamp", "--speed"],
    ("slip", "zeros"): ["--ratio"],
    ("slip", "traction"): ["--ratio", "--slip"],
    ("slip", "rootlocus"): ["--ratio", "--slip", "--cb-min", "--cb-max"],
    ("slip", "frf", "--n", "5"): ["--fmin", "--fmax", "--n", "--input", "--output"],
    ("slip", "map", "--slip", "0.01:0.04:3", "--ratio", "0.5:2:3"): ["--chunk", "--workers",
                                                                      "--clamp", "--method"],
    ("linearize",): ["--ratio", "--slip", "--tau", "--clamp", "--load-torque", "--speed",
                     "--drive", "--load", "--shift-law", "--format"],
    ("nmp", "--ratios", "1"): ["--ratios", "--slip", "--tau", "--clamp", "--load-torque",
                               "--speed", "--fmax", "--drive", "--load", "--slip-signal"],
    ("plants", "--ratio", "0.5,1"): ["--ratio", "--slip", "--tau", "--clamp", "--speed",
                                     "--load-torque", "--drive", "--load", "--workers",
                                     "--scheduler-timeout"],
    ("identify", "--ratios", "1", "--order", "0"): ["--ratios", "--slip", "--clamp", "--speed",
                                                    "--step"],
    ("rig", "--out", "r.csv", "--seed", "-1"): ["--ratio", "--slip", "--clamp", "--speed",
                                                "--rms", "--band", "--duration", "--fs",
                                                "--friction", "--excite"],
    ("control", "design", "--out", "c.json", "--nominal", "99,99"): [
        "--bandwidth", "--alpha-min", "--ratio", "--slip", "--tau", "--load-torque"],
    ("montecarlo", "--runs", "0"): ["--seed", "--workers", "--scheduler-timeout", "--analysis"],
    ("simulate", "--example", "servo-torque-steps", "--quiet", "--out", "."): ["--duration"],
    ("reproduce", "--out", "."): ["--formats", "--sections"],
}

HOSTILE = ["nan", "NaN", "inf", "-inf", "1e400", "-1e400", "", " ", ",", "1,,2", ",1",
           "1,", "x", "1:2", "1:2:0", "1:2:x", "0:0:5", "1e9", "-1e9", "0", "-0", "1e-320",
           "0x10", "1_000", "1;2", "9" * 400, "0.5:2:100000", "--", "１", "1 2", "true",
           "[1]", "1e3.5", "+-1", "-1"]

N_CASES = 240


def _cases():
    rng = np.random.default_rng(20261122)
    items = [(base, opt) for base, opts in TARGETS.items() for opt in opts]
    out = []
    for k in range(N_CASES):
        base, opt = items[k % len(items)] if k < len(items) else \
            items[rng.integers(len(items))]
        out.append((base, opt, HOSTILE[rng.integers(len(HOSTILE))]))
    return out


CASES = _cases()


@pytest.mark.parametrize("base, option, value", CASES,
                         ids=[f"{' '.join(b[:2])} {o}={v[:12]!r}" for b, o, v in CASES])
def test_hostile_option_values(tmp_path, monkeypatch, base, option, value):
    monkeypatch.chdir(tmp_path)
    args = [*base, option, value]
    if "montecarlo" in base:
        (tmp_path / "s.toml").write_text('[spread."actuation.k_w"]\ndistribution = "normal"\n'
                                         'rel_std = 0.05\n')
        args += ["--spread", "s.toml"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code in (0, 1, 2), (args, res.output)
    assert res.exception is None or isinstance(res.exception, SystemExit), (args, res.output)
    assert LEAKS.search(res.output) is None, (args, res.output)
    if res.exit_code == 2:
        lines = [ln for ln in res.output.strip().splitlines() if not PROGRESS.match(ln)]
        assert len(lines) == 1 and lines[0].startswith("error: "), (args, res.output)
        assert list(tmp_path.glob("*")) in ([], [tmp_path / "s.toml"]), args  # nothing written


def test_the_fuzzer_reaches_every_option_and_both_outcomes(tmp_path, monkeypatch):
    """Every listed option is fuzzed; the seeded values include accepted and refused ones."""
    assert {(b, o) for b, o, _ in CASES} == {(b, o) for b, opts in TARGETS.items()
                                            for o in opts}
    monkeypatch.chdir(tmp_path)
    codes = [CliRunner().invoke(main, [*base, option, value]).exit_code
             for base, option, value in CASES[:80] if base[0] in ("modes", "frf", "slip")]
    assert codes.count(0) >= 1 and codes.count(2) >= 20, codes


# -- issue 35: hostile paths for every path option and argument (walked, so that new commands
# and options are fuzzed without a line here) -----------------------------------------------
from test_cli import ALL_COMMANDS  # noqa: E402 (the walk of test_cli)

PATH_HOSTILE = ["", " ", "x" * 300, "x" * 200 + "/" + "y" * 256 + ".json", "pipe", "/dev/null",
                "/dev/zero", "plain.txt/sub.json", "dangling", "dangling.json", "\t"]

N_PATH_CASES = 160


def _path_cases():
    import click

    items = [(path, max(p.opts, key=len) if isinstance(p, click.Option) else None)
             for path, cmd in ALL_COMMANDS for p in cmd.params
             if isinstance(p.type, click.Path)]
    rng = np.random.default_rng(20261202)
    return [(*items[k % len(items)], PATH_HOSTILE[rng.integers(len(PATH_HOSTILE))])
            for k in range(max(N_PATH_CASES, len(items)))]


PATH_CASES = _path_cases()


@pytest.mark.parametrize("path, option, value", PATH_CASES,
                         ids=[f"{' '.join(p)} {o} {v[:10]!r}" for p, o, v in PATH_CASES])
def test_hostile_paths(tmp_path, monkeypatch, path, option, value):
    """A path that cannot be a file empact reads or writes (empty, too long, a FIFO, a
    device, through a file, a dangling link) is refused in one line, exit 2, nothing written,
    nothing left behind."""
    monkeypatch.chdir(tmp_path)
    os.mkfifo(tmp_path / "pipe")
    (tmp_path / "plain.txt").write_text("mine")
    os.symlink(tmp_path / "nowhere" / "x", tmp_path / "dangling")
    os.symlink(tmp_path / "nowhere" / "x.json", tmp_path / "dangling.json")
    before = sorted(p.name for p in tmp_path.iterdir())
    args = [*path, option, value] if option else [*path, value]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 2, (args, res.output)
    lines = [ln for ln in res.output.strip().splitlines() if not PROGRESS.match(ln)]
    assert len(lines) == 1 and lines[0].startswith("error: "), (args, res.output)
    assert LEAKS.search(res.output) is None, (args, res.output)
    assert sorted(p.name for p in tmp_path.iterdir()) == before, args
    assert (tmp_path / "plain.txt").read_text() == "mine"

"""`empact._compile.compile_all` compiles every entry a command or a test compiles (issue 36,
item 1): a first run after ``make`` (which runs it) is as fast as the second.

The cache is warm in a test session, so a compile event proves nothing missing; what does is
the set of signatures a process holds (`loaded_signatures`): one that a run holds after
`compile_all` and that `compile_all` alone does not would be compiled on a fresh install's
first run.  `compile_all` runs alone in a subprocess (``python -m empact._compile --json``)
and its signatures are compared with those of (1) the commands' compiled paths (a rig run,
every shipped scenario and closed loop, a family, a stability map, a Monte Carlo) run in a
subprocess after it, and (2) this test session itself (the test runs last: conftest), every
test module it ran included.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from empact._compile import cold_signatures, loaded_signatures, record_path

SRC = Path(__file__).resolve().parents[1] / "src"
TESTS = Path(__file__).resolve().parent

#: the commands' compiled paths, each run briefly after `compile_all` in one process: the
#: signatures it then holds that `compile_all` did not load, and numba's compile events
COMMANDS = r"""
import json, sys
import numpy as np
from numba.core import event
from empact._compile import compile_all, loaded_signatures

compiled = []
class Listener(event.Listener):
    def on_start(self, ev):
        d = ev.data["dispatcher"]
        compiled.append(f"{d.py_func.__module__}.{d.py_func.__qualname__}")
    def on_end(self, ev):
        pass
event.register("numba:compile", Listener())
compile_all()
before = loaded_signatures()

from empact.control.closed_loop import control_examples, control_example_path, run_closed_loop
from empact.control.family import plant_family
from empact.experiments.rig import RigSettings, rig_frf, run_rig
from empact.montecarlo import load_spread, monte_carlo
from empact.nonlinear.scenario import example_path, list_examples, load_scenario
from empact.nonlinear.simulation import run_scenario
from empact.params import default_params
from empact.slip.stability import stability_map
from importlib.resources import files

params = default_params()
rec = run_rig(params, RigSettings(duration=0.512, period=128, settle=0.128))  # Rodas5P
rig_frf(rec)
for name in list_examples(closed_loop=False):
    run_scenario(load_scenario(example_path(name)).with_duration(0.01), params)
for name in control_examples():
    sc = load_scenario(control_example_path(name))
    run_closed_loop(sc.with_duration(min(0.01, sc.duration)), params)
plant_family(params, r_g=np.array([0.7, 1.3]), nu=np.array([0.005, 0.01]))
stability_map(params, "nu", [0.005, 0.01], "r_g", [0.7, 1.3], workers=1)
spread = load_spread(str(files("empact.data") / "montecarlo" / "example-spread.toml"), params)
sc = load_scenario(control_example_path("slip-load-step-r1")).with_duration(0.05)
monte_carlo(params, spread, 2, "closed-loop", scenario=sc)
monte_carlo(params, spread, 2, "plant")
monte_carlo(params, spread, 2, "slip")
json.dump({"new": sorted(loaded_signatures() - before), "compiled": compiled}, sys.stdout)
"""


def _run(args: list[str], **env: str) -> str:
    proc = subprocess.run([sys.executable, *args], capture_output=True, text=True,
                          timeout=600, env={**os.environ, "MPLBACKEND": "Agg", **env})
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc.stdout.strip().splitlines()[-1]


@pytest.fixture(scope="module")
def compile_all_signatures(tmp_path_factory) -> set[tuple[str, str, str]]:
    """The signatures `compile_all` alone holds in a fresh process with an empty cache, as
    ``make`` runs it on a fresh install.  Compiling, a process also holds (and caches) the
    callees a caller compiles in; loading the caller from a warm cache it holds neither: a
    session that compiled (its sources newer than the cache) holds those callees, which a
    warm `compile_all` would not list though ``make`` writes them.

    ``make``'s compile on an empty cache records them with a digest of the package's files
    and the compiler's versions (`empact._compile.record_if_cold`); while the digest is the
    sources' (`cold_signatures`) that record is this answer.  Else (a source edited since)
    `compile_all` runs on an empty cache here (about 200 s of CPU) and its record is kept
    for the next session."""
    recorded = cold_signatures()
    if recorded is not None:
        return recorded
    cache = tmp_path_factory.mktemp("numba-cache")
    doc = json.loads(_run(["-m", "empact._compile", "--json"], NUMBA_CACHE_DIR=str(cache)))
    record, keep = cache / "empact-compile-all.json", record_path()
    if record.is_file():  # the compile of these sources on an empty cache: kept for the next
        tmp = keep.with_name(f"{keep.name}.{os.getpid()}.tmp")
        keep.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(record, tmp)
        tmp.replace(keep)
    return {tuple(s) for s in doc["signatures"]}


def test_the_record_of_a_compile_on_an_empty_cache_is_its_signatures(compile_all_signatures):
    """The record (`cold_signatures`) and a fresh compile on an empty cache agree: the one
    the fixture read or wrote carries the digest of these sources, and lists a callee that
    only a compile holds (the kernel's right-hand side, compiled into the integrators)."""
    assert cold_signatures() == compile_all_signatures
    assert any(f == "_eval" and m.endswith("_kernel") for m, f, _ in compile_all_signatures)


@pytest.mark.slow
def test_the_commands_compile_nothing_after_compile_all(compile_all_signatures):
    """A rig (Rodas5P), every shipped scenario and closed loop, a family, a stability map
    and the three Monte Carlo analyses, after `compile_all` in the same process: no
    signature it did not load, no compile."""
    doc = json.loads(_run(["-c", COMMANDS]))
    assert doc["new"] == [], "compile_all misses: " + "; ".join(map(str, doc["new"]))
    assert doc["compiled"] == []


def test_the_session_compiled_nothing_compile_all_does_not(compile_all_signatures):
    """Every signature this test session holds (of the package's dispatchers and the tests'
    own) is one `compile_all` loads: the tests that ran before this one (it runs last, see
    conftest) compile nothing on a fresh install after ``make``."""
    held = loaded_signatures((SRC / "empact", TESTS))
    missing = sorted(held - compile_all_signatures)
    assert missing == [], "compile_all misses: " + "; ".join(map(str, missing))

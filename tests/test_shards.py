"""Streamed studies (issue 36, item 5): shards and manifest written as chunks complete, a
killed study resumed from its shards, bitwise the in-memory table for 1 and 2 workers and
after a resume, a resume of another study refused in one line."""
from __future__ import annotations

import dataclasses
import json
import os
import re
import signal
import subprocess
import sys
import time
import tracemalloc

import numpy as np
import pytest
from click.testing import CliRunner

from empact.cli import main
from empact.export import jsonable
from empact.montecarlo import monte_carlo, save_montecarlo, spread_from_dict
from empact.montecarlo import study as study_mod
from empact.params import default_params
from empact.shards import MANIFEST, SHARDS, ShardStore, StudyMismatch
from empact.sweep import SweepOptions

P = default_params()

#: a spread that makes some runs fail (a negative stiffness is out of its allowed range), so
#: that failed runs and their reasons go through the shards too
FAILING = {"spread": {"actuation.k_w": {"distribution": "normal", "mean": 10.0, "std": 12.0},
                      "operating.nu": {"distribution": "uniform", "lower": 0.003,
                                       "upper": 0.008}}}
SPREAD = spread_from_dict(FAILING, P)
#: chunks of 2 slip runs (SECONDS_PER_RUN["slip"] = 2 ms): 6 chunks for 12 runs
TINY = 0.004
#: runs of the tiny study (seed 7: one of them fails)
RUNS = 12


def same_table(a, b) -> None:
    """Bitwise the same runs: samples, values (NaN where failed), ok, reasons, the CSV."""
    np.testing.assert_array_equal(a.samples, b.samples)
    np.testing.assert_array_equal(a.values, b.values)
    np.testing.assert_array_equal(a.ok, b.ok)
    assert a.reasons == b.reasons
    assert a.to_csv() == b.to_csv()


@pytest.fixture(scope="module")
def in_memory():
    res = monte_carlo(P, SPREAD, RUNS, "slip", seed=7)
    assert 0 < res.failures < RUNS  # failures are among the runs stored
    return res


def test_stored_study_writes_shards_and_manifest(tmp_path, in_memory):
    res = monte_carlo(P, SPREAD, RUNS, "slip", seed=7, store=tmp_path, chunk_seconds=TINY)
    same_table(in_memory, res)
    doc = json.loads((tmp_path / MANIFEST).read_text())
    assert doc["schema"]["name"] == "empact.study.manifest"
    assert doc["spec"]["seed"] == 7 and doc["spec"]["runs"] == RUNS and doc["runs"] == RUNS
    assert doc["spec"]["analysis"] == "slip" and doc["chunk_size"] == 2
    assert doc["chunks"][0] == [0, 2] and doc["chunks"][-1] == [10, 12]
    assert doc["completed"] == list(range(6))
    shards = sorted(p.name for p in (tmp_path / SHARDS).iterdir())
    assert shards == [f"chunk-{k:06d}.npz" for k in range(6)]  # no temporary file left
    with np.load(tmp_path / SHARDS / shards[3]) as z:  # runs 6 and 7, whatever columns
        assert set(z.files) == {"samples", "values", "ok", "reasons"}
        np.testing.assert_array_equal(z["values"], in_memory.values[6:8])


def test_a_killed_study_resumes_bitwise_and_reruns_only_the_lost_chunks(tmp_path, monkeypatch,
                                                                        in_memory):
    """The study is killed (an exception, as a Ctrl-C) while its 4th chunk runs: 3 shards
    stay; the resume computes the other 3 chunks only and gives the in-memory table."""
    real, calls = study_mod._run_chunk, []

    def dies_at_the_fourth(task):
        calls.append(task[4])
        if len(calls) == 4:
            raise KeyboardInterrupt
        return real(task)

    monkeypatch.setattr(study_mod, "_run_chunk", dies_at_the_fourth)
    with pytest.raises(KeyboardInterrupt):
        monte_carlo(P, SPREAD, RUNS, "slip", seed=7, store=tmp_path, chunk_seconds=TINY)
    assert json.loads((tmp_path / MANIFEST).read_text())["completed"] == [0, 1, 2]
    assert len(list((tmp_path / SHARDS).iterdir())) == 3
    calls.clear()
    monkeypatch.setattr(study_mod, "_run_chunk", lambda task: calls.append(task[4])
                        or real(task))
    res = monte_carlo(P, SPREAD, RUNS, "slip", seed=7, store=tmp_path, resume=True,
                      chunk_seconds=TINY)
    assert calls == [6, 8, 10]  # the lost chunk and the 2 not started
    same_table(in_memory, res)


def test_one_and_two_workers_and_a_resume_on_two_are_bitwise_equal(tmp_path, in_memory):
    one = monte_carlo(P, SPREAD, RUNS, "slip", seed=7, store=tmp_path / "one",
                      chunk_seconds=TINY)
    two = monte_carlo(P, SPREAD, RUNS, "slip", seed=7, store=tmp_path / "two",
                      chunk_seconds=TINY, sweep=SweepOptions(workers=2))
    for k in (1, 4, 5):  # lose three chunks, resume on two workers
        (tmp_path / "two" / SHARDS / f"chunk-{k:06d}.npz").unlink()
    again = monte_carlo(P, SPREAD, RUNS, "slip", seed=7, store=tmp_path / "two", resume=True,
                        chunk_seconds=TINY, sweep=SweepOptions(workers=2))
    for res in (one, two, again):
        same_table(in_memory, res)


def test_a_study_on_dask_streams_and_resumes_bitwise(tmp_path, cluster, in_memory):
    """The dask-jobqueue recipe with a `LocalCluster` standing in (the suite's cluster: slow):
    the shards written from Dask's completed futures; two lost, the resume on it bitwise."""
    opts = SweepOptions(scheduler=cluster)
    res = monte_carlo(P, SPREAD, RUNS, "slip", seed=7, store=tmp_path, chunk_seconds=TINY,
                      sweep=opts)
    same_table(in_memory, res)
    for k in (0, 3):
        (tmp_path / SHARDS / f"chunk-{k:06d}.npz").unlink()
    again = monte_carlo(P, SPREAD, RUNS, "slip", seed=7, store=tmp_path, resume=True,
                        chunk_seconds=TINY, sweep=opts)
    same_table(in_memory, again)


@pytest.fixture(scope="module")
def stored(tmp_path_factory):
    folder = tmp_path_factory.mktemp("stored")
    monte_carlo(P, SPREAD, RUNS, "slip", seed=7, store=folder, chunk_seconds=TINY)
    return folder


@pytest.mark.parametrize("change, field", [
    ({"seed": 8}, "seed"), ({"runs": 41}, "runs"), ({"analysis": "plant"}, "analysis"),
    ({"spread": spread_from_dict({"spread": {"actuation.k_w": {
        "distribution": "uniform", "lower": 5.0, "upper": 6.0}}}, P)}, "spread"),
    ({"params": P.from_dotted({"actuation.k_w": 11.0})}, "parameters")])
def test_resume_refuses_another_study(stored, change, field):
    """Checked before any run: the manifest is left as it was."""
    before = (stored / MANIFEST).read_bytes()
    args = {"params": P, "spread": SPREAD, "runs": RUNS, "analysis": "slip", "seed": 7,
            **change}
    with pytest.raises(StudyMismatch, match=rf"the study there differs \({field} "):
        monte_carlo(args["params"], args["spread"], args["runs"], args["analysis"],
                    seed=args["seed"], store=stored, resume=True)
    assert (stored / MANIFEST).read_bytes() == before


def test_resume_of_a_folder_that_is_no_study(tmp_path):
    (tmp_path / MANIFEST).write_text("{not json")
    with pytest.raises(StudyMismatch, match="not a study folder"):
        ShardStore.open(tmp_path, {"seed": 1})


def cli(*args):
    return CliRunner().invoke(main, ["montecarlo", *[str(a) for a in args]])


def test_cli_resume_bad_input_one_line_exit_2(tmp_path):
    spread = tmp_path / "spread.toml"
    spread.write_text('[spread."operating.nu"]\ndistribution = "uniform"\nlower = 0.004\n'
                      'upper = 0.006\n')
    base = ["--spread", spread, "--runs", 6, "--analysis", "slip", "--quiet"]
    cases = [(["--resume"], "--resume: give the study's folder with --out DIR"),
             (["--resume", "--out", tmp_path / "none"], "not a study folder (no manifest"),
             (["--resume", "--out", tmp_path], "not a study folder (no manifest")]
    for extra, text in cases:
        res = cli(*base, *extra)
        assert res.exit_code == 2 and res.output.count("\n") == 1, res.output
        assert res.output.startswith("error: ") and text in res.output
    assert not (tmp_path / "none").exists()
    study = tmp_path / "study"
    assert cli(*base, "--out", study).exit_code == 0
    table = (study / "runs.csv").read_bytes()
    res = cli(*base, "--out", study, "--resume", "--seed", 3)
    assert res.exit_code == 2 and res.output.count("\n") == 1
    assert "the study there differs (seed 0 there, 3 here)" in res.output
    assert (study / "runs.csv").read_bytes() == table  # nothing written
    (study / SHARDS / "chunk-000000.npz").unlink()
    assert cli(*base, "--out", study, "--resume").exit_code == 0
    assert (study / "runs.csv").read_bytes() == table


#: a study in a child process: 40 slip runs in chunks of 4 (`TINY` * 2), 10 shards
CHILD = """
import sys
from empact.montecarlo import monte_carlo, spread_from_dict
from empact.params import default_params
P = default_params()
spread = spread_from_dict({spread!r}, P)
monte_carlo(P, spread, 40, "slip", seed=7, store=sys.argv[1], chunk_seconds={seconds!r})
"""


def test_a_sigkilled_study_resumes_bitwise(tmp_path):
    """A real ``kill -9`` of a process running a stored study once its first chunk is
    written (a subprocess, slow); the resume here completes it: the in-memory table."""
    code = CHILD.format(spread=FAILING, seconds=2 * TINY)
    proc = subprocess.Popen([sys.executable, "-c", code, str(tmp_path)], env=os.environ.copy())
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:
            m = tmp_path / MANIFEST
            if m.is_file() and json.loads(m.read_text())["completed"]:
                break
            time.sleep(0.01)
        assert proc.poll() is None, "the study ended before it could be killed"
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.wait()
    done = json.loads((tmp_path / MANIFEST).read_text())
    assert 1 <= len(done["completed"]) < len(done["chunks"]) == 10
    res = monte_carlo(P, SPREAD, 40, "slip", seed=7, store=tmp_path, resume=True,
                      chunk_seconds=2 * TINY)
    same_table(monte_carlo(P, SPREAD, 40, "slip", seed=7), res)


def test_a_manifest_is_trusted_only_when_it_checks_and_a_damaged_shard_is_named(tmp_path):
    """`ShardStore.open` reads the manifest through the guarded reader and checks it (issue
    35's campaign: a manifest nested 50 000 deep raised RecursionError, one of schema version
    99 or with completed chunks -5 and 1e9 was resumed, a damaged shard raised BadZipFile):
    each is one `StudyMismatch` line naming the file and what is wrong."""
    spec = {"analysis": "plant", "seed": 0, "runs": 4}
    store = ShardStore.create(tmp_path / "s", spec, [(0, 2), (2, 4)])
    store.write(0, {"x": np.arange(2.0)})
    assert ShardStore.open(tmp_path / "s", spec).completed == {0}
    doc = json.loads((tmp_path / "s" / MANIFEST).read_text())
    cases = {"[" * 50_000 + "]" * 50_000: "nested deeper than 32 levels",
             json.dumps({**doc, "schema": {**doc["schema"], "version": 99}}):
                 "schema version 99 is newer than this empact reads (up to 1)",
             json.dumps({**doc, "completed": [-5, 10**9]}):
                 "completed must list chunk indices 0 to 1",
             json.dumps({**doc, "chunks": [[0, 2], [3, 4]]}):
                 "chunks must cover the runs from 0, in order",
             json.dumps({**doc, "chunks": [[0, True], [2, 4]]}):
                 "chunks must be a list of [start, stop] run pairs",
             "{not json": "not a study manifest file (not JSON text)"}
    for text, match in cases.items():
        (tmp_path / "s" / MANIFEST).write_text(text)
        with pytest.raises(StudyMismatch, match=re.escape(match)) as err:
            ShardStore.open(tmp_path / "s", spec)
        assert "\n" not in str(err.value) and "Error" not in str(err.value)
    (tmp_path / "s" / MANIFEST).write_text(json.dumps(doc))
    shard = tmp_path / "s" / SHARDS / "chunk-000000.npz"
    shard.write_bytes(shard.read_bytes()[:50])
    with pytest.raises(StudyMismatch, match="shards/chunk-000000.npz is damaged .not an .npz "
                                            "archive.; delete it and --resume computes"):
        ShardStore.open(tmp_path / "s", spec)
    with pytest.raises(StudyMismatch, match="damaged"):
        store.read(0)


def test_saving_a_study_holds_one_run_at_a_time_and_writes_the_same_files(tmp_path,
                                                                          in_memory):
    """`save_montecarlo` streams runs.csv and runs.json a run at a time (issue 36: built
    whole, the two texts held about 8 kB a run, the peak RSS of a 1e4-run study 1.47x a
    200-run one's): the same bytes as the texts built whole, and the memory it allocates
    (tracemalloc's peak, no clock) grows by less than 200 bytes a run from 20 to 2000 runs
    (the summary's quantiles take a column of floats at a time: about 45 bytes a run)."""
    save_montecarlo(in_memory, tmp_path / "s")
    doc = {"schema": {"name": "empact.montecarlo.runs", "version": study_mod.SCHEMA_VERSION},
           "analysis": in_memory.analysis, "seed": in_memory.seed, "units": in_memory.units,
           "parameters": list(in_memory.spread.names), "outputs": list(in_memory.outputs),
           "runs": in_memory.table()}
    assert (tmp_path / "s" / "runs.json").read_text() == \
        json.dumps(jsonable(doc), indent=1) + "\n"
    assert (tmp_path / "s" / "runs.csv").read_text() == in_memory.to_csv()

    def peak(runs: int) -> int:
        rep = -(-runs // RUNS)
        big = dataclasses.replace(in_memory, samples=np.tile(in_memory.samples, (rep, 1)),
                                  values=np.tile(in_memory.values, (rep, 1)),
                                  ok=np.tile(in_memory.ok, rep),
                                  reasons=in_memory.reasons * rep)
        tracemalloc.start()
        try:
            save_montecarlo(big, tmp_path / f"r{runs}")
            return tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    small, large = peak(20), peak(2000)
    assert (large - small) / 1980 < 200, (small, large)  # built whole: 7.6 kB a run

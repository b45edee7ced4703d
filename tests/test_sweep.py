"""The sweep layer (issue 14): in process and on Dask, bitwise the same; Monte Carlo over
parameter spread; faults (a killed worker, an unreachable scheduler); the core without Dask.

The Dask tests use a local cluster of worker *processes* (the `dask` extra is installed by the
Makefile's test set-up, so they run in CI, and fail rather than skip without it); each is
bounded by a pytest-timeout.
"""
from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from empact import sweep as sweep_mod
from empact.cli import main
from empact.control import family as family_mod
from empact.control.family import plant_family
from empact.montecarlo import monte_carlo, spread_from_dict
from empact.montecarlo.analyses import SECONDS_PER_RUN
from empact.montecarlo.spread import Distribution
from empact.params import default_params
from empact.slip.stability import stability_map
from empact.sweep import (SweepError, SweepOptions, chunk_count, chunk_slices, plan_chunks,
                          run_chunks, taper_chunks)

P = default_params()

#: a spread that makes some runs fail (a negative stiffness is out of its allowed range)
FAILING = {"spread": {"actuation.k_w": {"distribution": "normal", "mean": 10.0, "std": 12.0},
                      "operating.nu": {"distribution": "uniform", "lower": 0.003,
                                       "upper": 0.008}}}


def family_arrays(fam):
    return [fam.A, fam.B, fam.C, fam.D]


# -- the layer itself ------------------------------------------------------------------------
def test_chunks_cover_the_items_in_order():
    for n, k in [(1, 1), (10, 3), (400, 7), (5, 9)]:
        sl = chunk_slices(n, k)
        assert [i for s in sl for i in range(n)[s]] == list(range(n))
        sizes = [s.stop - s.start for s in sl]
        assert max(sizes) - min(sizes) <= 1
    # >= 50 ms of compute per chunk: 400 points of 40 us are one chunk in process
    assert chunk_count(400, 4e-5, 1) == 1
    # 200 runs of 0.5 s: one run per chunk (each already >= 50 ms)
    assert chunk_count(200, 0.5, 2) == 200
    # the parallelism the chunks are planned for: the workers (in process by default)
    assert SweepOptions().parallelism == 1
    assert SweepOptions("none", workers=4).parallelism == 4  # forked workers
    assert SweepOptions("local", workers=3).parallelism == 3
    # 20000 points of 40 us (0.8 s) on 3 workers: 16 chunks of 50 ms, in order; in process
    # the same arithmetic with one worker
    sl = plan_chunks(20000, 4e-5, SweepOptions("local", workers=3))
    assert len(sl) == 16 and [i for s in sl for i in range(20000)[s]] == list(range(20000))
    assert plan_chunks(20000, 4e-5) == chunk_slices(20000, chunk_count(20000, 4e-5, 1))
    # 5000 points (0.2 s) on 3 workers: too little work for two chunks per worker -> 4 chunks
    assert len(plan_chunks(5000, 4e-5, SweepOptions("local", workers=3))) == 4


def test_tapered_chunks_start_with_one_item_and_shrink_to_the_end():
    """A streamed study's plan on several workers (`taper_chunks`): one item first (run here
    before the fork), full chunks, then chunks that shrink to a quarter of a full one."""
    for n, per, workers in [(200, 13, 2), (12, 2, 2), (10_000, 13, 2), (1, 13, 2), (3, 13, 4),
                            (1000, 1, 3), (97, 40, 8)]:
        sl = taper_chunks(n, per, workers)
        assert [i for s in sl for i in range(n)[s]] == list(range(n))
        sizes = [s.stop - s.start for s in sl]
        assert sizes[0] == 1 and max(sizes) <= per and min(sizes) >= 1
        # shrinking, not below a quarter of a full chunk (the last one: what is left)
        assert all(a >= b for a, b in zip(sizes[1:], sizes[2:-1]))
        assert all(x >= -(-per // 4) for x in sizes[1:-1])
    sizes = [s.stop - s.start for s in taper_chunks(200, 13, 2)]
    assert sizes == [1] + [13] * 12 + [11, 8, 6, 5, 4, 4, 4, 1]
    # plan_chunks tapers only when asked and with more than one worker
    one, two = SweepOptions(), SweepOptions(workers=2)
    assert plan_chunks(200, 0.08, one, target=1.0, taper=True) == \
        plan_chunks(200, 0.08, one, target=1.0) == chunk_slices(200, 16)
    assert plan_chunks(200, 0.08, two, target=1.0, taper=True) == taper_chunks(200, 13, 2)


def test_core_never_imports_dask():
    """`import empact` and a default (in-process) sweep of each kind leave Dask unimported."""
    code = ("import sys, empact, empact.sweep, empact.montecarlo, empact.cli\n"
            "from empact.params import default_params\n"
            "from empact.control.family import plant_family\n"
            "from empact.slip.stability import stability_map\n"
            "p = default_params()\n"
            "plant_family(p, r_g=[0.8, 1.2])\n"
            "stability_map(p, 'nu', [0.004, 0.01], 'r_g', [0.8, 1.2])\n"
            "bad = sorted(m for m in sys.modules if m.split('.')[0] in ('dask', 'distributed'))\n"
            "print(bad)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, check=True)
    assert out.stdout.strip() == "[]", out.stdout


def test_missing_dask_is_one_line(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import fails as if not installed
    with pytest.raises(SweepError, match=r"^--scheduler local: Dask is not installed \(pip "
                                         r"install 'empact\[dask\]'\)$"):
        run_chunks(abs, [1], SweepOptions(scheduler="local"))


def test_family_chunking_does_not_change_a_bit(monkeypatch):
    """The family computed in one chunk and in 13 chunks: bitwise equal (per-point trim
    convergence, one compiled linearisation per point)."""
    kw = dict(r_g=np.geomspace(0.5, 2.0, 13), nu=[0.004, 0.008, 0.012])
    one = plant_family(P, **kw)
    monkeypatch.setattr(family_mod, "SECONDS_PER_POINT", 1.0)  # one point per chunk
    many = plant_family(P, **kw)
    assert one.ok.all()
    for a, b in zip(family_arrays(one), family_arrays(many)):
        np.testing.assert_array_equal(a, b)


# -- Dask: bitwise equal to the serial run ---------------------------------------------------
@pytest.mark.timeout(180)
def test_family_on_dask_is_bitwise_the_serial_one(cluster):
    kw = dict(r_g=np.geomspace(0.5, 2.0, 20), nu=np.linspace(0.004, 0.012, 20))
    serial = plant_family(P, **kw)
    dask = plant_family(P, sweep=SweepOptions(scheduler=cluster), **kw)
    assert serial.size == 400
    for a, b in zip(family_arrays(serial), family_arrays(dask)):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(serial.ok, dask.ok)


@pytest.mark.timeout(180)
def test_stability_map_on_dask_is_bitwise_the_serial_one(cluster):
    args = (P, "nu", np.linspace(0.001, 0.06, 120), "r_g", np.linspace(0.5, 2.2, 150))
    serial = stability_map(*args, workers=1)
    dask = stability_map(*args, chunk_size=1000, sweep=SweepOptions(scheduler=cluster))
    np.testing.assert_array_equal(serial.max_real, dask.max_real)
    np.testing.assert_array_equal(serial.min_damping, dask.min_damping)
    assert 0 < serial.unstable_fraction < 1  # the map crosses the traction peak


@pytest.mark.timeout(180)
def test_montecarlo_does_not_depend_on_workers_or_chunks(cluster, monkeypatch):
    """Serial, serial in one-run chunks, and on the 2-worker cluster: the same table to the
    bit, failures (out-of-range samples) included with the same reasons."""
    from empact.montecarlo import analyses

    spread = spread_from_dict(FAILING, P)
    serial = monte_carlo(P, spread, 60, "slip", seed=7)
    on_dask = monte_carlo(P, spread, 60, "slip", seed=7, sweep=SweepOptions(scheduler=cluster))
    monkeypatch.setitem(analyses.SECONDS_PER_RUN, "slip", 1.0)  # one run per chunk
    chunked = monte_carlo(P, spread, 60, "slip", seed=7)
    assert 0 < serial.failures < 60  # some runs fail, the others are kept
    for other in (on_dask, chunked):
        np.testing.assert_array_equal(serial.samples, other.samples)
        np.testing.assert_array_equal(serial.values, other.values)
        np.testing.assert_array_equal(serial.ok, other.ok)
        assert serial.reasons == other.reasons


def test_forked_workers_are_bitwise_the_serial_run(monkeypatch):
    """Two forked workers on this machine (the CLI's default): the same table to the bit as
    the serial run, failures (out-of-range samples) included with the same reasons, in run
    order although the chunks complete in any order (one run per chunk: 40 chunks)."""
    from empact.montecarlo import analyses

    spread = spread_from_dict(FAILING, P)
    serial = monte_carlo(P, spread, 40, "slip", seed=7)
    monkeypatch.setitem(analyses.SECONDS_PER_RUN, "slip", 1.0)  # one run per chunk
    forked = monte_carlo(P, spread, 40, "slip", seed=7, sweep=SweepOptions(workers=2))
    assert 0 < serial.failures < 40
    np.testing.assert_array_equal(serial.samples, forked.samples)
    np.testing.assert_array_equal(serial.values, forked.values)
    np.testing.assert_array_equal(serial.ok, forked.ok)
    assert serial.reasons == forked.reasons


def test_forked_workers_raise_a_chunks_error_and_run_the_first_chunk_here():
    """A chunk that raises in a forked worker raises here; the first chunk runs in this
    process (the workers inherit what it loaded), the others in the workers."""
    pids = run_chunks(_pid_or_fail, [0, 1, 2, 3], SweepOptions(workers=2))
    assert pids[0] == os.getpid() and os.getpid() not in pids[1:]
    with pytest.raises(ValueError, match="chunk 3 fails"):
        run_chunks(_pid_or_fail, [0, 1, 2, -3], SweepOptions(workers=2))


def _pid_or_fail(k: int) -> int:
    if k < 0:
        raise ValueError(f"chunk {-k} fails")
    return os.getpid()


# -- Monte Carlo itself ----------------------------------------------------------------------
def test_failed_runs_are_recorded_with_their_reason():
    res = monte_carlo(P, spread_from_dict(FAILING, P), 40, "slip", seed=1)
    k_w = res.samples[:, 0]
    # a run fails exactly when its k_w is outside the allowed range (0.001, 1e8] N m/rad
    np.testing.assert_array_equal(res.ok, k_w > 1e-3)
    for i in np.flatnonzero(~res.ok):
        assert res.reasons[i].startswith("parameters: parameters: actuation.k_w = ")
        assert np.isnan(res.values[i]).all()
    assert np.isfinite(res.values[res.ok]).all()
    s = res.summary()
    assert s["failures"] == res.failures and s["succeeded"] + s["failures"] == 40
    assert s["failure_reasons"]["parameters"]["count"] == res.failures
    assert s["outputs"]["max_real"]["n"] == 40 - res.failures


def test_a_run_is_its_own_stream():
    """Run i's sample depends on the seed and i only (not on the runs drawn with it)."""
    spread = spread_from_dict(FAILING, P)
    all_runs = spread.sample(11, np.arange(50))
    np.testing.assert_array_equal(spread.sample(11, [17, 3]), all_runs[[17, 3]])
    assert not np.array_equal(spread.sample(12, np.arange(50)), all_runs)


def test_truncated_distributions_match_closed_forms():
    """Means and bounds of 40,000 samples against the closed forms of the truncated
    distributions (tolerance: 5 standard errors)."""
    from scipy import stats

    n = 40_000
    u = np.random.default_rng(0).random(n)
    cases = [Distribution("x", "normal", 10.0, 2.0, 9.0, 15.0),
             Distribution("x", "lognormal", 3.0, 0.4, -np.inf, 4.0),
             Distribution("x", "uniform", 2.0, 5.0)]
    ref_means = [stats.truncnorm((9 - 10) / 2, (15 - 10) / 2, loc=10, scale=2).mean(),
                 _trunc_lognormal_mean(3.0, 0.4, 4.0), 3.5]
    for d, ref_mean in zip(cases, ref_means):
        x = d.ppf(u)
        assert x.min() >= d.lower and x.max() <= d.upper
        assert abs(x.mean() - ref_mean) < 5 * x.std() / np.sqrt(n), (d, x.mean(), ref_mean)


def _trunc_lognormal_mean(median, sigma, upper):
    """E[X | X < upper] for ln X ~ N(ln median, sigma^2), in closed form."""
    from scipy.special import ndtr

    m = np.log(median)
    b = (np.log(upper) - m) / sigma
    return np.exp(m + sigma**2 / 2) * ndtr(b - sigma) / ndtr(b)


def test_plant_analysis_nominal_run_is_the_plant():
    """A spread of (almost) zero width reproduces `empact nmp` at the operating point: the
    same right-half-plane zeros of T_mp -> nu (to 1e-6 relative: k_w moves by < 1e-12)."""
    from empact.nonlinear.nmp import nmp_analysis

    spread = spread_from_dict({"spread": {"actuation.k_w": {
        "distribution": "uniform", "lower": P.actuation.k_w, "upper": P.actuation.k_w * (1 +
                                                                                   1e-12)}}}, P)
    res = monte_carlo(P, spread, 1, "plant", seed=0)
    ref = nmp_analysis(P, [P.operating.r_g], f_max_hz=100.0, drive="speed")  # the test bench
    assert res.ok.all()
    assert res.values[0, res.outputs.index("n_rhp_zeros")] == ref.n_rhp[0] > 0
    np.testing.assert_allclose(res.values[0, res.outputs.index("rhp_zero_hz")],
                               np.abs(ref.rhp_zeros[0]).min() / (2 * np.pi), rtol=1e-6)


def test_plant_analysis_slowest_mode_is_the_slowest_resonance():
    """``f_slow_hz`` / ``zeta_slow`` are the lowest-frequency pole pair with damping below
    1/sqrt(2), checked run by run against python-control's `damp` of the same plant (an
    independent eigen-analysis) on the shipped example spread; some runs have a slower,
    heavily damped pair, which must be skipped."""
    import control as ct
    from importlib import resources

    from empact.montecarlo.spread import load_spread
    from empact.nonlinear.linearization import plant

    spread = load_spread(str(resources.files("empact.data").joinpath(
        "montecarlo", "example-spread.toml")), P)
    res = monte_carlo(P, spread, 60, "plant", seed=1)
    assert res.ok.all()
    f_out = res.values[:, res.outputs.index("f_slow_hz")]
    z_out = res.values[:, res.outputs.index("zeta_slow")]
    skipped = 0
    for k, row in enumerate(res.samples):
        p_k = P.from_dotted(dict(zip(spread.names, row.tolist())))
        sys_k = plant(p_k, p_k.operating, disturbance=False).system
        wn, zeta, poles = ct.damp(sys_k, doprint=False)
        pair = poles.imag > 1e-3
        wn, zeta = wn[pair], zeta[pair]
        resonant = zeta < 1 / np.sqrt(2)
        i = np.argmin(np.where(resonant, wn, np.inf))
        np.testing.assert_allclose(f_out[k], wn[i] / (2 * np.pi), rtol=1e-9)
        np.testing.assert_allclose(z_out[k], zeta[i], rtol=1e-9, atol=1e-12)
        skipped += bool(np.min(wn) < wn[i])
    assert skipped > 0  # the damped pairs the definition is there for occur in this sample


# -- faults ----------------------------------------------------------------------------------
@pytest.mark.timeout(240)
def test_a_worker_killed_mid_sweep_is_survived(cluster, monkeypatch):
    """Kill one of two worker processes while a 1,500-run sweep is running (when its first
    chunk has completed): Dask reruns its chunks elsewhere and the table equals the serial
    one."""
    import distributed
    spread = spread_from_dict(FAILING, P)
    serial = monte_carlo(P, spread, 1500, "slip", seed=3)
    opts = SweepOptions(scheduler=cluster)
    monte_carlo(P, spread, 4, "slip", seed=3, sweep=opts)  # workers have imported empact
    with distributed.Client(cluster) as client:  # (closed: one client at a time here)
        pids = sorted(client.run(os.getpid).values())
    killed: dict[str, float] = {}
    bar = sweep_mod.progress_bar

    class KillAtFirstChunk:  # the sweep's progress: told as each chunk completes
        def __init__(self, *args, **kwargs):
            self.inner = bar(*args, **kwargs)

        def __enter__(self):
            self.inner.__enter__()
            return self

        def __exit__(self, *exc):
            return self.inner.__exit__(*exc)

        def update(self, n=1):
            if not killed:  # the first chunk is back, the others are still to come
                os.kill(pids[0], signal.SIGKILL)
                killed["t"] = time.perf_counter()
            self.inner.update(n)

    monkeypatch.setattr(sweep_mod, "progress_bar", KillAtFirstChunk)
    t_start = time.perf_counter()
    res = monte_carlo(P, spread, 1500, "slip", seed=3, sweep=opts)
    t_end = time.perf_counter()
    n_chunks = len(plan_chunks(1500, SECONDS_PER_RUN["slip"], opts))
    print(f"sweep {t_end - t_start:.2f} s, kill at {killed.get('t', 0) - t_start:.2f} s")
    assert "t" in killed and killed["t"] < t_end  # the kill came while the sweep ran
    assert n_chunks > 2  # ... with chunks still to run on both workers
    with pytest.raises(ProcessLookupError):
        os.kill(pids[0], 0)  # that worker is gone
    with distributed.Client(cluster) as client:  # its nanny restarts it (a shared cluster)
        client.wait_for_workers(2, timeout=60)
    np.testing.assert_array_equal(serial.values, res.values)
    np.testing.assert_array_equal(serial.ok, res.ok)
    assert serial.reasons == res.reasons


#: the line of a command's work indicator (`empact._progress.WORKING_FORMAT`)
WORKING = re.compile(r"^[\w ]+: working, [\d:]+ elapsed$")


@pytest.mark.timeout(120)
def test_unreachable_scheduler_one_line_exit_2(tmp_path):
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    exe = Path(sys.executable).with_name("empact")
    out = subprocess.run([str(exe), "plants", "--ratio", "0.5:2:4", "--scheduler",
                          f"tcp://127.0.0.1:{port}", "--scheduler-timeout", "0.5",
                          "--out", str(tmp_path / "f.npz")],
                         capture_output=True, text=True, timeout=90)
    assert out.returncode == 2, out.stderr
    # the one error line, after at most the command's work indicator (`empact._progress`):
    # an unreachable scheduler is known only after trying it, which may outlast the
    # indicator's first second (importing Dask, the timeout itself)
    lines = [ln for ln in out.stderr.strip().splitlines() if not WORKING.match(ln)]
    assert len(lines) == 1, out.stderr
    assert lines[0].startswith(f"error: --scheduler tcp://127.0.0.1:{port}: cannot reach the "
                               "scheduler within 0.5 s")
    assert not list(tmp_path.iterdir())  # nothing written


# -- the command line ------------------------------------------------------------------------
@pytest.mark.timeout(180)
def test_montecarlo_cli_local_cluster_equals_serial(tmp_path):
    """`empact montecarlo` in process and with --scheduler local --workers 2: the same files
    to the byte; progress on stderr; the summary's counts and quantiles."""
    spread = tmp_path / "spread.toml"
    res = CliRunner().invoke(main, ["montecarlo", "--example-spread"])
    assert res.exit_code == 0
    spread.write_text(res.output)
    args = ["montecarlo", "--spread", str(spread), "--runs", "40", "--analysis", "slip",
            "--seed", "5"]
    a = CliRunner().invoke(main, args + ["--out", str(tmp_path / "a")])
    assert a.exit_code == 0, a.output
    exe = Path(sys.executable).with_name("empact")
    b = subprocess.run([str(exe)] + args + ["--out", str(tmp_path / "b"), "--scheduler",
                                            "local", "--workers", "2"],
                       capture_output=True, text=True, timeout=150)
    assert b.returncode == 0, b.stderr
    # nothing on stderr but the progress bar (which shows once the sweep has run a second)
    # and the closing line,
    # after at most the command's work indicator while the local cluster starts (it ends
    # when the bar begins): no warnings or logs from the cluster's workers
    lines = b.stderr.splitlines()
    working = [ln for ln in lines if WORKING.match(ln)]  # one a 10 s while it starts
    assert all(ln.startswith("montecarlo: ") for ln in working), b.stderr
    lines = [ln for ln in lines if not WORKING.match(ln)]
    # then the closing line naming what was written (issue 35), last
    assert lines and lines[-1].startswith("written: ") and "runs.csv" in lines[-1], b.stderr
    assert all(re.match(r"^monte carlo \(slip\): +\d+%\|", ln) for ln in lines[:-1]), \
        b.stderr
    for name in ("runs.csv", "runs.json", "summary.json"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    summary = json.loads((tmp_path / "a" / "summary.json").read_text())
    assert summary["runs"] == 40 and summary["failures"] == 0
    q = summary["outputs"]["min_damping"]
    assert q["min"] <= q["q05"] <= q["q50"] <= q["q95"] <= q["max"]
    rows = (tmp_path / "a" / "runs.csv").read_text().splitlines()
    assert rows[0].startswith("# empact Monte Carlo: analysis slip, seed 5, 40 runs, 0 failed")
    header = next(r for r in rows if not r.startswith("#"))
    assert header.startswith("run,status,actuation.k_w [N m/rad],")
    assert len([r for r in rows if r[:1].isdigit()]) == 40


def test_montecarlo_closed_loop_cli(tmp_path):
    """Two closed-loop runs of a shipped scenario with the shipped PI controller."""
    spread = tmp_path / "s.toml"
    spread.write_text('[spread."traction.D_med"]\ndistribution = "uniform"\nlower = 0.095\n'
                      'upper = 0.105\n')
    res = CliRunner().invoke(main, ["montecarlo", "--spread", str(spread), "--runs", "2",
                                    "--analysis", "closed-loop", "--example",
                                    "slip-load-step-r1", "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)  # (the progress bar is on stderr)
    assert doc["schema"]["name"] == "empact.montecarlo" and doc["runs"] == 2
    assert doc["outputs"]["ratio_error"]["n"] + doc["failures"] == 2


def _pool_threads(_):
    from threadpoolctl import threadpool_info
    return sorted({p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"})


def test_a_chunk_runs_on_one_blas_thread_and_new_libraries_are_seen(monkeypatch):
    """`run_chunks` limits every loaded BLAS to one thread inside a chunk, from a scan of the
    loaded libraries kept until a module is imported (`sweep._thread_pools`): the same
    controller while nothing was imported, a new scan after an import."""
    import sys
    import types

    from empact import sweep

    assert sweep.run_chunks(_pool_threads, [0, 1]) == [[1], [1]]
    first = sweep._thread_pools()
    assert sweep._thread_pools() is first
    monkeypatch.setitem(sys.modules, "_empact_test_new_module", types.ModuleType("x"))
    assert sweep._thread_pools() is not first


def test_local_cluster_leaves_nothing_in_the_temporary_folder(tmp_path, monkeypatch):
    """Issue 35, item 4: a local Dask cluster's scratch space (worker folders and Dask's
    ``dask-scratch-space/global.lock``, ``purge.lock``, which its default left in the system's
    temporary folder) lives in a folder of the run, removed when the cluster closes."""
    import tempfile

    monkeypatch.setenv("TMPDIR", str(tmp_path))
    monkeypatch.setattr(tempfile, "tempdir", None)  # re-read TMPDIR
    assert run_chunks(abs, [-1, -2], SweepOptions(scheduler="local", workers=1)) == [1, 2]
    assert sorted(p.name for p in tmp_path.iterdir()) == []


@pytest.mark.parametrize("address", ["tcp:/x", "tcp://host", "host:0", "host:99999", "a b:1",
                                     "tcp://host:x"])
def test_scheduler_address_checked_before_connecting(address):
    """A malformed address is one line (it leaked "invalid literal for int() with base 10")."""
    with pytest.raises(SweepError, match=r"give none, local or a scheduler address HOST:PORT"):
        SweepOptions(scheduler=address)
    for good in ("tcp://127.0.0.1:8786", "localhost:8786", "tls://[::1]:8786"):
        assert SweepOptions(scheduler=good).scheduler == good

"""Benchmark: a streamed closed-loop Monte Carlo of many runs against 200 runs (issue 36,
item 5).

Workload: ``empact montecarlo --analysis closed-loop --example slip-load-step-r1`` on the
shipped example spread, seed 1, ``--workers 2``, ``--out`` a fresh folder (the runs stream to
shards of about a second each), as whole processes, the baseline of 200 runs first, then the
large study.  Each process's wall time, CPU time (its own and its forked workers') and peak
resident set size (``wait4``'s ``ru_maxrss``: the largest of the process and its waited-for
workers) are printed, per run and as the ratio against the baseline, with the load average
before and after (the machine is shared: another busy core moves wall times).  Then the large
study's table is checked bitwise against a resume of its folder with one chunk's shard
removed (one chunk recomputed).

Then the baseline study again on one worker (``--one-worker-large``: the large one too), its
table compared bitwise with the ``--workers`` one.

Run: ``.venv/bin/python bench/bench_study.py [--runs 10000] [--base 200] [--workers 2]
[--one-worker-large]``
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SPREAD = Path(__file__).parent.parent / "src" / "empact" / "data" / "montecarlo" / \
    "example-spread.toml"


def study(runs: int, out: Path, workers: int, resume: bool = False) -> dict[str, float]:
    """Run one study as a whole process: wall [s], CPU [s], peak RSS [MiB]."""
    cmd = [str(Path(sys.executable).parent / "empact"), "montecarlo", "--spread", str(SPREAD), "--runs",
           str(runs), "--analysis", "closed-loop", "--example", "slip-load-step-r1",
           "--seed", "1", "--workers", str(workers), "--out", str(out), "--quiet"]
    if resume:
        cmd.append("--resume")
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL)
    _, status, ru = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"study of {runs} runs failed: {status}")
    return {"wall": wall, "cpu": ru.ru_utime + ru.ru_stime, "rss": ru.ru_maxrss / 1024}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=10_000)
    ap.add_argument("--base", type=int, default=200)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--one-worker-large", action="store_true",
                    help="also run the large study on one worker (its table compared)")
    a = ap.parse_args()
    root = Path(tempfile.mkdtemp(prefix="bench-study-"))
    try:
        print(f"{os.cpu_count()} cores; load average before {os.getloadavg()}")
        rows = {}
        for n in (a.base, a.runs):
            r = rows[n] = study(n, root / f"s{n}", a.workers)
            print(f"{n:6d} runs: wall {r['wall']:8.1f} s ({1e3 * r['wall'] / n:6.1f} ms a run), "
                  f"CPU {r['cpu']:8.1f} s ({1e3 * r['cpu'] / n:6.1f} ms a run), peak RSS "
                  f"{r['rss']:6.1f} MiB; load average {os.getloadavg()}", flush=True)
        b, g = rows[a.base], rows[a.runs]
        print(f"ratios {a.runs} / {a.base} runs: wall a run {g['wall'] / a.runs / (b['wall'] / a.base):.3f}, "
              f"CPU a run {g['cpu'] / a.runs / (b['cpu'] / a.base):.3f}, peak RSS "
              f"{g['rss'] / b['rss']:.3f}")
        big = root / f"s{a.runs}"
        table = (big / "runs.csv").read_bytes()
        manifest = json.loads((big / "manifest.json").read_text())
        k = len(manifest["chunks"]) // 2
        (big / "shards" / f"chunk-{k:06d}.npz").unlink()  # as if killed while it ran
        r = study(a.runs, big, a.workers, resume=True)
        same = (big / "runs.csv").read_bytes() == table
        print(f"resume with chunk {k} of {len(manifest['chunks'])} lost: wall {r['wall']:.1f} s, "
              f"runs.csv bitwise equal: {same}; load average after {os.getloadavg()}")
        assert same
        # the same tables on one worker: the baseline study (and the large one with
        # --one-worker-large, another ~40 ms of CPU a run)
        for n in (a.base, a.runs) if a.one_worker_large else (a.base,):
            r = study(n, root / f"one{n}", 1)
            same = (root / f"one{n}" / "runs.csv").read_bytes() == \
                (root / f"s{n}" / "runs.csv").read_bytes()
            print(f"{n:6d} runs on 1 worker: wall {r['wall']:.1f} s, CPU {r['cpu']:.1f} s, peak "
                  f"RSS {r['rss']:.1f} MiB; runs.csv bitwise the {a.workers}-worker table's: "
                  f"{same}; load average {os.getloadavg()}", flush=True)
            assert same
    finally:
        shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()

"""Benchmark: the report build (issue 11, item 1): per section (compute and render, one
process), and the whole build in parallel against the sequential build (the old route),
formats PNG + SVG, in one run; plus the largest SVG.

Target: the whole build (``empact reproduce``, default settings) <= 12 s on this machine.

Run: ``.venv/bin/python bench/bench_report.py``
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MPLBACKEND", "Agg")

from empact.params import default_params  # noqa: E402
from empact.report import SECTIONS, build_report  # noqa: E402
from empact.report.context import Context  # noqa: E402

TARGET = 12.0


def main() -> None:
    params = default_params()
    tmp = Path(tempfile.mkdtemp())
    try:
        ctx = Context(params=params, out=tmp, formats=("png", "svg"))
        print(f"{'section':12s} {'compute [s]':>11s} {'render [s]':>10s}")
        total_c = total_r = 0.0
        for s in SECTIONS:
            t0 = time.perf_counter()
            res = s.compute(params)
            t1 = time.perf_counter()
            s.render(ctx, res)
            t2 = time.perf_counter()
            total_c, total_r = total_c + t1 - t0, total_r + t2 - t1
            print(f"{s.anchor:12s} {t1 - t0:11.2f} {t2 - t1:10.2f}")
        print(f"{'all':12s} {total_c:11.2f} {total_r:10.2f}  (one process, warm)")
        for workers in (1, None):
            out = tmp / f"rep{workers}"
            t0 = time.perf_counter()
            build_report(params, out, progress=False, workers=workers)
            label = "sequential (old route)" if workers == 1 else f"parallel ({os.cpu_count()} "\
                "processes)"
            print(f"build_report, {label:24s}: {time.perf_counter() - t0:6.2f} s")
        svg = max(out.glob("*.svg"), key=lambda p: p.stat().st_size)
        print(f"largest SVG: {svg.name} {svg.stat().st_size / 1e6:.2f} MB (target < 1 MB)")
        cli = Path(sys.executable).with_name("empact")
        t0 = time.perf_counter()
        subprocess.run([str(cli), "reproduce", "--out", str(tmp / "cli"), "--quiet"], check=True,
                       stdout=subprocess.DEVNULL)
        t = time.perf_counter() - t0
        print(f"empact reproduce (whole process, default): {t:.2f} s (target <= {TARGET:g} s: "
              f"{'met' if t <= TARGET else 'NOT met'})")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()

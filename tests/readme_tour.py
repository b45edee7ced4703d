"""Runs the README's tour (`tests/test_readme.py`): its commands verbatim and in order in an
empty folder, each by a shell (redirections and pipes included), then its Python example and
the figure call of its prose in a fresh interpreter.  ``python readme_tour.py FOLDER RESULTS``
writes one JSON record per step (command, exit status, seconds, stderr); the test suite starts
it in the background when the session starts (`conftest.py`) and its test reads the records.
"""
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

README = Path(__file__).parents[1] / "README.md"

#: files the tour names; each must exist afterwards (no step was refused)
WRITTEN = ("my.toml", "modes.json", "frf.png", "map.png", "plant.mat", "rec.csv",
           "rig-frf.png", "family.npz", "pi.json", "spread.toml", "report/index.html",
           "fig2/models.json", "mc/summary.json", "sim/shift-and-load-step.csv")


def _strip_comment(line: str) -> str:
    """The line without a shell comment (a ``#`` at the start or after a blank, outside
    quotes)."""
    quote = None
    for k, ch in enumerate(line):
        if quote:
            quote = None if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch == "#" and (k == 0 or line[k - 1].isspace()):
            return line[:k].rstrip()
    return line.rstrip()


def tour_commands(text: str) -> list[str]:
    """The commands of the README's tour: its first ``sh`` block after "## A short tour",
    comments dropped, continued lines joined."""
    section = text[text.index("## A short tour"):]
    block = re.search(r"```sh\n(.*?)```", section, re.S).group(1)
    commands, pending = [], ""
    for raw in block.splitlines():
        line = _strip_comment(raw)
        if not line.strip():
            continue
        if line.endswith("\\"):
            pending += line[:-1]
            continue
        commands.append((pending + line).strip())
        pending = ""
    return commands


def python_examples(text: str) -> tuple[str, str]:
    """The README's ``python`` block after the tour, and the figure call of its prose."""
    section = text[text.index("## A short tour"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    call = re.search(r"`(empact\.plotting\.plot_bode\(.*?\))`", section, re.S).group(1)
    return code, call


def run(folder: Path) -> list[dict]:
    """Every step of the tour in `folder`, in order, until one fails."""
    text = README.read_text()
    env = {**os.environ, "MPLBACKEND": "Agg",
           "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}"}
    code, call = python_examples(text)
    script = (code + "\nimport matplotlib.pyplot as plt\nfig, my_axes = plt.subplots(2, 1)\n"
              f"plot = {call}\nassert plot.figure is fig\n")
    steps = [(c, ["bash", "-o", "pipefail", "-c", c]) for c in tour_commands(text)]
    steps.append(("python example", [sys.executable, "-c", script]))
    records = []
    for name, args in steps:
        t0 = time.perf_counter()
        try:
            res = subprocess.run(args, cwd=folder, env=env, capture_output=True, text=True,
                                 timeout=240)
        except subprocess.TimeoutExpired as exc:  # a record naming the step, not no records
            err = exc.stderr.decode(errors="replace") if isinstance(exc.stderr, bytes) \
                else (exc.stderr or "")
            records.append({"step": name, "status": "timed out after 240 s",
                            "seconds": time.perf_counter() - t0, "stderr": err[-3000:]})
            break
        records.append({"step": name, "status": res.returncode,
                        "seconds": time.perf_counter() - t0, "stderr": res.stderr[-3000:]})
        if res.returncode:
            break
    return records


if __name__ == "__main__":
    folder, results = Path(sys.argv[1]), Path(sys.argv[2])
    out = run(folder)
    results.write_text(json.dumps(out))

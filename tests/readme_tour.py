"""Runs the README's tour (`tests/test_readme.py`): its commands verbatim and in order in an
empty folder, each by a shell (redirections and pipes included), then its Python example and
the figure call of its prose in a fresh interpreter; then, in the same folder (the tour's
files are what the pages' commands name), the shell and Python snippets of the docs site's
pages (`DOCS_STEPS`).  ``python readme_tour.py FOLDER RESULTS`` writes one JSON record per
step (command, exit status, seconds, stderr, and the snippet it runs); the test suite starts
it in the background when the session starts (`conftest.py`) and its tests read the records.

Every code snippet of the README and of the site's pages (`snippets`: fenced blocks,
``code-block`` and literal blocks, doctests, ``plot`` and ``literalinclude`` directives) has
its entry in `COVERAGE`: run here, checked by a named test, or excluded with the reason, in
one list; `tests/test_readme.py` fails on a snippet without one, or an entry without a
snippet.
"""
import json
import os
import re
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

README = Path(__file__).parents[1] / "README.md"
DOCS = README.parent / "docs"

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


# --- the snippets of the README and of the site's pages --------------------------------------


@dataclass(frozen=True)
class Snippet:
    """One code snippet of a page: its file (``README.md``, ``docs/fmu.rst``), its language
    (``sh``, ``python``, ``matlab``, ``toml``, ``text``, ``json``; ``doctest``, ``plot``,
    ``literalinclude`` for the directives; ``""`` for a block without one), its text and
    line."""

    source: str
    kind: str
    text: str
    line: int

    @property
    def key(self) -> tuple[str, str]:
        """``(source, first line)``: the first non-blank line without a shell or MATLAB
        comment, blanks collapsed, at most 60 characters (its entry in `COVERAGE`)."""
        first = next(ln for ln in self.text.splitlines() if ln.strip())
        if self.kind not in ("text", "json", ""):  # (a text's first line may be a comment)
            first = re.split(r"\s[#%] ", _strip_comment(first))[0]
        return self.source, " ".join(first.split())[:60]


def _markdown_snippets(path: Path, name: str) -> list[Snippet]:
    text = path.read_text()
    return [Snippet(name, m.group(1), m.group(2), text[:m.start()].count("\n") + 1)
            for m in re.finditer(r"^```(\w*)\n(.*?)^```", text, re.S | re.M)]


def _rst_snippets(path: Path, name: str) -> list[Snippet]:
    """The blocks of an reST page: ``code-block`` (its language), ``plot`` and
    ``literalinclude`` directives, literal blocks after ``::`` (language ``""``) and each run
    of doctest lines (``>>>`` and what follows up to a blank line)."""
    lines = path.read_text().splitlines()
    out, k = [], 0

    def body(start: int) -> tuple[str, int]:
        """The indented block after line `start` (options and blank lines skipped)."""
        j = start + 1
        while j < len(lines) and (not lines[j].strip() or lines[j].lstrip().startswith(":")
                                  and lines[j].startswith("   ")):
            j += 1
        block = []
        while j < len(lines) and (not lines[j].strip() or lines[j].startswith("   ")):
            block.append(lines[j][3:])
            j += 1
        return "\n".join(block).strip("\n") + "\n", j

    while k < len(lines):
        line = lines[k]
        m = re.match(r"\.\. (code-block|plot|literalinclude)::\s*(\S*)", line)
        if m:
            kind = m.group(2) if m.group(1) == "code-block" else m.group(1)
            if m.group(1) == "literalinclude":
                out.append(Snippet(name, kind, m.group(2) + "\n", k + 1))
                k += 1
                continue
            text, end = body(k)
            out.append(Snippet(name, kind, text, k + 1))
            k = end
        elif line.startswith(">>>"):
            start = k
            while k < len(lines) and lines[k].strip():
                k += 1
            out.append(Snippet(name, "doctest", "\n".join(lines[start:k]) + "\n", start + 1))
        elif line.rstrip().endswith("::") and not line.startswith(".."):
            text, end = body(k)
            out.append(Snippet(name, "", text, k + 2))
            k = end
        else:
            k += 1
    return out


def snippets() -> list[Snippet]:
    """Every code snippet of the README and of the site's hand-written pages, in page order."""
    out = _markdown_snippets(README, "README.md")
    for page in sorted(DOCS.glob("*.rst")):
        out += _rst_snippets(page, f"docs/{page.name}")
    return out


#: run here: the README's tour and Python example, the pages' shell and Python snippets
RUN = "run"
#: how each snippet is covered, by `Snippet.key`: (RUN,), ("checked", test) or
#: ("excluded", why).  A new snippet needs its entry (tests/test_readme.py).
COVERAGE: dict[tuple[str, str], tuple[str, str] | tuple[str]] = {
    ("README.md", "make reproduce"): (
        "excluded", "the project's own entry points: each creates .venv and installs from "
        "PyPI (minutes, network); CI runs all three (.ci/run)"),
    ("README.md", "empact params show > my.toml"): (RUN,),
    ("README.md", "import numpy as np"): (RUN,),
    ("README.md", "s = load('family.mat');"): (
        "checked", "test_readme.py::test_the_matlab_snippet_reads_fields_the_tour_writes"),
    ("README.md", "pip install -e '.[dask]'"): (
        "excluded", "needs a Dask cluster: a scheduler on a head node, workers on compute "
        "nodes (tests/test_sweep.py runs the same study on a LocalCluster)"),
    ("README.md", "from dask_jobqueue import SLURMCluster"): (
        "excluded", "needs SLURM or PBS and dask-jobqueue (not installed here)"),
    ("README.md", "src/empact/"): ("excluded", "not code: the source tree's layout"),
    ("docs/changelog.rst", "../CHANGELOG.md"): ("excluded", "not code: the changelog's text"),
    ("docs/control.rst", "u = diag(R_j(s) Lambda_j(s)) (K_p + K_i / s) diag(g(sigma)) "): (
        "excluded", "not code: the H-infinity controller's structure as a formula"),
    ("docs/control.rst", "gamma = max over plants and frequencies of sbar([W1 S; W2 K "): (
        "excluded", "not code: the H-infinity design's criterion as a formula"),
    ("docs/control.rst", ">>> import empact"): (
        "checked", "test_docs.py::test_control_chapter_examples_run"),
    ("docs/control.rst", ">>> from empact.control.closed_loop import control_example_p"): (
        "checked", "test_docs.py::test_control_chapter_examples_run"),
    ("docs/control.rst", ">>> from empact.control.loop import loop_model"): (
        "checked", "test_docs.py::test_control_chapter_examples_run"),
    ("docs/control.rst", ">>> pi_1khz = pi.discretize(1e-3)"): (
        "checked", "test_docs.py::test_control_chapter_examples_run"),
    ("docs/control.rst", ">>> import json, pathlib, tempfile, control as ct, numpy as "): (
        "checked", "test_docs.py::test_control_chapter_examples_run"),
    ("docs/control.rst", "k = load('k.mat');"): (
        "checked", "test_readme.py::test_the_pages_matlab_snippets_read_fields_written"),
    ("docs/dask.rst", "pip install -e '.[dask]'"): (
        "excluded", "needs a Dask cluster: a scheduler on a head node, workers on compute "
        "nodes (tests/test_sweep.py runs a study on a LocalCluster)"),
    ("docs/dask.rst", "from dask_jobqueue import SLURMCluster"): (
        "excluded", "needs SLURM or PBS and dask-jobqueue (not in the CI; run by hand on a "
        "one-node SLURM, as the page says)"),
    ("docs/dask.rst", "empact montecarlo --spread spread.toml --runs 100000 --analy"): (
        "excluded", "needs a Dask scheduler at tcp://head:8786 and hours of runs "
        "(tests/test_shards.py kills and resumes a stored study on forked workers and on a "
        "LocalCluster)"),
    ("docs/drive_cycle.rst", "empact cycle --cycle wltc3b"): (RUN,),
    ("docs/fmu.rst", "empact fmu export --out machine.fmu"): (RUN,),
    ("docs/fmu.rst", "import fmpy"): (RUN,),
    ("docs/getting_started.rst", "../README.md"): (
        "checked", "test_docs.py::test_getting_started_shows_the_readme_tour"),
    ("docs/interchange.rst", "[operating]"): (
        "checked", "test_readme.py::test_the_pages_data_snippets_are_what_empact_reads_and_"
        "writes"),
    ("docs/interchange.rst", "# empact rig: multisine on T_ms at r_g = 0.5, nu = 0, F_s = "): (
        "checked", "test_readme.py::test_the_pages_data_snippets_are_what_empact_reads_and_"
        "writes"),
    ("docs/interchange.rst", '{"schema": {"name": "empact.modes", "version": 1},'): (
        "checked", "test_readme.py::test_the_pages_data_snippets_are_what_empact_reads_and_"
        "writes"),
    ("docs/interchange.rst", "s = load('plant.mat');"): (
        "checked", "test_readme.py::test_the_pages_matlab_snippets_read_fields_written"),
    ("docs/interchange.rst", "s = load('family.mat');"): (
        "checked", "test_readme.py::test_the_pages_matlab_snippets_read_fields_written"),
    ("docs/interchange.rst", "k = load('k.mat');"): (
        "checked", "test_readme.py::test_the_pages_matlab_snippets_read_fields_written"),
    ("docs/model.rst", "import empact"): (
        "checked", "the docs build (make docs: Sphinx runs each plot directive, warnings "
        "are errors)"),
    ("docs/model.rst", "import numpy as np"): (
        "checked", "the docs build (make docs: Sphinx runs each plot directive, warnings "
        "are errors)"),
}

#: files the pages' snippets take as the reader's own, written before they run: a speed
#: trace (docs/drive_cycle.rst) and measured traction curves (docs/fmu.rst; here the shipped
#: magic formula, tabulated)
SETUP_FILES = {
    "my-trace.csv": "# a trace of my own: 0 to 50 km/h and back\ntime [s],speed [km/h]\n"
                    + "".join(f"{t},{min(t, 50, 100 - t) if t < 100 else 0}\n"
                              for t in range(0, 121, 2)),
}
SETUP_PYTHON = """
import numpy as np, empact
tr = empact.traction_from_params(empact.load_params())
rows = ["r_g,nu,mu"] + [f"{r},{float(n)!r},{float(tr.mu(n, r))!r}" for r in (0.5, 1.0, 2.0)
                        for n in np.linspace(0.0, 0.08, 33)]
open("curves.csv", "w").write("\\n".join(rows) + "\\n")
"""
#: commands the pages' prose names, whose files the checks of their MATLAB and data
#: snippets read: a family of 3 ratios x 2 torque ratios (docs/interchange.rst) and the
#: controller folded at a point (docs/interchange.rst, docs/control.rst)
PROSE_COMMANDS = (
    "empact plants --ratio 0.5:2:3 --tau 0.8,0.95 --out family.mat",
    "empact control discretize pi.json --at r_g=1,tau=0.9,F_s=10000 --out k.mat",
)


def shell_commands(block: str) -> list[str]:
    """The commands of a shell block: comments dropped, continued lines joined."""
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


def docs_steps() -> list[tuple[str, str, list[str]]]:
    """``(snippet, step, command)`` of the pages' snippets `COVERAGE` marks run, after the
    setup (`SETUP_FILES`, `SETUP_PYTHON`, `PROSE_COMMANDS`; snippet ``"setup"``)."""
    steps = [("setup", "setup: curves.csv", [sys.executable, "-c", SETUP_PYTHON])]
    steps += [("setup", c, ["bash", "-o", "pipefail", "-c", c]) for c in PROSE_COMMANDS]
    for sn in snippets():
        if sn.source == "README.md" or COVERAGE.get(sn.key) != (RUN,):
            continue
        name = f"{sn.source}:{sn.line}"
        if sn.kind == "sh":
            steps += [(name, c, ["bash", "-o", "pipefail", "-c", c])
                      for c in shell_commands(sn.text)]
        elif sn.kind == "python":
            steps.append((name, f"{name} (python)", [sys.executable, "-c", sn.text]))
        else:
            raise ValueError(f"{name}: a {sn.kind!r} snippet cannot be run; check it instead")
    return steps


def _step(name: str, args: list[str], folder: Path, env: dict, snippet: str) -> dict:
    t0 = time.perf_counter()
    try:
        res = subprocess.run(args, cwd=folder, env=env, capture_output=True, text=True,
                             timeout=240)
    except subprocess.TimeoutExpired as exc:  # a record naming the step, not no records
        err = exc.stderr.decode(errors="replace") if isinstance(exc.stderr, bytes) \
            else (exc.stderr or "")
        return {"step": name, "snippet": snippet, "status": "timed out after 240 s",
                "seconds": time.perf_counter() - t0, "stderr": err[-3000:]}
    return {"step": name, "snippet": snippet, "status": res.returncode,
            "seconds": time.perf_counter() - t0, "stderr": res.stderr[-3000:]}


def run(folder: Path) -> list[dict]:
    """Every step of the tour in `folder`, in order, until one fails; then the pages'
    snippets (`docs_steps`) in the same folder, until one fails."""
    text = README.read_text()
    env = {**os.environ, "MPLBACKEND": "Agg",
           "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}"}
    code, call = python_examples(text)
    script = (code + "\nimport matplotlib.pyplot as plt\nfig, my_axes = plt.subplots(2, 1)\n"
              f"plot = {call}\nassert plot.figure is fig\n")
    steps = [("README.md", c, ["bash", "-o", "pipefail", "-c", c])
             for c in tour_commands(text)]
    steps.append(("README.md", "python example", [sys.executable, "-c", script]))
    records = []
    for snippet, name, args in steps:
        records.append(_step(name, args, folder, env, snippet))
        if records[-1]["status"]:
            return records
    for file, content in SETUP_FILES.items():
        (folder / file).write_text(content)
    for snippet, name, args in docs_steps():
        records.append(_step(name, args, folder, env, snippet))
        if records[-1]["status"]:
            break
    return records


if __name__ == "__main__":
    folder, results = Path(sys.argv[1]), Path(sys.argv[2])
    out = run(folder)
    results.write_text(json.dumps(out))

"""The README is executed (issue 22, item 2): the commands of its "A short tour", verbatim and
in order, in an empty folder (any non-zero exit fails), then its Python example in a fresh
interpreter and the figure call its prose shows (``empact.plotting.plot_bode(...)`` after
``import empact`` alone).  Then the docs site's shell and Python snippets run in the same
folder, and the pages' MATLAB and data snippets are checked against the files the commands
wrote (issue 35, item 3; `readme_tour.COVERAGE` lists how each snippet is covered).  The
tour (mostly process start-up: 85 s at load 6, 468 s at load 14 on the shared 2-core machine;
the pages' snippets add 110 s at load 14) runs in the background from the start of the
session (`conftest.py`, `readme_tour.py`); its tests read the records."""
import json
import re

import pytest
from readme_tour import (
    COVERAGE,
    README,
    RUN,
    WRITTEN,
    _strip_comment,
    python_examples,
    snippets,
    tour_commands,
)


def test_the_tour_parses():
    """The parser sees every command line of the block (each begins with `empact`) and joins
    the continued Monte Carlo line; the Python example names no subpackage import."""
    commands = tour_commands(README.read_text())
    assert len(commands) >= 20 and all(c.startswith("empact ") for c in commands), commands
    assert any("--runs" in c and "--scheduler local" in c for c in commands)
    assert _strip_comment("empact x --a 'b # c'  # comment") == "empact x --a 'b # c'"
    code, call = python_examples(README.read_text())
    assert "import empact.plotting" not in code and call.startswith("empact.plotting.")


@pytest.mark.timeout(900)
def test_the_readme_tour_runs_as_written(readme_tour):
    records, folder = readme_tour.result()
    steps = tour_commands(README.read_text()) + ["python example"]
    for rec in records:
        assert rec["status"] == 0, f"{rec['step']}\n{rec['stderr']}"
    records = [r for r in records if r["snippet"] == "README.md"]
    assert [r["step"] for r in records] == steps  # every step ran, in order
    for name in WRITTEN:  # each file the tour names is its own (no step was refused)
        assert (folder / name).is_file(), name
    total = sum(r["seconds"] for r in records)
    print(f"README tour: {len(records)} steps in {total:.1f} s; slowest: "
          + ", ".join(f"{r['seconds']:.1f} s {' '.join(r['step'].split()[1:3])}"
                      for r in sorted(records, key=lambda r: -r["seconds"])[:6]))


@pytest.mark.timeout(900)
def test_the_matlab_snippet_reads_fields_the_tour_writes(readme_tour):
    """Every ``s.<field>`` of the README's MATLAB snippet is a variable of the family the tour
    writes, in the .mat layout (`PlantFamily._layout`, what `save_family` writes): it read
    ``s.grid_nu`` of a family whose axes are r_g and tau (issue 35)."""
    import re

    from empact.control.family import load_family

    text = README.read_text()
    snippet = re.search(r"```matlab\n(.*?)```", text, re.S).group(1)
    fields = set(re.findall(r"\bs\.(\w+)", snippet))
    _, folder = readme_tour.result()
    layout = load_family(folder / "family.npz")._layout()
    assert fields and fields <= set(layout), fields - set(layout)


#: files the pages' run snippets (and the prose commands their checks read) write
DOCS_WRITTEN = ("cycle/cycle.json", "cycle/samples.csv", "cycle.png", "machine.fmu", "low.fmu",
                "loop.fmu", "family.mat", "k.mat", "curves.csv")


@pytest.mark.timeout(900)
def test_the_docs_snippets_run_as_written(readme_tour):
    """Every shell and Python snippet of the site's pages that `COVERAGE` marks run ran, in
    the tour's folder, with exit status 0 (the FMU page's second export wrote the first's
    file: it was refused until it got its own name)."""
    records, folder = readme_tour.result()
    failed = [f"{r['step']}\n{r['stderr']}" for r in records if r["status"] != 0]
    assert failed == []
    ran = {r["snippet"] for r in records}
    wanted = {f"{s.source}:{s.line}" for s in snippets()
              if s.source != "README.md" and COVERAGE[s.key] == (RUN,)}
    assert wanted and wanted <= ran, wanted - ran
    for name in DOCS_WRITTEN:
        assert (folder / name).is_file(), name
    total = sum(r["seconds"] for r in records if r["snippet"] != "README.md")
    print(f"docs snippets: {len(records)} steps with the tour's, {total:.1f} s after it")


def _mat_fields(snippet: str) -> dict[str, set[str]]:
    """``{file: fields}`` of a MATLAB snippet: each ``v = load('f.mat')`` and the ``v.NAME``
    it reads."""
    out = {}
    code = re.sub(r"'[^']*'", "''", snippet)  # (not the file names in quotes: 'k.mat')
    for var, name in re.findall(r"(\w+) = load\('([\w.]+)'\)", snippet):
        out[name] = set(re.findall(rf"\b{var}\.(\w+)", code))
    return out


@pytest.mark.timeout(900)
def test_the_pages_matlab_snippets_read_fields_written(readme_tour):
    """Every field a MATLAB snippet of the site reads (``s.grid_tau``, ``k.loop_plant_A``) is
    a variable of the ``.mat`` file the command writes (the tour's ``plant.mat``, the pages'
    ``family.mat`` and ``k.mat``, read as MATLAB would, by scipy.io.loadmat); the family's
    ``A`` has the shape the page states, (19, 19, 3, 2) for 3 ratios x 2 torque ratios."""
    from scipy.io import loadmat

    _, folder = readme_tour.result()
    checked = 0
    for sn in snippets():
        if sn.kind != "matlab" or sn.source == "README.md":
            continue
        for name, fields in _mat_fields(sn.text).items():
            have = set(loadmat(folder / name))
            assert fields and fields <= have, (sn.source, sn.line, name, fields - have)
            checked += 1
    assert checked == 4
    assert loadmat(folder / "family.mat")["A"].shape == (19, 19, 3, 2)


@pytest.mark.timeout(900)
def test_the_pages_data_snippets_are_what_empact_reads_and_writes(readme_tour, tmp_path):
    """The interchange page's TOML is a parameter file `params validate` accepts; its CSV
    lines are the header of the record `empact rig` writes (the tour's rec.csv: the same
    columns and units, the comment as far as the page shows it, a row of as many numbers);
    its JSON is what `modes actuation --ratio 1 --json-out` writes (the tour's modes.json:
    the same schema and units, the frequencies to the page's 3 significant digits)."""
    from click.testing import CliRunner

    from empact.cli import main

    _, folder = readme_tour.result()
    page = {sn.kind: sn.text for sn in snippets() if sn.source == "docs/interchange.rst"}
    (tmp_path / "p.toml").write_text(page["toml"])
    res = CliRunner().invoke(main, ["params", "validate", str(tmp_path / "p.toml"), "--quiet"])
    assert res.exit_code == 0 and res.output.strip() == f"{tmp_path / 'p.toml'}: ok", res.output
    shown = page["text"].splitlines()
    written = (folder / "rec.csv").read_text().splitlines()
    header = next(k for k, line in enumerate(written) if not line.startswith("#"))
    assert shown[1] == written[header]
    assert written[0].startswith(shown[0].removesuffix("...").rstrip())
    assert len(shown[2].split(",")) == len(written[header + 1].split(","))
    doc, modes = json.loads(page["json"]), json.loads((folder / "modes.json").read_text())
    assert doc["schema"] == modes["schema"]
    assert {k: modes["units"][k] for k in doc["units"]} == doc["units"]
    assert doc["frequencies_hz"] == [float(f"{f:.3g}") for f in modes["frequencies_hz"]]
    others = set(doc) - {"schema", "units", "frequencies_hz"}
    assert others and {k: modes[k] for k in others} == {k: doc[k] for k in others}

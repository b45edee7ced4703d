"""The README is executed (issue 22, item 2): the commands of its "A short tour", verbatim and
in order, in an empty folder (any non-zero exit fails), then its Python example in a fresh
interpreter and the figure call its prose shows (``empact.plotting.plot_bode(...)`` after
``import empact`` alone).  The tour (30-50 s, mostly process start-up) runs in the
background from the start of the session (`conftest.py`, `readme_tour.py`); its test reads
the records."""
import pytest
from readme_tour import README, WRITTEN, _strip_comment, python_examples, tour_commands


def test_the_tour_parses():
    """The parser sees every command line of the block (each begins with `empact`) and joins
    the continued Monte Carlo line; the Python example names no subpackage import."""
    commands = tour_commands(README.read_text())
    assert len(commands) >= 20 and all(c.startswith("empact ") for c in commands), commands
    assert any("--runs" in c and "--scheduler local" in c for c in commands)
    assert _strip_comment("empact x --a 'b # c'  # comment") == "empact x --a 'b # c'"
    code, call = python_examples(README.read_text())
    assert "import empact.plotting" not in code and call.startswith("empact.plotting.")


@pytest.mark.timeout(400)
def test_the_readme_tour_runs_as_written(readme_tour):
    records, folder = readme_tour.result()
    steps = tour_commands(README.read_text()) + ["python example"]
    for rec in records:
        assert rec["status"] == 0, f"{rec['step']}\n{rec['stderr']}"
    assert [r["step"] for r in records] == steps  # every step ran, in order
    for name in WRITTEN:  # each file the tour names is its own (no step was refused)
        assert (folder / name).is_file(), name
    total = sum(r["seconds"] for r in records)
    print(f"README tour: {len(records)} steps in {total:.1f} s; slowest: "
          + ", ".join(f"{r['seconds']:.1f} s {' '.join(r['step'].split()[1:3])}"
                      for r in sorted(records, key=lambda r: -r["seconds"])[:6]))


@pytest.mark.timeout(400)
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

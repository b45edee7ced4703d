"""The report (`empact.report`) on a reduced section set: page structure, contents, verdict
summary, claims.json, tables and figures (the full build is in test_cli.py)."""
import json
import re

import numpy as np

from empact.report import SECTIONS, build_report
from empact.report.context import fmt_cell


def test_reduced_report_structure(tmp_path, params):
    sections = [s for s in SECTIONS if s.anchor in ("table1", "table2", "fig10")]
    out = build_report(params, tmp_path / "rep", progress=False, sections=sections,
                       formats=("png",))
    page = (out / "index.html").read_text()
    # contents with anchors to every section, and a verdict summary before the sections
    for s in sections:
        assert f'href="#{s.anchor}"' in page and f'<section id="{s.anchor}">' in page
    assert page.index('id="summary"') < page.index('<section id="table1">')
    claims = json.loads((out / "claims.json").read_text())
    n = sum(len(s.compute(params).claims) for s in sections)
    assert len(claims) == n
    assert re.search(rf"{n} claims checked: {n} shown, 0 NOT shown", page)
    assert (out / "fig10_traction.png").exists() and not (out / "fig10_traction.svg").exists()
    assert (out / "table2.csv").read_text().startswith("r_g,mode,paper [Hz]")
    assert (out / "params.toml").exists()


def test_rebuild_keeps_foreign_files(tmp_path, params):
    sections = [s for s in SECTIONS if s.anchor == "table1"]
    out = tmp_path / "rep"
    build_report(params, out, progress=False, sections=sections, formats=("png",))
    (out / "notes.txt").write_text("mine")
    build_report(params, out, progress=False, sections=sections, formats=("png",))
    assert (out / "notes.txt").read_text() == "mine"  # only empact's own files are replaced
    assert [p.name for p in tmp_path.iterdir()] == ["rep"]  # no temporary folder left


CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                  "--no-first-run", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync"]


def _chromium():
    import shutil

    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    assert exe, "Chromium is missing: `make test` installs it (apt-get install -y chromium)"
    return exe


def test_report_renders_in_a_real_browser_with_every_image(tmp_path, params):
    """Headless Chromium loads the page; the page's own check counts images that failed."""
    import subprocess

    sections = [s for s in SECTIONS if s.anchor in ("table1", "fig4-5", "fig10")]
    out = build_report(params, tmp_path / "rep", progress=False, sections=sections,
                       formats=("png", "svg"))
    (out / "fig10_traction.png").unlink()  # one missing image must be noticed ...
    dom = subprocess.run([_chromium(), *CHROMIUM_FLAGS, f"--user-data-dir={tmp_path / 'ud'}",
                          "--virtual-time-budget=2000", "--dump-dom",
                          (out / "index.html").as_uri()],
                         capture_output=True, text=True, timeout=120).stdout
    images = int(re.search(r'data-images="(\d+)"', dom).group(1))
    broken = int(re.search(r'data-broken-images="(\d+)"', dom).group(1))
    # Table 1 has none; Figs. 4-5 four (Sec. 2.1 rows and the machine); Fig. 10 one
    assert images == 5 and broken == 1, (images, broken)
    # every id once (the section "table1" and its table were both id="table1")
    assert re.search(r'data-duplicate-ids="0"', dom), re.findall(r"data-duplicate-ids=\S+", dom)
    build_report(params, out, progress=False, sections=sections, formats=("png",))
    dom = subprocess.run([_chromium(), *CHROMIUM_FLAGS, f"--user-data-dir={tmp_path / 'ud2'}",
                          "--virtual-time-budget=2000", "--dump-dom",
                          (out / "index.html").as_uri()],
                         capture_output=True, text=True, timeout=120).stdout
    # ... and after a rebuild every image loads
    assert re.search(r'data-images="5"', dom) and re.search(r'data-broken-images="0"', dom)


def test_a_table_cell_without_a_value_is_a_dash_not_nan():
    """A reader never sees ``nan`` (the fair-saving table's open loop that finds no steady
    start has no mean clamping): NaN is an en dash, a float four significant digits, text
    escaped; the CSV beside keeps ``nan`` for scripts."""
    assert fmt_cell(float("nan")) == fmt_cell(np.float64("nan")) == "\u2013"
    assert fmt_cell(1.234567) == "1.235" and fmt_cell("a<b") == "a&lt;b"

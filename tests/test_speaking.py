"""Every command speaks the same way (issue 35, item 2): a command that writes ends with one
line on stderr naming every file it wrote (`empact.cli._common.closing_line`, from what
`empact._io`'s writers record), whatever it writes (a file, a folder, both, a figure and its
JSON); ``--quiet`` leaves stderr to errors; a run shows progress on stderr off a terminal;
the text of the commands added since the last round gives a unit for every number.

The walk (`WRITES`) runs every command that has an output option once, with every output it
has, in one folder, and compares the closing line with the files that appeared or changed
there; a new command with an output fails `test_every_writing_command_is_walked` until it
has its row."""
import re
from importlib import resources

import click
import pytest
from click.testing import CliRunner
from test_cli import GOOD_TARGETS, PROGRESS
from test_outputs import COMMANDS

from empact._io import recording
from empact.cli import main
from empact.cli._common import MOST_NAMED, OutputFile, written_line

SPREAD = '[spread."actuation.k_w"]\ndistribution = "normal"\nrel_std = 0.05\n'
TRACE = "# a short trace\ntime [s],speed [km/h]\n" + "".join(
    f"{t},{min(t, 40 - t) if t < 40 else 0}\n" for t in range(0, 61, 2))

#: command -> arguments that write every output it has (in walk order: a later row reads
#: what an earlier one wrote: fam.npz, pi.json, r.csv)
WRITES = {
    ("params", "show"): None,  # (writes nothing: stdout)
    ("params", "validate"): None,
    ("calibrate",): ["targets.toml", "--out", "cal.toml"],
    ("modes",): ["driveline", "--json-out", "m.json"],
    ("frf",): ["actuation", "--n", "20", "--plot", "f.png", "--json-out", "f.json"],
    ("slip", "poles"): ["--slip", "0.01,0.02", "--plot", "sp.png", "--json-out", "sp.json"],
    ("slip", "statespace"): ["--json-out", "ss.json"],
    ("slip", "frf"): ["--n", "10", "--plot", "sf.png", "--json-out", "sf.json"],
    ("slip", "map"): ["--slip", "0.01:0.04:3", "--ratio", "0.5:2:3", "--plot", "map.png",
                      "--json-out", "map.json"],
    ("slip", "rootlocus"): ["--plot", "rl.png", "--json-out", "rl.json"],
    ("slip", "traction"): ["--plot", "tr.png", "--json-out", "tr.json"],
    ("slip", "zeros"): ["--plot", "z.png", "--json-out", "z.json"],
    ("simulate",): ["--example", "servo-torque-steps", "--duration", "0.1", "--out", "sim",
                    "--formats", "png,svg", "--json-out", "sim.json"],
    ("linearize",): ["--out", "plant.mat"],
    ("nmp",): ["--ratios", "1", "--plot", "nmp.png", "--json-out", "nmp.json"],
    ("identify",): ["--ratios", "1", "--order", "4", "--out", "id", "--plot", "id.png",
                    "--json-out", "id.json"],
    ("rig",): ["--duration", "2", "--fs", "200", "--band", "0.5:50", "--out", "r.csv"],
    ("frf-estimate",): ["r.csv", "--input", "T_mp", "--output", "theta_mp", "--time", "time",
                        "--plot", "fe.png", "--json-out", "fe.json"],
    ("reproduce",): ["--sections", "table1", "--out", "rep"],
    ("plants",): ["--ratio", "0.5,1", "--tau", "0.9", "--out", "fam.npz", "--json-out",
                  "fam.json"],
    ("control", "design"): ["--ratio", "0.5,1", "--tau", "0.9", "--clamp", "10000",
                            "--out", "pi.json", "--json-out", "design.json"],
    ("control", "check"): ["pi.json", "--family", "fam.npz", "--json-out", "check.json"],
    ("control", "tune"): ["pi.json", "--family", "fam.npz", "--maxiter", "2", "--out",
                          "tuned.json", "--json-out", "tune.json"],
    ("control", "simulate"): ["step.toml", "--out", "cl.csv", "--json-out", "cl.json"],
    ("control", "discretize"): ["pi.json", "--at", "r_g=1,tau=0.9,F_s=10000", "--out",
                                "k.mat"],
    ("montecarlo",): ["--spread", "s.toml", "--runs", "2", "--analysis", "plant",
                      "--workers", "1", "--out", "mc", "--json-out", "mc.json"],
    ("efficiency",): ["--ratio", "1", "--torque", "50", "--plot", "eff.png", "--json-out",
                      "eff.json"],
    ("cycle",): ["--cycle", "trace.csv", "--strategies", "sf1.3", "--out", "cy", "--plot",
                 "cy.png", "--json-out", "cy.json"],
    ("fmu", "export"): ["--out", "m.fmu"],
}


def _writes(cmd: click.Command) -> bool:
    return any(isinstance(p.type, OutputFile)
               or isinstance(p.type, click.Path) and not p.type.file_okay for p in cmd.params)


def test_every_writing_command_is_walked():
    """Each command with an output option (a file or a folder) has its row in `WRITES`, and
    each row names every output option of its command."""
    names = {path: cmd for path, cmd in COMMANDS}
    assert sorted(p for p, c in COMMANDS if _writes(c) and WRITES.get(p) is None) == []
    assert sorted(set(WRITES) - set(names)) == []
    for path, args in WRITES.items():
        if args is None:
            assert not _writes(names[path]), path
            continue
        outputs = {max(p.opts, key=len) for p in names[path].params if isinstance(p, click.Option)
                   and (isinstance(p.type, OutputFile) or isinstance(p.type, click.Path)
                        and not p.type.file_okay)}
        assert outputs <= set(args), (path, outputs - set(args))


def _state(folder):
    return {p.relative_to(folder).as_posix(): (p.stat().st_mtime_ns, p.stat().st_ino)
            for p in folder.rglob("*") if p.is_file()}


def _parse(line: str) -> tuple[set[str], dict[str, dict[str, int]]]:
    """The files a closing line names, and per folder it counts: ``{suffix: count}`` (a file
    it names in a counted folder counts under its own name)."""
    assert line.startswith("written: "), line
    named, counted = set(), {}
    for item in re.split(r", (?![^(]*\))", line[len("written: "):]):
        m = re.fullmatch(r"(.+)/ \((.*)\)", item)
        if not m:
            named.add(item)
            continue
        folder, counts = m.group(1), {}
        for part in m.group(2).split(", "):
            n = re.fullmatch(r"(\d+) (\.\w+) files", part)
            if n:
                counts[n.group(2)] = int(n.group(1))
            else:
                named.add(f"{folder}/{part}")
        counted[folder] = counts
    return named, counted


def test_the_closing_line_names_or_counts_each_file(tmp_path, monkeypatch):
    """`written_line` names each file (relative to the current folder inside it, absolute
    outside), in the order written; a folder with more than `MOST_NAMED` files is counted by
    suffix, a file alone with its suffix still named; `_parse` reads it back."""
    monkeypatch.chdir(tmp_path)
    files = [tmp_path / "a.csv", tmp_path / "sub" / "b.png"] + \
        [tmp_path / "rep" / f"f{k}.png" for k in range(MOST_NAMED)] + \
        [tmp_path / "rep" / "index.html", tmp_path.parent / "elsewhere.json"]
    line = written_line(files)
    assert line == (f"written: a.csv, sub/b.png, rep/ (index.html, {MOST_NAMED} .png files), "
                    f"{(tmp_path.parent / 'elsewhere.json').as_posix()}")
    named, counted = _parse(line)
    assert named == {"a.csv", "sub/b.png", "rep/index.html",
                     (tmp_path.parent / "elsewhere.json").as_posix()}
    assert counted == {"rep": {".png": MOST_NAMED}}
    assert written_line([]) == ""


def test_recording_sees_files_and_folders_at_their_destination(tmp_path):
    """`empact._io.recording` holds the destination of an atomic file, of every file of an
    atomic folder (a file written into the folder's temporary by an atomic writer too, at
    its destination, not the temporary's), once each."""
    from empact._io import atomic_folder, atomic_write_text

    with recording() as rec:
        atomic_write_text(tmp_path / "a.txt", "1")
        atomic_write_text(tmp_path / "a.txt", "2")
        with atomic_folder(tmp_path / "f") as tmp:
            atomic_write_text(tmp / "inner.json", "{}")
            (tmp / "sub").mkdir()
            (tmp / "sub" / "plain.csv").write_text("x")
    assert list(rec) == [tmp_path / "a.txt", tmp_path / "f" / "inner.json",
                         tmp_path / "f" / "sub" / "plain.csv"]
    with recording() as rec:
        pass
    assert list(rec) == []


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """The walk's folder, with the inputs the rows read."""
    path = tmp_path_factory.mktemp("speaking")
    (path / "targets.toml").write_text(GOOD_TARGETS)
    (path / "s.toml").write_text(SPREAD)
    (path / "trace.csv").write_text(TRACE)
    step = resources.files("empact.data").joinpath("control", "slip-load-step-r1.toml")
    text = step.read_text()
    assert "duration = 2.5\n" in text
    (path / "step.toml").write_text(text.replace("duration = 2.5\n", "duration = 0.2\n")
                                     .replace("load_step_time = 0.5\n", "load_step_time = 0.1\n"))
    return path


@pytest.mark.parametrize("path", [p for p, a in WRITES.items() if a is not None],
                         ids=[" ".join(p) for p, a in WRITES.items() if a is not None])
def test_the_closing_line_lists_every_file_written(folder, monkeypatch, path):
    """The command (one run, every output it has) ends with one line on stderr that names
    (or, in a folder of many, counts by suffix) exactly the files that appeared or changed in
    its folder; stdout holds no path of them."""
    monkeypatch.chdir(folder)
    before = _state(folder)
    res = CliRunner().invoke(main, [*path, *WRITES[path]])
    assert res.exit_code == 0, res.output
    after = _state(folder)
    written = {p for p in after if before.get(p) != after[p]}
    assert written, path
    lines = [ln for ln in res.stderr.splitlines() if not PROGRESS.match(ln)]
    closing = [ln for ln in lines if ln.startswith("written: ")]
    assert len(closing) == 1 and lines[-1] == closing[0], res.stderr
    named, counted = _parse(closing[0])
    in_counted = {p for p in written if p.rpartition("/")[0] in counted}
    assert named == written - in_counted | (named & in_counted), (named, written)
    for sub, counts in counted.items():
        mine = [p for p in written if p.rpartition("/")[0] == sub and p not in named]
        by_suffix = {}
        for p in mine:
            suffix = "." + p.rpartition(".")[2]
            by_suffix[suffix] = by_suffix.get(suffix, 0) + 1
        assert by_suffix == counts, (sub, by_suffix, counts)
    assert not any(p in res.stdout for p in written if "/" not in p), res.stdout


def _no_delay(monkeypatch):
    """Progress lines at once (the first line waits a second of work otherwise): the
    indicator's and the bars' `delay` set to 0."""
    from empact import _progress

    monkeypatch.setitem(_progress.working.__wrapped__.__kwdefaults__, "delay", 0.0)
    monkeypatch.setitem(_progress.progress.__kwdefaults__, "delay", 0.0)


#: the commands added since the last round, each a short run that writes a file
NEW = {
    "cycle": ["cycle", "--cycle", "trace.csv", "--strategies", "sf1.3", "--plot", "c.png"],
    "efficiency": ["efficiency", "--ratio", "1", "--torque", "50", "--json-out", "e.json"],
    "control tune": ["control", "tune", "shipped:pi", "--family", "fam.npz", "--maxiter",
                     "1", "--out", "t.json"],
    "fmu export": ["fmu", "export", "--out", "f.fmu"],
}


@pytest.fixture(scope="module")
def family(tmp_path_factory):
    """A two-point plant family (for `control tune`)."""
    path = tmp_path_factory.mktemp("family") / "fam.npz"
    res = CliRunner().invoke(main, ["plants", "--ratio", "0.5,1", "--tau", "0.9", "--out",
                                    str(path), "--quiet"])
    assert res.exit_code == 0, res.output
    return path


def _inputs(folder, family):
    (folder / "trace.csv").write_text(TRACE)
    (folder / "fam.npz").write_bytes(family.read_bytes())


@pytest.mark.parametrize("name", list(NEW))
def test_new_commands_show_progress_and_quiet_silences_stderr(tmp_path, monkeypatch, name,
                                                              family):
    """Off a terminal (CliRunner's stderr is not one) a run shows progress lines on stderr
    (here at once: `_no_delay`), then the closing line; with --quiet stderr is empty and the
    file is written all the same."""
    monkeypatch.chdir(tmp_path)
    _inputs(tmp_path, family)
    _no_delay(monkeypatch)
    res = CliRunner().invoke(main, NEW[name])
    assert res.exit_code == 0, res.output
    lines = res.stderr.splitlines()
    assert any(PROGRESS.match(ln) for ln in lines[:-1]), res.stderr
    assert lines[-1].startswith("written: "), res.stderr
    out = NEW[name][-1]
    (tmp_path / out).unlink()
    res = CliRunner().invoke(main, [*NEW[name], "--quiet"])
    assert res.exit_code == 0 and res.stderr == "", res.stderr
    assert (tmp_path / out).is_file()


#: a number in text: digits with an optional fraction and exponent, not inside a name
NUMBER = re.compile(r"(?<![\w.\-+])[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?(?![\w.])")
#: what gives a number its unit after it: a unit (``[-]`` too), a percent sign, a count's
#: noun, or the unit of the value it changes to (``0.5 -> 0.6 [-]``)
UNIT = (r"(?:%|\[[^\]]*\]|[kMG]?(?:m|s|J|W|N m|N|Hz|dB|deg|rad/s|rad|g|l|km|kN|rpm)\b|"
        r"l/100 ?km|/s\b|(?:plants?|evaluations?|runs?|samples?|points?|strategies|states?|"
        r"files?)\b)")
UNIT_AFTER = re.compile(rf"\s*(?:{UNIT}|->\s*[-+]?[\d.e+-]+\s*{UNIT})")
#: a list's unit before it in its line (``multipliers [-]: a 1, b 2``)
LIST_UNIT = re.compile(r"\[[^\]]*\]:")
#: dimensionless variables, whose value needs no unit (``mu = 0.1``, ``r_g = 1``)
DIMENSIONLESS = re.compile(r"\b(?:mu|tau|r_g|nu|kappa|Ms ratio|slip|margin)\s*(?:=|->)?\s*$")
#: a line of units heading a table's columns (``[kJ]  [%]  [-]``)
UNITS_ROW = re.compile(r"^(?:\s*\[[^\]]*\])+\s*$")


def unitless(text: str) -> list[str]:
    """The lines of `text` with a number that has no unit: none follows it (`UNIT_AFTER`),
    it is not the value of a dimensionless variable (`DIMENSIONLESS`), and it is not in a
    table's row under a row of units (at most as many numbers as the table has units)."""
    bad, columns = [], 0
    for line in text.splitlines():
        if UNITS_ROW.match(line):
            columns = line.count("[")
            continue
        numbers = list(NUMBER.finditer(line))
        if columns and 0 < len(numbers) <= columns:
            continue  # a row of the table above
        columns = 0 if not numbers else columns
        if any(not UNIT_AFTER.match(line[m.end():]) and not LIST_UNIT.search(line[:m.start()])
               and not DIMENSIONLESS.search(line[:m.start()]) for m in numbers):
            bad.append(line)
    return bad


def test_the_unit_check_sees_a_number_without_a_unit():
    """`unitless` flags a bare number and passes a unit, a count, a dimensionless value and a
    table's row."""
    assert unitless("torque 0.5, peak 3.2") == ["torque 0.5, peak 3.2"]
    assert unitless("12.3 km in 40 s; 2 plants; mu = 0.1; 5 %; 0.5 -> 0.6 [-]") == []
    assert unitless("gains [-]: a 1, b 2") == [] and unitless("gains: a 1") == ["gains: a 1"]
    assert unitless("name  a  b\n      [kJ] [%]\nx     1.0  2.0") == []


@pytest.mark.parametrize("name", list(NEW))
def test_new_commands_give_a_unit_for_every_number(tmp_path, monkeypatch, name, family):
    """The text of the commands added since the last round: every number has its unit, in
    its line (``12.3 km``, ``(+-1.2 dB)``) or in its column's header (a table's row of units);
    a dimensionless value is named (``mu = 0.1``) or a count (``2 plants``)."""
    monkeypatch.chdir(tmp_path)
    _inputs(tmp_path, family)
    res = CliRunner().invoke(main, [*NEW[name], "--quiet"])
    assert res.exit_code == 0, res.output
    assert unitless(res.stdout) == [], res.stdout

"""Atomic output (`empact._io`), lazy imports (`empact._lazy`) and progress bars
(`empact._progress`)."""
import os
import stat
import subprocess
import sys

import pytest

from empact._io import atomic_file, atomic_folder, atomic_write_text, umask


def _mode(p):
    return stat.S_IMODE(os.stat(p).st_mode)


def test_atomic_file_is_complete_or_absent(tmp_path):
    path = tmp_path / "a.txt"
    atomic_write_text(path, "one")
    with pytest.raises(RuntimeError):
        with atomic_file(path) as tmp:
            tmp.write_text("half")
            raise RuntimeError("interrupted")
    assert path.read_text() == "one"  # the old content survives a failed write
    assert [p.name for p in tmp_path.iterdir()] == ["a.txt"]  # no temporary left
    assert _mode(path) == 0o666 & ~umask()  # an ordinary file, not mkstemp's 0600


def test_atomic_folder_merges_and_cleans_up(tmp_path):
    dest = tmp_path / "out"
    with pytest.raises(RuntimeError):
        with atomic_folder(dest) as tmp:
            (tmp / "x.csv").write_text("1")
            raise RuntimeError("interrupted")
    assert not dest.exists() and list(tmp_path.iterdir()) == []
    with atomic_folder(dest) as tmp:
        (tmp / "x.csv").write_text("1")
    (dest / "mine.txt").write_text("keep")
    with atomic_folder(dest) as tmp:
        (tmp / "x.csv").write_text("2")
    assert (dest / "x.csv").read_text() == "2" and (dest / "mine.txt").read_text() == "keep"
    assert _mode(dest) == 0o777 & ~umask() and _mode(dest / "x.csv") == 0o666 & ~umask()


def test_lazy_module_defers_the_import():
    code = ("import sys; from empact._lazy import lazy_module; c = lazy_module('control'); "
            "a = 'matplotlib.pyplot' in sys.modules; c.ss; "
            "print(a, 'matplotlib.pyplot' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["False", "True"]


def test_progress_off_a_terminal_writes_plain_lines(capsys):
    """Captured or redirected stderr gets whole lines (first and final state), no carriage
    returns or escapes; disabled, nothing."""
    from empact._progress import progress
    assert list(progress(range(7), desc="work", unit="step", delay=0)) == list(range(7))
    err = capsys.readouterr().err
    assert "\r" not in err and "\x1b" not in err
    lines = err.splitlines()
    assert lines[0].startswith("work:   0%") and lines[-1].startswith("work: 100%")
    assert "7/7" in lines[-1] and len(lines) == 2  # at most one line per 10 s in between
    with progress(total=3, desc="quiet", unit="step", enabled=False) as bar:
        bar.update(3)
    assert capsys.readouterr().err == ""


def test_progress_lines_wait_for_a_second(capsys):
    """Off a terminal a bar writes nothing when its work ends within `delay` (a quick run, bad
    input found at once: its one error line stays alone); a bar still running when the delay's
    timer fires writes its state then, and its final state."""
    from empact._progress import progress
    with progress(total=3, desc="quick", unit="step") as bar:
        bar.update(3)
    assert capsys.readouterr().err == ""
    with progress(total=3, desc="long", unit="step", delay=60.0) as bar:
        bar.update(1)
        bar.show()  # what the timer does after 60 s
        bar.update(2)
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 2 and "1/3" in lines[0] and "3/3" in lines[1], lines


def test_a_first_run_says_that_the_model_compiles(capsys):
    """numba's compile event (it fires on a cache miss only) for a function of empact prints
    one line, once; a compile of someone else's function prints nothing."""
    import numba
    from numba.core import event

    from empact.cli import _common
    from empact.nonlinear import _kernel

    _common.announce_compilation()
    _common._announced.value = 0  # (as in a fresh process: a first run)
    other = numba.njit(lambda x: x + 1)
    for disp in (other, _kernel.traction_mu, _kernel.law.belt_geometry):
        with event.trigger_event("numba:compile", data={"dispatcher": disp, "args": (),
                                                        "return_type": None}):
            pass
    assert capsys.readouterr().err == _common.COMPILING + "\n"


# -- issue 35: guarded input files, temporary names that fit, the work indicator --------------
def test_guarded_reader_refuses_what_would_hang_or_overflow(tmp_path):
    """`check_input` / `parse_json` / `parse_toml`: a FIFO is refused without opening it
    (opening one blocks), a file above its size limit, non-UTF-8 text, and nesting deeper
    than `MAX_DEPTH` (100 000 levels raised RecursionError before); each one line naming the
    file."""
    from empact._io import MAX_DEPTH, check_input, parse_json, parse_toml, read_input_text
    from empact.errors import ParameterError

    os.mkfifo(tmp_path / "pipe")
    with pytest.raises(ParameterError, match=r"pipe: is a FIFO \(named pipe\), not a table "
                                             r"file$"):
        check_input(tmp_path / "pipe", "table")
    big = tmp_path / "big.csv"
    big.write_text("x" * 3000)
    with pytest.raises(ParameterError, match=r"big.csv: 0 MiB; a data file may hold at most 0 "
                                             r"MiB$"):
        check_input(big, "data", max_bytes=2048)
    (tmp_path / "l1.toml").write_bytes("a = 'r\xe9glage'\n".encode("latin-1"))
    with pytest.raises(ParameterError, match=r"l1.toml: not a UTF-8 text file"):
        read_input_text(tmp_path / "l1.toml", "parameter")
    for depth, fails in ((MAX_DEPTH, False), (MAX_DEPTH + 1, True), (100_000, True)):
        (tmp_path / "d.json").write_text("[" * depth + "]" * depth)
        (tmp_path / "d.toml").write_text("a = " + "[" * (depth - 1) + "]" * (depth - 1) + "\n")
        for parse, name in ((parse_json, "d.json"), (parse_toml, "d.toml")):
            if fails:
                with pytest.raises(ParameterError, match=f"{name}: nested deeper than "
                                                         f"{MAX_DEPTH} levels"):
                    parse(tmp_path / name, "test")
            else:
                parse(tmp_path / name, "test")


def test_temporary_names_fit_the_file_system(tmp_path):
    """A destination whose name is within the 255-byte limit gets a temporary name within it
    too (a 250-byte name failed with 'File name too long' in the temporary's longer name)."""
    dest = tmp_path / ("y" * 245 + ".json")
    atomic_write_text(dest, "{}")
    assert dest.read_text() == "{}" and sorted(p.name for p in tmp_path.iterdir()) == [dest.name]
    folder = tmp_path / ("z" * 255)
    with atomic_folder(folder) as tmp:
        (tmp / "a.txt").write_text("a")
    assert (folder / "a.txt").read_text() == "a"


def test_working_indicator_off_a_terminal(capsys):
    """`working`: nothing for a block shorter than its delay; a line ``desc: working, 00:00
    elapsed`` after it; ended (no more lines, no final line) by a real progress bar."""
    import time

    from empact._progress import progress, working

    with working("quick", delay=5.0):
        pass
    assert capsys.readouterr().err == ""
    with working("slow", delay=0.05):
        time.sleep(0.4)
    err = capsys.readouterr().err.splitlines()
    assert err == ["slow: working, 00:00 elapsed"], err
    with working("outer", delay=0.05):
        time.sleep(0.3)
        with progress(total=2, desc="inner", unit="step", delay=0) as bar:
            bar.update(2)
        time.sleep(0.2)
    err = capsys.readouterr().err.splitlines()
    assert err[0] == "outer: working, 00:00 elapsed" and all("outer" not in e for e in err[1:])
    with working("off", delay=0.0, enabled=False):
        time.sleep(0.1)
    assert capsys.readouterr().err == ""

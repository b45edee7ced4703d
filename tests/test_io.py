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

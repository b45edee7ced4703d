import os

os.environ.setdefault("MPLBACKEND", "Agg")

import pytest  # noqa: E402

from empact.params import default_params  # noqa: E402


@pytest.fixture(scope="session")
def params():
    return default_params()


@pytest.fixture(scope="session")
def full_report(tmp_path_factory):
    """The suite's one full build of the report (`empact reproduce`), shared by the tests of
    the command and of the claims: (the CLI result, the report folder)."""
    from click.testing import CliRunner

    from empact.cli import main

    out = tmp_path_factory.mktemp("full") / "rep"
    res = CliRunner().invoke(main, ["reproduce", "--out", str(out), "--quiet"])
    return res, out


class _Tour:
    """The README tour, run in the background by `readme_tour.py` (started once)."""

    def __init__(self) -> None:
        import subprocess
        import sys
        import tempfile
        from pathlib import Path

        self.folder = Path(tempfile.mkdtemp(prefix="empact-readme-tour-"))
        self.results = self.folder.with_suffix(".json")
        (self.folder / "tour").mkdir()
        self.proc = subprocess.Popen(
            [sys.executable, str(Path(__file__).with_name("readme_tour.py")),
             str(self.folder / "tour"), str(self.results)],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    def result(self, timeout: float = 380.0):
        """(the records of the steps, the tour's folder), once the tour has finished."""
        import json

        self.proc.wait(timeout=timeout)
        return json.loads(self.results.read_text()), self.folder / "tour"

    def close(self) -> None:
        import shutil

        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        shutil.rmtree(self.folder, ignore_errors=True)
        self.results.unlink(missing_ok=True)


_TOUR: list = []


def pytest_collection_finish(session):
    """Start the README tour in the background as soon as the session knows it will run its
    test (it is mostly process start-up, which the rest of the suite overlaps)."""
    if session.config.option.collectonly:
        return
    if any(getattr(item, "originalname", "") == "test_the_readme_tour_runs_as_written"
           for item in session.items):
        _TOUR.append(_Tour())


def pytest_sessionfinish(session):
    while _TOUR:
        _TOUR.pop().close()


@pytest.fixture(scope="session")
def readme_tour():
    """The README tour running in the background (`readme_tour.py`)."""
    if not _TOUR:
        _TOUR.append(_Tour())
    return _TOUR[0]

import os

os.environ.setdefault("MPLBACKEND", "Agg")

import pytest  # noqa: E402

from empact._compile import drop_stale_cache  # noqa: E402
from empact.params import default_params  # noqa: E402

# an edited kernel must not be tested through integrators compiled against its old version
drop_stale_cache()


@pytest.fixture(scope="session")
def params():
    return default_params()


@pytest.fixture(scope="session")
def cluster():
    """The suite's one local Dask cluster (2 worker processes), shared by the sweep tests
    that use an address: its scheduler's address."""
    import distributed  # the 'dask' extra: the Makefile installs it, so a missing one fails
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0", silence_logs=50) as c:
        yield c.scheduler_address


#: the figures the tests read from the full report (png and svg); the background build draws
#: only these (`report_build.py`): every section, table, claim and the page are written
REPORT_FIGURES = ("fig4_actuation_modes", "fig5_actuation_energy", "fig6_actuation_frf",
                  "fig8_driveline_modes", "fig8_driveline_energy", "fig9_root_locus_cb",
                  "slip_stability_map", "fig2_identified_plant", "fig14_rig_T_mp")


class _Report:
    """The suite's one full build of the report (`empact reproduce`), run in the background
    by `report_build.py` from the start of the session (it overlaps the rest of the suite)."""

    def __init__(self) -> None:
        import subprocess
        import sys
        import tempfile
        from pathlib import Path

        self.folder = Path(tempfile.mkdtemp(prefix="empact-full-report-"))
        self.out = self.folder / "full" / "rep"
        self.out.parent.mkdir()
        self.results = self.folder / "results.json"
        self.proc = subprocess.Popen(
            [sys.executable, str(Path(__file__).with_name("report_build.py")), str(self.out),
             str(self.results), *REPORT_FIGURES],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    def result(self, timeout: float = 900.0):
        """(the CLI result: exit_code and output, the report folder), once built."""
        import json
        from types import SimpleNamespace

        self.proc.wait(timeout=timeout)
        return SimpleNamespace(**json.loads(self.results.read_text())), self.out

    def close(self) -> None:
        import shutil

        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        shutil.rmtree(self.folder, ignore_errors=True)


_REPORT: list = []


@pytest.fixture(scope="session")
def full_report():
    """The suite's one full build of the report (`empact reproduce`), shared by the tests of
    the command and of the claims: (the CLI result, the report folder).  Only the figures the
    tests read are drawn (`REPORT_FIGURES`)."""
    if not _REPORT:
        _REPORT.append(_Report())
    return _REPORT[0].result()


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


#: the end-to-end tiers' files: every test in them is marked ``e2e`` (``make test-fast`` leaves
#: them out; ``make test`` and CI run them)
E2E_FILES = {"test_readme.py", "test_report.py", "test_interrupt.py", "test_docs_site.py"}
#: the fixtures of the end-to-end tests (the full report build, the README tour, a Dask
#: cluster): a test that uses one is ``e2e`` wherever it is
E2E_FIXTURES = {"full_report", "readme_tour", "cluster"}


#: the test that runs last: every signature the session compiled is one `compile_all` loads
LAST = "test_the_session_compiled_nothing_compile_all_does_not"


def pytest_collection_modifyitems(session, config, items):
    """Mark the end-to-end tests ``e2e`` (by file, by fixture, or marked so in their file;
    every other test, a new one included, is in the fast tier), then run the tests that read
    the full report last (stable order otherwise: the rest of the suite runs while the
    report builds in the background, instead of waiting for it) and `LAST` after them."""
    for item in items:
        if (item.path.name in E2E_FILES
                or E2E_FIXTURES & set(getattr(item, "fixturenames", ()))):
            item.add_marker(pytest.mark.e2e)
    # the check that the session compiled nothing `compile_all` does not runs after the rest
    items.sort(key=lambda item: (getattr(item, "originalname", "") == LAST,
                                 "full_report" in getattr(item, "fixturenames", ())))


def pytest_collection_finish(session):
    """Start the full report build and the README tour in the background as soon as the
    session knows it will run their tests (the rest of the suite overlaps them)."""
    if session.config.option.collectonly:
        return
    if any("full_report" in getattr(item, "fixturenames", ()) for item in session.items):
        _REPORT.append(_Report())
    if any(getattr(item, "originalname", "") == "test_the_readme_tour_runs_as_written"
           for item in session.items):
        _TOUR.append(_Tour())


def pytest_sessionfinish(session):
    while _TOUR:
        _TOUR.pop().close()
    while _REPORT:
        _REPORT.pop().close()


@pytest.fixture(scope="session")
def readme_tour():
    """The README tour running in the background (`readme_tour.py`)."""
    if not _TOUR:
        _TOUR.append(_Tour())
    return _TOUR[0]

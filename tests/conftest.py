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

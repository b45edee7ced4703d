import os

os.environ.setdefault("MPLBACKEND", "Agg")

import pytest  # noqa: E402

from empact.params import default_params  # noqa: E402


@pytest.fixture(scope="session")
def params():
    return default_params()

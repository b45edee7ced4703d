"""Packaging (issue 24, item 4): one source for the version, the SPDX licence, the licence file
in the distribution. (That `pip install` prints no build warning is checked where the install
happens: the Makefile's install step fails on one.)"""
import importlib.metadata
import tomllib
from pathlib import Path

import empact

ROOT = Path(__file__).resolve().parents[1]


def test_the_version_has_one_source():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert "version" not in project and "version" in project["dynamic"]
    assert importlib.metadata.version("empact") == empact.__version__


def test_the_licence_is_an_spdx_expression_with_its_file():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["license"] == "MIT" and project["license-files"] == ["LICENSE"]
    meta = importlib.metadata.metadata("empact")
    assert meta["License-Expression"] == "MIT"
    assert "LICENSE" in meta.get_all("License-File")
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")


def test_the_build_backend_supports_the_spdx_licence():
    """setuptools reads `license = "MIT"` as an SPDX expression from version 77 on; an older
    floor would let a build fail or warn on the table form."""
    requires = tomllib.loads((ROOT / "pyproject.toml").read_text())["build-system"]["requires"]
    assert "setuptools>=77" in requires


def test_the_changelog_has_a_section_for_the_version():
    """``CHANGELOG.md`` has a dated section for `empact.__version__` (Keep a Changelog's
    ``## X.Y.Z - YYYY-MM-DD``), above the previous release's."""
    import re
    heads = re.findall(r"^## (\d+\.\d+\.\d+) - \d{4}-\d{2}-\d{2}$",
                       (ROOT / "CHANGELOG.md").read_text(), re.M)
    assert heads[:1] == [empact.__version__], heads
    assert heads == sorted(heads, key=lambda v: tuple(map(int, v.split("."))), reverse=True)

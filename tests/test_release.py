"""Release metadata agrees with the one version (sql/tgsis.control): PGXN's META.json, the changelog, pyproject."""

from __future__ import annotations

import json
import re
import tomllib
from pathlib import Path

import tgsis
from tgsis.db.sqlsource import ExtensionSources

ROOT = Path(__file__).resolve().parents[1]


def test_meta_json_is_this_version_and_names_a_built_script() -> None:
    meta = json.loads((ROOT / "META.json").read_text(encoding="utf-8"))
    version = ExtensionSources.default().version
    assert meta["version"] == version == tgsis.__version__
    provided = meta["provides"]["tgsis"]
    assert provided["version"] == version
    assert provided["file"] == f"sql/build/tgsis--{version}.sql", "the script sql/Makefile builds"
    assert (ROOT / provided["docfile"]).is_file()
    assert meta["meta-spec"]["version"] == "1.0.0" and meta["license"] == "bsd"
    requires = meta["prereqs"]["runtime"]["requires"]
    assert set(ExtensionSources.default().requires) <= set(requires), "the control file's requires"


def test_the_changelog_has_this_version_and_the_first_release_commit() -> None:
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    versions = re.findall(r"^## (\d+\.\d+\.\d+) - \d{4}-\d\d-\d\d$", text, re.MULTILINE)
    assert versions[0] == tgsis.__version__, "the newest section is the version being released"
    frozen = sorted(ExtensionSources.default().frozen_scripts)
    assert all(v in versions for v in frozen), "every version a database may be upgraded from is described"
    assert "48d1da2" in text


def test_pyproject_says_where_the_project_lives() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert {"Homepage", "Repository", "Issues", "Changelog"} <= set(project["urls"])
    assert project["authors"] and project["keywords"]
    assert "License :: OSI Approved :: BSD License" in project["classifiers"]

"""Release metadata agrees with the one version (sql/tgsis.control): PGXN's META.json, the changelog, pyproject;
the released versions (sql/upgrade/releases.txt) are frozen, described, tagged and older than the version in development."""

from __future__ import annotations

import json
import re
import subprocess
import tomllib
from pathlib import Path

import pytest

import tgsis
from tgsis.db import _upgrade
from tgsis.db.sqlsource import PSQL_GUARD, ExtensionSources, parse_version

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


def _releases() -> list[tuple[str, str, str]]:
    """(version, commit, date) of sql/upgrade/releases.txt."""
    lines = (ROOT / "sql" / "upgrade" / "releases.txt").read_text(encoding="utf-8").splitlines()
    return [tuple(line.split()) for line in lines if line.strip() and not line.startswith("#")]  # type: ignore[misc]


def test_every_release_is_frozen_described_and_older_than_this_version() -> None:
    """A released version has its frozen install script, its changelog section (with its commit and date),
    and the version in development is newer: SQL changed after a release goes into the next version."""
    releases = _releases()
    assert [v for v, _, _ in releases] == ["0.1.0", "0.2.0", *[v for v, _, _ in releases[2:]]]
    sources = ExtensionSources.default()
    assert sorted(sources.frozen_scripts) == sorted(v for v, _, _ in releases), "one frozen script per release"
    assert all(parse_version(v) < parse_version(sources.version) for v, _, _ in releases), (
        "default_version is still a released version: bump it (docs/developing.md, 'At a release')"
    )
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    sections = re.findall(r"^## (Unreleased|\d+\.\d+\.\d+ - \d{4}-\d\d-\d\d)$", text, re.MULTILINE)
    released = [f"{v} - {date}" for v, _, date in reversed(releases)]
    assert sections == ["Unreleased", *released], "the changelog: Unreleased, then each release, newest first"
    for version, commit, _ in releases:
        section = text.split(f"## {version} - ", 1)[1].split("\n## ", 1)[0]
        assert commit in section, f"the changelog's {version} section names its commit {commit}"
    # the upgrade chain from every release reaches this version
    for version, _, _ in releases:
        assert sources.upgrade_path(version, sources.version), version


def test_every_frozen_script_is_the_build_of_its_release_commit(tmp_path: Path) -> None:
    """sql/upgrade/tgsis--X.sql is what `make -C sql` built at the commit of release X (git tag vX)."""
    if not (ROOT / ".git").exists():
        pytest.skip("not a git checkout (the repository copied without its history, as .ci/run does)")
    for version, commit, _ in _releases():
        tree = tmp_path / version
        tree.mkdir()
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", commit, "sql"], capture_output=True, check=True)
        subprocess.run(["tar", "-x", "-C", str(tree)], input=archive.stdout, check=True)
        sql = tree / "sql"
        control = (sql / "tgsis.control").read_text(encoding="utf-8")
        assert f"default_version = '{version}'" in control, f"{commit} is not version {version}"
        names = [
            n for n in (line.split("#", 1)[0].strip() for line in (sql / "sources.txt").read_text().splitlines()) if n
        ]
        built = f"-- tgsis {version}: built from sql/sources.txt, do not edit\n{PSQL_GUARD}\n" + "".join(
            f"\n-- ==== {n} ====\n" + (sql / n).read_text(encoding="utf-8") for n in names
        ).replace("@TGSIS_VERSION@", version)
        built = built.replace(_upgrade.FINGERPRINT_TOKEN, _upgrade.fingerprint(built))  # (from 0.3.0 on)
        frozen = (ROOT / "sql" / "upgrade" / f"tgsis--{version}.sql").read_text(encoding="utf-8")
        assert frozen == built, f"sql/upgrade/tgsis--{version}.sql is not the build of {commit}"
        tagged = subprocess.run(
            ["git", "-C", str(ROOT), "rev-parse", "--verify", "--quiet", f"v{version}^{{commit}}"],
            capture_output=True,
            text=True,
            check=False,
        )
        if tagged.returncode == 0:  # a clone without tags has none; where the tag is, it names the commit
            assert tagged.stdout.startswith(
                subprocess.run(
                    ["git", "-C", str(ROOT), "rev-parse", commit], capture_output=True, text=True, check=True
                ).stdout.strip()
            )


def test_the_frozen_upgrades_no_longer_follow_the_sources() -> None:
    """Between released versions the upgrade scripts are frozen whole (sql/updates); only the one to the
    version in development is assembled from a hand part and the current sources."""
    sources = ExtensionSources.default()
    releases = [v for v, _, _ in _releases()]
    for (old, new), path in sources.updates.items():
        if new in releases:
            assert path.parent.name == "updates", f"{path.name} leads to a release: frozen in sql/updates"
        else:
            assert new == sources.version and path.parent.name == "upgrade" and old == releases[-1]
    assert (releases[-1], sources.version) in sources.updates, "the upgrade from the last release is in the making"


def test_pyproject_says_where_the_project_lives() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert {"Homepage", "Repository", "Issues", "Changelog"} <= set(project["urls"])
    assert project["authors"] and project["keywords"]
    assert "License :: OSI Approved :: BSD License" in project["classifiers"]

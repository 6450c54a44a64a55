"""The Docker images (docker/Dockerfile), checked without a Docker engine.

No engine runs where this suite runs (docker/README.md), so the images are
not built here. What can be checked is: the stages and their order, that the
images carry no build tools, that PostGIS is pinned to the version the suite
runs against, and that the build stages' commands work on exactly the files
they copy (run here in a folder laid out as the stage's). The first start
of the server image is tests/test_install_commands.py's.
"""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from tgsis.db.sqlsource import ExtensionSources

ROOT = Path(__file__).resolve().parents[1]
DOCKERFILE = ROOT / "docker" / "Dockerfile"
BUILD_TOOLS = ("make", "gcc", "python3", "postgresql-server-dev", "hatchling", "build-essential")


def _instructions() -> list[tuple[str, str]]:
    """(INSTRUCTION, arguments) with continuation lines joined and comments dropped."""
    text = re.sub(r"\\\n", " ", DOCKERFILE.read_text(encoding="utf-8"))
    out = []
    for line in text.splitlines():
        line = line.strip()
        if line and not line.startswith("#"):
            word, _, rest = line.partition(" ")
            out.append((word.upper(), rest.strip()))
    return out


def _stages() -> dict[str, list[tuple[str, str]]]:
    stages: dict[str, list[tuple[str, str]]] = {}
    current: list[tuple[str, str]] = []
    for word, rest in _instructions():
        if word == "FROM":
            match = re.match(r"(\S+)\s+AS\s+(\S+)$", rest, re.IGNORECASE)
            assert match, f"every stage is named: FROM {rest}"
            current = stages.setdefault(match.group(2), [("FROM", match.group(1))])
        else:
            current.append((word, rest))
    return stages


def _args() -> dict[str, str]:
    return dict(re.findall(r"^ARG (\w+)=(\S+)$", DOCKERFILE.read_text(encoding="utf-8"), re.MULTILINE))


def _copies(stage: str) -> list[tuple[list[str], str]]:
    """(sources, destination) of the stage's COPY instructions from the build context."""
    found = []
    for word, rest in _stages()[stage]:
        if word == "COPY" and not rest.startswith("--from"):
            *sources, destination = shlex.split(rest)
            found.append((sources, destination))
    return found


def _lay_out(stage: str, root: Path) -> None:
    """Copy the build context's files where the stage's COPY puts them, under ``root``."""
    for sources, destination in _copies(stage):
        for source in sources:
            src = ROOT / source
            target = root / destination.lstrip("/")
            if destination.endswith("/"):
                target = target / src.name
            if src.is_dir():
                shutil.copytree(src, target, ignore=shutil.ignore_patterns("build", "__pycache__"))
            else:
                target.parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(src, target)


def test_the_stages_and_the_default_target() -> None:
    stages = list(_stages())
    assert stages == ["extension", "wheel", "client", "server"]
    assert stages[-1] == "server", "docker build without --target (and testcontainers) gives the server"


@pytest.mark.parametrize("stage", ["server", "client"])
def test_the_images_have_no_build_tools(stage: str) -> None:
    for word, rest in _stages()[stage]:
        if word == "RUN":
            installs = re.findall(r"(?:apt-get install|pip install)([^&]*)", rest)
            for words in installs:
                assert not any(tool in words for tool in BUILD_TOOLS), f"{stage} installs a build tool: {words}"
        if word == "COPY" and rest.startswith("--from"):
            assert rest.split()[0] in ("--from=extension", "--from=wheel"), rest


def test_postgis_is_pinned_to_the_version_the_suite_runs_against() -> None:
    server = " ".join(rest for word, rest in _stages()["server"] if word == "RUN")
    assert '"postgresql-${PG_MAJOR}-postgis-3=${POSTGIS_VERSION}"' in server
    assert '"postgresql-${PG_MAJOR}-postgis-3-scripts=${POSTGIS_SCRIPTS_VERSION}"' in server
    args = _args()
    assert args["PG_MAJOR"] == "15"
    installed = subprocess.run(
        ["dpkg-query", "-W", "-f", "${Version}\\n", "postgresql-15-postgis-3", "postgresql-15-postgis-3-scripts"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert installed.returncode == 0, (
        f"PostGIS for PostgreSQL 15 is not installed here (make test installs it: tools/setup-machine): {installed.stderr}"
    )
    assert installed.stdout.split() == [args["POSTGIS_VERSION"], args["POSTGIS_SCRIPTS_VERSION"]]


def test_the_extension_stage_builds_from_what_it_copies(tmp_path: Path) -> None:
    """make -C sql install DESTDIR=/staging on exactly the stage's files (python3 for the upgrade script)."""
    _lay_out("extension", tmp_path)
    run = next(rest for word, rest in _stages()["extension"] if word == "RUN" and "make -C" in rest)
    assert run == "make -C /usr/src/tgsis/sql install DESTDIR=/staging"
    staging = tmp_path / "staging"
    done = subprocess.run(
        ["make", "-C", str(tmp_path / "usr/src/tgsis/sql"), "install", f"DESTDIR={staging}", "PG_CONFIG=pg_config"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    copied = next(rest for word, rest in _stages()["server"] if word == "COPY" and rest.startswith("--from=extension"))
    source = copied.split()[1].replace("${PG_MAJOR}", _args()["PG_MAJOR"])
    extension = staging / source.removeprefix("/staging/").strip("/")
    sources = ExtensionSources.default()
    assert (extension / f"tgsis--{sources.version}.sql").read_text(encoding="utf-8") == sources.script()
    for (old, new), path in sources.updates.items():
        assert (extension / f"tgsis--{old}--{new}.sql").read_text(encoding="utf-8") == sources.update_script(path)
    assert (extension / "tgsis.control").is_file() and (extension / "tgsis--0.1.0.sql").is_file()


def test_the_wheel_stage_builds_a_wheel_with_the_command(tmp_path: Path) -> None:
    _lay_out("wheel", tmp_path)
    project = tmp_path / "usr/src/tgsis"
    run = next(rest for word, rest in _stages()["wheel"] if word == "RUN" and "WheelBuilder" in rest)
    code = re.search(r'python -c "(.*)"$', run)
    assert code, run
    done = subprocess.run(
        [sys.executable, "-c", code.group(1).replace("'/dist'", repr(str(tmp_path / "dist")))],
        capture_output=True,
        text=True,
        check=False,
        cwd=project,
    )
    assert done.returncode == 0, done.stderr
    (wheel,) = (tmp_path / "dist").glob("tgsis-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    assert (
        "tgsis/cli/__init__.py" in names
        and "tgsis/_sql/tgsis.control" in names
        and "tgsis/_sql/upgrade/tgsis--0.1.0.sql" in names
    )
    entry_points = next(n for n in names if n.endswith("entry_points.txt"))
    assert "tgsis = tgsis.cli:main" in zipfile.ZipFile(wheel).read(entry_points).decode()
    client = _stages()["client"]
    assert ("ENTRYPOINT", '["tgsis"]') in client
    assert ("USER", "tgsis") in client, "the client does not run as root"

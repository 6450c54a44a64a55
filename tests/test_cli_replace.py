"""Importing a file whose object names a class already has: a warning, or `--replace` (one transaction, versioned)."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import psycopg
import pytest

import tgsis
from tests.local_helpers import child_env
from tgsis.cli import main

FLAGGED = Path(__file__).parent / "data" / "gocad" / "flagged.ts"  # surfaces F1 and F2


def _names(dsn: str, version: str = "DEFAULT") -> list[tuple[int, str]]:
    with psycopg.connect(dsn) as conn, tgsis.in_version(conn, version):
        return [
            (int(r[0]), str(r[1]))
            for r in conn.execute(
                "SELECT g.geoid, g.geoname FROM faults f JOIN tgsis.geometry g ON g.geoid = f._geoid ORDER BY 1"
            )
        ]


def _moved(path: Path, tmp_path: Path, dz: float) -> Path:
    """flagged.ts with every z moved by dz."""
    mesh = tgsis.formats.read(path)
    for m in mesh:
        m.vertices[:, 2] += dz
    out = tmp_path / "flagged.ts"
    tgsis.formats.write(tgsis.GeometryCollection(mesh) if len(mesh) > 1 else mesh[0], out)
    return out


@pytest.fixture
def faults(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> str:
    assert main(["--dsn", db_dsn, "class", "create", "faults", "--geotype", "SURFACE"]) == 0
    assert main(["--dsn", db_dsn, "import", str(FLAGGED), "--class", "faults"]) == 0
    capsys.readouterr()
    return db_dsn


def test_a_second_import_warns_and_replace_replaces(
    faults: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = _names(faults)
    assert main(["--dsn", faults, "import", str(FLAGGED), "--class", "faults"]) == 0
    err = capsys.readouterr().err
    assert (
        f"tgsis: warning: class faults already has a feature named 'F1' (id {before[0][0]}): this import adds "
        "another one; --replace replaces it"
        in err
        and "'F2'" in err
    )
    assert len(_names(faults)) == 4
    # two of each name now: --replace cannot tell which, and changes nothing
    assert main(["--dsn", faults, "import", str(FLAGGED), "--class", "faults", "--replace"]) == 1
    err = capsys.readouterr().err
    assert "--replace: class faults has 2 features named 'F1'" in err and "HINT: tgsis ls --class faults" in err
    assert len(_names(faults)) == 4


def test_replace_keeps_the_id_and_writes_by_difference(
    faults: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = _names(faults)
    moved = _moved(FLAGGED, tmp_path, 10.0)
    assert main(["--dsn", faults, "import", str(moved), "--class", "faults", "--replace", "--json"]) == 0
    out, err = capsys.readouterr()
    assert "warning" not in err
    doc = json.loads(out)
    assert [(f["id"], f["replaced"]) for f in doc["features"]] == [(fid, fid) for fid, _ in before]
    assert _names(faults) == before
    with psycopg.connect(faults) as conn:
        z = tgsis.fetch_feature(conn, "faults", before[0][0]).mesh.vertices[:, 2]  # type: ignore[union-attr]
    assert (z == tgsis.formats.read(FLAGGED)[0].vertices[:, 2] + 10.0).all()


def test_replace_in_a_version_is_a_change_of_that_version(
    faults: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = _names(faults)
    assert main(["--dsn", faults, "versioning", "enable", "features"]) == 0
    assert main(["--dsn", faults, "version", "create", "v"]) == 0
    moved = _moved(FLAGGED, tmp_path, 10.0)
    assert main(["--dsn", faults, "--in", "v", "import", str(moved), "--class", "faults", "--replace"]) == 0
    capsys.readouterr()
    assert _names(faults, "v") == _names(faults, "DEFAULT") == before
    with psycopg.connect(faults) as conn:
        original = tgsis.fetch_feature(conn, "faults", before[0][0]).mesh
        with tgsis.in_version(conn, "v"):
            edited = tgsis.fetch_feature(conn, "faults", before[0][0]).mesh
        keys = {d.objectkey for d in tgsis.diff_versions(conn, "DEFAULT", "v")}
    assert (edited.vertices[:, 2] == original.vertices[:, 2] + 10.0).all()  # type: ignore[union-attr]
    assert keys == {str(fid) for fid, _ in before}


def test_two_sessions_replacing_one_name_at_once_leave_one_feature(faults: str, tmp_path: Path) -> None:
    """Both imports wait on the name's lock; the second then sees the first's feature and replaces it."""
    fresh = tmp_path / "fresh.ts"
    mesh = tgsis.formats.read(FLAGGED)[1]
    mesh.name = "F9"
    tgsis.formats.write(mesh, fresh)
    tgsis_command = str(Path(sys.executable).parent / "tgsis")
    with psycopg.connect(faults, autocommit=True) as holder:
        # hold the lock of the name F9 in class faults, as one import would, while both start
        holder.execute("BEGIN")
        holder.execute("SELECT pg_advisory_xact_lock(hashtextextended(%s, 0))", ("tgsis import: public.faults: F9",))
        runs = [
            subprocess.Popen(
                [tgsis_command, "--dsn", faults, "import", str(fresh), "--class", "faults", "--replace"],
                env=child_env(),
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
            )
            for _ in range(2)
        ]
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            waiting = holder.execute(
                "SELECT count(*) FROM pg_locks WHERE locktype = 'advisory' AND NOT granted"
            ).fetchone()
            if waiting == (2,):
                break
            time.sleep(0.05)
        assert waiting == (2,), "both imports should wait on the name's lock"
        holder.execute("COMMIT")
        results = [run.communicate(timeout=120) for run in runs]
    assert [run.returncode for run in runs] == [0, 0], results
    assert [name for _, name in _names(faults)].count("F9") == 1


def test_a_collection_is_replaced_whole(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--dsn", db_dsn, "class", "create", "models", "--geotype", "GEOMETRYCOLLECTION"]) == 0
    capsys.readouterr()
    assert main(["--dsn", db_dsn, "import", str(FLAGGED), "--class", "models", "--json"]) == 0
    first = json.loads(capsys.readouterr().out)["features"][0]["id"]
    assert main(["--dsn", db_dsn, "import", str(FLAGGED), "--class", "models", "--replace", "--json"]) == 0
    out, err = capsys.readouterr()
    doc = json.loads(out)["features"][0]
    assert doc["replaced"] == first and doc["id"] != first and "warning" not in err
    with psycopg.connect(db_dsn) as conn:
        assert conn.execute("SELECT count(*) FROM models").fetchone() == (1,)
        # the members went with the collection they belonged to
        assert conn.execute("SELECT count(*) FROM tgsis.geometry").fetchone() == (3,)

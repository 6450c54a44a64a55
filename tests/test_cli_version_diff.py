"""`tgsis version diff` (issue 38, point 2): one line per object saying what differs, progress on a terminal.

A feature deleted in one version used to show as one line per table with its removed rows (two million of
them for a large surface) and nothing on the screen while the comparison ran; the summary now says
"only in DEFAULT", and `--tables` still gives the rows per table.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import psycopg
import pytest

import tgsis
from tests.test_cli_terminal import _on_a_terminal
from tgsis.cli import main

FLAGGED = Path(__file__).parent / "data" / "gocad" / "flagged.ts"  # F1 and F2


@pytest.fixture
def data(
    db_dsn: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> dict[str, Any]:
    """In version a: F1 deleted, F2 moved, F3 added."""
    monkeypatch.setenv("TGSIS_HOME", str(tmp_path / "home"))
    f1, f2 = tgsis.formats.read(FLAGGED)
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "faults", "SURFACE")
        gone, moved = (tgsis.insert_feature(conn, "faults", m) for m in (f1, f2))
        tgsis.enable_feature_versioning(conn)
        tgsis.create_version(conn, "a")
        with tgsis.in_version(conn, "a"):
            tgsis.delete_feature(conn, "faults", gone)
            conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = %s AND vrtxid = 1", (moved,))
            added = tgsis.insert_feature(conn, "faults", f1)
        conn.commit()
    capsys.readouterr()
    return {"dsn": db_dsn, "gone": gone, "moved": moved, "added": added}


def diff(data: dict[str, Any], capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[str, str]:
    assert main(["--dsn", data["dsn"], "version", "diff", *argv]) == 0
    out, err = capsys.readouterr()
    return out, err


def test_diff_says_per_feature_what_differs(data: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    out, err = diff(data, capsys, "DEFAULT", "a")
    header, *rows = (line.split("\t") for line in out.splitlines())
    assert header == ["class", "key", "difference", "tables", "added", "removed", "changed"]
    by_key = {int(r[1]): r for r in rows}
    assert list(by_key) == sorted(by_key) and set(by_key) == {data["gone"], data["moved"], data["added"]}
    assert by_key[data["gone"]][2] == "only in DEFAULT" and by_key[data["gone"]][5] != "-0"
    assert by_key[data["added"]][2] == "only in a" and by_key[data["added"]][4] != "+0"
    assert by_key[data["moved"]][2] == "changed" and by_key[data["moved"]][4:] == ["+0", "-0", "~1"]
    assert "vrtx" in by_key[data["gone"]][3].split(",")
    assert err == "3 objects differ: 1 only in DEFAULT, 1 only in a, 1 changed\n"
    # the other way round, the sides swap
    out, _ = diff(data, capsys, "a", "DEFAULT")
    assert {int(line.split("\t")[1]): line.split("\t")[2] for line in out.splitlines()[1:]} == {
        data["gone"]: "only in DEFAULT",
        data["added"]: "only in a",
        data["moved"]: "changed",
    }


def test_diff_json_has_objects_and_rows(data: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    doc = json.loads(diff(data, capsys, "DEFAULT", "a", "--json")[0])
    objects = {int(o["objectkey"]): o for o in doc["objects"]}
    assert objects[data["gone"]]["difference"] == "only in DEFAULT" and objects[data["gone"]]["added"] == 0
    assert objects[data["moved"]] == {
        "objectclass": "feature",
        "objectkey": str(data["moved"]),
        "difference": "changed",
        "tables": ["vrtx"],
        "added": 0,
        "removed": 0,
        "changed": 1,
    }
    assert sum(o["removed"] for o in doc["objects"]) == sum(d["removed"] for d in doc["differences"])


def test_diff_tables_keeps_the_rows_per_table(data: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    out, _ = diff(data, capsys, "DEFAULT", "a", "--tables")
    header, *rows = (line.split("\t") for line in out.splitlines())
    assert header == ["class", "key", "table", "added", "removed", "changed"]
    assert ["feature", str(data["moved"]), "vrtx", "+0", "-0", "~1"] in rows


def test_diff_shows_progress_on_a_terminal(data: dict[str, Any]) -> None:
    code, out, terminal = _on_a_terminal(["--dsn", data["dsn"], "version", "diff", "DEFAULT", "a"])
    assert code == 0, terminal
    assert "comparing DEFAULT and a" in terminal
    assert "only in DEFAULT" in out


def test_diff_shows_progress_over_the_tables(data: dict[str, Any]) -> None:
    """A bar over the versioned tables (not a spinner alone): done/total tables on the terminal, none in a pipe."""
    with psycopg.connect(data["dsn"]) as conn:
        tables = len(tgsis.versioned_tables(conn))
    assert tables > 2
    code, out, terminal = _on_a_terminal(["--dsn", data["dsn"], "version", "diff", "DEFAULT", "a"])
    assert code == 0, terminal
    assert "comparing DEFAULT and a" in terminal and f"{tables}/{tables}" in terminal and "table" in terminal
    assert f" 1/{tables}" in terminal  # table by table, not all at the end
    code, piped, quiet = _in_a_pipe(["--dsn", data["dsn"], "version", "diff", "DEFAULT", "a"])
    assert code == 0 and piped == out
    assert quiet == "3 objects differ: 1 only in DEFAULT, 1 only in a, 1 changed\n"  # the summary alone


def _in_a_pipe(argv: list[str]) -> tuple[int, str, str]:
    import subprocess

    from tests.local_helpers import child_env
    from tests.test_cli_terminal import TGSIS

    run = subprocess.run([TGSIS, *argv], env=child_env(), capture_output=True, text=True, check=False)
    return run.returncode, run.stdout, run.stderr

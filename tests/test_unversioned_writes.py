"""Writes "in" a version while feature versioning is off are refused (TG305), not put into DEFAULT.

Issue 15: an import with ``--in v1`` into plain (unversioned) feature tables
showed up in DEFAULT without a word. Every write path refuses it now, with a
hint in the words of the interface used, and leaves the database unchanged.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis.cli import main
from tgsis.db import features as F
from tgsis.db import temporal as T
from tgsis.db.checkin import save_feature

Conn = psycopg.Connection[Any]

TABLES = (
    "tgsis.geometry",
    "tgsis.vrtx",
    "tgsis.trgl",
    "tgsis.times",
    "tgsis.times_vrtx",
    "tgsis.timem",
    "tgsis.node",
    "faults",
    "faults_cellpros",
    "layers",
    "moving",
)


def _surface(z: float = 0.0) -> tgsis.Surface:
    return tgsis.Surface(
        np.array([[0, 0, z], [1, 0, z], [0, 1, z], [1, 1, z]], dtype=float), np.array([[0, 1, 2], [1, 3, 2]]), name="s"
    )


def _state(conn: Conn) -> dict[str, Any]:
    """Every row of the written tables: equal before and after a refused write."""
    return {t: sorted(map(str, conn.execute(f"SELECT * FROM {t}").fetchall())) for t in TABLES}  # noqa: S608


@pytest.fixture
def plain(conn: Conn) -> Conn:
    """Feature classes of all three models with one feature each, feature versioning off, a version v1."""
    tgsis.create_feature_class(conn, "faults", "SURFACE", feature_properties={"release": "text"})
    tgsis.create_feature_class(conn, "layers", "SURFACE", time_model="INSTANTS", time_unit="Ma")
    tgsis.create_feature_class(conn, "moving", "SURFACE", time_model="EVOLVING", time_unit="Ma")
    tgsis.insert_feature(conn, "faults", _surface(), {"release": "5.3"})
    tgsis.insert_feature(conn, "layers", tgsis.SurfaceSeries([0.0, 1.0], [_surface(), _surface(1)]))
    tgsis.create_version(conn, "v1")
    conn.commit()
    return conn


def _ids(conn: Conn) -> tuple[int, int]:
    fault = conn.execute("SELECT _geoid FROM faults").fetchone()
    layer = conn.execute("SELECT _geoid FROM layers").fetchone()
    assert fault is not None and layer is not None
    return int(fault[0]), int(layer[0])


def _python_writes(conn: Conn) -> dict[str, Any]:
    fault, layer = _ids(conn)
    period = tgsis.TopologyPeriod([-1.0, 0.0], _surface().triangles, [_surface().vertices, _surface(2).vertices])
    return {
        "insert_feature": lambda: tgsis.insert_feature(conn, "faults", _surface(5)),
        "insert_feature (collection)": lambda: tgsis.insert_feature(
            conn, F.create_feature_class(conn, "bag", "GEOMETRYCOLLECTION"), tgsis.GeometryCollection([_surface()])
        ),
        "insert_series": lambda: tgsis.insert_feature(conn, "layers", tgsis.SurfaceSeries([0.0], [_surface()])),
        "insert_evolving": lambda: tgsis.insert_feature(conn, "moving", tgsis.EvolvingSurface([period])),
        "add_instant": lambda: T.add_instant(conn, "layers", layer, 2.0, _surface(2)),
        "delete_instant": lambda: T.delete_instant(conn, layer, 1.0),
        "save_feature": lambda: save_feature(conn, "faults", fault, _surface(3)),
        "delete_feature": lambda: tgsis.delete_feature(conn, "faults", fault),
    }


@pytest.mark.parametrize(
    "write",
    [
        "insert_feature",
        "insert_feature (collection)",
        "insert_series",
        "insert_evolving",
        "add_instant",
        "delete_instant",
        "delete_feature",
        "save_feature",
    ],
)
def test_python_writes_in_a_version_are_refused(plain: Conn, write: str) -> None:
    before = _state(plain)
    with tgsis.in_version(plain, "v1"):
        with pytest.raises(tgsis.NotVersionedError, match="is not versioned: a write in version 'v1'") as caught:
            _python_writes(plain)[write]()
    plain.rollback()
    assert caught.value.sqlstate == "TG305"
    assert caught.value.hint is not None and "tgsis.enable_feature_versioning(conn)" in caught.value.hint
    assert "tgsis.goto_version(conn, 'DEFAULT')" in caught.value.hint
    assert _state(plain) == before


def test_the_same_writes_in_default_still_work(plain: Conn) -> None:
    for write in _python_writes(plain).values():
        write()
        plain.commit()
    assert plain.execute("SELECT count(*) FROM faults").fetchone() == (1,)  # one deleted, one added


def test_a_write_while_viewing_an_old_revision_of_default_is_refused(plain: Conn) -> None:
    before = _state(plain)
    tgsis.goto_revision(plain, "DEFAULT", 0)
    with pytest.raises(tgsis.NotVersionedError, match="DEFAULT viewed at revision 0 cannot be written"):
        tgsis.insert_feature(plain, "faults", _surface(5))
    plain.rollback()
    assert _state(plain) == before


def test_writes_in_a_version_work_once_features_are_versioned(plain: Conn) -> None:
    tgsis.enable_feature_versioning(plain)
    with tgsis.in_version(plain, "v1"):
        fid = tgsis.insert_feature(plain, "faults", _surface(5))
    plain.commit()
    assert plain.execute("SELECT count(*) FROM faults WHERE _geoid = %s", (fid,)).fetchone() == (0,)  # DEFAULT


SQL_WRITES = {
    "new_geometry": "SELECT tgsis.new_geometry('SURFACE', 'x', NULL, 0, 0)",
    "delete_geometry": "SELECT tgsis.delete_geometry({fault})",
    "add_instant": "SELECT tgsis.add_instant({layer}, 5)",
    "delete_instant": "SELECT tgsis.delete_instant({layer}, 1)",
}


@pytest.mark.parametrize("write", sorted(SQL_WRITES))
def test_sql_writes_in_a_version_are_refused(plain: Conn, write: str) -> None:
    fault, layer = _ids(plain)
    before = _state(plain)
    plain.execute("SELECT tgsis.goto_version('v1')")
    with pytest.raises(psycopg.Error) as caught:
        plain.execute(SQL_WRITES[write].format(fault=fault, layer=layer))
    diag = caught.value.diag
    assert caught.value.sqlstate == "TG305", diag.message_primary
    assert diag.message_primary is not None and "is not versioned: a write in version 'v1'" in diag.message_primary
    assert diag.message_detail is not None and "tgsis.version" in diag.message_detail
    assert diag.message_hint == (
        "SELECT tgsis.enable_feature_versioning() to write features in versions, "
        "or SELECT tgsis.goto_version('DEFAULT') to write in DEFAULT"
    )
    plain.rollback()
    assert _state(plain) == before


def test_sql_writes_in_default_still_work(plain: Conn) -> None:
    fault, layer = _ids(plain)
    for write in SQL_WRITES.values():
        plain.execute(write.format(fault=fault, layer=layer))
    plain.commit()


def test_cli_import_in_a_version_is_refused(
    plain: Conn, db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("TGSIS_HOME", str(tmp_path))
    monkeypatch.delenv("TGSIS_VERSION", raising=False)
    path = tmp_path / "s.ts"
    from tgsis import formats

    formats.write(_surface(7), path)
    before = _state(plain)
    plain.commit()
    assert main(["--dsn", db_dsn, "--in", "v1", "import", str(path), "--class", "faults"]) == 1
    err = capsys.readouterr().err
    assert "tgsis: error: table tgsis.geometry is not versioned: a write in version 'v1'" in err
    assert "HINT: tgsis versioning enable features" in err and "--in DEFAULT" in err
    assert _state(plain) == before
    assert main(["--dsn", db_dsn, "import", str(path), "--class", "faults"]) == 0  # DEFAULT: fine

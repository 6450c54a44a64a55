"""Snapshots with their properties: vertex and cell property values at t in SQL and in get_at (issue 18, part 2).

``tgsis.property_at`` and ``get_at(..., properties=True)`` must give the
values :meth:`EvolvingSurface.at` / :meth:`SurfaceSeries.at` give, to the
bit, at the instants and between them; ``tgsis at`` writes them to the file.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.temporal_data import evolving, series
from tgsis import formats
from tgsis.cli import main
from tgsis.mesh import Surface

Conn = psycopg.Connection[Any]


@pytest.fixture
def stored(conn: Conn) -> dict[str, Any]:
    fault = evolving(np.random.default_rng(7), [-10.0, -6.0], instants_per_period=4, with_properties=True)
    horizon = series(np.random.default_rng(8), [0.0, 1.0, 2.5], alive=True, with_properties=True)
    flat = Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], vertex_properties={"porosity": [0.1, 0.2, 0.3]})
    tgsis.create_feature_class(
        conn,
        "faults",
        "SURFACE",
        time_model="EVOLVING",
        cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "float8"), ("note_code", "integer")],
    )
    tgsis.create_feature_class(
        conn,
        "horizons",
        "SURFACE",
        time_model="INSTANTS",
        cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "float8")],
    )
    tgsis.create_feature_class(conn, "plain", "SURFACE", cell_properties=[("porosity", "float8"), ("wet", "boolean")])
    ids = {
        "fault": tgsis.insert_feature(conn, "faults", fault),
        "horizon": tgsis.insert_feature(conn, "horizons", horizon, drop_extra_properties=True),
        "flat": tgsis.insert_feature(
            conn,
            "plain",
            Surface(
                flat.vertices,
                flat.cells,
                vertex_properties={"porosity": [0.1, 0.2, 0.3], "wet": np.array([True, False, True])},
            ),
        ),
    }
    conn.commit()
    return {"ids": ids, "fault": fault, "horizon": horizon}


def test_properties_at_t_equal_the_python_snapshot(conn: Conn, stored: dict[str, Any]) -> None:
    rng = np.random.default_rng(0)
    for key, times in (("fault", [-10.0, -8.0, -6.0, -5.0]), ("horizon", [0.0, 0.5, 1.0, 2.5, 3.0])):
        for t in [*times, *rng.uniform(times[0], times[-1], 5)]:
            got, want = tgsis.get_at(conn, stored["ids"][key], float(t), properties=True), stored[key].at(float(t))
            assert (got is None) == (want is None)
            if got is not None and want is not None:
                assert (
                    got.vertex_properties["porosity"].tobytes()
                    == np.asarray(want.vertex_properties["porosity"], dtype=np.float64).tobytes()
                ), (key, t)
    flat = tgsis.get_at(conn, stored["ids"]["flat"], 12.0, properties=True)
    assert flat is not None and flat.vertex_properties["porosity"].tolist() == [0.1, 0.2, 0.3]
    assert "wet" not in flat.vertex_properties  # a boolean is not interpolated


def test_property_at_in_sql_and_its_errors(conn: Conn, stored: dict[str, Any]) -> None:
    fid = stored["ids"]["fault"]
    rows = conn.execute("SELECT idx, value FROM tgsis.property_at('faults', %s, 'porosity', -8.0)", (fid,)).fetchall()
    want = stored["fault"].at(-8.0).vertex_properties["porosity"]
    assert [r[1] for r in rows] == [float(v) for v in want]
    assert conn.execute(
        "SELECT count(*) FROM tgsis.property_at('faults', %s, 'porosity', -20.0)", (fid,)
    ).fetchone() == (0,)
    conn.commit()
    for args, state in (
        (("faults", fid, "depth", -8.0), "TG103"),
        (("plain", stored["ids"]["flat"], "wet", 0.0), "TG103"),
        (("faults", fid, "porosity", float("nan")), "TG100"),
        (("nope", fid, "porosity", 0.0), "TG200"),
    ):
        with pytest.raises(psycopg.Error) as error:
            conn.execute("SELECT * FROM tgsis.property_at(%s, %s, %s, %s)", args)
        conn.rollback()
        assert error.value.sqlstate == state, args


def test_tgsis_at_writes_the_properties(
    db_dsn: str, stored: dict[str, Any], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fid = stored["ids"]["fault"]
    assert main(["--dsn", db_dsn, "at", str(fid), "-7.25", str(tmp_path / "at.vtu")]) == 0
    back = formats.read_one(tmp_path / "at.vtu")
    want = stored["fault"].at(-7.25)
    assert np.array_equal(
        np.asarray(back.vertex_properties["porosity"], dtype=np.float64),
        np.asarray(want.vertex_properties["porosity"], dtype=np.float64),
    )

"""The property tables of temporal classes (models 2 and 3) in chunks (issue 40, plan O area C).

docs/storage.md, "Property chunks: the contract": ``<class>_cellpros`` of an INSTANTS class
(keyed ``_geoid, _times, _idx``) or an EVOLVING class (``_geoid, _timem, _timet, _idx``) is
chunked by ``_idx`` with the time keys between ``_geoid`` and ``chunk``, as model 2's and
model 3's own chunk tables are. Each test keeps a rows twin of a class switched by
``tgsis.store_class_in_chunks`` and runs the same public calls on both: what the property
tables hold (doubles by their bits), the snapshots at t with their properties, the SQL
``property_at`` / ``first_time`` and the downloads must be the same, and
``tgsis.store_class_in_rows`` must bring every row back.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import psycopg
import pytest
from psycopg import sql

import tgsis
from tests.merge_data import sqlstate
from tests.storage_data import classes_as_rows
from tests.temporal_data import evolving, series
from tgsis.mesh import Surface
from tgsis.temporal import EvolvingSurface, SurfaceSeries, TopologyPeriod

Conn = psycopg.Connection[Any]


@pytest.fixture(autouse=True)
def _classes_as_rows(db_dsn: str) -> None:
    """The twins start as rows whatever the default; the tests switch one of each pair themselves."""
    classes_as_rows(db_dsn)


def _keys(model: str) -> list[str]:
    return ["_times"] if model == "INSTANTS" else ["_timem", "_timet"]


def _table(conn: Conn, name: str, model: str) -> list[tuple[Any, ...]]:
    """A class's property rows, the feature named by its place among the class's features, doubles by their bits."""
    keys = sql.SQL(", ").join(sql.SQL("float8send({})").format(sql.Identifier(k)) for k in _keys(model))
    query = sql.SQL(
        "SELECT dense_rank() OVER (ORDER BY _geoid), {}, _idx, float8send(porosity) FROM {} ORDER BY _geoid, {}, _idx"
    ).format(keys, sql.Identifier(f"{name}_cellpros"), sql.SQL(", ").join(sql.Identifier(k) for k in _keys(model)))
    return [tuple(r) for r in conn.execute(query).fetchall()]


def _in_chunks(conn: Conn, name: str) -> bool:
    row = conn.execute("SELECT tgsis.stored_in_chunks('public', %s)", (f"{name}_cellpros",)).fetchone()
    assert row is not None
    return bool(row[0])


def _snapshots(conn: Conn, geoid: int, times: list[float]) -> list[Any]:
    """get_at with properties (Python) and property_at / first_time (SQL) at each t, as bytes."""
    out: list[Any] = []
    for t in times:
        got = tgsis.get_at(conn, geoid, t, properties=True)
        out.append(None if got is None else (got.vertices.tobytes(), got.vertex_properties["porosity"].tobytes()))
    return out


def _sql_reads(conn: Conn, name: str, geoid: int, times: list[float]) -> list[Any]:
    out: list[Any] = []
    for t in times:
        out.append(
            conn.execute(
                "SELECT array_agg(float8send(value) ORDER BY idx) FROM tgsis.property_at(%s, %s, 'porosity', %s)",
                (name, geoid, t),
            ).fetchone()
        )
    out.append(
        conn.execute(
            "SELECT array_agg(float8send(t) ORDER BY idx) FROM tgsis.first_time(%s, %s, 'porosity', '>', 0.2)",
            (name, geoid),
        ).fetchone()
    )
    return out


def _twins(conn: Conn, model: str) -> tuple[str, str]:
    """Two classes of ``model`` made alike, the second switched to chunks while empty."""
    for name in ("onrows", "inchunks"):
        tgsis.create_feature_class(
            conn,
            name,
            "SURFACE",
            time_model=model,  # type: ignore[arg-type]
            cell_properties=[("porosity", "float8")],
            instant_properties=[("throw", "float8"), ("note_code", "integer")],
        )
    conn.execute("SELECT tgsis.store_class_in_chunks('inchunks')")
    conn.commit()
    assert not _in_chunks(conn, "onrows") and _in_chunks(conn, "inchunks")
    return "onrows", "inchunks"


def _same(conn: Conn, model: str, ids: dict[str, int], times: list[float]) -> None:
    assert _table(conn, "onrows", model) == _table(conn, "inchunks", model)
    assert _snapshots(conn, ids["onrows"], times) == _snapshots(conn, ids["inchunks"], times)
    assert _sql_reads(conn, "onrows", ids["onrows"], times) == _sql_reads(conn, "inchunks", ids["inchunks"], times)
    conn.commit()


def _big_series() -> SurfaceSeries:
    """Three instants of grids of 1,600 vertices and more: two chunks of 1,024 ids and more per instant."""
    rng = np.random.default_rng(5)
    surfaces = []
    for i in range(3):
        side = 40 + i
        u, v = np.meshgrid(np.linspace(0, 1, side), np.linspace(0, 1, side))
        vertices = np.stack([u.ravel(), v.ravel(), rng.normal(size=side * side)], axis=1)
        idx = np.arange(side * side).reshape(side, side)
        a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
        cells = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
        porosity = rng.uniform(0, 0.4, side * side)
        porosity[::97] = -0.0
        surfaces.append(Surface(vertices, cells, vertex_properties={"porosity": porosity}))
    return SurfaceSeries(
        [0.0, 1.0, 2.5],
        surfaces,
        properties={"throw": np.asarray([1.0, 2.0, 3.0]), "note_code": np.arange(3)},
        alive=True,
    )


def test_an_instants_class_in_chunks_answers_as_its_rows_twin(conn: Conn) -> None:
    _twins(conn, "INSTANTS")
    data = _big_series()
    ids = {name: tgsis.insert_feature(conn, name, data) for name in ("onrows", "inchunks")}
    small = series(np.random.default_rng(8), [0.0, 1.0, 2.5], alive=True, with_properties=True)
    for name in ("onrows", "inchunks"):
        tgsis.insert_feature(conn, name, small, drop_extra_properties=True)
    conn.commit()
    times = [0.0, 0.5, 1.0, 1.7, 2.5, 3.0]
    _same(conn, "INSTANTS", ids, times)
    # a new instant, one removed, a value changed and a row deleted from psql: the same on both
    extra = data.surfaces[0]
    for name in ("onrows", "inchunks"):
        tgsis.add_instant(conn, name, ids[name], 4.0, extra, {"throw": 4.0})
        tgsis.delete_instant(conn, ids[name], 1.0)
        conn.execute(
            sql.SQL("UPDATE {} SET porosity = 0.5 WHERE _geoid = %s AND _times = 2.5 AND _idx IN (3, 1500)").format(
                sql.Identifier(f"{name}_cellpros")
            ),
            (ids[name],),
        )
        conn.commit()
    _same(conn, "INSTANTS", ids, [*times, 4.0])
    for name in ("onrows", "inchunks"):
        got = tgsis.fetch_series(conn, name, ids[name])
        assert [s.vertex_properties["porosity"].tobytes() for s in got.surfaces] == [
            s.vertex_properties["porosity"].tobytes()
            for s in tgsis.fetch_series(conn, "onrows", ids["onrows"]).surfaces
        ]
    for name in ("onrows", "inchunks"):
        tgsis.delete_feature(conn, name, ids[name])
        conn.commit()
    assert _table(conn, "onrows", "INSTANTS") == _table(conn, "inchunks", "INSTANTS")
    before = _table(conn, "inchunks", "INSTANTS")
    conn.execute("SELECT tgsis.store_class_in_rows('inchunks')")
    conn.commit()
    assert not _in_chunks(conn, "inchunks") and _table(conn, "inchunks", "INSTANTS") == before


def test_an_evolving_class_in_chunks_answers_as_its_rows_twin(conn: Conn) -> None:
    _twins(conn, "EVOLVING")
    data = evolving(np.random.default_rng(7), [-10.0, -6.0], instants_per_period=4, side=17, with_properties=True)
    ids = {name: tgsis.insert_feature(conn, name, data) for name in ("onrows", "inchunks")}
    conn.commit()
    times = [-10.0, -9.0, -7.3, -6.0, -5.5, -5.0, 0.0]
    _same(conn, "EVOLVING", ids, times)
    last = data.periods[-1]
    after = TopologyPeriod(
        last.times - last.times[0] + last.times[-1],
        last.triangles,
        np.stack([last.positions[-1]] * len(last.times)),
        vertex_properties={"porosity": last.vertex_properties["porosity"][::-1].copy()},
        properties={k: np.asarray(v) for k, v in last.properties.items()},
    )
    for name in ("onrows", "inchunks"):
        tgsis.append_period(conn, name, ids[name], after)
        conn.commit()
    _same(conn, "EVOLVING", ids, [*times, -4.5, -4.0, -3.0])
    for name in ("onrows", "inchunks"):
        assert tgsis.delete_period(conn, ids[name], -10.0)
        conn.execute(
            sql.SQL("UPDATE {} SET porosity = -porosity WHERE _geoid = %s AND _timem = -6.0 AND _idx = 1100").format(
                sql.Identifier(f"{name}_cellpros")
            ),
            (ids[name],),
        )
        conn.commit()
    assert _table(conn, "onrows", "EVOLVING") == _table(conn, "inchunks", "EVOLVING")
    fetched = [tgsis.fetch_evolving(conn, name, ids[name]) for name in ("onrows", "inchunks")]
    assert [p.vertex_properties["porosity"].tobytes() for p in fetched[0].periods] == [
        p.vertex_properties["porosity"].tobytes() for p in fetched[1].periods
    ]
    before = _table(conn, "inchunks", "EVOLVING")
    conn.execute("SELECT tgsis.store_class_in_rows('inchunks')")
    conn.commit()
    assert not _in_chunks(conn, "inchunks") and _table(conn, "inchunks", "EVOLVING") == before


@pytest.mark.parametrize("model", ["INSTANTS", "EVOLVING"])
def test_a_versioned_temporal_class_in_chunks_merges_as_its_rows_twin(conn: Conn, model: str) -> None:
    _twins(conn, model)
    tgsis.enable_feature_versioning(conn)
    if model == "INSTANTS":
        data: SurfaceSeries | EvolvingSurface = _big_series()
        key = "_times = 2.5"
    else:
        data = evolving(np.random.default_rng(3), [0.0], instants_per_period=3, side=33, with_properties=True)
        key = "_timet = 1.0"
    ids = {name: tgsis.insert_feature(conn, name, data) for name in ("onrows", "inchunks")}
    tgsis.create_version(conn, "child")
    conn.commit()
    for name in ("onrows", "inchunks"):
        table = sql.Identifier(f"{name}_cellpros")
        with tgsis.in_version(conn, "child"):
            conn.execute(
                sql.SQL("UPDATE {} SET porosity = porosity + 1 WHERE _geoid = %s AND {} AND _idx < 40").format(
                    table, sql.SQL(key)
                ),
                (ids[name],),
            )
        conn.commit()
        conn.execute(
            sql.SQL("UPDATE {} SET porosity = -porosity WHERE _geoid = %s AND {} AND _idx >= 1050").format(
                table, sql.SQL(key)
            ),
            (ids[name],),
        )
        conn.commit()
    with tgsis.in_version(conn, "child"):
        assert _table(conn, "onrows", model) == _table(conn, "inchunks", model)
    conn.commit()
    tgsis.merge_version(conn, "child")
    conn.commit()
    assert _table(conn, "onrows", model) == _table(conn, "inchunks", model)
    times = [0.0, 1.0, 2.0, 2.5] if model == "INSTANTS" else [0.0, 0.5, 1.0]
    assert _snapshots(conn, ids["onrows"], times) == _snapshots(conn, ids["inchunks"], times)
    conn.commit()
    before = {v: None for v in ("DEFAULT", "child")}
    for version in before:
        with tgsis.in_version(conn, version):
            before[version] = _table(conn, "inchunks", model)  # type: ignore[assignment]
    conn.commit()
    conn.execute("SELECT tgsis.store_class_in_rows('inchunks')")
    conn.commit()
    for version, rows in before.items():
        with tgsis.in_version(conn, version):
            assert _table(conn, "inchunks", model) == rows
    conn.commit()


def test_a_gmap_class_is_refused_by_name(conn: Conn) -> None:
    tgsis.create_feature_class(
        conn, "cells", "GMAP", time_model="GMAP", cell_properties=[("porosity", "float8")], cell_level=0
    )
    conn.commit()
    state, message = sqlstate(conn, "SELECT tgsis.store_class_in_chunks('cells')")
    assert state == "TG100" and "GMAP" in message
    assert not _in_chunks(conn, "cells")


@pytest.mark.parametrize("model", ["INSTANTS", "EVOLVING"])
def test_dropping_the_last_property_of_a_temporal_class_in_chunks_leaves_rows(conn: Conn, model: str) -> None:
    """The time keys are no property column: the last property's drop takes the class back to rows first."""
    _twins(conn, model)
    data = (
        series(np.random.default_rng(8), [0.0, 1.0], with_properties=True)
        if model == "INSTANTS"
        else evolving(np.random.default_rng(3), [0.0], instants_per_period=3, with_properties=True)
    )
    ids = {name: tgsis.insert_feature(conn, name, data, drop_extra_properties=True) for name in ("onrows", "inchunks")}
    conn.commit()
    for name in ("onrows", "inchunks"):
        tgsis.drop_property(conn, name, "porosity", force=True)
        conn.commit()
    assert not _in_chunks(conn, "inchunks")
    keys = ", ".join(_keys(model))
    rows = [
        conn.execute(
            f"SELECT {keys}, _idx FROM {name}_cellpros WHERE _geoid = %s ORDER BY 1, 2", (ids[name],)
        ).fetchall()
        for name in ("onrows", "inchunks")
    ]
    assert rows[0] == rows[1] and rows[0]
    conn.commit()


def test_the_psql_merge_by_slice_writes_the_property_chunks(conn: Conn) -> None:
    """An instant added on one side and values changed on the other: ``merge_version`` merges the object slice by
    slice (tgsis.merge_instants_by_slice), whose writer (tgsis.merge_write_keyed_rows) wrote ``<table>_ver``."""
    _twins(conn, "INSTANTS")
    tgsis.enable_feature_versioning(conn)
    data = _big_series()
    ids = {name: tgsis.insert_feature(conn, name, data) for name in ("onrows", "inchunks")}
    tgsis.create_version(conn, "child")
    conn.commit()
    for name in ("onrows", "inchunks"):
        tgsis.add_instant(conn, name, ids[name], 4.0, data.surfaces[1], {"throw": 4.0})
        conn.commit()
        with tgsis.in_version(conn, "child"):
            conn.execute(
                sql.SQL(
                    "UPDATE {} SET porosity = porosity + 1 WHERE _geoid = %s AND _times = 1.0 AND _idx > 1000"
                ).format(sql.Identifier(f"{name}_cellpros")),
                (ids[name],),
            )
        conn.commit()
    for version in ("DEFAULT", "child"):
        with tgsis.in_version(conn, version):
            assert _table(conn, "onrows", "INSTANTS") == _table(conn, "inchunks", "INSTANTS")
    conn.commit()
    conn.execute("SELECT tgsis.merge_version('child')")
    conn.commit()
    for version in ("DEFAULT", "child"):
        with tgsis.in_version(conn, version):
            assert _table(conn, "onrows", "INSTANTS") == _table(conn, "inchunks", "INSTANTS")
    conn.commit()
    times = [0.0, 1.0, 2.5, 4.0]
    assert _snapshots(conn, ids["onrows"], times) == _snapshots(conn, ids["inchunks"], times)
    conn.commit()


@pytest.mark.parametrize("model", ["STATIC", "INSTANTS"])
def test_a_class_written_through_its_face_is_dropped_in_the_same_transaction(conn: Conn, model: str) -> None:
    """The face's work tables of the session (typed by the face's row type) kept DROP VIEW of the face from running
    in the transaction that wrote through it (2BP01)."""
    tgsis.create_feature_class(
        conn,
        "gone",
        "SURFACE",
        time_model=model,  # type: ignore[arg-type]
        cell_properties=[("porosity", "float8")],
        instant_properties=[("throw", "float8")] if model == "INSTANTS" else None,
    )
    conn.execute("SELECT tgsis.store_class_in_chunks('gone')")
    conn.commit()
    if model == "INSTANTS":
        data: Any = series(np.random.default_rng(8), [0.0, 1.0], with_properties=True)
        geoid = tgsis.insert_feature(conn, "gone", data, drop_extra_properties=True)
    else:
        geoid = tgsis.insert_feature(
            conn,
            "gone",
            Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], vertex_properties={"porosity": [0.1, 0.2, 0.3]}),
        )
        conn.commit()
        conn.execute("UPDATE gone_cellpros SET porosity = 0.5 WHERE _geoid = %s AND _idx = 1", (geoid,))
    assert tgsis.drop_feature_class(conn, "gone", force=True) == 1
    conn.commit()
    assert conn.execute("SELECT to_regclass('public.gone_cellpros_chunk')").fetchone() == (None,)

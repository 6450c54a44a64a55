"""The registry of data models (tgsis.data_models, tgsis.model_tables): storage, grants, versioning and deletion read it.

Adding a data model must mean a new SQL folder whose storage file registers
its tables, and nothing typed elsewhere: the last test registers a whole
model the way an upgrade script would and drives every core function over it.
"""

from __future__ import annotations

from typing import Any

import psycopg
import pytest

import tgsis
from tgsis.db import features as F
from tgsis.errors import reraise

Conn = psycopg.Connection[Any]


def _registered(conn: Conn) -> set[str]:
    return {r[0] for r in conn.execute("SELECT tablename FROM tgsis.model_tables")}


def test_the_registry_is_exactly_the_storage(conn: Conn) -> None:
    # every plain table of schema tgsis that is not part of the extension is storage, and registered
    storage = {
        r[0]
        for r in conn.execute(
            """SELECT c.relname FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace
            WHERE n.nspname = 'tgsis' AND c.relkind = 'r' AND c.relpersistence = 'p'
              AND NOT EXISTS (SELECT FROM pg_depend d WHERE d.classid = 'pg_class'::regclass AND d.objid = c.oid
                                                        AND d.deptype = 'e')"""
        )
    }
    # a registered table is its own storage, or, stored in chunks (the default for those registered for chunks:
    # docs/storage.md), its chunk table and its row definition kept without rows (tgsis.<table>_shape)
    expected = {
        str(r[0])
        for r in conn.execute(
            "SELECT s.name FROM tgsis.model_tables t, LATERAL (SELECT t.tablename AS name"
            " WHERE NOT tgsis.stored_in_chunks(t.tablename) UNION ALL SELECT unnest(ARRAY[t.tablename || '_chunk',"
            " t.tablename || '_shape']) WHERE tgsis.stored_in_chunks(t.tablename)) AS s"
        ).fetchall()
    }
    assert storage == expected
    assert {
        r[0]
        for r in conn.execute(
            "SELECT split_part(tgsis.storage_table('tgsis', tablename), '.', 2) FROM tgsis.model_tables"
        ).fetchall()
    } <= storage, "tgsis.storage_table names each table's storage"
    assert {"geometry", "vrtx", "trgl", "atom", "part", "times_vrtx", "d4dvrtx"} <= _registered(conn)
    assert {"geometry", "atom", "part", "times", "d4dvrtx"} <= storage  # (times_vrtx: chunks by default)
    # the time models of geometry rows and feature classes are the registered ones (Python's registry: tgsis.datamodels)
    assert [r[0] for r in conn.execute("SELECT timemodel FROM tgsis.data_models ORDER BY model")] == [
        None,
        *(m.time_model for m in tgsis.data_models()),
    ]


def test_every_hook_of_the_registry_exists_with_its_signature(conn: Conn) -> None:
    rows = conn.execute(
        "SELECT model, create_function, extent_function, check_function FROM tgsis.data_models"
    ).fetchall()
    for model, create, extent, check in rows:
        assert conn.execute("SELECT to_regprocedure(%s)", (f"tgsis.{create}()",)).fetchone() != (None,), (model, create)
        for hook, columns in (
            (extent, "bbox cube, nvrtx bigint, ncell bigint"),
            (check, "problem text, count bigint, example text"),
        ):
            if model == 0:
                assert hook is None
                continue
            result = conn.execute(
                "SELECT pg_get_function_result(to_regprocedure(%s))", (f"tgsis.{hook}(bigint)",)
            ).fetchone()
            assert result == (f"TABLE({columns})",), (model, hook)


def test_a_model_whose_tables_are_gone_is_created_again_with_its_grants(conn: Conn) -> None:
    # (the time tables are stored in chunks by default: back to plain tables first, so that the model's tables go)
    conn.execute(
        "SELECT tgsis.store_in_rows(t) FROM unnest(ARRAY['times_trgl', 'times_vrtx']) t WHERE tgsis.stored_in_chunks(t)"
    )
    conn.execute("DROP TABLE tgsis.times_trgl, tgsis.times_vrtx, tgsis.times")
    assert conn.execute("SELECT tgsis.create_storage()").fetchone() == (True,)
    # made again as a new database makes them: the time tables in chunks (chunkdefault), tgsis.storage unset
    assert conn.execute(
        "SELECT bool_and(tgsis.stored_in_chunks(t)) FROM unnest(ARRAY['times_trgl', 'times_vrtx']) t"
    ).fetchone() == (True,)
    for table in ("times", "times_vrtx", "times_trgl"):
        assert conn.execute(
            "SELECT has_table_privilege('tgsis_reader', %s, 'SELECT'), "
            "has_table_privilege('tgsis_editor', %s, 'INSERT'), "
            "has_table_privilege('tgsis_reader', %s, 'INSERT')",
            (f"tgsis.{table}",) * 3,
        ).fetchone() == (True, True, False)
    assert conn.execute("SELECT tgsis.create_storage()").fetchone() == (False,)  # nothing missing: nothing done


def test_a_model_with_some_tables_missing_is_refused_naming_them(conn: Conn) -> None:
    conn.execute("DROP TABLE tgsis.d4dvrtx")
    conn.commit()
    with pytest.raises(tgsis.InstallationError, match="some tables of data model 3 exist") as info, reraise():
        conn.execute("SELECT tgsis.create_storage()")
    assert "tgsis.d4dvrtx: missing" in str(info.value.detail)
    conn.rollback()
    assert conn.execute("SELECT to_regclass('tgsis.d4dvrtx'), to_regclass('tgsis.node') IS NOT NULL").fetchone() == (
        None,
        True,
    )


def test_the_class_tables_view_lists_each_table_of_each_class(conn: Conn) -> None:
    F.create_feature_class(
        conn, "tops", "SURFACE", cell_properties=[("p", "float8"), F.Property("n", "int4", 1, "CELL")]
    )
    F.create_feature_class(conn, "moving", "SURFACE", time_model="EVOLVING", instant_properties={"age": "float8"})
    rows = conn.execute(
        "SELECT classname, tablename, kind FROM tgsis.class_tables ORDER BY classname, position"
    ).fetchall()
    assert rows == [
        ("moving", "moving", "feature"),
        ("moving", "moving_cellpros", "cell"),
        ("moving", "moving_pros", "instant"),
        ("tops", "tops", "feature"),
        ("tops", "tops_cellpros", "cell"),
        ("tops", "tops_simplexpros", "other"),
    ]


TEST_MODEL = """
CREATE FUNCTION tgsis.create_test9_storage() RETURNS void LANGUAGE plpgsql AS $$
BEGIN
    CREATE TABLE tgsis.test9_point (geoid bigint NOT NULL, pid bigint NOT NULL, x double precision NOT NULL,
                                    PRIMARY KEY (geoid, pid));
END $$;
CREATE FUNCTION tgsis.test9_extent(p_geoid bigint) RETURNS TABLE (bbox cube, nvrtx bigint, ncell bigint)
LANGUAGE plpgsql AS $$
BEGIN
    RETURN QUERY SELECT cube(ARRAY[min(p.x), 0, 0], ARRAY[max(p.x), 0, 0]), count(*), 0::bigint
                   FROM tgsis.test9_point p WHERE p.geoid = p_geoid;
END $$;
CREATE FUNCTION tgsis.test9_check(p_geoid bigint) RETURNS TABLE (problem text, count bigint, example text)
LANGUAGE plpgsql AS $$
BEGIN
    RETURN QUERY SELECT 'negative x'::text, count(*), min(p.pid)::text FROM tgsis.test9_point p
                  WHERE p.geoid = p_geoid AND p.x < 0 HAVING count(*) > 0;
END $$;
INSERT INTO tgsis.data_models (model, name, timemodel, geotypes, timekey, create_function, extent_function,
                               check_function, description)
VALUES (9, 'test points in steps', 'STEPS', '{MULTIPOINT}', '[{"name": "_step", "comment": "the step"}]',
        'create_test9_storage', 'test9_extent', 'test9_check', 'a model of the test');
INSERT INTO tgsis.model_tables (tablename, model, iudorder, description) VALUES ('test9_point', 9, 1, 'a test point');
"""


def test_a_new_data_model_is_registered_and_every_core_function_serves_it(conn: Conn) -> None:
    """What an upgrade adding model 9 would run; no core function is changed for it."""
    conn.execute(TEST_MODEL)
    assert conn.execute("SELECT tgsis.create_storage()").fetchone() == (True,)
    conn.commit()
    assert conn.execute("SELECT has_table_privilege('tgsis_editor', 'tgsis.test9_point', 'INSERT')").fetchone() == (
        True,
    )

    # its geometries are legal rows of the core (the core's check follows the registry) ...
    with pytest.raises(psycopg.errors.CheckViolation, match="geometry_kind"):
        conn.execute("INSERT INTO tgsis.geometry (geotype, timemodel) VALUES ('SURFACE', 'STEPS')")
    conn.rollback()
    # ... refreshed and checked by its hooks
    geoid = conn.execute("SELECT tgsis.new_geometry('MULTIPOINT', 'p', NULL, 0, 0, p_timemodel => 'steps')").fetchone()[
        0
    ]  # type: ignore[index]
    conn.execute("INSERT INTO tgsis.test9_point VALUES (%s, 0, 2.5), (%s, 1, -1)", (geoid, geoid))
    assert conn.execute("SELECT nvrtx, ncell, bbox::text FROM tgsis.refresh_geometry(%s)", (geoid,)).fetchone() == (
        2,
        0,
        "(-1, 0, 0),(2.5, 0, 0)",
    )
    assert conn.execute("SELECT problem, count, example FROM tgsis.check_geometry(%s)", (geoid,)).fetchall() == [
        ("negative x", 1, "1")
    ]
    with (
        pytest.raises(tgsis.InvalidGeometryError, match="time model 'STEPS' is not one of a SURFACE geometry") as info,
        reraise(),
    ):
        conn.execute("SELECT tgsis.new_geometry('SURFACE', 's', NULL, 0, 0, p_timemodel => 'STEPS')")
    assert "STEPS for MULTIPOINT" in str(info.value.hint)
    conn.rollback()

    # a feature class of the model gets its time key
    conn.execute(
        "SELECT tgsis.register_feature_class('stepped', 'MULTIPOINT', p_cell_properties => '{\"v\": \"float8\"}', "
        "p_time_model => 'STEPS')"
    )
    columns = [
        r[0]
        for r in conn.execute(
            "SELECT attname FROM pg_attribute WHERE attrelid = 'stepped_cellpros'::regclass "
            "AND attnum > 0 ORDER BY attnum"
        )
    ]
    assert columns == ["_geoid", "_step", "_idx", "v"]
    assert conn.execute("SELECT col_description('stepped_pros'::regclass, 2)").fetchone() == ("the step",)

    # deleting the geometry empties the model's table
    conn.execute("SELECT tgsis.delete_geometry(%s)", (geoid,))
    assert conn.execute("SELECT count(*) FROM tgsis.test9_point").fetchone() == (0,)

    # versioning takes its table in the feature object class, in its order
    tgsis.enable_feature_versioning(conn)
    assert conn.execute("SELECT iudorder FROM tgsis.versioned_tables WHERE tablename = 'test9_point'").fetchone() == (
        1,
    )


def test_a_table_added_to_a_model_is_deleted_with_its_geometries_in_every_version(conn: Conn) -> None:
    conn.execute("CREATE TABLE tgsis.extra_rows (geoid bigint NOT NULL, k bigint NOT NULL, PRIMARY KEY (geoid, k))")
    conn.execute(
        "INSERT INTO tgsis.model_tables (tablename, model, iudorder, geotype, description) "
        "VALUES ('extra_rows', 1, 2, 'SURFACE', 'a test side table')"
    )
    fc = F.create_feature_class(conn, "tops", "SURFACE")
    surface = tgsis.Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    first = F.insert_feature(conn, fc, surface, name="a")
    second = F.insert_feature(conn, fc, surface, name="b")
    conn.execute(
        "INSERT INTO tgsis.extra_rows SELECT g, k FROM unnest(%s::bigint[]) g, generate_series(1, 3) k",
        ([first, second],),
    )
    conn.execute("SELECT tgsis.delete_geometry(%s)", (first,))
    assert conn.execute("SELECT geoid, count(*) FROM tgsis.extra_rows GROUP BY geoid").fetchall() == [(second, 3)]
    # a MULTIPOINT geometry has no rows there, and its deletion does not touch the table
    assert conn.execute(
        "SELECT t FROM tgsis.model_tables_of(ARRAY[%s]::bigint[]) t WHERE t = 'extra_rows'", (second,)
    ).fetchall() == [("extra_rows",)]
    points = F.create_feature_class(conn, "wells", "MULTIPOINT")
    well = F.insert_feature(conn, points, tgsis.PointSet([[0, 0, 0]]), name="w")
    assert "extra_rows" not in {
        r[0] for r in conn.execute("SELECT * FROM tgsis.model_tables_of(ARRAY[%s]::bigint[])", (well,))
    }
    # dropping the class removes the rows from the storage of every version
    conn.execute("SELECT tgsis.drop_feature_class('tops', p_force => true)")
    assert conn.execute("SELECT count(*) FROM tgsis.extra_rows").fetchone() == (0,)

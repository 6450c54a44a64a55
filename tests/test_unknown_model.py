"""Functions that answer per data model refuse a model they have no rule for (issue 36, point 6).

tgsis.exists_at once sent any model it did not know to model 3's rule
(exists_at false, features_at empty, no error). Each function that
dispatches on the time model now refuses another model with TG203, naming
it from the registry (tgsis.data_models). The model here is the throwaway
model 9 of tests/test_model_registry.py, registered as an upgrade would.
"""

from __future__ import annotations

from typing import Any

import psycopg
import pytest

import tgsis
from tests.test_model_registry import TEST_MODEL
from tgsis.errors import reraise

Conn = psycopg.Connection[Any]


def _stepped(conn: Conn) -> int:
    conn.execute(TEST_MODEL)
    conn.execute("SELECT tgsis.create_storage()")
    conn.execute(
        "SELECT tgsis.register_feature_class('stepped', 'MULTIPOINT', p_cell_properties => '{\"v\": \"float8\"}', "
        "p_instant_properties => '{\"w\": \"float8\"}', p_time_model => 'STEPS')"
    )
    row = conn.execute("SELECT tgsis.new_geometry('MULTIPOINT', 'p', NULL, 0, 0, p_timemodel => 'STEPS')").fetchone()
    assert row is not None
    geoid = int(row[0])
    conn.execute("INSERT INTO tgsis.test9_point VALUES (%s, 0, 2.5)", (geoid,))
    conn.execute("INSERT INTO stepped (_geoid) VALUES (%s)", (geoid,))
    conn.execute("INSERT INTO stepped_pros (_geoid, _step, w) VALUES (%s, 0, 1)", (geoid,))
    conn.execute("INSERT INTO stepped_cellpros (_geoid, _step, _idx, v) VALUES (%s, 0, 0, 1)", (geoid,))
    conn.commit()
    return geoid


CALLS = [
    ("tgsis.exists_at", "SELECT tgsis.exists_at(%(g)s, 0)"),
    ("tgsis.features_at", "SELECT * FROM tgsis.features_at('stepped', 0)"),
    ("tgsis.vertices_at", "SELECT * FROM tgsis.vertices_at(%(g)s, 0)"),
    ("tgsis.triangles_at", "SELECT * FROM tgsis.triangles_at(%(g)s, 0)"),
    ("tgsis.property_at", "SELECT * FROM tgsis.property_at('stepped', %(g)s, 'v', 0)"),
    ("tgsis.first_time", "SELECT * FROM tgsis.first_time('stepped', %(g)s, 'v', '>', 0)"),
    ("tgsis.property_periods", "SELECT * FROM tgsis.property_periods('stepped', %(g)s, 'w', '>', 0)"),
    ("tgsis.class_property_periods", "SELECT * FROM tgsis.class_property_periods('stepped', 'w', '>', 0)"),
    ("tgsis.check_temporal_geometry", "SELECT * FROM tgsis.check_temporal_geometry(%(g)s)"),
]


@pytest.mark.parametrize(("function", "query"), CALLS, ids=[c[0] for c in CALLS])
def test_a_registered_model_without_a_rule_is_refused(conn: Conn, function: str, query: str) -> None:
    geoid = _stepped(conn)
    with pytest.raises(tgsis.UnknownDataModelError) as caught, reraise():
        conn.execute(query, {"g": geoid})
    assert str(caught.value).startswith(
        f"{function} has no rule for data model 9 (test points in steps, time model STEPS)"
    )
    assert caught.value.sqlstate == "TG203"
    conn.rollback()


def test_a_class_of_such_a_model_without_features_is_refused_too(conn: Conn) -> None:
    geoid = _stepped(conn)
    conn.execute("DELETE FROM stepped")
    with pytest.raises(tgsis.UnknownDataModelError, match="tgsis.features_at has no rule for data model 9"), reraise():
        conn.execute("SELECT * FROM tgsis.features_at('stepped', 0)")
    conn.rollback()
    with pytest.raises(tgsis.UnknownDataModelError, match="tgsis.class_property_periods has no rule"), reraise():
        conn.execute("SELECT * FROM tgsis.class_property_periods('stepped', 'w', '>', 0)")
    conn.rollback()
    assert geoid > 0


def test_an_unregistered_time_model_is_named(conn: Conn) -> None:
    with (
        pytest.raises(tgsis.UnknownDataModelError, match="time model 'NOPE' is no registered data model") as caught,
        reraise(),
    ):
        conn.execute("SELECT tgsis.no_model_rule('NOPE', 'tgsis.exists_at', ARRAY['STATIC'])")
    assert caught.value.hint == "SELECT model, name, timemodel FROM tgsis.data_models lists the registered models"
    conn.rollback()
    # the known models still answer
    fc = tgsis.create_feature_class(conn, "tops", "SURFACE")
    fid = tgsis.insert_feature(conn, fc, tgsis.Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]))
    assert conn.execute(
        "SELECT tgsis.exists_at(%s, 5), (SELECT count(*) FROM tgsis.vertices_at(%s, 5))", (fid, fid)
    ).fetchone() == (True, 3)

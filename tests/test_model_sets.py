"""Models as sets of objects (tgsis.model, tgsis.model_object): in versions, with roles, two sessions at once."""

from __future__ import annotations

import threading
from typing import Any

import psycopg
import pytest

import tgsis
from tgsis.db import features as F
from tgsis.db import modelsets as M

from .roles import login_roles

Conn = psycopg.Connection[Any]


def _objects(conn: Conn) -> tuple[int, int, int]:
    fc = F.create_feature_class(conn, "orebody", "SURFACE")
    tri = tgsis.Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    ids = tuple(F.insert_feature(conn, fc, tri, name=n) for n in ("ore", "fault", "dyke"))
    conn.commit()
    return ids  # type: ignore[return-value]


def test_an_object_belongs_to_several_models(conn: Conn) -> None:
    ore, fault, dyke = _objects(conn)
    M.create_model(conn, "resource 2024", [ore, fault], description="after the 2024 survey")
    M.create_model(conn, "geotechnical", [fault, dyke])
    assert [o.id for o in M.model_objects(conn, "resource 2024")] == [ore, fault]
    assert [(o.feature_class, o.name) for o in M.model_objects(conn, "geotechnical")] == [
        ("orebody", "fault"),
        ("orebody", "dyke"),
    ]
    assert M.add_to_model(conn, "resource 2024", [dyke, ore]) == 1  # ore is in already
    assert M.remove_from_model(conn, "geotechnical", [dyke]) == 1
    assert [(m.name, m.objects) for m in M.list_models(conn)] == [("geotechnical", 1), ("resource 2024", 3)]
    # a deleted object leaves every model it was in
    F.delete_feature(conn, "orebody", fault)
    assert [o.id for o in M.model_objects(conn, "resource 2024")] == [ore, dyke]
    assert M.model_objects(conn, "geotechnical") == []


def test_bad_input_is_refused_naming_it_and_nothing_is_written(conn: Conn) -> None:
    ore, _, _ = _objects(conn)
    with pytest.raises(tgsis.NotFoundError, match=r"objects \{999\} are not stored features"):
        M.create_model(conn, "m", [ore, 999])
    with pytest.raises(tgsis.InvalidNameError, match="a model needs a name"):
        M.create_model(conn, " ", [ore])
    M.create_model(conn, "m", [ore])
    with pytest.raises(tgsis.AlreadyExistsError, match="model 'm' exists already"):
        M.create_model(conn, "m", [])
    with pytest.raises(tgsis.NotFoundError, match="model 'nope' does not exist"):
        M.add_to_model(conn, "nope", [ore])
    assert conn.execute("SELECT count(*) FROM tgsis.model").fetchone() == (1,)


def test_models_change_in_versions_and_cost_only_their_changes(conn: Conn) -> None:
    ore, fault, dyke = _objects(conn)
    tgsis.enable_feature_versioning(conn)
    M.create_model(conn, "resource", [ore, fault])
    conn.commit()
    tgsis.create_version(conn, "survey2")
    with tgsis.in_version(conn, "survey2"):
        M.add_to_model(conn, "resource", [dyke])
        M.remove_from_model(conn, "resource", [fault])
        conn.commit()
        assert [o.id for o in M.model_objects(conn, "resource")] == [ore, dyke]
        conn.commit()
    conn.commit()
    assert [o.id for o in M.model_objects(conn, "resource")] == [ore, fault]  # DEFAULT unchanged
    # the model's own row and ore's membership were not stored again for survey2
    rows = conn.execute("SELECT count(*) FROM tgsis.model_object_ver").fetchone()
    assert rows == (3,)  # ore, fault; dyke added
    assert conn.execute("SELECT count(*) FROM tgsis.model_ver").fetchone() == (1,)
    tgsis.merge_version(conn, "survey2")
    conn.commit()
    assert [o.id for o in M.model_objects(conn, "resource")] == [ore, dyke]


def test_two_sessions_creating_one_name_take_turns(db_dsn: str) -> None:
    with psycopg.connect(db_dsn) as conn:
        ore, _, _ = _objects(conn)
    barrier, results = threading.Barrier(2), []

    def create() -> None:
        with psycopg.connect(db_dsn) as conn:
            barrier.wait()
            try:
                M.create_model(conn, "same", [ore])
                conn.commit()
                results.append("created")
            except tgsis.AlreadyExistsError:
                results.append("refused")

    threads = [threading.Thread(target=create) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(results) == ["created", "refused"]
    with psycopg.connect(db_dsn) as conn:
        assert conn.execute("SELECT count(*) FROM tgsis.model WHERE name = 'same'").fetchone() == (1,)


def test_readers_read_models_and_cannot_change_them(db_dsn: str) -> None:
    with psycopg.connect(db_dsn) as admin:
        ore, _, _ = _objects(admin)
        M.create_model(admin, "resource", [ore])
        admin.commit()
    with login_roles(db_dsn, {"rita": "tgsis_reader", "ed": "tgsis_editor"}) as roles:
        rita, ed = roles.connect("rita"), roles.connect("ed")
        assert [o.id for o in M.model_objects(rita, "resource")] == [ore]
        with pytest.raises(tgsis.MissingPrivilegeError):
            M.create_model(rita, "mine", [ore])
        rita.rollback()
        assert M.create_model(ed, "editor's", [ore]) > 0  # editors may
        ed.commit()

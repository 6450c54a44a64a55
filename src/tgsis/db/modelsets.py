"""Models as sets of objects: a mine's resource model, a geotechnical model, each a named set of features.

An object may belong to several models; a model's objects change from
version to version like the objects themselves (``tgsis.model`` is versioned
as object class ``model``, each membership in ``tgsis.model_object`` with
its object, and deleted with it). Every call works in the session's version.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import psycopg

from tgsis.arguments import checked, checked_ids
from tgsis.errors import reraise

__all__ = ["Model", "ModelObject", "create_model", "add_to_model", "remove_from_model", "model_objects", "list_models"]

Conn = psycopg.Connection[Any]


@dataclass(frozen=True)
class Model:
    """A row of ``tgsis.model`` as the session's version sees it, with its number of objects."""

    id: int
    name: str
    description: str | None
    objects: int


@dataclass(frozen=True)
class ModelObject:
    """An object of a model: its id, its feature class and its name."""

    id: int
    feature_class: str | None
    name: str | None


def _ids(objects: Sequence[int]) -> list[int]:
    return checked_ids("objects", objects)


@checked
def create_model(conn: Conn, name: str, objects: Sequence[int] = (), *, description: str | None = None) -> int:
    """Create a model (unique by name in the session's version) holding these stored objects; return its id.

    Raises
    ------
    AlreadyExistsError, NotFoundError (an id that is no stored object), InvalidNameError
    """
    with reraise(), conn.transaction():
        row = conn.execute("SELECT tgsis.create_model(%s, %s, %s)", (name, _ids(objects), description)).fetchone()
    assert row is not None
    return int(row[0])


@checked
def add_to_model(conn: Conn, name: str, objects: Sequence[int]) -> int:
    """Put stored objects into model ``name`` (members stay); return how many were added."""
    with reraise(), conn.transaction():
        row = conn.execute("SELECT tgsis.add_to_model(%s, %s)", (name, _ids(objects))).fetchone()
    assert row is not None
    return int(row[0])


@checked
def remove_from_model(conn: Conn, name: str, objects: Sequence[int]) -> int:
    """Take objects out of model ``name`` (the objects stay); return how many left it."""
    with reraise(), conn.transaction():
        row = conn.execute("SELECT tgsis.remove_from_model(%s, %s)", (name, _ids(objects))).fetchone()
    assert row is not None
    return int(row[0])


@checked
def model_objects(conn: Conn, name: str) -> list[ModelObject]:
    """The objects of model ``name`` in the session's version, by id."""
    with reraise():
        rows = conn.execute("SELECT geoid, classname, geoname FROM tgsis.model_objects(%s)", (name,)).fetchall()
    return [ModelObject(int(r[0]), r[1], r[2]) for r in rows]


@checked
def list_models(conn: Conn) -> list[Model]:
    """The models of the session's version, by name."""
    with reraise():
        rows = conn.execute(
            "SELECT m.modelid, m.name, m.description, (SELECT count(*) FROM tgsis.model_object o "
            "WHERE o.modelid = m.modelid) FROM tgsis.model m ORDER BY m.name"
        ).fetchall()
    return [Model(int(r[0]), r[1], r[2], int(r[3])) for r in rows]

"""The attributes of a feature the parent alone changed, brought into the version before it replaces the parent's object.

A merge by region (:mod:`tgsis.db.merging`) and the object-level ``average``
(:func:`tgsis.db.regions.resolve_object_average`) write a merged mesh into
the version and record the conflict ``manual``: the merge then takes the
version's whole object, its geometry row and feature row included. An
attribute only the parent changed must be written into the version too, or
the merge puts the base's value back without a word.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import psycopg
from psycopg import sql

from tgsis.db._merge_states import MergeInputs, SlicedInputs
from tgsis.db._settings import read_version_settings, restore_version_settings

__all__ = ["GEOMETRY_ATTRIBUTES", "AttributeEdits", "attribute_edits", "write_attribute_edits"]

Conn = psycopg.Connection[Any]

#: the columns of an object's ``tgsis.geometry`` row that are its attributes, not derived from its rows
GEOMETRY_ATTRIBUTES = (
    "geoname",
    "collection",
    "alive",
    "colorred",
    "colorgreen",
    "colorblue",
    "zpositive",
    "crs",
    "metadata",
)


@dataclass(frozen=True)
class AttributeEdits:
    """The parent's edits of an object's attributes the version does not have: (view, key column, {column: text})."""

    updates: tuple[tuple[sql.Composable, str, dict[str, str | None]], ...]
    both: tuple[str, ...]  # columns both sides changed to other values


def attribute_edits(conn: Conn, inputs: MergeInputs | SlicedInputs, version: str, geoid: int) -> AttributeEdits:
    """Three ways, column by column: the parent's edits of the geometry row's attributes and of the feature row.

    A merge by region writes the merged mesh into the version and records
    the object ``manual``: the version's object then replaces the parent's,
    its geometry and feature rows included. So an attribute only the parent
    changed (a new name, colour, CRS, metadata or feature property) must be
    brought into the version as well, or it is lost. Values are compared as
    text with exact floats, dates and instants in ISO form (which reads back
    under any DateStyle: the session's, e.g. ``Postgres, YMD``, writes a date
    its own input refuses); the session's settings are put back.
    """
    fc = inputs.feature_class
    columns = conn.execute(
        "SELECT attname FROM pg_catalog.pg_attribute WHERE attrelid = pg_catalog.to_regclass(format('%%I.%%I', %s::text, %s::text))"
        " AND attnum > 0 AND NOT attisdropped AND attname <> '_geoid' ORDER BY attnum",
        (fc.schema, fc.featuretable),
    ).fetchall()
    tables: list[tuple[sql.Composable, str, tuple[str, ...]]] = [
        (sql.SQL("tgsis.geometry"), "geoid", GEOMETRY_ATTRIBUTES),
        (fc.qualified(fc.featuretable), "_geoid", tuple(str(c[0]) for c in columns)),
    ]
    base_revision, parent_revision, working = inputs.revisions
    sides = ((version, base_revision), (inputs.parent, parent_revision), (version, working))
    settings = read_version_settings(conn)
    digits, datestyle = conn.execute(
        "SELECT current_setting('extra_float_digits'), current_setting('DateStyle')"
    ).fetchone()  # type: ignore[misc]
    # floats as text, exactly; dates and instants as ISO text
    conn.execute("SELECT set_config('extra_float_digits', '3', true), set_config('DateStyle', 'ISO, YMD', true)")
    updates, both = [], []
    try:
        for view, keycol, names in tables:
            if not names:
                continue
            read = sql.SQL("SELECT {} FROM {} WHERE {} = %s").format(
                sql.SQL(", ").join(sql.SQL("{}::text").format(sql.Identifier(n)) for n in names),
                view,
                sql.Identifier(keycol),
            )
            rows = []
            for side, revision in sides:
                conn.execute("SELECT tgsis.goto_revision(%s, %s, true)", (side, revision))
                rows.append(conn.execute(read, (geoid,)).fetchone() or (None,) * len(names))
            base, theirs, ours = rows
            take = {}
            for i, name in enumerate(names):
                if theirs[i] == ours[i] or theirs[i] == base[i]:
                    continue
                if ours[i] == base[i]:
                    take[name] = theirs[i]
                else:
                    both.append(name)
            if take:
                updates.append((view, keycol, take))
    finally:
        conn.execute(
            "SELECT set_config('extra_float_digits', %s, true), set_config('DateStyle', %s, true)",
            (str(digits), str(datestyle)),
        )
        restore_version_settings(conn, settings, local=True)
    return AttributeEdits(tuple(updates), tuple(both))


def write_attribute_edits(conn: Conn, geoid: int, edits: AttributeEdits) -> int:
    """Bring the parent's attribute edits into the version (the session is in its working revision); rows changed."""
    changed = 0
    for view, keycol, values in edits.updates:
        changed += conn.execute(
            sql.SQL("UPDATE {} SET {} WHERE {} = %s").format(
                view,
                sql.SQL(", ").join(sql.SQL("{} = %s").format(sql.Identifier(n)) for n in values),
                sql.Identifier(keycol),
            ),
            (*values.values(), geoid),
        ).rowcount
    return max(changed, 0)

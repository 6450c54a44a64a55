"""Long transactions: versions, revisions and versioned tables (``sql/versioning``).

A version is a named logical copy of the database; versions form a tree
rooted at ``DEFAULT``. A session works in one version (and may look at an
older revision of it, read-only); plain SQL on a versioned table then reads
and writes that version's rows. These functions are thin, typed wrappers of
the SQL API, so Python and ``psql`` users get the same answers.

The session's version lives in the settings ``tgsis.version`` and
``tgsis.revision``. Like every setting changed in a transaction, a change
made by :func:`goto_version` is undone if that transaction rolls back.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import re
import shlex
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from datetime import datetime, timedelta
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
import psycopg

from tgsis._optional import require
from tgsis.arguments import checked
from tgsis.db._settings import read_version_settings, restore_statement, restore_version_settings
from tgsis.db._transfer import one_snapshot
from tgsis.errors import InvalidInputError, MissingPrivilegeError, VersioningError, reraise

if TYPE_CHECKING:
    from tgsis.merge3 import RegionDiscard

__all__ = [
    "Version",
    "VersionedTable",
    "create_version",
    "delete_version",
    "save_revision",
    "goto_version",
    "goto_revision",
    "working_version",
    "working_revision",
    "viewing_revision",
    "revisions",
    "list_versions",
    "format_tree",
    "show_name",
    "version_graph",
    "in_version",
    "at_revision",
    "enable_versioning",
    "disable_versioning",
    "versioned_tables",
    "storage_table",
    "enable_feature_versioning",
    "disable_feature_versioning",
    "Conflict",
    "ConflictRegion",
    "Discard",
    "find_conflicts",
    "resolve_conflict",
    "conflict_rows",
    "conflict_discards",
    "describe_discards",
    "recorded_discards",
    "merge_version",
    "refresh_version",
    "Difference",
    "diff_versions",
    "diff_table",
    "set_version_validity",
    "version_chain",
    "version_believed_at",
    "VersionGrant",
    "grant_version",
    "revoke_version",
    "set_version_owner",
    "has_version_privilege",
    "version_privileges",
    "ObjectLock",
    "lock_objects",
    "unlock_objects",
    "object_locks",
    "Compressed",
    "compress_versions",
]

Conn = psycopg.Connection[Any]


@dataclass(frozen=True)
class Version:
    """A row of ``tgsis.version_tree``.

    Attributes
    ----------
    name : str
    parent : str or None
        None for DEFAULT.
    depth : int
        Distance from DEFAULT.
    initrevision : int or None
        The parent's working revision when the version was created.
    workingrevision : int
        The revision its changes are labelled with.
    revisions : tuple of int
        Its own revisions, ascending.
    saved : dict of str to int
        Saved (frozen) revisions by name.
    owner : str
    created_at : datetime
    description : str or None
    """

    name: str
    parent: str | None
    depth: int
    initrevision: int | None
    workingrevision: int
    revisions: tuple[int, ...]
    saved: dict[str, int]
    owner: str
    created_at: datetime
    description: str | None


@dataclass(frozen=True)
class VersionedTable:
    """A row of ``tgsis.versioned_tables``."""

    schema: str
    table: str
    shortname: str
    objectkeyfield: str
    objectclass: str
    iudorder: int
    keycolumns: tuple[str, ...]


def _scalar(conn: Conn, query: str, params: Sequence[Any] = ()) -> Any:
    with reraise():
        row = conn.execute(query, params).fetchone()
    assert row is not None
    return row[0]


def _run_committed(conn: Conn, query: str, params: Sequence[Any] = ()) -> Any:
    """Run a statement in its own transaction when none is open, so that it sticks."""
    if conn.info.transaction_status == psycopg.pq.TransactionStatus.IDLE and not conn.autocommit:
        with reraise(), conn.transaction():
            return _scalar(conn, query, params)
    return _scalar(conn, query, params)


# --------------------------------------------------------------------------- versions and revisions


@checked
def create_version(
    conn: Conn, name: str, parent: str = "DEFAULT", *, description: str | None = None, base: int | None = None
) -> int:
    """Create a child version of ``parent``; return the child's working revision.

    Parameters
    ----------
    conn : psycopg.Connection
    name : str
        Free text, as the design's: 1 to 63 printable characters, no blank
        at either end, no ``@`` (the command line's VERSION@REVISION).
    parent : str
    description : str, optional
    base : int, optional
        Base the child on this frozen revision of ``parent`` (one of its own
        revisions since its base) instead of its working revision: the child
        sees what that revision saw, and the parent's later changes count as
        the parent's side in :func:`find_conflicts`.

    Raises
    ------
    InvalidNameError, NotFoundError, AlreadyExistsError
        NotFoundError also when ``base`` is not such a revision.
    """
    return int(_run_committed(conn, "SELECT tgsis.create_version(%s, %s, %s, %s)", (name, parent, description, base)))


@checked
def delete_version(conn: Conn, name: str) -> int:
    """Delete a version without children, its revisions and row versions; return the rows removed.

    Raises
    ------
    NotFoundError, InUseError (it has children), InvalidInputError (DEFAULT)
    """
    return int(_run_committed(conn, "SELECT tgsis.delete_version(%s)", (name,)))


@checked
def save_revision(conn: Conn, name: str) -> int:
    """Freeze the working revision of the session's version under ``name``; return its number.

    ``name`` is free text, as the design's ``revisionname``: 1 to 63
    printable characters (``"first pick"``), no blank at either end.

    Raises
    ------
    InvalidNameError
        An empty, too long or unprintable name (TG101).
    AlreadyExistsError
        The version has a revision of that name.
    ReadOnlyRevisionError
        The session views an older revision.
    """
    return int(_run_committed(conn, "SELECT tgsis.save_revision(%s)", (name,)))


@checked
def goto_version(conn: Conn, name: str, *, local: bool = False) -> None:
    """Work in version ``name`` (``local``: only until the current transaction ends)."""
    _run_committed(conn, "SELECT tgsis.goto_version(%s, %s)", (name, local))


@checked
def goto_revision(conn: Conn, version: str, revision: int, *, local: bool = False) -> None:
    """Look at ``revision`` of ``version``'s history, read-only, until :func:`goto_version`."""
    _run_committed(conn, "SELECT tgsis.goto_revision(%s, %s, %s)", (version, revision, local))


@checked
def working_version(conn: Conn) -> str:
    """Name of the session's working version."""
    return str(_scalar(conn, "SELECT tgsis.get_working_version()"))


@checked
def working_revision(conn: Conn) -> int:
    """Working revision of the session's working version."""
    return int(_scalar(conn, "SELECT tgsis.get_working_revision()"))


@checked
def viewing_revision(conn: Conn) -> int | None:
    """The older revision the session looks at, or None."""
    value = _scalar(conn, "SELECT tgsis.get_viewing_revision()")
    return None if value is None else int(value)


@checked
def revisions(conn: Conn, viewing: bool = True) -> list[int]:
    """The session's viewing (``True``) or working (``False``) revision set, ascending."""
    return [int(r) for r in _scalar(conn, "SELECT tgsis.get_revisions(%s)", (viewing,))]


@checked
def list_versions(conn: Conn) -> list[Version]:
    """All versions, depth-first from DEFAULT."""
    with reraise():
        rows = conn.execute(
            "SELECT name, parent, depth, initrevision, workingrevision, revisions, saved, owner, created_at, "
            "description FROM tgsis.version_tree"
        ).fetchall()
    return [
        Version(
            r[0],
            r[1],
            int(r[2]),
            r[3],
            int(r[4]),
            tuple(r[5] or ()),
            dict(json.loads(r[6]) if isinstance(r[6], str) else r[6]),
            r[7],
            r[8],
            r[9],
        )
        for r in rows
    ]


_PLAIN_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.+-]*")


def show_name(name: str) -> str:
    """A version or revision name as output shows it: as it is when it is plain (letters, digits, ``_ . + -``),
    else quoted as an SQL literal (``'first pick'``, a quote doubled), so a name with blanks reads as one name."""
    return name if _PLAIN_NAME.fullmatch(name) else "'" + name.replace("'", "''") + "'"


def format_tree(versions: Sequence[Version]) -> str:
    """The version tree as indented text, one line per version with its revisions.

    Parameters
    ----------
    versions : sequence of Version
        In depth-first order, as :func:`list_versions` returns them.
    """
    lines = []
    for v in versions:
        saved = {rev: name for name, rev in v.saved.items()}
        revs = ", ".join(f"{r} ({show_name(saved[r])})" if r in saved else str(r) for r in v.revisions)
        base = "" if v.initrevision is None else f" from {show_name(v.parent or '')}@{v.initrevision}"
        lines.append(f"{'    ' * v.depth}{show_name(v.name)}{base}: revisions {revs}; working {v.workingrevision}")
    return "\n".join(lines)


@checked
def version_graph(conn: Conn) -> Any:
    """The version tree as a :class:`networkx.DiGraph`, for graph questions and drawings.

    Needs networkx, the optional extra ``graph`` (``pip install 'tgsis[graph]'``).

    Returns
    -------
    networkx.DiGraph
        A node per version name, with the attribute ``version`` (its
        :class:`Version`) and, for convenience, ``owner``, ``revisions`` and
        ``created_at``; an edge from each parent to each child, with
        ``initrevision``: the parent's revision the child started from.
        ``networkx.ancestors(g, name)`` is the line of descent up to DEFAULT,
        ``networkx.descendants(g, name)`` what a merge of ``name`` concerns.

    Raises
    ------
    InstallationError
        If networkx is not installed.
    """
    nx = require("networkx", "tgsis.version_graph")
    graph = nx.DiGraph()
    for v in list_versions(conn):
        graph.add_node(v.name, version=v, owner=v.owner, revisions=v.revisions, created_at=v.created_at)
        if v.parent is not None:
            graph.add_edge(v.parent, v.name, initrevision=v.initrevision)
    return graph


@contextlib.contextmanager
def _restoring_settings(conn: Conn, local: bool) -> Iterator[None]:
    if local and conn.info.transaction_status == psycopg.pq.TransactionStatus.IDLE:
        with conn.transaction():  # SET LOCAL values vanish when this transaction ends
            yield
        return
    # A transaction the block begins is the block's, as in conn.transaction():
    # left open at its end, the settings put back inside it would be undone
    # by the caller's later rollback, and the next writes would land in the
    # block's version.
    began = conn.info.transaction_status == psycopg.pq.TransactionStatus.IDLE and not conn.autocommit
    with reraise():
        restore = restore_statement(read_version_settings(conn), local=local)
    try:
        yield
    except BaseException:
        if began or conn.info.transaction_status == psycopg.pq.TransactionStatus.INERROR:
            conn.rollback()  # the block failed; nothing of it is kept, but the settings can be put back
        _run_committed(conn, *restore)
        raise
    if conn.info.transaction_status == psycopg.pq.TransactionStatus.INERROR:
        conn.rollback()  # an error caught inside the block: its transaction cannot be kept either
    _run_committed(conn, *restore)
    if began and conn.info.transaction_status != psycopg.pq.TransactionStatus.IDLE:
        conn.commit()


@checked
@contextlib.contextmanager
def in_version(conn: Conn, name: str, *, local: bool = False) -> Iterator[Conn]:
    """Work in version ``name`` inside the block; the previous version is restored after it.

    A transaction the block begins (the connection idle when it is entered)
    ends with it, as in ``conn.transaction()``: committed when the block ends
    normally, rolled back when it raises or when an error caught inside it
    left the transaction failed (nothing of it can be kept then; the
    version is put back all the same); otherwise a later rollback would
    undo the restored version too, and the next writes would land in
    ``name``. Entered inside the caller's transaction, the block leaves it
    open: a rollback then undoes the version change with the rest.

    Parameters
    ----------
    local : bool
        Run the block as one transaction with the version set only for it
        (``SET LOCAL``): the form to use behind a pooler in transaction mode.

    Examples
    --------
    >>> with tgsis.in_version(conn, "v1"):                  # doctest: +SKIP
    ...     conn.execute("UPDATE wells SET depth = 2 WHERE id = 1")
    """
    with _restoring_settings(conn, local):
        goto_version(conn, name, local=local)
        yield conn


@checked
@contextlib.contextmanager
def at_revision(conn: Conn, revision: int, version: str | None = None, *, local: bool = False) -> Iterator[Conn]:
    """Look at ``revision`` of ``version`` (default: the working version) inside the block, read-only.

    The transaction the block begins ends with it, as for :func:`in_version`.
    """
    with _restoring_settings(conn, local):
        goto_revision(conn, version if version is not None else working_version(conn), revision, local=local)
        yield conn


# --------------------------------------------------------------------------- versioned tables


def _table_from_row(row: Sequence[Any]) -> VersionedTable:
    return VersionedTable(row[0], row[1], row[2], row[3], row[4], int(row[5]), tuple(row[6]))


_TABLE_COLUMNS = "schemaname, tablename, shortname, objectkeyfield, objectclass, iudorder, keycolumns"


@checked
def enable_versioning(
    conn: Conn, table: str, objectkeyfield: str, objectclass: str, iudorder: int = 0, shortname: str | None = None
) -> VersionedTable:
    """Version a table in place (``tgsis.enable_versioning``); applications keep using its name.

    Parameters
    ----------
    table : str
        ``name`` or ``schema.name`` as SQL would spell it.
    objectkeyfield : str
        Column holding the key of the object a row belongs to.
    objectclass : str
        Object class: the tables that together store one kind of object.
    iudorder : int
        Order of the table within its class when changes are merged.
    shortname : str, optional
        Name in conflict reports (default: the table name).
    """
    with reraise(), conn.transaction():
        row = conn.execute(
            f"SELECT {_TABLE_COLUMNS} FROM tgsis.enable_versioning(%s, %s, %s, %s, %s)",
            (table, objectkeyfield, objectclass, iudorder, shortname),
        ).fetchone()
    assert row is not None
    return _table_from_row(row)


@checked
def disable_versioning(conn: Conn, table: str, *, force: bool = False) -> int:
    """Make a versioned table plain again with DEFAULT's rows; return the row versions removed."""
    with reraise(), conn.transaction():
        return int(_scalar(conn, "SELECT tgsis.disable_versioning(%s, %s)", (table, force)))


@checked
def storage_table(conn: Conn, schema: str, table: str) -> str:
    """The relation that stores a table's rows, quoted as SQL writes it (``tgsis.storage_table``).

    ``tgsis.<table>_chunk`` when the model table is stored in chunks,
    ``schema.<table>_ver`` when the table is versioned, else the table
    itself; never made in Python, so that it is the name a statement finds.
    """
    return str(_scalar(conn, "SELECT tgsis.storage_table(%s, %s)", (schema, table)))


@checked
def versioned_tables(conn: Conn) -> list[VersionedTable]:
    """The versioned tables, by object class and iudorder."""
    with reraise():
        rows = conn.execute(
            f"SELECT {_TABLE_COLUMNS} FROM tgsis.versioned_tables ORDER BY objectclass, iudorder, schemaname, tablename"
        ).fetchall()
    return [_table_from_row(r) for r in rows]


@checked
def enable_feature_versioning(conn: Conn) -> int:
    """Version model 1 and all feature classes as object class ``feature``; return the tables newly versioned."""
    with reraise(), conn.transaction():
        return int(_scalar(conn, "SELECT tgsis.enable_feature_versioning()"))


@checked
def disable_feature_versioning(conn: Conn, *, force: bool = False) -> int:
    """Undo :func:`enable_feature_versioning`, keeping DEFAULT's rows; return the row versions removed."""
    with reraise(), conn.transaction():
        return int(_scalar(conn, "SELECT tgsis.disable_feature_versioning(%s)", (force,)))


# --------------------------------------------------------------------------- conflicts


@dataclass(frozen=True)
class Discard:
    """What one solution of a conflict throws away of one table of the object (a row of ``tgsis.conflict_discards``).

    Until merges are three-way a solution takes one side's whole object:
    ``child`` (and ``manual``) loses the parent's edits since the version's
    base, ``parent`` the version's. An edit is a row whose state differs from
    the base's; it is lost when the kept side's row differs from it (an edit
    both sides made alike is kept).

    Attributes
    ----------
    objectclass, objectkey : str
        The conflicting object.
    solution : {"child", "parent", "base"}
        The solution (``manual`` keeps the version's object: it loses what ``child`` loses; ``base``
        loses both sides' edits: one row per side).
    discarded : {"parent", "child"}
        Whose edits are lost: the other side's.
    shortname, tablename : str
        The table (its short name in conflict reports, and ``schema.table``).
    description : str
        What a row of it is (``"a vertex of a static geometry"``), from the registries.
    rows_added, rows_removed, rows_changed : int
        Rows the other side added (dropped), removed (brought back), changed (reverted or overwritten).
    values_changed : int
        Column values among those rows (every value of an added or removed row).
    """

    objectclass: str
    objectkey: str
    solution: str
    discarded: str
    shortname: str
    tablename: str
    description: str
    rows_added: int
    rows_removed: int
    rows_changed: int
    values_changed: int

    def summary(self) -> str:
        """``"vrtx: 1 added, 4 changed (7 values)"``: the counts that are not zero."""
        counts = [
            f"{n} {what}"
            for n, what in ((self.rows_added, "added"), (self.rows_removed, "removed"), (self.rows_changed, "changed"))
            if n
        ]
        return f"{self.shortname}: {', '.join(counts)} ({self.values_changed} value{'s' * (self.values_changed != 1)})"


def _side_words(discarded: str) -> str:
    return "the parent's edits" if discarded == "parent" else "the version's edits"


def describe_discards(discards: Sequence[Discard]) -> str:
    """One line: whose edits are lost and, per table, how many rows and values (``""`` for none)."""
    if not discards:
        return ""
    return f"{_side_words(discards[0].discarded)}: " + "; ".join(d.summary() for d in discards)


@dataclass(frozen=True, eq=False)
class ConflictRegion:
    """One region of a conflicting mesh (a row of ``tgsis.conflict_regions``, docs/merge.md).

    Ids are in the merged numbering (the child's new ids renumbered as
    :func:`tgsis.merge3.three_way_merge` does).

    Attributes
    ----------
    region : int
        Index of the region in the merge (0-based): solutions are keyed by it.
    conflict : bool
        Both sides changed the region to different rows: it needs a solution.
    changed_by : {"parent", "child", "both"}
    vertex_ids, cell_ids : (a,), (b,) int64
        Every vertex and cell of the region, its one-ring margin included.
    parent_vertex_ids, parent_cell_ids, child_vertex_ids, child_cell_ids : int64 arrays
        The rows of the region each side changed.
    bbox : (6,) float64 or None
        ``xmin, ymin, zmin, xmax, ymax, zmax`` of the region in the three states (stored z).
    parent_displacement, child_displacement : float
        Largest distance a vertex of the region moved on that side.
    solution : {"unsolved", "automatic", "parent", "child", "base", "average", "manual"}
        ``automatic`` exactly for a region that is no conflict.
    childmark, parentmark : str
        The conflict's marks the region was found on.
    solved_at : datetime or None
    solved_by : str or None
    times : float or None
        A region of a temporal surface: the instant (model 2) or geometry instant (model 3) it lies in; None for model 1.
    timem : float or None
        Model 3: the topology period of that geometry instant.
    """

    region: int
    conflict: bool
    changed_by: str
    vertex_ids: npt.NDArray[np.int64]
    cell_ids: npt.NDArray[np.int64]
    parent_vertex_ids: npt.NDArray[np.int64]
    parent_cell_ids: npt.NDArray[np.int64]
    child_vertex_ids: npt.NDArray[np.int64]
    child_cell_ids: npt.NDArray[np.int64]
    bbox: npt.NDArray[np.float64] | None
    parent_displacement: float
    child_displacement: float
    solution: str
    childmark: str = ""
    parentmark: str = ""
    solved_at: datetime | None = None
    solved_by: str | None = None
    times: float | None = None
    timem: float | None = None

    def as_json(self) -> dict[str, Any]:
        """The region as plain JSON values (what ``tgsis version conflicts --json`` prints).

        A region of a temporal surface names its slice: ``times`` (the
        instant of model 2, the geometry instant of model 3) and ``timem``
        (model 3: the topology period).
        """
        return {
            **({} if self.times is None else {"times": self.times}),
            **({} if self.timem is None else {"timem": self.timem}),
            "region": self.region,
            "conflict": self.conflict,
            "changed_by": self.changed_by,
            "solution": self.solution,
            "vertex_ids": [int(i) for i in self.vertex_ids],
            "cell_ids": [int(i) for i in self.cell_ids],
            "parent": {
                "vertex_ids": [int(i) for i in self.parent_vertex_ids],
                "cell_ids": [int(i) for i in self.parent_cell_ids],
                "largest_displacement": self.parent_displacement,
            },
            "child": {
                "vertex_ids": [int(i) for i in self.child_vertex_ids],
                "cell_ids": [int(i) for i in self.child_cell_ids],
                "largest_displacement": self.child_displacement,
            },
            "bbox": None if self.bbox is None else [float(v) for v in self.bbox],
        }


@dataclass(frozen=True)
class Conflict:
    """An object changed both in a version and in its parent (a row of ``tgsis.conflicts``).

    Attributes
    ----------
    objectclass, objectkey : str
        The object (its key as text).
    conflicttype : tuple of str
        Short names of the tables changed on both sides.
    childtables, parenttables : tuple of str
        Tables each side changed.
    solution : {"unsolved", "parent", "child", "manual"}
    discarded : tuple of Discard or None
        Set by :func:`resolve_conflict`: what the recorded solution throws away
        of the other side's edits, per table (empty: nothing, or unsolved;
        None: not counted, the caller may not read some of the object's rows).
    regions : tuple of ConflictRegion
        Set by the region-aware :func:`tgsis.find_conflicts`: the regions of a
        model-1 mesh (empty for an object that merges as a whole only).
    region_refusal : str or None
        Set by the region-aware :func:`tgsis.find_conflicts`: why the object
        does not merge by region (None when it does, or was not looked at).
    region_discards : tuple of RegionDiscard
        Set by :func:`resolve_conflict` with ``average``: what the average
        written into the version discards of each side, per region.
    """

    objectclass: str
    objectkey: str
    conflicttype: tuple[str, ...]
    childtables: tuple[str, ...]
    parenttables: tuple[str, ...]
    solution: str
    discarded: tuple[Discard, ...] | None = field(default=(), compare=False)
    regions: tuple[ConflictRegion, ...] = field(default=(), compare=False)
    region_refusal: str | None = field(default=None, compare=False)
    region_discards: tuple[RegionDiscard, ...] = field(default=(), compare=False)

    @classmethod
    def from_row(cls, row: Sequence[Any]) -> Conflict:
        """A conflict from a row of ``tgsis.find_conflicts`` (its columns in the order of ``COLUMNS``)."""
        return cls(row[0], row[1], tuple(row[2]), tuple(row[3]), tuple(row[4]), row[5])


#: the columns of ``tgsis.conflicts`` :meth:`Conflict.from_row` reads
CONFLICT_COLUMNS = "objectclass, objectkey, conflicttype, childtables, parenttables, solution"


@checked
def find_conflicts(conn: Conn, version: str) -> list[Conflict]:
    """(Re)compute the objects changed both in ``version`` and in its parent since its base.

    Solutions recorded before are kept while neither side changed the object again.
    """
    with reraise(), conn.transaction():
        rows = conn.execute(f"SELECT {CONFLICT_COLUMNS} FROM tgsis.find_conflicts(%s)", (version,)).fetchall()
    return [Conflict.from_row(r) for r in rows]


def _key_text(key: object) -> str:
    """An object key as text the key column's type reads alike under every session setting.

    The server reads it in the key column's type with the session's settings and
    names the object by its canonical text (``tgsis.canonical_object_keys``); Python's
    ``str`` of dates, times, numbers and UUIDs is ISO or plain decimal already. An
    interval goes as ISO 8601 (``str(timedelta)`` has a comma PostgreSQL does not
    read), bytes as hex (``\\x...``).
    """
    if isinstance(key, timedelta):
        return f"P{key.days}DT{key.seconds}.{key.microseconds:06d}S"
    if isinstance(key, (bytes, bytearray, memoryview)):
        return "\\x" + bytes(key).hex()
    return str(key)


@checked
def conflict_discards(
    conn: Conn, version: str, objectclass: str | None = None, objectkey: object | None = None
) -> list[Discard]:
    """What each solution of ``version``'s conflicts would throw away of the other side's edits.

    Per conflicting object (all of them, those of one class, or one object),
    solution (``child``, ``parent``) and table with something lost; computed
    now, with the caller's rights. See :class:`Discard`.
    """
    with reraise():
        rows = conn.execute(
            "SELECT objectclass, objectkey, solution, discarded, shortname, tablename, description,"
            "       rows_added, rows_removed, rows_changed, values_changed"
            "  FROM tgsis.conflict_discards(%s, %s, %s)",
            (version, objectclass, None if objectkey is None else _key_text(objectkey)),
        ).fetchall()
    return [Discard(*r[:7], *(int(n) for n in r[7:])) for r in rows]


def _lost_by(solution: str) -> str | None:
    """The row of ``tgsis.conflict_discards`` a recorded solution stands for (manual keeps the version's object)."""
    return {"child": "child", "manual": "child", "parent": "parent"}.get(solution)


@checked
def recorded_discards(conn: Conn, version: str) -> dict[tuple[str, str], tuple[str, list[Discard]]]:
    """What the solutions recorded now for ``version`` throw away, as a merge or refresh would apply them.

    Returns ``{(objectclass, objectkey): (solution, discards)}`` for the solved
    conflicts that lose something. Call it in the merge's transaction to
    report what that merge discarded.
    """
    solutions = {(c.objectclass, c.objectkey): c.solution for c in find_conflicts(conn, version)}
    lost: dict[tuple[str, str], tuple[str, list[Discard]]] = {}
    if not any(_lost_by(s) for s in solutions.values()):
        return lost
    for d in conflict_discards(conn, version):
        solution = solutions.get((d.objectclass, d.objectkey), "unsolved")
        if _lost_by(solution) == d.solution:
            lost.setdefault((d.objectclass, d.objectkey), (solution, []))[1].append(d)
    return lost


@checked
def resolve_conflict(
    conn: Conn, version: str, objectclass: str, objectkey: object, solution: str, *, discard_other: bool = True
) -> Conflict:
    """Record how a conflicting object is merged: ``parent``, ``child``, ``base``, ``manual`` (or back to ``unsolved``).

    Parameters
    ----------
    discard_other : bool
        With ``False``, a ``child`` or ``parent`` solution that would throw away
        edits of the other side (:func:`conflict_discards`) is refused and
        nothing is recorded. The check and the record are one transaction.

    ``base`` writes the object as the version was based on it into the
    version (only the rows that differ) and records ``manual``: the
    returned row's solution is ``manual``, its ``discarded`` both sides'
    edits (computed before anything is written). A mesh whose stored regions
    include one that merges by itself is refused (``RegionSolutionError``):
    :func:`tgsis.resolve_all_regions` with ``base`` solves its conflicting
    regions and keeps the rest (docs/merge.md, "Whole-object solutions").

    Returns
    -------
    Conflict
        The recorded row; ``discarded`` says what the solution throws away.

    Raises
    ------
    NotFoundError
        The object is not in conflict in that version.
    InvalidInputError
        Unknown solution; ``average`` (computed by the region-aware :func:`tgsis.resolve_conflict`,
        :func:`tgsis.db.regions.resolve_conflict`).
    VersioningError
        ``discard_other=False`` and the solution loses the other side's edits (the message counts them).
    RegionSolutionError
        ``base`` for a mesh with regions that merge by themselves.
    MissingPrivilegeError
        ``discard_other=False`` and the caller may not read the object's rows, so what it loses cannot be counted;
        ``base`` and the role may not change the object.
    """
    wanted = solution.lower() if isinstance(solution, str) else solution
    if wanted == "average":  # computed in numpy: the region-aware tgsis.resolve_conflict (tgsis.db.regions)
        raise InvalidInputError(
            f"solution average of {objectclass} {objectkey} in version {show_name(version)} is the average shape of "
            "a feature's two meshes, computed by tgsis.resolve_conflict (tgsis.db.regions.resolve_conflict)",
            hint=f"tgsis version resolve {shlex.quote(version)} {shlex.quote(objectclass)} "
            f"{shlex.quote(_key_text(objectkey))} average",
        )
    fresh = conn.info.transaction_status == psycopg.pq.TransactionStatus.IDLE
    with reraise(), conn.transaction():
        before: tuple[Discard, ...] | None = ()
        if wanted == "base" and fresh:  # base writes after waiting for writers: READ COMMITTED (TG300 otherwise)
            conn.execute("SET TRANSACTION ISOLATION LEVEL READ COMMITTED")
        if wanted == "base":  # both sides' edits, counted before the version's are overwritten
            _lock_object_in_version(conn, version, objectclass, objectkey)  # none committed between count and write
            before = _base_discards(conn, version, objectclass, objectkey, discard_other)
        row = conn.execute(
            f"SELECT {CONFLICT_COLUMNS} FROM tgsis.resolve_conflict(%s, %s, %s, %s)",
            (version, objectclass, _key_text(objectkey), solution),
        ).fetchone()
        assert row is not None
        conflict = Conflict.from_row(row)
        if wanted == "base":
            return dataclasses.replace(conflict, discarded=before)
        lost_by = _lost_by(conflict.solution)
        discards: tuple[Discard, ...] | None = ()
        try:
            with conn.transaction():  # read with the caller's rights: a role may resolve what it may not read
                discards = (
                    tuple(
                        d
                        for d in conflict_discards(conn, version, conflict.objectclass, conflict.objectkey)
                        if d.solution == lost_by
                    )
                    if lost_by
                    else ()
                )
        except MissingPrivilegeError as exc:
            if not discard_other and conflict.solution in ("child", "parent"):
                raise MissingPrivilegeError(
                    f"cannot tell what solving {conflict.objectclass} {conflict.objectkey} of version {show_name(version)} with "
                    f"{conflict.solution} discards of the other side's edits: {exc.message}",
                    sqlstate=exc.sqlstate,
                    hint="pass discard_other=True to record it all the same, or write the merged object into the "
                    "version and record manual (tgsis.conflict_rows shows both sides' rows)",
                ) from exc
            discards = None
        if discards and not discard_other and conflict.solution in ("child", "parent"):
            raise VersioningError(
                f"solving {conflict.objectclass} {conflict.objectkey} of version {show_name(version)} with "
                f"{conflict.solution} would discard {describe_discards(discards)}",
                detail="A solution takes one side's whole object: the other side's edits since the version was "
                "based are lost (rows added, removed or changed; the values among them).",
                hint="pass discard_other=True to record it all the same, or write the merged object into the "
                "version and record manual (tgsis.conflict_rows shows both sides' rows)",
            )
    return dataclasses.replace(conflict, discarded=discards)


def _lock_object_in_version(conn: Conn, version: str, objectclass: str, objectkey: object) -> None:
    """Take the locks of a write of the object in ``version``, as tgsis.resolve_conflict's base does.

    Taken before the discards are counted, in the writers' order: the
    version's row shared (tgsis.write_revision, which also checks the write
    right: TG002), then the object's write lock (tgsis.object_write_lock's).
    A writer of the object in the version then commits before the count or
    after the base is written, never in between (its edit would be
    overwritten without being counted); a merge or refresh holding the
    version waits, or is waited for, without a deadlock.
    """
    settings = read_version_settings(conn)
    try:
        conn.execute("SELECT tgsis.goto_version(%s, true)", (version,))  # this transaction only
        conn.execute("SELECT FROM tgsis.write_revision()")
        conn.execute(
            "SELECT tgsis.object_write_lock(%s, tgsis.canonical_object_keys(%s, ARRAY[%s]))",
            (objectclass, objectclass, _key_text(objectkey)),
        )
    finally:
        if conn.info.transaction_status != psycopg.pq.TransactionStatus.INERROR:
            restore_version_settings(conn, settings, local=True)


def _base_discards(
    conn: Conn, version: str, objectclass: str, objectkey: object, discard_other: bool
) -> tuple[Discard, ...] | None:
    """What ``base`` throws away of both sides' edits (read with the caller's rights); refused as ``discard_other`` says."""
    name = f"solving {objectclass} {objectkey} of version {show_name(version)} with base"
    hint = (
        "pass discard_other=True to record it all the same, or write the merged object into the version and record "
        "manual (tgsis.conflict_rows shows both sides' rows)"
    )
    try:
        with conn.transaction():
            found = tuple(d for d in conflict_discards(conn, version, objectclass, objectkey) if d.solution == "base")
    except MissingPrivilegeError as exc:
        if not discard_other:
            raise MissingPrivilegeError(
                f"cannot tell what {name} discards of either side's edits: {exc.message}",
                sqlstate=exc.sqlstate,
                hint=hint,
            ) from exc
        return None
    if found and not discard_other:
        sides = (describe_discards([d for d in found if d.discarded == side]) for side in ("parent", "child"))
        raise VersioningError(
            f"{name} would discard " + "; and ".join(said for said in sides if said),
            detail="base takes the object as the version was based on it: both sides' edits since are lost.",
            hint=hint,
        )
    return found


@checked
def conflict_rows(conn: Conn, version: str, objectclass: str, objectkey: object) -> list[tuple[str, str, Any, Any]]:
    """Rows of an object that differ between ``version`` (side ``child``) and its parent: (table, side, key, row)."""
    with reraise():
        return [
            (r[0], r[1], r[2], r[3])
            for r in conn.execute(
                "SELECT shortname, side, rowkey, row FROM tgsis.conflict_rows(%s, %s, %s)",
                (version, objectclass, _key_text(objectkey)),
            ).fetchall()
        ]


@checked
def merge_version(conn: Conn, version: str, *, remove: bool = False) -> int:
    """Apply ``version``'s changes to its parent in one transaction; return the rows written.

    Without ``remove`` the version goes on from the merged state; with it, it is deleted.

    Raises
    ------
    UnsolvedConflictsError
        Objects changed on both sides have no recorded solution (the message names them).
    """
    with reraise(), conn.transaction():
        return int(_scalar(conn, "SELECT tgsis.merge_version(%s, %s)", (version, remove)))


@checked
def refresh_version(conn: Conn, version: str) -> int:
    """Bring the parent's changes since ``version``'s base into it; return the rows written.

    Raises
    ------
    UnsolvedConflictsError
        Objects changed on both sides have no recorded solution.
    """
    with reraise(), conn.transaction():
        return int(_scalar(conn, "SELECT tgsis.refresh_version(%s)", (version,)))


@dataclass(frozen=True)
class Difference:
    """Rows of one object and table that differ from version ``a`` to version ``b``."""

    objectclass: str
    objectkey: str
    table: str
    added: int
    removed: int
    changed: int


@checked
def diff_versions(
    conn: Conn,
    a: str,
    b: str,
    *,
    a_revision: int | None = None,
    b_revision: int | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> list[Difference]:
    """Objects whose rows differ between two versions (or revisions of them), per table.

    ``added`` rows are seen in ``b`` only, ``removed`` in ``a`` only, ``changed``
    rows have the same row key and other values. The same rows, in the same
    order, as ``tgsis.diff_versions``.

    ``progress(done, total)``, when given, is called after each versioned table
    (:func:`diff_table`). The tables are then compared one by one, all in one
    snapshot: a new read-only repeatable-read transaction, or the caller's
    transaction when it is ``REPEATABLE READ`` or ``SERIALIZABLE``. In a caller's
    ``READ COMMITTED`` transaction, where each statement would see what other
    sessions committed meanwhile, they are compared in one statement and
    ``progress`` is called once, at the end.
    """
    if progress is None:
        with reraise():
            rows = conn.execute(
                "SELECT * FROM tgsis.diff_versions(%s, %s, %s, %s)", (a, b, a_revision, b_revision)
            ).fetchall()
        return [_difference(r) for r in rows]
    with reraise(), one_snapshot(conn) as stepwise:
        tables = [
            str(r[0])
            for r in conn.execute(
                "SELECT format('%I.%I', schemaname, tablename) FROM tgsis.versioned_tables"
                " ORDER BY objectclass, iudorder, shortname"
            ).fetchall()
        ]
        if not stepwise or not tables:
            rows = conn.execute(
                "SELECT * FROM tgsis.diff_versions(%s, %s, %s, %s)", (a, b, a_revision, b_revision)
            ).fetchall()
            progress(len(tables), len(tables))
            return [_difference(r) for r in rows]
        differences: list[Difference] = []
        for done, table in enumerate(tables, start=1):
            differences += _diff_table(conn, table, a, b, a_revision, b_revision)
            progress(done, len(tables))
        return differences


@checked
def diff_table(
    conn: Conn, table: str, a: str, b: str, *, a_revision: int | None = None, b_revision: int | None = None
) -> list[Difference]:
    """Objects whose rows of one versioned table differ between two versions (or revisions of them).

    :func:`diff_versions` is this over every versioned table
    (:func:`versioned_tables`), in one snapshot.

    Parameters
    ----------
    table : str
        The versioned table (its view): ``name`` or ``schema.name`` as SQL
        would spell it, e.g. ``tgsis.vrtx``.

    Raises
    ------
    NotFoundError
        The table is not versioned, or a version or revision does not exist.
    """
    with reraise():
        return _diff_table(conn, table, a, b, a_revision, b_revision)


def _diff_table(
    conn: Conn, table: str, a: str, b: str, a_revision: int | None, b_revision: int | None
) -> list[Difference]:
    rows = conn.execute(
        "SELECT * FROM tgsis.diff_table(%s::regclass, %s, %s, %s, %s)", (table, a, b, a_revision, b_revision)
    ).fetchall()
    return [_difference(r) for r in rows]


def _difference(row: Sequence[Any]) -> Difference:
    return Difference(row[0], row[1], row[2], int(row[3]), int(row[4]), int(row[5]))


# --------------------------------------------------------------------------- valid time


@checked
def set_version_validity(
    conn: Conn, version: str, valid_from: datetime | None, valid_to: datetime | None = None
) -> None:
    """Set the period ``[valid_from, valid_to)`` in which ``version`` was believed true (``valid_to`` None: still)."""
    _run_committed(conn, "SELECT tgsis.set_version_validity(%s, %s, %s)", (version, valid_from, valid_to))


@checked
def version_chain(conn: Conn, root: str = "DEFAULT") -> list[tuple[str, datetime, datetime | None]]:
    """The versions with a validity period at or below ``root``, oldest first: (name, valid_from, valid_to).

    Raises
    ------
    InvalidInputError
        They are not one line of descent, or their periods overlap.
    """
    with reraise():
        rows = conn.execute("SELECT name, valid_from, valid_to FROM tgsis.version_chain(%s)", (root,)).fetchall()
    return [(r[0], r[1], r[2]) for r in rows]


@checked
def version_believed_at(conn: Conn, at: datetime, root: str = "DEFAULT") -> str | None:
    """The version of the chain below ``root`` believed true at ``at``, or None."""
    value = _scalar(conn, "SELECT tgsis.version_believed_at(%s, %s)", (at, root))
    return None if value is None else str(value)


# --------------------------------------------------------------------------- rights on versions

VERSION_PRIVILEGES = ("write", "create", "merge", "delete")


@dataclass(frozen=True)
class VersionGrant:
    """A row of ``tgsis.version_privileges``: ``grantee`` (a role, or ``public``) holds ``privilege`` on ``version``."""

    version: str
    grantee: str
    privilege: str
    granted_by: str
    granted_at: datetime


@checked
def grant_version(conn: Conn, version: str, privilege: str, role: str) -> None:
    """Give ``role`` (or ``"public"``) a right on ``version``: ``write``, ``create``, ``merge``, ``delete`` or ``all``.

    Owners and members of ``tgsis_admin`` hold every right without grants.

    Raises
    ------
    MissingPrivilegeError
        The caller neither owns the version nor is a ``tgsis_admin``.
    NotFoundError, InvalidInputError
    """
    _run_committed(conn, "SELECT tgsis.grant_version(%s, %s, %s)", (version, privilege, role))


@checked
def revoke_version(conn: Conn, version: str, privilege: str, role: str) -> None:
    """Take back a right granted with :func:`grant_version` (``all``: every one)."""
    _run_committed(conn, "SELECT tgsis.revoke_version(%s, %s, %s)", (version, privilege, role))


@checked
def set_version_owner(conn: Conn, version: str, role: str) -> None:
    """Make ``role`` the owner of ``version`` (owner or ``tgsis_admin`` only)."""
    _run_committed(conn, "SELECT tgsis.set_version_owner(%s, %s)", (version, role))


@checked
def has_version_privilege(conn: Conn, version: str, privilege: str, role: str | None = None) -> bool:
    """Whether ``role`` (default: the session's role) holds ``privilege`` on ``version``."""
    return bool(_scalar(conn, "SELECT tgsis.has_version_privilege(%s, %s, %s)", (version, privilege, role)))


@checked
def version_privileges(conn: Conn, version: str | None = None) -> list[VersionGrant]:
    """The grants on ``version`` (default: on every version), by version, grantee and right."""
    with reraise():
        rows = conn.execute(
            "SELECT v.name, p.grantee, p.privilege, p.granted_by, p.granted_at"
            "  FROM tgsis.version_privileges p JOIN tgsis.versions v USING (versionid)"
            " WHERE %s::text IS NULL OR v.name = %s"
            " ORDER BY v.name, p.grantee, array_position(%s::text[], p.privilege)",
            (version, version, list(VERSION_PRIVILEGES)),
        ).fetchall()
    return [VersionGrant(*r) for r in rows]


# --------------------------------------------------------------------------- object locks


@dataclass(frozen=True)
class ObjectLock:
    """A row of ``tgsis.object_locks``: ``version`` holds the object; nobody else may change it."""

    objectclass: str
    objectkey: str
    version: str
    exclusive: bool
    locked_by: str
    locked_at: datetime


@checked
def lock_objects(conn: Conn, version: str, objectclass: str, keys: Sequence[object], *, exclusive: bool = False) -> int:
    """Lock objects for ``version``: writes to them from any other version fail until unlocked.

    Parameters
    ----------
    keys : sequence
        Object keys (for features: feature ids); they must exist in ``version``.
    exclusive : bool
        Also keep other roles from changing them in ``version``.

    Returns
    -------
    int
        Locks newly taken (objects the version held already do not count).

    Raises
    ------
    ObjectLockedError
        Another version (or role) holds one of them: nothing is locked.
    MissingPrivilegeError, NotFoundError
    """
    return int(
        _run_committed(
            conn,
            "SELECT tgsis.lock_objects(%s, %s, %s, %s)",
            (version, objectclass, [_key_text(k) for k in keys], exclusive),
        )
    )


@checked
def unlock_objects(
    conn: Conn, version: str, objectclass: str | None = None, keys: Sequence[object] | None = None
) -> int:
    """Release ``version``'s locks (all, those of a class, or of some keys); return how many."""
    return int(
        _run_committed(
            conn,
            "SELECT tgsis.unlock_objects(%s, %s, %s)",
            (version, objectclass, None if keys is None else [_key_text(k) for k in keys]),
        )
    )


@checked
def object_locks(conn: Conn, version: str | None = None) -> list[ObjectLock]:
    """The object locks ``version`` holds (default: every lock), by class and key."""
    with reraise():
        rows = conn.execute(
            "SELECT l.objectclass, l.objectkey, v.name, l.exclusive, l.locked_by, l.locked_at"
            "  FROM tgsis.object_locks l JOIN tgsis.versions v USING (versionid)"
            " WHERE %s::text IS NULL OR v.name = %s ORDER BY l.objectclass, l.objectkey",
            (version, version),
        ).fetchall()
    return [ObjectLock(*r) for r in rows]


# --------------------------------------------------------------------------- compress


@dataclass(frozen=True)
class Compressed:
    """One line of the report of :func:`compress_versions`.

    Attributes
    ----------
    what : {"rows", "lastrevs", "revisions", "set entries"}
        Row versions deleted, entries taken out of ``lastrevs``, revisions
        deleted, or revision numbers taken out of working sets and of the
        stored sets of kept revisions.
    name : str
        ``schema.table`` for ``rows`` and ``lastrevs``, the version for
        ``revisions`` and ``set entries``.
    removed : int
        How many (always more than 0).
    """

    what: str
    name: str
    removed: int


@checked
def compress_versions(conn: Conn, *, dry_run: bool = False) -> list[Compressed]:
    """Remove the revisions, and the row versions, that no version, named revision or child can reach any more.

    Kept are every version's working revision, every named (saved) revision,
    every version's base (``initrevision``), and the revisions a version's
    next merge or conflict check reads (its own revisions since its base,
    its parent's revisions since its base). Every version and every kept
    revision sees exactly what it saw before, and ``find_conflicts`` gives
    the same conflicts and solutions; other revisions can no longer be
    looked at (:class:`NotFoundError` from :func:`goto_revision`).

    Parameters
    ----------
    conn : psycopg.Connection
        As a member of ``tgsis_admin``. Runs in one transaction (a
        savepoint if one is open): writers of any version wait for it, and
        it waits for them.
    dry_run : bool
        Only report what would be removed; change nothing and block no writer.

    Returns
    -------
    list of Compressed
        What was (or would be) removed, per table and per version; empty
        when there is nothing to compress.

    Raises
    ------
    MissingPrivilegeError
        The role is not a member of ``tgsis_admin``.
    """
    with reraise(), conn.transaction():
        rows = conn.execute("SELECT what, name, removed FROM tgsis.compress_versions(%s)", (dry_run,)).fetchall()
    return [Compressed(r[0], r[1], int(r[2])) for r in rows]

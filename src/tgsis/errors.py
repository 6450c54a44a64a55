"""The tgsis exception tree.

Every error tgsis raises derives from :class:`Error`. Errors raised by the
database carry one of our SQLSTATEs (class ``TG``, listed in the table
``tgsis.error_codes`` and in ``docs/errors.md``); :func:`translate` maps them to
the class whose :attr:`Error.sqlstate` matches, or, for a code this client does
not know yet, to the class of its area (``TG1xx`` to :class:`InvalidInputError`,
and so on). Database errors that are not ours become :class:`DatabaseError`.

Errors found by the client before anything reaches the database (a bad mesh, a
server that cannot start) use the same classes, with ``sqlstate`` left at the
class's code so that callers catch one thing whichever side noticed.
"""

from __future__ import annotations

import contextlib
import re
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any, ClassVar

if TYPE_CHECKING:  # imported where a database error is translated: the numpy modules raise these classes too
    import psycopg  # noqa: TID251 - types of translate()'s parameter only

__all__ = [
    "Error",
    "InstallationError",
    "MissingPrivilegeError",
    "ConcurrentReadError",
    "InvalidInputError",
    "InvalidNameError",
    "InvalidGeometryError",
    "InvalidPropertyError",
    "InvalidGMapError",
    "FileFormatError",
    "NotFoundError",
    "ObjectLockedError",
    "CheckoutConflictError",
    "NotVersionedError",
    "UnsupportedViewStatementError",
    "PeriodTopologyError",
    "RegionSolutionError",
    "AlreadyExistsError",
    "InUseError",
    "UnknownDataModelError",
    "DiscontinuousPeriodsError",
    "VersioningError",
    "ReadOnlyRevisionError",
    "UnsolvedConflictsError",
    "InvalidMergeError",
    "DatabaseError",
    "LocalServerError",
    "SkippedObjectWarning",
    "PolygonsSplitWarning",
    "class_for_sqlstate",
    "translate",
    "reraise",
]


class Error(Exception):
    """Root of every tgsis error.

    Attributes
    ----------
    sqlstate : str or None
        The SQLSTATE of the condition: the class's own code, or the code the
        server sent when the error came from the database.
    detail, hint : str or None
        The server's DETAIL and HINT fields, when the error came from the
        database (client-side errors may set them too).
    """

    #: SQLSTATE this class stands for (``None``: not one of ours).
    code: ClassVar[str | None] = "TG000"

    def __init__(
        self,
        message: str,
        *,
        sqlstate: str | None = None,
        detail: str | None = None,
        hint: str | None = None,
    ) -> None:
        super().__init__(message)
        self.message = message
        self.sqlstate = sqlstate if sqlstate is not None else self.code
        self.detail = detail
        self.hint = hint

    def __str__(self) -> str:
        parts = [self.message]
        if self.detail:
            parts.append(f"DETAIL: {self.detail}")
        if self.hint:
            parts.append(f"HINT: {self.hint}")
        return "\n".join(parts)


class InstallationError(Error):
    """The tgsis objects cannot be installed, upgraded or used at this version."""

    code = "TG001"


class MissingPrivilegeError(Error):
    """The current role lacks a right tgsis needs."""

    code = "TG002"


class ConcurrentReadError(Error):
    """A read of several statements in a ``READ COMMITTED`` transaction met other sessions' commits at every try.

    Its statements would have seen different states (each takes a new
    snapshot under ``READ COMMITTED``); nothing was returned, and the
    caller's transaction is as it was. Read outside a transaction, or in a
    ``REPEATABLE READ`` one.
    """

    code = "TG003"


class InvalidInputError(Error, ValueError):
    """An argument is out of range, missing or malformed."""

    code = "TG100"


class InvalidNameError(InvalidInputError):
    """A name is empty, too long, or would need quoting where that is not allowed."""

    code = "TG101"


class InvalidGeometryError(InvalidInputError):
    """NaN/infinite coordinates, or simplices with out-of-range or repeated indices."""

    code = "TG102"


class InvalidPropertyError(InvalidInputError):
    """Unknown property, disallowed type, or wrong number of values."""

    code = "TG103"


class InvalidGMapError(InvalidGeometryError):
    """Arrays that are no valid n-G-map, or a G-map an operation cannot take.

    An alpha_i that is not an involution, a fixed point below alpha_n, an
    alpha_i o alpha_j (i + 2 <= j) that is not an involution, darts of one
    0-cell on different points, a dart whose alpha_i lies in another topology
    period (model 4), or cells that are not what an operation needs; the
    message names the darts or cells.
    """

    code = "TG104"


class FileFormatError(InvalidInputError):
    """A geometry file cannot be read or written: unknown format, or bad content.

    Attributes
    ----------
    path : str or None
        The file.
    line : int or None
        1-based line number of the offending line, for text formats.
    """

    def __init__(self, message: str, *, path: object = None, line: int | None = None, **kwargs: Any) -> None:
        where = f"{path}:{line}: " if path is not None and line is not None else (f"{path}: " if path else "")
        super().__init__(where + message, **kwargs)
        self.path = None if path is None else str(path)
        self.line = line


class NotFoundError(Error, LookupError):
    """A named object (feature class, feature, version, table) does not exist."""

    code = "TG200"


class AlreadyExistsError(Error):
    """An object with that name or key exists already."""

    code = "TG201"


class InUseError(Error):
    """An object cannot be dropped or changed while others depend on it."""

    code = "TG202"


class UnknownDataModelError(Error):
    """A geometry or feature class of a data model that a function has no rule for, or that tgsis.data_models does not register."""

    code = "TG203"


class DiscontinuousPeriodsError(Error, ValueError):
    """A topology period whose first shape lies farther than the tolerance from the last shape of the one before.

    Models 3 and 4: at a topology instant the shape before and the shape
    after must be the same (the design's pre- and post-object share their
    geometry). The message names the period, the largest gap and the node
    (or dart) where it is; nothing is written.
    """

    code = "TG204"


class VersioningError(Error):
    """A versioning error that fits no narrower code."""

    code = "TG300"


class ReadOnlyRevisionError(VersioningError):
    """A write while the session views an older revision, or into a frozen (saved) revision."""

    code = "TG301"


class UnsolvedConflictsError(VersioningError):
    """A merge or refresh while objects changed on both sides have no recorded solution."""

    code = "TG302"


class InvalidMergeError(VersioningError):
    """A three-way merge of a mesh whose result would not be a valid mesh; refused, nothing merged.

    A cell on a vertex the merged mesh no longer has, a cell or a non-manifold
    edge (face) neither side had, a vertex left without cells that both sides
    used (:mod:`tgsis.merge3`); the message names the object and the ids.
    Its SQLSTATE is ``TG300``, the class's.
    """


class ObjectLockedError(VersioningError):
    """A write (or merge) would change an object another version, or another role, holds a lock on."""

    code = "TG303"


class CheckoutConflictError(VersioningError):
    """A check-in of an object that another writer changed (or deleted) since it was checked out."""

    code = "TG304"


class NotVersionedError(VersioningError):
    """A write in a version other than DEFAULT (or at an older revision) to what is not versioned.

    Plain tables while feature versioning is off, or the features of a class
    registered without versioning: such a write would land in DEFAULT, the
    one state they hold, which every version sees.
    """

    code = "TG305"


class UnsupportedViewStatementError(VersioningError):
    """A statement a versioned view cannot write as a plain table would; refused before anything is written.

    ``INSERT ... ON CONFLICT`` meeting a row that is there (the view cannot
    skip or update it), or a change of the session's version, revision or
    role by a function an ``UPDATE`` of the view calls.
    """

    code = "TG306"


class RegionSolutionError(VersioningError):
    """A solution the stored regions of a conflicting mesh refuse; nothing is recorded.

    A solution for a region that is no conflict (it merges by itself), for a
    region found on a state either side changed since (find the regions
    again), or a whole side of an object (``parent``, ``child``) that would
    drop the other side's edits in regions that are no conflict (docs/merge.md).
    """

    code = "TG307"


class PeriodTopologyError(VersioningError):
    """A merge by region of an evolving surface (model 3) whose merged topology would differ within one period.

    Model 3 merges per geometry instant of a topology period; all the
    instants of a period share its nodes and triangles, so a merge whose
    instants disagree there (a side added a geometry instant to a period
    whose topology the other changed, or a solution re-meshed one instant
    only) is refused for that object, naming the period.
    """

    code = "TG308"


class DatabaseError(Error):
    """A database error that is not one of tgsis's own SQLSTATEs.

    The original :class:`psycopg.Error` is the ``__cause__``; its SQLSTATE is in
    :attr:`sqlstate`.
    """

    code = None


class ConcurrentChangeError(DatabaseError):
    """The transaction met a concurrent one and was refused as a whole: retry it.

    PostgreSQL's ``40001`` (serialization_failure), which a write through a
    versioned view also raises when the row it read was changed by a
    transaction that committed meanwhile, and ``40P01`` (deadlock_detected).
    Nothing of the transaction was written.
    """

    code = None


class LocalServerError(Error):
    """The local PostgreSQL server that tgsis manages could not be found, started or stopped."""

    code = None


class SkippedObjectWarning(UserWarning):
    """A reader skipped an object of a file that it cannot read (a GOCAD SGrid beside the surfaces it reads).

    A warning, not an :class:`Error`: the other objects of the file were read.
    Readers take ``skip_unsupported=False`` to raise
    :class:`FileFormatError` instead; ``tgsis import --strict`` does the same.

    Attributes
    ----------
    path : str or None
        The file.
    line : int
        1-based line where the skipped object begins.
    object_type : str
        The object's type as the file names it (``SGrid``, ``Model3d`` ...).
    name : str or None
        The object's name, when its header gives one.
    skipped : tuple of str
        When only some of the object was not read (the regions of a GOCAD
        ``Model3d`` whose surfaces were read): what, e.g. ``("REGION 'Upper'",)``.
    """

    def __init__(
        self,
        message: str,
        *,
        path: object = None,
        line: int,
        object_type: str,
        name: str | None = None,
        skipped: tuple[str, ...] = (),
    ) -> None:
        super().__init__(message)
        self.message = message
        self.path = None if path is None else str(path)
        self.line = line
        self.object_type = object_type
        self.name = name
        self.skipped = skipped

    def __str__(self) -> str:
        return self.message


class PolygonsSplitWarning(UserWarning):
    """A reader split faces of more than three corners into triangles (planar convex ones: no shape changed).

    A file's quads and polygons become triangles of a :class:`~tgsis.mesh.Surface`
    (``metadata["polygons_split"]`` counts them; each triangle keeps its face's
    properties). Faces that are not planar or not convex are refused with
    :class:`FileFormatError` instead.

    Attributes
    ----------
    path : str or None
        The file.
    count : int
        How many faces were split.
    """

    def __init__(self, message: str, *, path: object = None, count: int) -> None:
        super().__init__(message)
        self.message = message
        self.path = None if path is None else str(path)
        self.count = count

    def __str__(self) -> str:
        return self.message


_AREA_FALLBACK: dict[str, type[Error]] = {
    "TG0": Error,
    "TG1": InvalidInputError,
    "TG2": NotFoundError,
    "TG3": VersioningError,
}

# PostgreSQL's own conditions that mean the same as one of ours.
_POSTGRES_EQUIVALENTS: dict[str, type[Error]] = {
    "42501": MissingPrivilegeError,  # insufficient_privilege
    "40001": ConcurrentChangeError,  # serialization_failure
    "40P01": ConcurrentChangeError,  # deadlock_detected
}

_SQLSTATE_RE = re.compile(r"^TG[0-9A-Z]{3}$")


def _all_subclasses(cls: type[Error]) -> Iterator[type[Error]]:
    for sub in cls.__subclasses__():
        yield sub
        yield from _all_subclasses(sub)


def class_for_sqlstate(sqlstate: str | None) -> type[Error]:
    """Return the exception class for an SQLSTATE.

    Parameters
    ----------
    sqlstate : str or None
        A five-character SQLSTATE.

    Returns
    -------
    type[Error]
        The class with that exact code; for an unknown ``TG`` code the class of
        its area; PostgreSQL's ``42501`` (insufficient privilege) gives
        :class:`MissingPrivilegeError`, ``40001`` and ``40P01`` give
        :class:`ConcurrentChangeError`; :class:`DatabaseError` for the rest.
    """
    if sqlstate in _POSTGRES_EQUIVALENTS:
        return _POSTGRES_EQUIVALENTS[sqlstate]
    if sqlstate is None or not _SQLSTATE_RE.match(sqlstate):
        return DatabaseError
    if sqlstate == Error.code:
        return Error
    for sub in _all_subclasses(Error):
        if sub.code == sqlstate:
            return sub
    return _AREA_FALLBACK.get(sqlstate[:3], Error)


def translate(exc: psycopg.Error) -> Error:
    """Turn a psycopg error into the matching tgsis error (not raised).

    Parameters
    ----------
    exc : psycopg.Error
        The error psycopg raised.

    Returns
    -------
    Error
        An instance of :func:`class_for_sqlstate` for the error's SQLSTATE, with
        the server's message, detail and hint, and ``exc`` as ``__cause__``.
    """
    diag = exc.diag
    sqlstate = exc.sqlstate
    message = diag.message_primary or str(exc).strip()
    if sqlstate == "42P01" and _MISSING_TGSIS_RELATION.match(message):
        # a tgsis table that is not there: storage never created (a bare CREATE EXTENSION) or
        # objects of another version than the client's
        err: Error = InstallationError(
            message + " (the tgsis objects of this database are incomplete or not this client's version)",
            sqlstate=sqlstate,
            detail=diag.message_detail,
            hint="`tgsis db status` says what is missing and `tgsis db install` adds it "
            "(in psql: SELECT tgsis.create_storage(); creates the storage tables)",
        )
    else:
        hint = diag.message_hint
        if sqlstate == "25006" and not hint:  # read_only_sql_transaction: the server says what, not where to write
            hint = _READ_ONLY_HINT
        err = class_for_sqlstate(sqlstate)(message, sqlstate=sqlstate, detail=diag.message_detail, hint=hint)
    err.__cause__ = exc
    return err


_READ_ONLY_HINT = (
    "this transaction may only read: on a hot standby (SELECT pg_is_in_recovery() says true) write on the primary;"
    " else the session or the transaction was made read-only (default_transaction_read_only, SET TRANSACTION)"
)

_MISSING_TGSIS_RELATION = re.compile(r'^relation "tgsis\.[^"]+" does not exist$')


@contextlib.contextmanager
def reraise() -> Iterator[None]:
    """Re-raise psycopg errors from the block as tgsis errors.

    Examples
    --------
    >>> with reraise():                                   # doctest: +SKIP
    ...     conn.execute("select tgsis.goto_version('nope')")
    """
    import psycopg  # noqa: TID251 - only where a database is used (reraise wraps database calls)

    try:
        yield
    except psycopg.Error as exc:
        raise translate(exc) from exc

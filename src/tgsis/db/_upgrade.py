"""Assembling an upgrade script ``tgsis--OLD--NEW.sql`` (standard library only).

An upgrade script is not written whole by hand. It is built from

* the frozen install script of the old version, ``sql/upgrade/tgsis--OLD.sql``
  (what a database of that version holds; split back into its source files
  by the ``-- ==== file ====`` lines the build writes);
* a hand-written part, ``sql/upgrade/tgsis--OLD--NEW.sql``, for what SQL
  cannot simply re-run: new and changed tables, types, rows. It may
  ``-- @include FILE`` a source file of the new version (copied in, with
  ``CREATE FUNCTION``/``CREATE VIEW`` made ``CREATE OR REPLACE``), say
  ``-- @rows FILE`` to upsert the shipped rows of a file (its ``INSERT``
  statements, on their first column), say ``-- @handled FILE`` of a file
  whose changed tables it alters by hand, say ``-- @moved OLD NEW`` of a
  source file of the old version that the new one has under another name
  (the two are then one file, and the directives may name it by either name),
  and put ``-- @sources`` where the generated part goes (at the end when absent);
* the generated part, from the current sources: ``DROP VIEW`` of every old
  view whose definition changed, ``DROP FUNCTION`` of every old function
  whose signature (arguments, defaults, result) changed or that is gone, then
  every function, procedure, view, comment and ``ALTER FUNCTION`` of the new
  version, in ``sources.txt`` order, as ``CREATE OR REPLACE`` (and its
  ``GRANT``/``REVOKE`` statements when new or about an object dropped here:
  :meth:`Upgrade.generated` says why). Re-running them over the old objects
  gives the new ones.

So a function, view or comment changed after the hand part was written flows
into the upgrade without an edit; a file whose *other* statements (tables,
rows, triggers, ``DO`` blocks) changed, or that is new or gone with such
statements, must be included, upserted or marked handled in the hand part
(:attr:`Upgrade.unhandled` lists those, and ``tests/test_upgrade.py`` fails
on them). docs/developing.md, "An upgrade script", is the rule.

This module imports nothing of tgsis: ``sql/Makefile`` runs it as a script
(``python3 - SQL_DIR OLD NEW < _upgrade.py``: run from stdin, so that
this folder, whose ``copy.py`` would shadow the standard library one, is not on
the path) for the PGXS build, and
:class:`tgsis.db.sqlsource.ExtensionSources` imports it, so both install
routes run the same text.
"""

from __future__ import annotations

import hashlib
import re
import sys
from dataclasses import dataclass
from pathlib import Path

__all__ = [
    "Statement",
    "Upgrade",
    "split_statements",
    "split_script",
    "assemble",
    "main",
    "install_text",
    "fingerprint",
    "FINGERPRINT_TOKEN",
]

# replaced in a built script (install or upgrade) by the fingerprint of the install script
FINGERPRINT_TOKEN = "@TGSIS_FINGERPRINT@"
INSTALL_GUARD = '\\echo Use "CREATE EXTENSION tgsis" to load this file. \\quit'

FILE_MARKER = re.compile(r"^-- ==== (\S+) ====$", re.MULTILINE)
_DIRECTIVE = re.compile(r"^--\s*@(include|handled|rows|sources)\b\s*(\S*)", re.MULTILINE)
_MOVED = re.compile(r"^--\s*@moved\s+(\S+)\s+(\S+)", re.MULTILINE)
_DOLLAR = re.compile(r"\$([A-Za-z_][A-Za-z0-9_]*)?\$")
# words that end a function's header (arguments and RETURNS clause)
_OPTION_WORDS = {
    "LANGUAGE",
    "AS",
    "IMMUTABLE",
    "STABLE",
    "VOLATILE",
    "SET",
    "SECURITY",
    "STRICT",
    "CALLED",
    "PARALLEL",
    "COST",
    "ROWS",
    "LEAKPROOF",
    "NOT",
    "SUPPORT",
    "WINDOW",
    "TRANSFORM",
    "BEGIN",
    "RETURN",
    "EXTERNAL",
}
_REPLACEABLE = re.compile(
    r"^(CREATE\s+(OR\s+REPLACE\s+)?(FUNCTION|PROCEDURE|VIEW)\b|COMMENT\s+ON\b|GRANT\b|REVOKE\b"
    r"|ALTER\s+(FUNCTION|PROCEDURE)\b)",
    re.IGNORECASE,
)


@dataclass(frozen=True)
class Statement:
    """One SQL statement of a source file.

    Attributes
    ----------
    text : str
        The statement as written, with its leading comments, without the ``;``.
    code : str
        The statement without leading comments and whitespace.
    """

    text: str
    code: str

    @property
    def kind(self) -> str:
        """``function``, ``view``, ``replaceable`` (comment, grant, ...) or ``state`` (anything else)."""
        match = re.match(r"CREATE\s+(?:OR\s+REPLACE\s+)?(FUNCTION|PROCEDURE|VIEW)\b", self.code, re.IGNORECASE)
        if match:
            return "view" if match.group(1).upper() == "VIEW" else "function"
        return "replaceable" if _REPLACEABLE.match(self.code) else "state"

    @property
    def name(self) -> str:
        """Qualified name of a function or view (``tgsis.version``)."""
        match = re.match(
            r"CREATE\s+(?:OR\s+REPLACE\s+)?(?:FUNCTION|PROCEDURE|VIEW)\s+([\w.\"]+)", self.code, re.IGNORECASE
        )
        return match.group(1) if match else ""

    def header(self) -> str:
        """A function's arguments and RETURNS clause, whitespace collapsed: its shape."""
        start = self.code.index("(", len(re.match(r"[^(]*", self.code).group(0)))  # type: ignore[union-attr]
        end = _matching_paren(self.code, start)
        rest = self.code[end + 1 :]
        words = []
        depth = 0
        for token in re.finditer(r"\(|\)|'[^']*'|\"[^\"]*\"|[^\s()]+", rest):
            word = token.group(0)
            if depth == 0 and word.upper() in _OPTION_WORDS:
                break
            depth += word == "("
            depth -= word == ")"
            words.append(word)
        return _collapse(self.code[start : end + 1]) + " " + _collapse(" ".join(words))

    def signature(self) -> str:
        """``name(arguments without defaults)``, as DROP FUNCTION takes it."""
        start = self.code.index("(", len(re.match(r"[^(]*", self.code).group(0)))  # type: ignore[union-attr]
        end = _matching_paren(self.code, start)
        args = []
        for arg in _split_top(self.code[start + 1 : end], ","):
            arg = re.split(r"\s+DEFAULT\s+|\s*=\s*", _strip_comments(arg), maxsplit=1, flags=re.IGNORECASE)[0]
            if arg.strip():
                args.append(_collapse(arg))
        return f"{self.name}({', '.join(args)})"

    def or_replace(self) -> str:
        """The statement text with ``CREATE FUNCTION``/``CREATE VIEW`` made ``CREATE OR REPLACE``."""
        if self.kind not in ("function", "view"):
            return self.text
        prefix = self.text[: len(self.text) - len(self.code)]
        return prefix + re.sub(r"^CREATE\s+(?!OR\s)", "CREATE OR REPLACE ", self.code, count=1, flags=re.IGNORECASE)


def _collapse(text: str) -> str:
    return re.sub(r"\s+", " ", _strip_comments(text)).strip().replace("( ", "(").replace(" )", ")")


def _strip_comments(text: str) -> str:
    return re.sub(r"--[^\n]*", "", text)


def _matching_paren(text: str, start: int) -> int:
    depth = 0
    i = start
    while i < len(text):
        c = text[i]
        if c == "'":
            i = text.index("'", i + 1)
        elif c == '"':
            i = text.index('"', i + 1)
        elif c == "-" and text.startswith("--", i):
            i = text.find("\n", i)
        elif c == "(":
            depth += 1
        elif c == ")":
            depth -= 1
            if depth == 0:
                return i
        i += 1
    raise ValueError(f"unbalanced parentheses in: {text[:80]}")


def _split_top(text: str, sep: str) -> list[str]:
    parts: list[str] = []
    current: list[str] = []
    depth = 0
    for c in text:
        depth += c == "("
        depth -= c == ")"
        if c == sep and depth == 0:
            parts.append("".join(current))
            current = []
        else:
            current.append(c)
    parts.append("".join(current))
    return parts


def split_statements(text: str) -> list[Statement]:
    """Split SQL text at top-level ``;`` (quotes, dollar quotes and comments respected)."""
    statements: list[Statement] = []
    i, begin, n = 0, 0, len(text)
    while i < n:
        c = text[i]
        if c == "-" and text.startswith("--", i):
            i = n if (j := text.find("\n", i)) < 0 else j
        elif c == "/" and text.startswith("/*", i):
            i = text.index("*/", i) + 1
        elif c == "'":
            i += 1
            while not (text[i] == "'" and not text.startswith("''", i)):
                i += 2 if text.startswith("''", i) else 1
        elif c == '"':
            i = text.index('"', i + 1)
        elif (
            c == "$" and (m := _DOLLAR.match(text, i)) and not (i > 0 and (text[i - 1].isalnum() or text[i - 1] == "_"))
        ):
            i = text.index(m.group(0), m.end()) + len(m.group(0)) - 1
        elif c == ";":
            _add(statements, text[begin:i])
            begin = i + 1
        i += 1
    _add(statements, text[begin:])
    return statements


def _add(statements: list[Statement], text: str) -> None:
    code = re.sub(r"^(\s|--[^\n]*(\n|$))*", "", text)
    if code.strip():
        statements.append(Statement(text, code.rstrip()))


def split_script(script: str) -> dict[str, str]:
    """A built install script back as ``{source file: its text}``, in order."""
    marks = list(FILE_MARKER.finditer(script))
    return {
        m.group(1): script[m.end() + 1 : marks[k + 1].start() if k + 1 < len(marks) else len(script)].rstrip("\n")
        + "\n"
        for k, m in enumerate(marks)
    }


def _is_grant(statement: Statement) -> bool:
    return re.match(r"(GRANT|REVOKE)\b", statement.code, re.IGNORECASE) is not None


def _file_text(text: str) -> str:
    """A source file with CREATE FUNCTION/VIEW made CREATE OR REPLACE (statements end with ``;``)."""
    return "".join(s.or_replace() + ";" for s in split_statements(text)) + "\n"


def _state(text: str | None) -> list[str]:
    """The statements of a file that re-running cannot apply (tables, rows, ...), whitespace collapsed."""
    return [] if text is None else [_collapse(s.code) for s in split_statements(text) if s.kind == "state"]


def _upsert(statement: Statement) -> str:
    """An ``INSERT INTO t (key, a, ...) VALUES ...`` of shipped rows as an upsert on its first column."""
    match = re.match(r"INSERT\s+INTO\s+(\S+)\s*\(([^)]*)\)", statement.code, re.IGNORECASE)
    if match is None or re.search(r"\bON\s+CONFLICT\b", statement.code, re.IGNORECASE):
        raise ValueError(f"@rows takes INSERT INTO table (key, columns...) without ON CONFLICT: {statement.code[:80]}")
    key, *rest = [c.strip() for c in match.group(2).split(",")]
    update = ", ".join(f"{c} = EXCLUDED.{c}" for c in rest)
    return statement.code + f"\nON CONFLICT ({key}) DO " + (f"UPDATE SET {update}" if rest else "NOTHING")


def install_text(version: str, files: dict[str, str]) -> str:
    """The install script ``tgsis--VERSION.sql`` of ``files`` (``{file: text}``, ``@TGSIS_VERSION@`` replaced)
    as ``sql/Makefile`` writes it before the fingerprint goes in: its header, then each file after a
    ``-- ==== file ====`` line."""
    header = f"-- tgsis {version}: built from sql/sources.txt, do not edit\n{INSTALL_GUARD}\n"
    return header + "".join(f"\n-- ==== {name} ====\n{text}" for name, text in files.items())


def fingerprint(script: str) -> str:
    """The fingerprint of an install script as :func:`install_text` gives it: the first 16 hex digits
    of its sha256 (what ``sql/Makefile`` computes with ``hashlib`` too).

    It is recorded in ``tgsis.installation.fingerprint`` by the install script and by every upgrade
    script to that version, so that a database built from other sources of the same version (a
    development version between two commits) is told apart from this client's.
    """
    return hashlib.sha256(script.encode("utf-8")).hexdigest()[:16]


@dataclass
class Upgrade:
    """An upgrade script being assembled.

    Attributes
    ----------
    old_files, new_files : dict of str to str
        Source files of the old and the new version, ``{file: text}`` in install order.
    hand : str
        The hand-written part.
    fingerprint : str
        The fingerprint of the new version's install script (:func:`fingerprint`), put where the
        hand part says ``@TGSIS_FINGERPRINT@``.
    """

    old_files: dict[str, str]
    new_files: dict[str, str]
    hand: str
    fingerprint: str = ""

    def _directives(self, *kinds: str) -> set[str]:
        return {self._new_name(m.group(2)) for m in _DIRECTIVE.finditer(self.hand) if m.group(1) in kinds}

    @property
    def moves(self) -> dict[str, str]:
        """``{old file: new file}`` of the hand part's ``-- @moved OLD NEW`` lines."""
        moves: dict[str, str] = {}
        for match in _MOVED.finditer(self.hand):
            if match.group(1) in moves:
                raise ValueError(f"@moved {match.group(1)}: moved twice")
            moves[match.group(1)] = match.group(2)
        return moves

    def _new_name(self, name: str) -> str:
        return self.moves.get(name, name)

    @property
    def unhandled(self) -> list[str]:
        """Files whose tables, rows or other state statements changed (or that are new or gone) and that
        the hand part neither includes nor marks handled (a moved file counts under its new name)."""
        dealt = self._directives("include", "handled", "rows")
        old_files = {self._new_name(name): text for name, text in self.old_files.items()}
        names = list(self.new_files) + [f for f in old_files if f not in self.new_files]
        return [
            name
            for name in names
            if name not in dealt and _state(old_files.get(name)) != _state(self.new_files.get(name))
        ]

    def generated(self) -> str:
        """DROPs of changed views and functions, then the functions, views, comments and grants of the new version."""
        old = [s for text in self.old_files.values() for s in split_statements(text)]
        new = [s for text in self.new_files.values() for s in split_statements(text)]
        new_views = {_collapse(s.or_replace()) for s in new if s.kind == "view"}
        new_headers = {(s.name, s.header()) for s in new if s.kind == "function"}
        lines = ["-- ---- generated: objects whose shape changed or that are gone are dropped first"]
        for s in reversed([s for s in old if s.kind == "view"]):
            if _collapse(s.or_replace()) not in new_views:
                lines.append(f"DROP VIEW IF EXISTS {s.name};")
        for s in old:
            if s.kind == "function" and (s.name, s.header()) not in new_headers:
                lines.append(f"DROP FUNCTION IF EXISTS {s.signature()};")
        # A GRANT or REVOKE run inside ALTER EXTENSION makes the object's whole
        # ACL, grants a DBA added since included, its "initial privileges",
        # which pg_dump then leaves out: only new ones, and those of objects
        # dropped above, run again.
        old_grants = {_collapse(s.code) for s in old if _is_grant(s)}
        dropped = [line.split(" IF EXISTS ", 1)[1].split("(")[0].rstrip(";") for line in lines[1:]]
        mentions = re.compile("|".join(rf"\b{re.escape(n)}\b" for n in dropped)) if dropped else None

        def wanted(statement: Statement) -> bool:
            if statement.kind == "state":
                return False
            if not _is_grant(statement) or _collapse(statement.code) not in old_grants:
                return True
            return mentions is not None and mentions.search(statement.code) is not None

        parts = ["\n".join(lines) + "\n"]
        for name, text in self.new_files.items():
            kept = "".join(s.or_replace() + ";" for s in split_statements(text) if wanted(s))
            if kept:
                parts.append(f"\n-- ==== {name} ====\n{kept}\n")
        return "".join(parts)

    def script(self, header: str) -> str:
        """The whole upgrade script, ``header`` first."""
        out = [header.rstrip("\n") + "\n"]
        placed = False
        for line in self.hand.splitlines(keepends=True):
            directive = _DIRECTIVE.match(line)
            kind, name = (directive.group(1), self._new_name(directive.group(2))) if directive else ("", "")
            if kind in ("include", "rows") and name not in self.new_files:
                raise ValueError(f"@{kind} {name}: not a source file of the new version")
            if kind == "include":
                out.append(f"-- ==== {name} (included) ====\n{_file_text(self.new_files[name])}")
            elif kind == "rows":
                rows = [
                    _upsert(st)
                    for st in split_statements(self.new_files[name])
                    if re.match(r"INSERT\b", st.code, re.IGNORECASE)
                ]
                out.append(f"-- ==== {name} (its rows) ====\n" + "".join(r + ";\n" for r in rows))
            elif kind == "sources":
                out.append(self.generated())
                placed = True
            else:
                out.append(line)
        if not placed:
            out.append(self.generated())
        if unhandled := self.unhandled:
            out.append(
                "\n-- NOT HANDLED (changed tables or rows that no hand-written line deals with; "
                "docs/developing.md): " + ", ".join(unhandled) + "\n"
            )
        script = "".join(out)
        return script.replace(FINGERPRINT_TOKEN, self.fingerprint) if self.fingerprint else script


def assemble(sql_dir: Path, old: str, new: str, new_files: dict[str, str]) -> Upgrade:
    """The upgrade from ``old`` to ``new`` of the sources in ``sql_dir``.

    Parameters
    ----------
    sql_dir : Path
        The ``sql/`` folder (``upgrade/tgsis--OLD.sql``, ``upgrade/tgsis--OLD--NEW.sql``).
    old, new : str
        Versions.
    new_files : dict of str to str
        The new version's source files in install order, ``@TGSIS_VERSION@`` replaced.
    """
    frozen = (sql_dir / "upgrade" / f"tgsis--{old}.sql").read_text(encoding="utf-8")
    hand = (
        (sql_dir / "upgrade" / f"tgsis--{old}--{new}.sql").read_text(encoding="utf-8").replace("@TGSIS_VERSION@", new)
    )
    return Upgrade(split_script(frozen), new_files, hand, fingerprint(install_text(new, new_files)))


def main(argv: list[str]) -> int:
    """``python3 - SQL_DIR OLD NEW < _upgrade.py``: print the upgrade script (for sql/Makefile)."""
    if len(argv) != 3:
        print("usage: python3 - SQL_DIR OLD NEW < _upgrade.py", file=sys.stderr)
        return 2
    sql_dir, old, new = Path(argv[0]), argv[1], argv[2]
    listing = (sql_dir / "sources.txt").read_text(encoding="utf-8")
    names = [n for n in (line.split("#", 1)[0].strip() for line in listing.splitlines()) if n]
    files = {n: (sql_dir / n).read_text(encoding="utf-8").replace("@TGSIS_VERSION@", new) for n in names}
    upgrade = assemble(sql_dir, old, new, files)
    sys.stdout.write(upgrade.script(header_for(old, new)))
    return 0


def header_for(old: str, new: str) -> str:
    """First lines of an assembled upgrade script."""
    return (
        f"-- tgsis {old} -> {new}: assembled from sql/upgrade/tgsis--{old}--{new}.sql and the "
        f"sources of {new} (src/tgsis/db/_upgrade.py), do not edit\n"
        '\\echo Use "ALTER EXTENSION tgsis UPDATE" to load this file. \\quit\n'
    )


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

"""The SQL folders are layers: each is one block of sql/sources.txt, and none uses a later one.

A folder of ``sql/`` may use the objects of the folders listed above it in
``sources.txt`` and of its own, never those of a folder below it, so the
install script is built ground first (docs/developing.md, "The layers").
The check parses the sources:

* what a file defines: ``CREATE [OR REPLACE] FUNCTION / PROCEDURE / TABLE /
  VIEW / TYPE / DOMAIN / SEQUENCE / AGGREGATE tgsis.NAME`` anywhere in it, also
  inside a function body (the storage tables are created by functions, see
  storage/create_storage.sql);
* what it uses: every ``tgsis.NAME`` left after dropping comments, ``COMMENT
  ON`` statements, the string literals of ``RAISE`` statements (their
  messages and hints name other functions for the reader, not for the server;
  the expressions of a ``RAISE`` count) and those of top-level ``INSERT`` rows
  (descriptions and hints of shipped rows). So calls and table references in
  function bodies (SQL and PL/pgSQL, also inside
  ``format()`` strings of dynamic SQL), views, column types, foreign keys,
  triggers (``ON tgsis.t ... EXECUTE FUNCTION tgsis.f()``), policies, grants
  and ``pg_extension_config_dump`` calls count.

What it does not see: names built at run time (``format('tgsis.%I', ...)``,
the ``create_function``/``check_function`` columns of ``tgsis.data_models``,
which name a model's functions without the schema) and unqualified names
(every function pins ``search_path`` to ``pg_catalog, pg_temp`` or to the
script's; only the storage functions use the latter). A name defined in two
files belongs to the first.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tgsis.db.sqlsource import ExtensionSources

SQL_DIR = Path(__file__).resolve().parents[1] / "sql"

# (file, name): a use of a later folder's object that is allowed, with the reason. Keep it empty
# if at all possible: move the file to the folder it belongs to instead.
ALLOWED: dict[tuple[str, str], str] = {}

_DEFINES = re.compile(
    r"\bCREATE\s+(?:OR\s+REPLACE\s+)?(?:UNLOGGED\s+|TEMP(?:ORARY)?\s+)?"
    r"(?:FUNCTION|PROCEDURE|TABLE|VIEW|MATERIALIZED\s+VIEW|TYPE|DOMAIN|SEQUENCE|AGGREGATE)\s+"
    r"(?:IF\s+NOT\s+EXISTS\s+)?tgsis\.(\w+)",
    re.IGNORECASE,
)
_USES = re.compile(r"\btgsis\.(\w+)")
_LITERAL = r"'(?:[^']|'')*'"
_LINE_COMMENT = re.compile(r"--[^\n]*")
_BLOCK_COMMENT = re.compile(r"/\*.*?\*/", re.DOTALL)
_RAISE = re.compile(rf"\bRAISE\b(?:[^;']|{_LITERAL})*;", re.IGNORECASE)
_COMMENT_ON = re.compile(rf"^[ \t]*COMMENT\s+ON\b(?:[^;']|{_LITERAL})*;", re.IGNORECASE | re.MULTILINE)
_TOP_INSERT = re.compile(rf"^INSERT\s+INTO\b(?:[^;']|{_LITERAL})*;", re.IGNORECASE | re.MULTILINE)


def code_of(text: str) -> str:
    """The text of an SQL source with what names objects only for a reader removed."""
    text = _COMMENT_ON.sub("", _BLOCK_COMMENT.sub("", _LINE_COMMENT.sub("", text)))
    for statement in (_RAISE, _TOP_INSERT):
        text = statement.sub(lambda m: re.sub(_LITERAL, "''", m.group(0)), text)
    return text


def folder_of(name: str) -> str:
    return name.split("/", 1)[0]


def folder_runs(files: list[str]) -> list[str]:
    """The folders of ``files`` in order, one entry per run of consecutive files of one folder."""
    runs: list[str] = []
    for name in files:
        if not runs or runs[-1] != folder_of(name):
            runs.append(folder_of(name))
    return runs


def later_folder_uses(sql_dir: Path, files: list[str]) -> list[tuple[str, str, str]]:
    """``(file, name, defining file)`` for every use of an object defined in a folder that comes later
    (a folder's place: its first file in ``files``)."""
    code = {name: code_of((sql_dir / name).read_text(encoding="utf-8")) for name in files}
    defined_in: dict[str, str] = {}
    for name in files:
        for obj in _DEFINES.findall(code[name]):
            defined_in.setdefault(obj.lower(), name)
    rank: dict[str, int] = {}
    for name in files:
        rank.setdefault(folder_of(name), len(rank))
    found = []
    for name in files:
        for obj in sorted({o.lower() for o in _USES.findall(code[name])}):
            home = defined_in.get(obj)
            if home is not None and rank[folder_of(home)] > rank[folder_of(name)]:
                found.append((name, obj, home))
    return found


@pytest.fixture(scope="module")
def files() -> list[str]:
    return ExtensionSources(SQL_DIR).files


def test_each_folder_is_one_block_of_sources(files: list[str]) -> None:
    runs = folder_runs(files)
    repeated = sorted({f for f in runs if runs.count(f) > 1})
    assert not repeated, f"sources.txt visits its folders in {len(runs)} runs; listed more than once: {repeated}"


def test_no_folder_uses_a_later_folder(files: list[str]) -> None:
    found = [use for use in later_folder_uses(SQL_DIR, files) if use[:2] not in ALLOWED]
    assert not found, "\n".join(f"{f} uses tgsis.{o}, defined later in {home}" for f, o, home in found)


def test_the_check_sees_the_uses_of_the_real_sources(files: list[str]) -> None:
    """Listed top down, the layers use each other only downwards, and the parse sees those uses: with
    the folders in the opposite order, each folder but the ground is found using a later one."""
    folders = list(dict.fromkeys(folder_of(name) for name in files))
    upside_down = [name for folder in reversed(folders) for name in files if folder_of(name) == folder]
    users = {folder_of(name) for name, _, _ in later_folder_uses(SQL_DIR, upside_down)}
    assert users == set(folders) - {"core"}
    assert ("final/grants.sql", "versions", "versioning/versions.sql") in later_folder_uses(SQL_DIR, upside_down)


def test_allowed_uses_are_still_needed(files: list[str]) -> None:
    found = {use[:2] for use in later_folder_uses(SQL_DIR, files)}
    assert set(ALLOWED) <= found, f"no longer used, remove from ALLOWED: {sorted(set(ALLOWED) - found)}"


def test_every_folder_is_a_documented_layer(files: list[str]) -> None:
    """docs/developing.md lists the layers in the order of sources.txt."""
    docs = (SQL_DIR.parent / "docs" / "developing.md").read_text(encoding="utf-8")
    section = docs.split("### The layers", 1)[1].split("\n#", 1)[0]
    items = re.findall(r"^\d+\.\s+([^:]*):", section, re.MULTILINE)
    listed = [folder for item in items for folder in re.findall(r"`(\w+)/`", item)]
    assert listed == list(dict.fromkeys(folder_of(name) for name in files))


def _layout(tmp_path: Path, sources: dict[str, str]) -> list[str]:
    for name, text in sources.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text, encoding="utf-8")
    return list(sources)


def test_the_check_sees_each_kind_of_use(tmp_path: Path) -> None:
    """A use of a later folder is found in a PL/pgSQL body, a dynamic SQL string, an SQL function,
    a view, a column type, a foreign key, a trigger and a grant; a mention in a comment, a COMMENT
    ON, a RAISE or a shipped row's description is not a use."""
    files = _layout(
        tmp_path,
        {
            "low/plpgsql.sql": "CREATE FUNCTION tgsis.a() RETURNS void LANGUAGE plpgsql AS $$\n"
            "BEGIN\n  PERFORM tgsis.f1();\n"
            "  RAISE EXCEPTION 'x; see tgsis.f8' USING HINT = 'call tgsis.f8(); then tgsis.f8';\n"
            "  EXECUTE format('SELECT tgsis.f2(%L)', 1);\nEND $$;\n"
            "COMMENT ON FUNCTION tgsis.a() IS 'like tgsis.f8; not tgsis.f8';\n",
            "low/sql.sql": "-- tgsis.f8 in a comment\nCREATE FUNCTION tgsis.b() RETURNS int LANGUAGE sql AS $$ SELECT tgsis.f3() $$;\n",
            "low/view.sql": "/* tgsis.f8 */ CREATE VIEW tgsis.v AS SELECT * FROM tgsis.t1;\n",
            "low/table.sql": "CREATE TABLE tgsis.c (k tgsis.ty, r text REFERENCES tgsis.t2 (k));\n"
            "INSERT INTO tgsis.c (k, r) VALUES ('x', 'made by tgsis.f8');\n",
            "low/trigger.sql": "CREATE TRIGGER tr AFTER INSERT ON tgsis.c FOR EACH ROW EXECUTE FUNCTION tgsis.f4();\n",
            "low/grant.sql": "GRANT SELECT ON tgsis.t3 TO PUBLIC;\n",
            "high/objects.sql": "CREATE FUNCTION tgsis.f1() RETURNS void LANGUAGE sql AS $$ $$;\n"
            "CREATE FUNCTION tgsis.f2(int) RETURNS void LANGUAGE sql AS $$ $$;\n"
            "CREATE OR REPLACE FUNCTION tgsis.f3() RETURNS int LANGUAGE sql AS $$ SELECT 1 $$;\n"
            "CREATE FUNCTION tgsis.f4() RETURNS trigger LANGUAGE plpgsql AS $$ BEGIN RETURN NULL; END $$;\n"
            "CREATE FUNCTION tgsis.f8() RETURNS void LANGUAGE sql AS $$ $$;\n"
            "CREATE TABLE tgsis.t1 (k int);\nCREATE UNLOGGED TABLE tgsis.t2 (k text PRIMARY KEY);\n"
            "CREATE DOMAIN tgsis.ty AS text;\nCREATE OR REPLACE VIEW tgsis.t3 AS SELECT 1;\n",
        },
    )
    found = {(f, o) for f, o, home in later_folder_uses(tmp_path, files)}
    assert found == {
        ("low/plpgsql.sql", "f1"),
        ("low/plpgsql.sql", "f2"),
        ("low/sql.sql", "f3"),
        ("low/view.sql", "t1"),
        ("low/table.sql", "ty"),
        ("low/table.sql", "t2"),
        ("low/trigger.sql", "f4"),
        ("low/grant.sql", "t3"),
    }
    # the same files with the folders the other way round: nothing is later
    assert later_folder_uses(tmp_path, files[-1:] + files[:-1]) == []


def test_a_folder_in_two_runs_is_found() -> None:
    assert folder_runs(["a/1.sql", "b/1.sql", "a/2.sql"]) == ["a", "b", "a"]
    assert folder_runs(["a/1.sql", "a/2.sql", "b/1.sql"]) == ["a", "b"]

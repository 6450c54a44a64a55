"""Hints in the ``tgsis`` command's own words.

The library and the SQL functions give hints in their interface's terms: a
Python keyword argument (``drop_extra_properties=True``, ``format=``), an SQL
call (``SELECT tgsis.resolve_conflict(...)``, ``force => true``). The command
line prints every hint through :func:`to_cli`, the one place where those
terms become its flags and commands. :func:`foreign_terms` finds what is
still in another interface's terms; ``tests/test_cli_hints.py`` drives real
failing commands and checks that no printed hint has any, and checks every
hint written in ``sql/`` and ``src/tgsis/`` through :func:`to_cli` too, so a
hint added later without a rule here fails a test.

A few hints have no command-line equivalent: statements a DBA runs in psql
(``GRANT ...``), repairs only SQL can make. Those are said as such, after
``in psql:``, which :func:`foreign_terms` accepts.
"""

from __future__ import annotations

import ast
import re
import shlex
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path

#: What a hint says before an SQL statement that has no command-line equivalent.
IN_PSQL = "in psql: "

Replacement = str | Callable[[re.Match[str]], str]

#: A version name as the Python library's hints write it (``{version!r}``: repr's quotes and backslash escapes).
_PY_LITERAL = r"""('(?:[^'\\\n]|\\.)*'|"(?:[^"\\\n]|\\.)*")"""
#: A word as :func:`shlex.quote` writes it (the hints that already print the command beside the Python call).
_SHELL_WORD = r"""(?:'(?:[^']|'"'"')*'|[\w@%+=:,./-]+)"""

#: (pattern, replacement), applied in order: the most specific first.
_RULES: list[tuple[str, Replacement]] = [
    # --- versions
    (
        r"record a solution for each: SELECT tgsis\.resolve_conflict\('((?:[^']|'')*)', class, key, [^)]*\)",
        lambda m: (
            f"record a solution for each: tgsis version resolve {_word(m[1])} CLASS KEY parent|child|manual "
            f"(tgsis version conflicts {_word(m[1])} lists them)"
        ),
    ),
    (
        r"pass discard_other=True to record it all the same, or write the merged object into the version and record "
        r"manual \(tgsis\.conflict_rows shows both sides' rows\)",
        "add --discard-other to record it all the same, or write the merged object into the version and record manual "
        "(tgsis version conflicts VERSION --rows shows both sides' rows)",
    ),
    # conflicts per region (tgsis.db.regions, sql/versioning/resolve_region.sql and friends)
    (
        r"call again with discard_other=True to discard them, or choose another solution",
        "add --discard-other to record it all the same, or choose another solution",
    ),
    (  # the Python library's (the name as repr), or SQL's naming no version (tgsis.resolve_all_regions)
        r"find the regions again(?: on the object's current state)?(?::| \()? ?tgsis\.find_conflicts\(conn, "
        rf"(?:{_PY_LITERAL}|(\w+))\)(?:, or tgsis version conflicts(?: {_SHELL_WORD})?| in Python, or tgsis version "
        r"conflicts| \(tgsis\.find_conflicts in Python, or tgsis version conflicts\))?\)?",
        lambda m: f"find the regions again: tgsis version conflicts {_py_word(m[1], m[2])}",
    ),
    (
        r"find the regions again(?: on the object's current state)? \(tgsis\.find_conflicts in Python, or tgsis version "
        r"conflicts\)(, then solve them)?",
        lambda m: "find the regions again: tgsis version conflicts VERSION" + (m[1] or ""),
    ),
    (  # resolve_conflict's parent/child from a role that may not read the class, no regions stored yet
        r"a role that may read the class finds its regions with SELECT FROM tgsis\.find_conflicts\('((?:[^']|'')*)'\)",
        lambda m: f"a role that may read the class finds its regions with tgsis version conflicts {_word(m[1])}",
    ),
    (
        rf"tgsis\.find_conflicts\(conn, (?:{_PY_LITERAL}|(\w+))\) finds and records them \(tgsis version conflicts "
        rf"{_SHELL_WORD}\)",
        lambda m: f"tgsis version conflicts {_py_word(m[1], m[2])} finds and records them",
    ),
    (
        r"SELECT region, conflict, solution FROM tgsis\.conflict_regions WHERE versionid = tgsis\.version_id\('((?:[^']|'')*)'\) "
        r"lists them; tgsis\.find_conflicts in Python finds them",
        lambda m: f"tgsis version conflicts {_word(m[1])} --json lists them (conflict_regions)",
    ),
    (
        r"only a region with conflict = true takes a solution: SELECT region FROM tgsis\.conflict_regions WHERE "
        r"versionid = tgsis\.version_id\('((?:[^']|'')*)'\) AND conflict",
        lambda m: (
            f'only a region with "conflict": true takes a solution (tgsis version conflicts {_word(m[1])} '
            "--json lists them)"
        ),
    ),
    (
        r"solve the conflicting regions with SELECT tgsis\.resolve_region\('((?:[^']|'')*)', '((?:[^']|'')*)', "
        r"'((?:[^']|'')*)', region, '(\w+)'\); the merge takes the rest by itself",
        lambda m: (
            f"solve the conflicting regions with tgsis version resolve {_word(m[1])} {_word(m[3])} {m[4]} "
            "--region N; the merge takes the rest by itself"
        ),
    ),
    (
        # the version's name from the Python literal (a name inside the backticks may hold a backtick itself)
        rf"the meshes (.*?) merge by region: `tgsis version (\w+) .*?` or tgsis\.\w+_version\(conn, {_PY_LITERAL}\) "
        r"in Python merges them \(solve their conflicting regions first: SELECT tgsis\.resolve_region\('(?:[^']|'')*', "
        r"[^)]*\)\); "
        r"record a solution for the others: SELECT tgsis\.resolve_conflict\('((?:[^']|'')*)', class, key, [^)]*\)",
        lambda m: (
            f"the meshes {m[1]} merge by region: tgsis version {m[2]} {_py_word(m[3])} merges them (solve their "
            f"conflicting regions first: tgsis version resolve {_word(m[4])} ID parent|child|base --region N); record "
            f"a solution for the others: tgsis version resolve {_word(m[4])} CLASS KEY parent|child|manual"
        ),
    ),
    (
        r"SELECT tgsis\.resolve_region\(version, class, key, region, 'parent'\|'child'\|'base'\) or 'average'\|'manual' "
        r"with a mesh",
        "tgsis version resolve VERSION ID parent|child|base|average|manual --region N [--mesh FILE]",
    ),
    (
        r"give the mesh as the sixth argument \(an \.npz of a MeshState: tgsis\.resolve_region in Python builds it\)",
        "give --mesh FILE",
    ),
    (r"leave the sixth argument out, or give the solution manual with the mesh", "leave --mesh out, or give manual"),
    (
        r"give the bytes numpy\.savez writes of a MeshState \(tgsis\.resolve_region in Python builds them\)",
        "give --mesh FILE, a mesh file",
    ),
    (r"give the region's number, as tgsis\.conflict_regions lists it", "give --region N"),
    (  # resolve_region's rows that are not its .npz's mesh: the command records both from one --mesh
        r"give the rows of the mesh the \.npz holds \(tgsis\.resolve_region in Python records both from one mesh\)",
        "give --mesh FILE: the command records the mesh and its rows from it",
    ),
    (r", or tgsis\.resolve_region in Python$", ""),
    (
        r"automatic is no choice: find_conflicts records it for the regions that merge by themselves",
        "automatic is no choice: the regions that are no conflict merge by themselves",
    ),
    (r"leave mesh out, or give solution='manual'( \(average is computed\))?", "leave --mesh out, or give manual"),
    (r"^give mesh=$", "give --mesh FILE"),
    (
        r"give a JSON array with one object per region \(''\[\]'' for none\)|each element of the array is an object "
        r"with the keys .*|give the childmark and parentmark of the row of tgsis\.find_conflicts",
        lambda m: f"{IN_PSQL}{m[0]}",
    ),
    (r", or give a MeshState$", ""),
    # tgsis.object_merge (tgsis version conflicts --regions)
    (
        rf"tgsis\.find_conflicts\(conn, (?:{_PY_LITERAL}|(\w+))\) lists the objects changed on both sides",
        lambda m: f"tgsis version conflicts {_py_word(m[1], m[2])} lists the objects changed on both sides",
    ),
    (
        r"tgsis\.resolve_conflict solves it as a whole object \(parent, child or manual\)",
        "tgsis version resolve VERSION feature ID parent|child|manual solves it as a whole object",
    ),
    (
        r"tgsis\.list_feature_classes and tgsis\.fetch_features show the features there are",
        "tgsis ls --in VERSION lists the features there are",
    ),
    (
        r"call tgsis\.object_merge outside a transaction, or in a REPEATABLE READ or SERIALIZABLE one",
        "run tgsis version conflicts VERSION --regions again",
    ),
    (
        r"SELECT \* FROM tgsis\.find_conflicts\('((?:[^']|'')*)'\) lists the conflicts",
        lambda m: f"tgsis version conflicts {_word(m[1])} lists the conflicts",
    ),
    (
        r"SELECT tgsis\.goto_version\('DEFAULT'\); SELECT name FROM tgsis\.versions lists the versions",
        "work in DEFAULT (--in DEFAULT, or tgsis version goto DEFAULT); tgsis version list lists the versions",
    ),
    (
        r"SELECT tgsis\.goto_version\('((?:[^']|'')*)'\) to work in its working revision",
        lambda m: f"--in {_word(m[1])} (or tgsis version goto {_word(m[1])}) works in its working revision",
    ),
    (
        r"SELECT tgsis\.goto_version\(tgsis\.get_working_version\(\)\) clears it",
        "leave out @REVISION (--in VERSION, or tgsis version goto VERSION) to work in the working revision",
    ),
    (
        r"SELECT tgsis\.goto_version\('DEFAULT'\)( to write the current state)?",
        lambda m: "work in DEFAULT (--in DEFAULT, or tgsis version goto DEFAULT)" + (m[1] or ""),
    ),
    (r"tgsis\.goto_version\(conn, 'DEFAULT'\)", "work in DEFAULT (--in DEFAULT, or tgsis version goto DEFAULT)"),
    (r"SELECT name FROM tgsis\.versions lists the versions", "tgsis version list lists the versions"),
    (r"or tgsis\.delete_version it first", "or delete it first (tgsis version delete NAME)"),
    (
        r"the holder releases them with SELECT tgsis\.unlock_objects\([^)]*\); SELECT \* FROM tgsis\.object_locks "
        r"lists locks",
        "the holder releases them with tgsis version unlock VERSION [CLASS [KEY...]]; tgsis version locks lists locks",
    ),
    (
        r"the owner or a tgsis_admin can run SELECT tgsis\.grant_version\('((?:[^']|'')*)', '((?:[^']|'')*)', "
        r"'((?:[^']|'')*)'\)",
        lambda m: f"the owner or a tgsis_admin can run tgsis version grant {_word(m[1])} {_word(m[2])} {_word(m[3])}",
    ),
    (r"end the earlier one \(tgsis\.set_version_validity\)", "end the earlier one (tgsis version valid NAME FROM TO)"),
    (
        r"valid_to must be later than valid_from \(NULL: still believed\)",
        "TO must be later than FROM (leave TO out: still believed)",
    ),
    (
        r"pass p_base => NULL to base the child on the parent's working revision",
        "create the child without a base revision: it starts from the parent's working revision",
    ),
    (
        r"check in into a new child version \(on_conflict=\"child\", tgsis checkin --on-conflict child\)",
        "check in into a new child version (tgsis checkin FILE --on-conflict child)",
    ),
    (
        r"\(or save it over that state with tgsis\.save_feature\), or check it in with on_conflict='raise' to see the "
        r"conflict only",
        "(tgsis checkout ID FILE), or check it in with --on-conflict raise to see the conflict only",
    ),
    (
        r"tgsis\.enable_feature_versioning\(conn\) \(or `tgsis versioning enable`\) makes on_conflict='child' work",
        "tgsis versioning enable features makes --on-conflict child work",
    ),
    (
        r"(?:SELECT )?tgsis\.enable_feature_versioning\((?:conn)?\) (?:to write features in versions|versions model 1 "
        r"and every feature class)[^;]*",
        "tgsis versioning enable features, to write features in versions; or work in "
        "DEFAULT (--in DEFAULT, or tgsis version goto DEFAULT)",
    ),
    (r"; tgsis\.compare_geometries compares two geometries", ""),
    (
        r"\(tgsis\.enable_feature_versioning versions the features\)",
        "(tgsis versioning enable features versions the features)",
    ),
    (r"tgsis\.enable_feature_versioning versions it", "tgsis versioning enable features versions it"),
    (
        r"tgsis\.enable_versioning versions a table and registers it",
        "tgsis versioning enable TABLE --key K --class C versions a table and registers it",
    ),
    (r"tgsis\.enable_versioning records what it drops", "tgsis versioning enable records what it drops"),
    (
        r"tgsis\.disable_versioning makes a versioned table plain and forgets it",
        "tgsis versioning disable TABLE makes a versioned table plain and forgets it",
    ),
    (
        r"SELECT \* FROM tgsis\.versioned_tables lists the versioned tables",
        "tgsis versioning list lists the versioned tables",
    ),
    (r"SELECT DISTINCT objectclass FROM tgsis\.versioned_tables lists them", "tgsis versioning list lists them"),
    (
        r"merge or delete those versions first, or pass p_force => true",
        "merge or delete those versions first, or repeat with --force",
    ),
    (r"pass another p_shortname", "give another --shortname"),
    (r"pass a non-empty array of keys without NULLs", "give at least one KEY"),
    # --- feature classes and features
    (
        r"delete them first, or drop with force => true to delete them with their geometries",
        "delete them first, or repeat with --force to delete them with their geometries",
    ),
    (r"SELECT classname FROM tgsis\.catalog lists the classes", "tgsis class list lists the classes"),
    (r"SELECT geoid(?:, geotype)? FROM tgsis\.geometry lists the stored geometries", "tgsis ls lists the features"),
    (r"SELECT _geoid FROM \S+ lists them", "tgsis ls --class CLASS lists them"),
    (
        r"SELECT tgsis\.delete_geometry\(([^)]*)\) deletes the (feature|collection with its members)",
        lambda m: f"{IN_PSQL}SELECT tgsis.delete_geometry({m[1]}) deletes the {m[2]}",
    ),
    (r"give time_model => (.+?) for a temporal class", lambda m: f"give --time-model {m[1]} for a temporal class"),
    (r"^p_cell_level => ", "--cell-level "),
    (
        r"leave p_cell_level out, or register a class of G-maps \(p_time_model => 'GMAP'\)",
        "leave --cell-level out, or create a class of G-maps (--time-model GMAP or MULTIDIM)",
    ),
    # --- G-maps (models 4 and 5)
    (r"SELECT geoid FROM tgsis\.(?:gmap|md_gmap) lists (?:the stored G-maps|them)", "tgsis ls lists the features"),
    (r"p_level => 0 \.\. (\S+)", lambda m: f"LEVEL is 0 .. {m[1]}"),
    (
        r"create a class with time_model=(\S+) and a cell_level for",
        lambda m: (
            f"create a class with tgsis class create NAME --geotype GMAP --time-model {m[1].strip(chr(39))} "
            "--cell-level LEVEL for"
        ),
    ),
    (r"tgsis\.gmaps\.extrude makes an axis", "tgsis extrude makes an axis"),
    (r"SELECT \* FROM tgsis\.(?:gmap_check|md_check)\(([^)]*)\)", lambda m: f"tgsis gmap check {m[1]}"),
    (
        r"write a slice of it \(tgsis\.gmaps\.slice\)",
        "write a slice of it (tgsis slice ID --axis AXIS --value V --output FILE)",
    ),
    # (SQL-only questions of models 4 and 5: no command asks them)
    (r"^(tgsis\.property_at gives .*|p_axes => .*|tgsis\.geometries_in_box finds .*)", lambda m: f"{IN_PSQL}{m[1]}"),
    (r"then run (SELECT tgsis\.create_storage\(\))", lambda m: f"then run, {IN_PSQL}{m[1]}"),
    (
        r"As tgsis's owner run SELECT tgsis\.create_storage\(\); \(or tgsis db install, which does it\)\.",
        "Run tgsis db install as tgsis's owner: it creates the storage tables.",
    ),
    (r"p_geotype => ", "--geotype "),
    (r"uninstall with cascade \(tgsis db uninstall --cascade\)", "repeat with --cascade"),
    (r"or install with method='sql'", "or install with --method sql"),
    (
        r"delete the feature and insert the edited collection \(tgsis\.insert_feature\)",
        "import the edited collection as a new feature (tgsis import FILE --class CLASS --replace)",
    ),
    (
        r"tgsis\.get_at\(conn, id, t\) gives the surface at model time t",
        "tgsis at ID T FILE writes the surface at model time T",
    ),
    (
        r"give a tgsis\.SurfaceSeries \(INSTANTS\) or tgsis\.EvolvingSurface \(EVOLVING\)",
        "import it at a model time with --at T (INSTANTS), or build surfaces over time with tgsis interpolate --class "
        "CLASS (EVOLVING)",
    ),
    (
        r"(?:tgsis\.)?features_at lists the features of any class that exist at t",
        "tgsis ls lists the features of every class",
    ),
    (r"(SELECT \* FROM tgsis\.check_geometry\([^)]*\))", lambda m: f"{IN_PSQL}{m[1]}"),
    (r"tgsis\.drop_feature_class removes it", "tgsis class drop NAME removes it"),
    # --- editing a class (tgsis class alter)
    (
        r"SELECT feature_properties, cell_properties, instant_properties FROM tgsis\.catalog WHERE classname = '[^']*'",
        "tgsis class list shows the properties of the classes",
    ),
    (r"say which: p_kind => 'feature', 'cell' or 'instant'", "say which: feature:NAME, cell:NAME or instant:NAME"),
    (
        r"add a feature property \(p_kind => 'feature'\) instead",
        "add a feature property (--add-feature-property) instead",
    ),
    (r"drop it with p_force => true to delete its values", "repeat with --force to delete its values"),
    (r"give p_default, e\.g\. '0'", "give the value stored rows get: --add-property NAME:TYPE=VALUE"),
    (
        r"compare its members one by one: (SELECT geoids FROM tgsis\.geometry WHERE .*)",
        lambda m: f"compare its members one by one ({IN_PSQL}{m[1]})",
    ),
    (r"(?<!in psql: )(tgsis\.delete_instant removes it first)", lambda m: f"{IN_PSQL}{m[1]}"),
    (
        r"give them rows first: SELECT \* FROM tgsis\.fill_property_rows\('((?:[^']|'')*)', '[^']*'\)",
        lambda m: f"give them rows first: tgsis class alter {_word(m[1])} --fill-property NAME=VALUE",
    ),
    (
        r"SELECT tgsis\.enable_feature_versioning\(\) versions them all",
        "tgsis versioning enable features versions them all",
    ),
    (
        r"read the class again \(tgsis\.get_feature_class\) and give the new properties' values",
        "run the command again: it reads the class anew (tgsis class list shows its properties)",
    ),
    # --- only the SQL functions take these (the command line reads them from the file)
    (r"^(p_(?:zpositive|crs|metadata) => .*)", lambda m: f"{IN_PSQL}{m[1]}"),
    (r"^(SELECT tgsis\.object_fingerprint\(geoid\) at check-out gives the fingerprint)", lambda m: f"{IN_PSQL}{m[1]}"),
    (r"in SQL, (quote names with capitals)", lambda m: f"{IN_PSQL}{m[1]}"),
    # --- a statement of the user's own that changes the version from inside an UPDATE of a view (SQL only)
    (
        r"^Change the version \(goto_version, SET tgsis\.version\) between statements, not from inside one\.",
        lambda m: f"{IN_PSQL}{m[0]}",
    ),
    # --- files
    (r"pass format= with one of ", "give --format with one of "),
    (r"use tgsis\.formats\.read_pvd or write_pvd", "tgsis series writes a .pvd"),
    (r"use tgsis\.formats\.read to get all of them", "tgsis import stores all of them"),
    (r"tgsis\.formats\.read or read_vt\w+ reads the members", "tgsis import reads the members"),
    (
        r"extract one kind first \(e\.g\. mesh\.extract_cells_by_type\([^)]*\)\), or store the kinds as members of a "
        r"tgsis\.GeometryCollection",
        "split the file by cell kind first (ParaView: Extract Cells By Type), one file each",
    ),
    (
        r"give it points \(and cells\), or build the empty tgsis mesh you mean \(e\.g\. .*\)\)$",
        "give a file with points (and cells)",
    ),
    (r"pass drop_extra_properties=True", "give --drop-extra-properties"),
    (r"drop_extra_properties=True", "--drop-extra-properties"),
    (
        r"read it as a file of GOCAD objects with format='tsurf'",
        "import it with --format tsurf (a file of GOCAD objects)",
    ),
    (
        r"pass skip_unsupported=True to read the other objects of the file",
        "import without --strict to store the other objects of the file",
    ),
    (r", or pass drop_properties=True", ""),
    (r"pass drop_cell_properties=True to write the mesh without them", "write it to a .vtu file, which keeps them"),
    (r"replace them \(overwrite=True; tgsis: --force\)", "add --force to replace them"),
    (
        r"give every member the property, or remove it before (?:writing|converting)",
        "export to a GOCAD file of the members' type (.ts, .pl, .vs, .so), where each object keeps its own properties, "
        "or import the objects into a class that is no GEOMETRYCOLLECTION (one feature each)",
    ),
    # --- time
    (r"give start, end and steps", "give --from, --to and --steps"),
    (
        r"the condition is \"value op v\", e\.g\. op => '>=' for values of at least v",
        "the condition is PROPERTY OP VALUE, e.g. throw '>=' 100 for throws of at least 100",
    ),
    # --- roles and storage: only SQL can do these
    (r"(a DBA may run: |Ask a DBA to run once: ?)", lambda m: f"{m[1]}{IN_PSQL}"),
    (
        r"the table's owner may run: (SELECT tgsis\.restore_storage_runner\([^)]*\))",
        lambda m: f"the table's owner may run, {IN_PSQL}{m[1]}",
    ),
    (
        r"its owner restores it with (tgsis\.restore_dropped_constraints\([^)]*\))",
        lambda m: f"its owner restores it, {IN_PSQL}SELECT {m[1]}",
    ),
    (
        r"or label the rows with (SELECT revision FROM tgsis\.write_revision\(\))",
        lambda m: f"or label the rows ({IN_PSQL}{m[1]})",
    ),
    (r"call it as (tgsis\.rows_at\([^)]*\))", lambda m: f"call it as {IN_PSQL}SELECT {m[1]}"),
]
RULES: list[tuple[re.Pattern[str], Replacement]] = [(re.compile(p, re.IGNORECASE), r) for p, r in _RULES]


def _unquote(literal: str) -> str:
    return literal.replace("''", "'")


def _word(literal: str) -> str:
    """An SQL literal's text as one shell word of a printed command (a version name with a space stays one)."""
    return shlex.quote(_unquote(literal))


def _py_word(literal: str | None, bare: str | None = None) -> str:
    """A Python literal's text (repr of a version name) as one shell word; a bare word as it is (``version``:
    the placeholder VERSION)."""
    if literal is None:
        return "VERSION" if bare is None or bare.lower() == "version" else bare
    return shlex.quote(str(ast.literal_eval(literal)))


#: An escape string literal, as format's %L writes a text holding a backslash (``E'dev\\ana'``).
#: (Only one that holds a backslash escape: %L writes no other, and a standard literal's text may hold " E''".)
_ESCAPE_LITERAL = re.compile(r"(?<![\w'])E'((?:[^'\\]|'')*\\.(?:[^'\\]|''|\\.)*)'", re.DOTALL)


def _standard_literal(m: re.Match[str]) -> str:
    """An escape string literal as the standard one of the same text, which the rules read (``'dev\\ana'``)."""
    return "'" + re.sub(r"\\(.)", r"\1", m[1], flags=re.DOTALL) + "'"


def to_cli(hint: str | None) -> str | None:
    """``hint`` in the command line's terms (its flags and commands), through :data:`RULES`."""
    if not hint:
        return hint
    hint = _ESCAPE_LITERAL.sub(_standard_literal, hint)
    for pattern, replacement in RULES:
        hint = pattern.sub(replacement, hint)
    return hint


@lru_cache(maxsize=1)
def _api_names() -> frozenset[str]:
    """Names an SQL call or a Python call of tgsis can have: the SQL functions, the Python package's names."""
    import tgsis

    names = set(getattr(tgsis, "__all__", ())) | {n for n in dir(tgsis) if not n.startswith("_")}
    sql = Path(__file__).resolve().parent / "_sql"
    if not sql.is_dir():
        sql = Path(__file__).resolve().parents[2] / "sql"
    for path in sql.rglob("*.sql"):
        names.update(re.findall(r"FUNCTION\s+tgsis\.(\w+)\s*\(", path.read_text(errors="replace"), re.IGNORECASE))
    return frozenset(n.lower() for n in names)


_KEYWORD = re.compile(r"(?<![\w-])([a-z_][a-z0-9_]*)\s*=(?![=>])\s*(?=[\w'\"{(\[-])")
_SQL = re.compile(r"=>|\bSELECT\b|\bFROM\s+tgsis\.\w+", re.IGNORECASE)
_CALL = re.compile(r"\btgsis\.([A-Za-z_]\w*)")
_FLAG_VALUE = re.compile(r"(--[a-z][\w-]*\s+)[A-Za-z_]\w*=")


def foreign_terms(text: str | None) -> list[str]:
    """The parts of ``text`` in the terms of another interface: Python keyword arguments, SQL calls.

    Text after :data:`IN_PSQL` (a statement only SQL can make) is not looked at.
    """
    if not text:
        return []
    text = text.split(IN_PSQL, 1)[0]
    # NAME=VALUE given to a flag (--fill-property porosity=0.2) is the command's own syntax, no keyword argument
    text = _FLAG_VALUE.sub(r"\1", text)
    found = [m[0] for m in _KEYWORD.finditer(text)]
    found += [m[0] for m in _SQL.finditer(text)]
    found += [m[0] for m in _CALL.finditer(text) if m[1].lower() in _api_names()]
    return found

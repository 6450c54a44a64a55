"""Every hint the `tgsis` command prints is in its own terms: flags and commands, no Python keyword or SQL call.

The hints come from the library and the SQL functions in their own terms;
tgsis.cli._hints maps them in one place. These tests drive real failing commands
against a real database and read the hint they print; the last one runs every
hint written in sql/ and src/tgsis/ through the mapping, so that a new hint
without a rule fails here.
"""

from __future__ import annotations

import re
from pathlib import Path

import psycopg
import pytest

from tests.shared_data import cfm
from tgsis.cli import main
from tgsis.cli._hints import foreign_terms, to_cli

ROOT = Path(__file__).resolve().parents[1]
FLAGGED = Path(__file__).parent / "data" / "gocad" / "flagged.ts"


def hint_of(dsn: str, capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    """Run a command that must fail; return the hint it printed (checked to be in CLI terms)."""
    assert main(["--dsn", dsn, *argv]) == 1
    err = capsys.readouterr().err
    assert err.startswith("tgsis: error: "), err
    hints = [line[len("HINT: ") :] for line in err.splitlines() if line.startswith("HINT: ")]
    assert len(hints) == 1, err
    assert foreign_terms(hints[0]) == [], f"tgsis {' '.join(argv)}: {hints[0]}"
    return hints[0]


@pytest.fixture
def dsn(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> str:
    assert main(["--dsn", db_dsn, "class", "create", "faults", "--geotype", "SURFACE"]) == 0
    assert main(["--dsn", db_dsn, "import", str(FLAGGED), "--class", "faults"]) == 0
    capsys.readouterr()
    return db_dsn


def test_hints_of_files_and_classes(dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    source = cfm("formats/CRFA-SJMZ-CHMN-Big_Spring_fault-50dip-CFM5.ts")  # has properties azi, dip
    assert "--drop-extra-properties" in hint_of(dsn, capsys, "import", str(source), "--class", "faults")
    assert "--format" in hint_of(dsn, capsys, "export", "1", str(tmp_path / "out.xyz"))
    assert "--format" in hint_of(dsn, capsys, "import", str(tmp_path / "in.xyz"), "--class", "faults")
    assert "--force" in hint_of(dsn, capsys, "class", "drop", "faults")
    assert "tgsis class list" in hint_of(dsn, capsys, "ls", "--class", "nope")
    assert "tgsis ls" in hint_of(dsn, capsys, "info", "999")


def test_hints_of_versions(dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    hint = hint_of(dsn, capsys, "--in", "nope", "ls")
    assert "tgsis version list" in hint
    assert main(["--dsn", dsn, "version", "create", "v"]) == 0
    hint = hint_of(dsn, capsys, "--in", "v", "import", str(FLAGGED), "--class", "faults")  # not versioned yet
    assert "tgsis versioning enable features" in hint and "--in DEFAULT" in hint
    assert "tgsis version delete" in hint_of(dsn, capsys, "version", "create", "v")
    assert main(["--dsn", dsn, "versioning", "enable", "features"]) == 0
    with psycopg.connect(dsn) as conn:  # both sides change feature 1: a conflict
        conn.execute("UPDATE tgsis.vrtx SET z = z + 1 WHERE geoid = 1 AND vrtxid = 1")
        conn.execute("SELECT tgsis.goto_version('v')")
        conn.execute("UPDATE tgsis.vrtx SET z = z - 1 WHERE geoid = 1 AND vrtxid = 1")
    capsys.readouterr()
    hint = hint_of(dsn, capsys, "version", "merge", "v")
    assert "tgsis version resolve v CLASS KEY parent|child|manual" in hint
    assert "tgsis version conflicts v" in hint_of(dsn, capsys, "version", "resolve", "v", "feature", "2", "child")
    assert "--force" in hint_of(dsn, capsys, "versioning", "disable", "features")
    assert main(["--dsn", dsn, "version", "save", "s"]) == 0
    assert main(["--dsn", dsn, "--in", "v", "version", "save", "t"]) == 0
    capsys.readouterr()
    hint = hint_of(dsn, capsys, "--in", "v@2", "import", str(FLAGGED), "--class", "faults")
    assert "tgsis version goto v" in hint or "--in v" in hint
    assert main(["--dsn", dsn, "version", "lock", "v", "feature", "2"]) == 0
    capsys.readouterr()
    assert "tgsis version unlock" in hint_of(dsn, capsys, "version", "lock", "DEFAULT", "feature", "2")


def test_the_python_and_sql_hints_map_to_cli_terms() -> None:
    """The hints the library gives in its own terms, as the command line prints them."""
    assert to_cli("pass format= with one of ts, vtu") == "give --format with one of ts, vtu"
    assert (
        to_cli("delete them first, or drop with force => true to delete them with their geometries")
        == "delete them first, or repeat with --force to delete them with their geometries"
    )
    assert foreign_terms("pass drop_extra_properties=True") == ["drop_extra_properties="]
    assert foreign_terms("SELECT tgsis.resolve_conflict('v', class, key, 'parent')") != []
    assert foreign_terms("tgsis version resolve v feature 3 child; tgsis checkin --on-conflict child") == []
    assert foreign_terms("a DBA may run: in psql: GRANT tgsis_admin TO ana") == []
    assert foreign_terms("e.g. --fill-property porosity=0.2") == []  # a flag's NAME=VALUE is the command's syntax
    assert foreign_terms("pass porosity=0.2") == ["porosity="]


# --------------------------------------------------------------------------- every hint written


def _sample(text: str) -> str:
    """A hint template with sample values for its placeholders (format's %s/%L/%I, f-string fields)."""
    text = re.sub(r"%[sIL]", lambda m: "'v'" if m[0] == "%L" else "v", text)
    return re.sub(r"\{[^{}]*\}", lambda m: "--v" if "flag" in m[0] else "v", text)  # {flag}: a --flag


def _written_hints() -> list[tuple[str, str]]:
    found = []
    sources = [
        line.strip()
        for line in (ROOT / "sql" / "sources.txt").read_text().splitlines()
        if line.strip() and not line.startswith("#")
    ]  # the sources, not a built script beside them
    for path in (ROOT / "sql" / name for name in sources):
        text = path.read_text()
        for m in re.finditer(r"HINT\s*=\s*(?:format\(\s*)?'((?:[^']|'')*)'((?:\s*'(?:[^']|'')*')*)", text):
            literal = (m[1] + "".join(re.findall(r"'((?:[^']|'')*)'", m[2]))).replace("''", "'")
            found.append((f"{path.relative_to(ROOT)}", _sample(literal)))
    for path in sorted((ROOT / "src" / "tgsis").rglob("*.py")):
        if path.name == "_hints.py":  # (the rest of the CLI's own hints are checked too: they pass through the mapping)
            continue
        text = path.read_text()
        for m in re.finditer(r"hint=((?:f?\"(?:[^\"\\]|\\.)*\"\s*)+)", text):
            parts = re.findall(r"f?\"((?:[^\"\\]|\\.)*)\"", m[1])
            found.append((f"{path.relative_to(ROOT)}", _sample("".join(parts))))
    return found


#: Hints of code the command line never reaches (Python-only or SQL-only entry points), with why.
NOT_FROM_THE_CLI = {
    "src/tgsis/gmaps": "tgsis.gmaps's constructors and builders of Python arrays (the commands read files)",
    "sql/postgis": "PostGIS functions are SQL only: no command calls them",
    "sql/modelsets": "models as sets of objects are SQL and Python only: no command",
    "src/tgsis/postgis.py": "WKB of Python objects: no command",
    "src/tgsis/datamodels.py": "the registration of data models, a Python API for who adds a model: no command calls it",
    "src/tgsis/db/postgis.py": "PostGIS from Python: no command",
    "src/tgsis/convert.py": "pyvista, meshio and trimesh objects of Python programs (the commands read files)",
    "src/tgsis/interpolation": "set-up mistakes say the set-up file's terms; surfaces= is the Python entry point",
    "src/tgsis/pictures.py": "colour= of tgsis.pictures, not reachable with wrong values from the command",
    "src/tgsis/temporal.py": "numpy-side checks; the command checks --from/--to/--steps first, with its flags",
    "src/tgsis/mesh.py": "Python constructors",
    "src/tgsis/formats/pvd.py": "write_pvd of Python objects",
    "src/tgsis/db/adapters.py": "psycopg adapters for Python programs (tgsis.register_types): no command",
    "sql/model4/gmap_conditions.sql": "an SQL building block of gmap_check and md_check, which the command calls with valid arguments",
    "sql/storage/partition_model_storage.sql": "a DBA's set-up step, SQL and Python only (docs/scaling.md): no command",
    "sql/chunks/partition_chunk_storage.sql": "the chunk part of partition_model_storage, a DBA's set-up step: no command",
    "sql/chunks/store_in_rows.sql": "the way back from chunks of a model table, a DBA's SQL step (docs/storage.md): "
    "no command",
    "sql/core/no_model_rule.sql": "a data model the registry lacks: only SQL and Python callers can name one "
    "(the commands work on stored features, whose models are registered)",
    "sql/geometry/class_denied_geoids.sql": "the privilege argument of an internal check tgsis's own code calls",
    "sql/geometry/check_class_write.sql": "the privilege argument of an internal check tgsis's own code calls",
    "sql/versioning/conflict_discards.sql": "a key without its class: the command always gives both",
    "sql/model5/md_vertices_in_box.sql": "box queries of multiply indexed G-maps are SQL and Python only: no command",
    "sql/versioning/mesh_merge_regions.sql": "SQL region detection of psql users: the command finds the regions in "
    "Python, and SQL calls it only after the same checks (tgsis.store_mesh_regions)",
    "sql/versioning/mesh_merge_work.sql": "the work tables of SQL region detection and of the psql merge by region: "
    "the command finds and merges the regions in Python",
    "sql/versioning/merge_mesh_by_region.sql": "the psql merge by region: the command merges by region in Python "
    "(tgsis.region_detection = 'client'), which never reaches it",
    "sql/versioning/merge_region_plan.sql": "the plan of the psql merges by region: the command merges by region in "
    "Python (tgsis.region_detection = 'client'), which never reaches it",
    "sql/versioning/instants_merge_regions.sql": "SQL region detection of surfaces at instants for psql users: the "
    "command finds the regions in Python, and SQL calls it only through tgsis.store_mesh_regions",
    "sql/versioning/merge_instant_by_region.sql": "the psql merge of an instant both sides changed: the command merges "
    "in Python (tgsis.region_detection = 'client'), which never reaches it",
    "sql/versioning/merge_instants_by_slice.sql": "the psql merge of surfaces at instants: the command merges them "
    "in Python (tgsis.region_detection = 'client'), which never reaches it",
    "sql/versioning/merge_sliced_hint.sql": "the psql merges of temporal surfaces: the command merges them in Python "
    "(tgsis.region_detection = 'client'), which never reaches it",
    "sql/versioning/merge_sliced_sets.sql": "the start of the psql merges of temporal surfaces: the command merges "
    "them in Python (tgsis.region_detection = 'client'), which never reaches it",
    "sql/temporal/merge_periods_by_slice.sql": "the psql merge of evolving surfaces: the command merges them "
    "in Python (tgsis.region_detection = 'client'), which never reaches it",
    "sql/versioning/merge_solution_rows.sql": "the psql merge's average/manual rows: the command merges in Python "
    "(tgsis.region_detection = 'client'), which never reaches it",
    "sql/versioning/resolve_all_regions.sql": "the psql face of --region all: the command calls the Python "
    "resolve_all_regions",
}


def test_every_written_hint_is_in_cli_terms_after_the_mapping() -> None:
    hints = _written_hints()
    assert len(hints) > 150  # the scan finds them
    left = [
        (where, hint, to_cli(hint))
        for where, hint in hints
        if not any(where.startswith(skip) for skip in NOT_FROM_THE_CLI) and foreign_terms(to_cli(hint))
    ]
    assert not left, "\n".join(f"{where}: {hint!r} -> {cli!r}" for where, hint, cli in left)

"""`tgsis version ...` and `tgsis versioning ...`: versions from the command line, remembered per database."""

from __future__ import annotations

from pathlib import Path

import psycopg
import pytest

from tests.shared_data import cfm
from tests.storage_data import storage_of
from tgsis.cli import main

RELEASE_5 = "cfm5.3/GRFS-GRFZ-WEST-Garlock_fault-CFM5_1000m.ts"
RELEASE_6 = "cfm6.1/GRFS-GRFZ-WEST-Garlock_fault-CFM5_1000m.ts"


@pytest.fixture(autouse=True)
def private_state(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("TGSIS_HOME", str(tmp_path))
    monkeypatch.delenv("TGSIS_VERSION", raising=False)
    return tmp_path / "cli-state.json"


def _run(dsn: str, capsys: pytest.CaptureFixture[str], *argv: str, code: int = 0) -> str:
    assert main(["--dsn", dsn, *argv]) == code, capsys.readouterr()
    captured = capsys.readouterr()
    return captured.out if code == 0 else captured.err


def test_a_fault_reinterpreted_in_a_version(
    db_dsn: str, capsys: pytest.CaptureFixture[str], private_state: Path
) -> None:
    _run(db_dsn, capsys, "class", "create", "faults", "--geotype", "SURFACE", "--feature-property", "release:text")
    assert "newly versioned" in _run(db_dsn, capsys, "versioning", "enable", "features")
    out = _run(
        db_dsn,
        capsys,
        "import",
        str(cfm(RELEASE_5)),
        "--class",
        "faults",
        "--set",
        "release=5.3",
        "--drop-extra-properties",
    )
    fid = out.splitlines()[1].split("\t")[0]
    assert (
        _run(db_dsn, capsys, "version", "create", "cfm6")
        == "created version cfm6 (parent DEFAULT), working revision 2\n"
    )
    assert "now work in version cfm6 (working revision 2)" in _run(db_dsn, capsys, "version", "goto", "cfm6")
    assert private_state.is_file()
    # the new release goes into the version; DEFAULT still has the old one only
    _run(
        db_dsn,
        capsys,
        "import",
        str(cfm(RELEASE_6)),
        "--class",
        "faults",
        "--set",
        "release=6.1",
        "--drop-extra-properties",
    )
    assert _run(db_dsn, capsys, "version", "current") == "cfm6\tworking revision 2\t(from tgsis version goto)\n"
    assert len(_run(db_dsn, capsys, "ls").splitlines()) == 1 + 2  # the header line and two features
    assert len(_run(db_dsn, capsys, "--in", "DEFAULT", "ls").splitlines()) == 1 + 1
    saved = _run(db_dsn, capsys, "version", "save", "imported")
    assert saved == "saved revision 2 of cfm6 as imported; new working revision 3\n"
    tree = _run(db_dsn, capsys, "version", "tree")
    assert tree == "DEFAULT: revisions 0, 1; working 1\n    cfm6 from DEFAULT@0: revisions 2 (imported), 3; working 3\n"
    listing = _run(db_dsn, capsys, "version", "list")
    assert listing.startswith(
        "current\tversion\tparent\tinitrevision\tworking\towner\tcreated\tdescription\n\tDEFAULT\t-\t-\t1\t"
    )
    assert "\n*\tcfm6\tDEFAULT\t0\t3\t" in listing
    # looking at a revision is read-only
    assert "look at revision 0 of version cfm6" in _run(db_dsn, capsys, "version", "goto", "cfm6@0")
    assert len(_run(db_dsn, capsys, "ls").splitlines()) == 1 + 1
    err = _run(db_dsn, capsys, "import", str(cfm(RELEASE_6)), "--class", "faults", "--drop-extra-properties", code=1)
    assert "viewed at revision 0, which cannot be changed" in err
    # back to DEFAULT; deleting the version removes its rows
    _run(db_dsn, capsys, "version", "goto", "DEFAULT")
    assert "deleted version cfm6" in _run(db_dsn, capsys, "version", "delete", "cfm6")
    with psycopg.connect(db_dsn) as conn:
        assert conn.execute("SELECT release FROM faults").fetchall() == [("5.3",)]
        vertices = storage_of(conn, "vrtx")  # rows or chunk versions
        assert conn.execute(f"SELECT count(DISTINCT geoid) FROM {vertices}").fetchone() == (1,)
    assert _run(db_dsn, capsys, "ls", "--no-header").startswith(f"{fid}\tfaults\t")


def test_errors(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert "version 'nope' does not exist" in _run(db_dsn, capsys, "version", "goto", "nope", code=1)
    assert "version 'nope' does not exist" in _run(db_dsn, capsys, "--in", "nope", "ls", code=1)
    assert "is not VERSION or VERSION@REVISION" in _run(db_dsn, capsys, "--in", "a@b", "ls", code=1)
    assert "version name 'bad\tname' is not allowed" not in _run(
        db_dsn, capsys, "version", "create", "bad\tname", code=1
    )
    assert "version name 'bad<U+0009>name' is not allowed" in _run(
        db_dsn, capsys, "version", "create", "bad\tname", code=1
    )
    assert "version name 'a@1' is not allowed: it holds @" in _run(db_dsn, capsys, "version", "create", "a@1", code=1)
    assert "needs --key and --class" in _run(db_dsn, capsys, "versioning", "enable", "wells", code=1)
    _run(db_dsn, capsys, "version", "create", "a")
    _run(db_dsn, capsys, "version", "create", "b", "--parent", "a")
    assert "version 'a' has child versions: 'b'" in _run(db_dsn, capsys, "version", "delete", "a", code=1)


def test_versioning_names_the_storage_table_as_sql_does(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    # issue 38, part 6: the message appended "_ver" to the bare table name in Python, so that a table of another
    # schema, or one whose name needs quotes, was told a storage name no SQL statement finds
    with psycopg.connect(db_dsn) as conn:
        conn.execute('CREATE SCHEMA "field data"')
        conn.execute('CREATE TABLE "field data"."My Wells" (id int PRIMARY KEY)')
    said = _run(db_dsn, capsys, "versioning", "enable", '"field data"."My Wells"', "--key", "id", "--class", "well")
    assert 'storage "field data"."My Wells_ver")' in said
    with psycopg.connect(db_dsn) as conn:
        storage = said.split("storage ", 1)[1].split(")")[0]
        assert conn.execute(f"SELECT count(*) FROM {storage}").fetchone() == (0,)  # the name SQL finds


def test_versioning_a_table_from_the_command_line(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    with psycopg.connect(db_dsn) as conn:
        conn.execute("CREATE TABLE wells (id int PRIMARY KEY, name text)")
        conn.execute("INSERT INTO wells VALUES (1, 'w1')")
    assert "public.wells is versioned (object class well, key id, storage public.wells_ver)" in _run(
        db_dsn, capsys, "versioning", "enable", "wells", "--key", "id", "--class", "well"
    )
    assert (
        _run(db_dsn, capsys, "versioning", "list")
        == "table\tclass\tkey\torder\tshortname\trow key\npublic.wells\twell\tid\t0\twells\tid\n"
    )
    assert "DEFAULT's rows kept, 0 row version(s) removed" in _run(db_dsn, capsys, "versioning", "disable", "wells")
    with psycopg.connect(db_dsn) as conn:
        assert conn.execute("SELECT relkind FROM pg_class WHERE relname = 'wells'").fetchone() == ("r",)


def _versioned_wells_and_version_a(dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    with psycopg.connect(dsn) as conn:
        conn.execute("CREATE TABLE wells (id int PRIMARY KEY, depth float8)")
        conn.execute("INSERT INTO wells VALUES (1, 10), (2, 20)")
    _run(dsn, capsys, "versioning", "enable", "wells", "--key", "id", "--class", "well")
    _run(dsn, capsys, "version", "create", "a")


def test_conflicts_and_resolve(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    _versioned_wells_and_version_a(db_dsn, capsys)
    with psycopg.connect(db_dsn) as conn:
        conn.execute("UPDATE wells SET depth = 11 WHERE id = 1")
        conn.execute("SELECT tgsis.goto_version('a')")
        conn.execute("UPDATE wells SET depth = 12 WHERE id = 1")
        conn.execute("UPDATE wells SET depth = 22 WHERE id = 2")
    out = _run(db_dsn, capsys, "version", "conflicts", "a", "--rows")
    assert out.splitlines() == [
        "class\tkey\tsolution\tboth changed\tchanged in a\tchanged in parent"
        "\tchild discards (the parent's edits)\tparent discards (the version's edits)",
        "\ttable\tside\trow key (JSON)\trow (JSON)",
        "well\t1\tunsolved\twells\twells\twells\twells: 1 changed (1 value)\twells: 1 changed (1 value)",
        '\twells\tchild\t{"id": 1}\t{"id": 1, "depth": 12}',
        '\twells\tparent\t{"id": 1}\t{"id": 1, "depth": 11}',
    ]
    # child throws the parent's depth away: asked for by name
    err = _run(db_dsn, capsys, "version", "resolve", "a", "well", "1", "child", code=1)
    assert "would discard the parent's edits: wells: 1 changed (1 value)" in err and "--discard-other" in err
    assert (
        _run(db_dsn, capsys, "version", "resolve", "a", "well", "1", "child", "--discard-other")
        == "well 1 in a: child\n  discarded the parent's edits: wells: 1 changed (1 value)\n"
    )
    assert "not in conflict" in _run(db_dsn, capsys, "version", "resolve", "a", "well", "2", "child", code=1)


def test_merge_refresh_and_diff(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    _versioned_wells_and_version_a(db_dsn, capsys)
    with psycopg.connect(db_dsn) as conn:
        conn.execute("SELECT tgsis.goto_version('a')")
        conn.execute("UPDATE wells SET depth = 12 WHERE id = 1")
        conn.execute("INSERT INTO wells VALUES (3, 30)")
    assert _run(db_dsn, capsys, "version", "diff", "DEFAULT", "a") == (
        "class\tkey\tdifference\ttables\tadded\tremoved\tchanged\n"
        "well\t1\tchanged\twells\t+0\t-0\t~1\nwell\t3\tonly in a\twells\t+1\t-0\t~0\n"
    )
    assert _run(db_dsn, capsys, "version", "diff", "DEFAULT", "a", "--tables") == (
        "class\tkey\ttable\tadded\tremoved\tchanged\nwell\t1\twells\t+0\t-0\t~1\nwell\t3\twells\t+1\t-0\t~0\n"
    )
    assert _run(db_dsn, capsys, "version", "merge", "a") == "merged a into its parent: 3 row(s) written\n"
    assert _run(db_dsn, capsys, "version", "diff", "DEFAULT", "a") == ""  # "hold the same rows" goes to stderr
    assert _run(db_dsn, capsys, "version", "diff", "DEFAULT@0", "DEFAULT").count("\n") == 1 + 2
    assert "refreshed a from its parent: 0 row(s) written" in _run(db_dsn, capsys, "version", "refresh", "a")
    assert "version removed" in _run(db_dsn, capsys, "version", "merge", "a", "--remove")


def test_locks_from_the_command_line(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    _versioned_wells_and_version_a(db_dsn, capsys)
    _run(db_dsn, capsys, "version", "create", "b")
    assert (
        _run(db_dsn, capsys, "version", "lock", "a", "well", "1", "2") == "a holds 2 well object(s) (2 newly locked)\n"
    )
    with psycopg.connect(db_dsn) as conn:
        me = conn.execute("SELECT current_user").fetchone()[0]  # type: ignore[index]
    assert [line.split("\t")[:5] for line in _run(db_dsn, capsys, "version", "locks").splitlines()] == [
        ["class", "key", "version", "role", "kind"],
        ["well", "1", "a", me, "version"],
        ["well", "2", "a", me, "version"],
    ]
    assert _run(db_dsn, capsys, "version", "locks", "b") == ""
    err = _run(db_dsn, capsys, "--in", "b", "version", "lock", "b", "well", "2", code=1)
    assert "locked by version 'a'" in err
    assert "has no object 9" in _run(db_dsn, capsys, "version", "lock", "b", "well", "9", code=1)
    assert _run(db_dsn, capsys, "version", "unlock", "a", "well", "1") == "released 1 lock(s) of a\n"
    assert [line.split("\t")[:3] for line in _run(db_dsn, capsys, "version", "locks", "--no-header").splitlines()] == [
        ["well", "2", "a"]
    ]
    assert _run(db_dsn, capsys, "version", "unlock", "a") == "released 1 lock(s) of a\n"
    assert _run(db_dsn, capsys, "version", "locks") == ""


def test_rights_from_the_command_line(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    _run(db_dsn, capsys, "version", "create", "a")
    assert (
        _run(db_dsn, capsys, "version", "grant", "a", "write", "tgsis_editor") == "granted write on a to tgsis_editor\n"
    )
    assert _run(db_dsn, capsys, "version", "grant", "a", "merge", "public") == "granted merge on a to public\n"
    listing = _run(db_dsn, capsys, "version", "privileges", "a", "--no-header").splitlines()
    assert [line.split("\t")[1:3] for line in listing[1:]] == [["public", "merge"], ["tgsis_editor", "write"]]
    assert listing[0].endswith("\towner (every right)")
    assert len(listing[1].split("\t")) == 4  # and who granted it
    _run(db_dsn, capsys, "version", "revoke", "a", "all", "public")
    assert len(_run(db_dsn, capsys, "version", "privileges", "a").splitlines()) == 1 + 2
    assert _run(db_dsn, capsys, "version", "owner", "a", "tgsis_admin") == "version a is owned by tgsis_admin\n"
    assert _run(db_dsn, capsys, "version", "privileges", "a").startswith(
        "version\trole\tright\tgranted by\na\ttgsis_admin\towner"
    )
    assert "role 'nobody' does not exist" in _run(db_dsn, capsys, "version", "grant", "a", "write", "nobody", code=1)
    assert "version 'zz' does not exist" in _run(db_dsn, capsys, "version", "privileges", "zz", code=1)
    # DEFAULT's grants come with the installation
    assert [
        line.split("\t")[1:3] for line in _run(db_dsn, capsys, "version", "privileges", "DEFAULT").splitlines()[2:]
    ] == [["tgsis_editor", "write"], ["tgsis_editor", "create"]]


def test_names_with_blanks_and_quotes_are_shown_quoted(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    """Free-text names (the design's, docs/versioning.md's 'first pick') print as one name: quoted unless plain."""
    assert (
        _run(db_dsn, capsys, "version", "create", "survey 2024")
        == "created version 'survey 2024' (parent DEFAULT), working revision 2\n"
    )
    assert "now work in version 'survey 2024' (working revision 2)" in _run(
        db_dsn, capsys, "version", "goto", "survey 2024"
    )
    assert (
        _run(db_dsn, capsys, "version", "save", "first pick")
        == "saved revision 2 of 'survey 2024' as 'first pick'; new working revision 3\n"
    )
    assert (
        _run(db_dsn, capsys, "version", "save", "Bob's pick")
        == "saved revision 3 of 'survey 2024' as 'Bob''s pick'; new working revision 4\n"
    )
    assert "'survey 2024' from DEFAULT@0: revisions 2 ('first pick'), 3 ('Bob''s pick'), 4; working 4" in _run(
        db_dsn, capsys, "version", "tree"
    )
    assert "look at revision 2 of version 'survey 2024'" in _run(db_dsn, capsys, "version", "goto", "survey 2024@2")
    _run(db_dsn, capsys, "version", "goto", "DEFAULT")
    assert "deleted version 'survey 2024'" in _run(db_dsn, capsys, "version", "delete", "survey 2024")

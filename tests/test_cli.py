"""The `tgsis` command: versions, install, status, errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import psycopg
import pytest

import tgsis
from tests.local_helpers import private_home, tgsis_cli
from tests.shared_data import cfm
from tgsis.cli import main
from tgsis.db.local import LocalServer, find_binaries


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"tgsis {tgsis.__version__}"


def test_db_install_then_again_is_a_no_op(make_database: object, capsys: pytest.CaptureFixture[str]) -> None:
    dsn = make_database()  # type: ignore[operator]
    assert main(["--dsn", dsn, "db", "install", "--method", "sql"]) == 0
    # (the roles are created by the first install on the cluster: whichever test that is)
    assert [line for line in capsys.readouterr().out.splitlines() if not line.startswith("  created the roles ")] == [
        f"installed tgsis {tgsis.__version__} (sql)",
        "  created the extension(s) tgsis needs: cube",
        f"  ran the install script of tgsis {tgsis.__version__} (plain SQL: schema tgsis with its storage tables)",
        "  stored in chunks: vrtx, point, segment, tetra, trgl, times_trgl, times_vrtx (docs/storage.md)",  # models 1, 2
    ]
    assert main(["--dsn", dsn, "db", "install"]) == 0
    assert "already installed (sql): nothing to do" in capsys.readouterr().out
    with psycopg.connect(dsn) as conn:
        assert conn.execute("SELECT tgsis.version()").fetchone() == (tgsis.__version__,)


def test_db_status_reports_versions(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--dsn", db_dsn, "db", "status"]) == 0
    out = capsys.readouterr().out
    assert f"tgsis:    {tgsis.__version__}" in out
    assert "(from argument)" in out and "PostgreSQL" in out


def test_uninstall_needs_yes(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--dsn", db_dsn, "db", "uninstall"]) == 1
    assert "repeat with --yes" in capsys.readouterr().err
    with psycopg.connect(db_dsn) as conn:
        assert tgsis.installed_version(conn) is not None
    assert main(["--dsn", db_dsn, "db", "uninstall", "--yes"]) == 0
    with psycopg.connect(db_dsn) as conn:
        assert tgsis.installed_version(conn) is None


def test_errors_are_one_clear_line_and_exit_1(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["--dsn", "host=/nonexistent-dir port=1 dbname=x connect_timeout=2", "db", "status"])
    assert code == 1
    err = capsys.readouterr().err
    assert err.startswith("tgsis: error: ") and "nonexistent-dir" in err
    assert "Traceback" not in err


def test_dsn_from_environment(db_dsn: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setenv("TGSIS_DSN", db_dsn)
    assert main(["db", "status"]) == 0
    assert "(from TGSIS_DSN)" in capsys.readouterr().out


@pytest.mark.own_server  # a server of TGSIS_PG's binaries, not the fixture pg's
def test_local_status_and_dsn_without_a_server() -> None:
    with private_home() as home:
        status = tgsis_cli("local", "status", home=home)
        assert status.returncode == 3
        assert "not created yet" in status.stdout
        dsn = tgsis_cli("local", "dsn", home=home)
        assert dsn.returncode == 0 and "dbname=tgsis" in dsn.stdout
        assert "not running" in dsn.stderr


@pytest.mark.own_server  # a server of TGSIS_PG's binaries, not the fixture pg's
def test_demo_runs_the_release_story(tmp_path: Path) -> None:
    from tgsis.formats.pvd import read_pvd

    with private_home() as home:
        result = tgsis_cli("demo", "--dir", str(tmp_path / "demo"), home=home)
        assert result.returncode == 0, result.stderr
        # the command stopped the local server it started (its cluster stays)
        server = LocalServer.persistent(find_binaries(), home=home)
        assert server.is_initialized() and not server.is_running()
        lines = result.stdout.splitlines()
        assert lines[0].startswith("PostgreSQL ") and "database 'tgsis_demo' (local server)" in lines[0]
        assert lines[1] in (
            f"tgsis {tgsis.__version__} (installed as extension)",
            f"tgsis {tgsis.__version__} (installed as sql)",
        )
        assert lines[2] == "roles: tgsis_reader, tgsis_editor, tgsis_admin"
        assert lines[3].startswith("data: SCEC Community Fault Model, releases 5.3 and 6.1")
        assert lines[4].startswith("1. stored 3 faults of release 5.3 in DEFAULT")
        assert lines[5].endswith(
            ": CRFA-OCNZ-MULT-Oceanic_fault-CFM5_1000m, CRFA-SLRS-MULT-San_Luis_Range_fault_system-CFM4_1000m"
        )
        assert lines[6].startswith("3. version cfm6.1: release 6.1 checked in over 3 fault(s) by difference")
        # the re-exported Garlock fault: every vertex kept within 1 cm, a handful of rows instead of 6754
        garlock = next(line for line in lines[7:10] if "Garlock" in line)
        assert "1746 of 1746 vertices kept, 0 moved" in garlock and "(a full upload: 6754)" in garlock
        assert int(garlock.split("; ")[1].split()[0]) <= 12
        assert (
            "Oceanic_fault-CFM5_1000m: DEFAULT sees release 5.3 (716 vertices); "
            "cfm6.1 sees release 6.1 (722 vertices)" in result.stdout
        )
        # each check-out froze the working revision it read (a base for a conflicting check-in's child)
        assert "    cfm6.1 from DEFAULT@0: revisions 2, 3, 4, 5 (release-6.1), 6; working 6" in result.stdout
        history = lines.index(
            "5. fault history (model 3): CRFA-OCNZ-MULT-Oceanic_fault-CFM5_1000m slipping 500 m "
            "at depth from -2.0 Ma to today, stored as feature 4 of class fault_history (EVOLVING)"
        )
        assert lines[history + 1 : history + 3] == [
            "   at -1.0 Ma (SQL snapshot): 716 vertices, the deepest 250 m from where it is today",
            f"   21 frames from -2.0 to 0.0 Ma written to {tmp_path / 'demo' / 'fault_history.pvd'} (open it in ParaView)",
        ]
        lost = lines.index("6. no lost update: ann and bob check out feature 3 in DEFAULT and both edit it")
        assert lines[lost + 1].startswith(
            "   ann checks in first; bob's check-in is refused: feature 3 was changed in "
            "version 'DEFAULT' since it was checked out"
        )
        assert lines[lost + 2].startswith("   with on_conflict='child' bob's edit goes into new version bob_edit")
        # the picture of release 6.1 over 5.3, coloured by how far 6.1 lies from 5.3, as the other scenarios draw
        png = tmp_path / "demo" / "cfm_release_6.1_over_5.3.png"
        drawn = next(line for line in lines if "release 6.1 over 5.3, coloured by its distance from 5.3" in line)
        assert drawn.endswith(f"m), drawn to {png}") and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert png.stat().st_size > 20_000
        frames = read_pvd(tmp_path / "demo" / "fault_history.pvd")
        assert [t for t, _ in frames] == np.linspace(-2.0, 0.0, 21).tolist()
        assert all(isinstance(g, tgsis.Surface) and g.n_vertices == 716 for _, g in frames)
        again = tgsis_cli("demo", "--dir", str(tmp_path / "demo"), home=home)  # a database of its own, made afresh
        assert again.returncode == 0, again.stderr
        assert again.stdout.splitlines()[4:] == lines[4:]
        assert not server.is_running()


@pytest.mark.own_server  # a server of TGSIS_PG's binaries, not the fixture pg's
def test_demo_without_the_shared_data_uses_synthetic_faults(tmp_path: Path) -> None:
    with private_home() as home:
        result = tgsis_cli("demo", "--dir", str(tmp_path / "out"), home=home, TGSIS_DEMO_DATA=str(tmp_path / "none"))
        assert result.returncode == 0, result.stderr
        assert "data: synthetic faults (no CFM data found)" in result.stdout
        assert "3. version cfm6.1: release 6.1 checked in over 3 fault(s) by difference" in result.stdout
        assert (
            "   north_fault: 360 of 360 vertices kept, 0 moved; 1 rows written" in result.stdout
        )  # the release property
        assert "6. no lost update:" in result.stdout
        assert (
            "middle_fault: DEFAULT sees release 5.3 (360 vertices); cfm6.1 sees release 6.1 (360 vertices)"
            in result.stdout
        )
        assert "5. fault history (model 3): north_fault slipping 500 m at depth" in result.stdout
        assert "   at -1.0 Ma (SQL snapshot): 360 vertices, the deepest 250 m from where it is today" in result.stdout
        assert (tmp_path / "out" / "fault_history.pvd").is_file()
        assert (tmp_path / "out" / "cfm_release_6.1_over_5.3.png").read_bytes()[:4] == b"\x89PNG"


# --------------------------------------------------------------------------- classes and features


def test_class_create_list_drop(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert (
        main(
            [
                "--dsn",
                db_dsn,
                "class",
                "create",
                "faults",
                "--geotype",
                "surface",
                "--feature-property",
                "release:text",
                "--property",
                "azi:float8",
                "--property",
                "dip:float8",
                "--srs",
                "26911",
            ]
        )
        == 0
    )
    assert "created feature class faults (SURFACE)" in capsys.readouterr().out
    assert main(["--dsn", db_dsn, "class", "list"]) == 0
    out = capsys.readouterr().out
    assert out.startswith(
        "class\tgeotype\tsrs\tschema\ttime\tfeature properties\tproperties\tper-instant properties\n"
        "faults\tSURFACE\t26911\tpublic\tstatic\trelease text\tvertex: azi double precision"
    )
    assert main(["--dsn", db_dsn, "class", "create", "Bad", "--geotype", "SURFACE"]) == 1
    assert "feature class name 'Bad' is not allowed" in capsys.readouterr().err
    assert main(["--dsn", db_dsn, "class", "create", "x", "--geotype", "SURFACE", "--property", "porosity"]) == 1
    assert "must be NAME:TYPE" in capsys.readouterr().err
    assert main(["--dsn", db_dsn, "class", "drop", "faults"]) == 0
    assert main(["--dsn", db_dsn, "class", "drop", "faults"]) == 1
    assert "does not exist" in capsys.readouterr().err


def test_import_ls_export_a_real_gocad_fault(db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from tgsis import formats

    source = cfm("formats/CRFA-SJMZ-CHMN-Big_Spring_fault-50dip-CFM5.ts")
    assert (
        main(
            [
                "--dsn",
                db_dsn,
                "class",
                "create",
                "faults",
                "--geotype",
                "SURFACE",
                "--feature-property",
                "release:text",
                "--property",
                "azi:float8",
                "--property",
                "dip:float8",
            ]
        )
        == 0
    )
    capsys.readouterr()
    assert main(["--dsn", db_dsn, "import", str(source), "--class", "faults", "--set", "release=CFM5"]) == 0
    fid, name, *_ = capsys.readouterr().out.splitlines()[1].split("\t")
    assert name == "CRFA-SJMZ-CHMN-Big_Spring_fault-50dip-CFM5"
    assert main(["--dsn", db_dsn, "ls"]) == 0
    assert capsys.readouterr().out.splitlines()[1].startswith(f"{fid}\tfaults\t{name}\tSURFACE\t")
    out = tmp_path / "back.ts"
    assert main(["--dsn", db_dsn, "export", fid, str(out)]) == 0
    original, back = formats.read_one(source), formats.read_one(out)
    assert back.vertices.tobytes() == original.vertices.tobytes()
    assert np.array_equal(back.cells, original.cells)
    assert np.array_equal(back.vertex_properties["azi"], original.vertex_properties["azi"], equal_nan=True)
    with psycopg.connect(db_dsn) as conn:
        assert conn.execute("SELECT release FROM faults").fetchone() == ("CFM5",)


def test_import_of_properties_the_class_lacks_needs_a_flag(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    source = cfm("formats/CRFA-SJMZ-CHMN-Big_Spring_fault-50dip-CFM5.ts")
    assert main(["--dsn", db_dsn, "class", "create", "plain", "--geotype", "SURFACE"]) == 0
    assert main(["--dsn", db_dsn, "import", str(source), "--class", "plain"]) == 1
    assert "has no column for properties ['azi', 'dip']" in capsys.readouterr().err
    assert main(["--dsn", db_dsn, "import", str(source), "--class", "plain", "--drop-extra-properties"]) == 0
    with psycopg.connect(db_dsn) as conn:
        assert conn.execute("SELECT count(*) FROM plain").fetchone() == (1,)


FLAGGED = Path(__file__).parent / "data" / "gocad" / "flagged.ts"  # F1: a duplicate vertex, a zero-area triangle


def _stored(dsn: str) -> tuple[int, ...]:
    with psycopg.connect(dsn) as conn:
        row = conn.execute(
            "SELECT (SELECT count(*) FROM tgsis.geometry), (SELECT count(*) FROM tgsis.vrtx), "
            "(SELECT count(*) FROM tgsis.trgl), (SELECT count(*) FROM faults), "
            "(SELECT count(*) FROM blocks)"
        ).fetchone()
    assert row is not None
    return tuple(row)


def test_reject_flagged_refuses_the_whole_file(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--dsn", db_dsn, "class", "create", "faults", "--geotype", "SURFACE"]) == 0
    assert main(["--dsn", db_dsn, "class", "create", "blocks", "--geotype", "GEOMETRYCOLLECTION"]) == 0
    capsys.readouterr()
    empty = _stored(db_dsn)
    for target in ("faults", "blocks"):
        assert main(["--dsn", db_dsn, "import", str(FLAGGED), "--class", target, "--reject-flagged"]) == 1
        err = capsys.readouterr().err
        assert err.startswith(
            f"tgsis: error: {FLAGGED}: refused, nothing imported: "
            "object 'F1': 1 duplicate vertices, 1 degenerate cells\n"
        )
        assert "F2" not in err and "HINT: fix the file, raise --tolerance" in err
        assert _stored(db_dsn) == empty

    # a thin triangle of F2 (area 5e-5) is flagged too once the tolerance says so
    assert (
        main(["--dsn", db_dsn, "import", str(FLAGGED), "--class", "faults", "--reject-flagged", "--tolerance", "1e-3"])
        == 1
    )
    assert (
        "object 'F1': 1 duplicate vertices, 1 degenerate cells; object 'F2': 0 duplicate vertices, 1 degenerate cells"
    ) in capsys.readouterr().err
    assert main(["--dsn", db_dsn, "import", str(FLAGGED), "--class", "faults", "--tolerance", "-1"]) == 1
    assert "--tolerance must be a finite number >= 0, got -1.0" in capsys.readouterr().err
    assert _stored(db_dsn) == empty

    # without the flag the file goes in, with the flags reported
    assert main(["--dsn", db_dsn, "import", str(FLAGGED), "--class", "faults", "--tolerance", "1e-3"]) == 0
    lines = [line.split("\t") for line in capsys.readouterr().out.splitlines()[1:]]
    assert [(line[1], line[-1]) for line in lines] == [
        ("F1", "1 duplicate vertices, 1 degenerate cells"),
        ("F2", "0 duplicate vertices, 1 degenerate cells"),
    ]
    assert _stored(db_dsn) == (2, 10, 6, 2, 0)


def test_reject_flagged_passes_clean_files(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    source = Path(__file__).parent / "data" / "gocad" / "two_lines.pl"
    assert main(["--dsn", db_dsn, "class", "create", "traces", "--geotype", "MULTILINESTRING"]) == 0
    assert (
        main(
            ["--dsn", db_dsn, "import", str(source), "--class", "traces", "--reject-flagged", "--drop-extra-properties"]
        )
        == 0
    )
    assert capsys.readouterr().out.splitlines()[-1].endswith("no duplicate vertices, no degenerate cells")
    with psycopg.connect(db_dsn) as conn:
        assert conn.execute("SELECT count(*) FROM traces").fetchone() == (1,)

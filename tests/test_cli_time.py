"""The `tgsis at` and `tgsis series` commands against a real database: model 2 and model 3 features."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import psycopg
import pytest

import tgsis
from tests.temporal_data import evolving, series
from tgsis import formats
from tgsis.cli import main
from tgsis.formats.pvd import read_pvd
from tgsis.mesh import Surface
from tgsis.temporal import EvolvingSurface, SurfaceSeries

STARTS = [-10.0, -6.5, -2.0]  # the evolving fault exists from -10 to -1 Ma, not after
INSTANTS = [0.0, 1.0, 2.5]  # the stepped horizon, alive after 2.5


@pytest.fixture
def stored(db_dsn: str) -> tuple[dict[str, int], EvolvingSurface, SurfaceSeries]:
    """A model-3 fault, a model-3 fault alive from -4 Ma on, a model-2 horizon and a static surface, committed."""
    fault = evolving(np.random.default_rng(21), STARTS, instants_per_period=4, with_properties=True)
    late = evolving(np.random.default_rng(22), [-4.0], alive=True, with_properties=True)
    horizon = series(np.random.default_rng(23), INSTANTS, alive=True, with_properties=True)
    with psycopg.connect(db_dsn) as conn:
        faults = tgsis.create_feature_class(
            conn,
            "moving_faults",
            "SURFACE",
            time_model="EVOLVING",
            time_unit="Ma",
            cell_properties=[("porosity", "double precision")],
            instant_properties=[("throw", "double precision"), ("note_code", "integer")],
        )
        horizons = tgsis.create_feature_class(
            conn,
            "horizons",
            "SURFACE",
            time_model="INSTANTS",
            cell_properties=[("porosity", "double precision")],
            instant_properties=[("throw", "double precision")],
        )
        plain = tgsis.create_feature_class(conn, "plain", "SURFACE")
        ids = {
            "fault": tgsis.insert_feature(conn, faults, fault),
            "late": tgsis.insert_feature(conn, faults, late),
            "horizon": tgsis.insert_feature(conn, horizons, horizon),
            "static": tgsis.insert_feature(conn, plain, Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])),
        }
    return ids, fault, horizon


def check_errors(
    dsn: str, capsys: pytest.CaptureFixture[str], command: list[str], cases: list[tuple[list[str], str]]
) -> None:
    """Each ``command + argv`` exits with status 1 and a ``tgsis: error:`` message holding the expected text."""
    for argv, message in cases:
        assert main(["--dsn", dsn, *command, *argv]) == 1, argv
        err = capsys.readouterr().err
        assert err.startswith("tgsis: error: ") and message in err and "Traceback" not in err, (argv, err)


def same_surface(back: Surface, expected: Surface | None) -> None:
    assert expected is not None
    assert back.vertices.tobytes() == expected.vertices.tobytes()
    np.testing.assert_array_equal(back.triangles, expected.triangles)


# --------------------------------------------------------------------------- tgsis at


def test_at_writes_the_evolving_surface_at_t(
    db_dsn: str,
    stored: tuple[dict[str, int], EvolvingSurface, SurfaceSeries],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    ids, fault, _ = stored
    fid = ids["fault"]
    t = -7.25
    out = tmp_path / "fault.vtu"
    assert main(["--dsn", db_dsn, "at", str(fid), str(t), str(out)]) == 0
    expected = fault.at(t)
    assert expected is not None
    assert capsys.readouterr().out == (
        f"wrote feature {fid} (moving_faults) at t = -7.25 Ma: {expected.n_vertices} "
        f"vertices, {expected.n_cells} triangles, to {out}\n"
    )
    same_surface(formats.read_one(out), expected)  # type: ignore[arg-type]
    # GOCAD keeps every digit too; --format picks the format whatever the extension
    assert main(["--dsn", db_dsn, "at", str(fid), "-2", str(tmp_path / "fault.ts")]) == 0
    same_surface(formats.read_one(tmp_path / "fault.ts"), fault.at(-2.0))  # type: ignore[arg-type]
    assert main(["--dsn", db_dsn, "at", str(fid), "-1.0", str(tmp_path / "fault.data"), "--format", "ply"]) == 0
    same_surface(formats.read_one(tmp_path / "fault.data", format="ply"), fault.at(-1.0))  # type: ignore[arg-type]


def test_at_records_the_time_in_the_file(
    db_dsn: str,
    stored: tuple[dict[str, int], EvolvingSurface, SurfaceSeries],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A snapshot says when it is: its name in the file (GOCAD header, VTK field data and title) and, with {t} in
    FILE or a folder as FILE, its file name."""
    ids, fault, _ = stored
    fid = ids["fault"]
    assert main(["--dsn", db_dsn, "at", str(fid), "-7.25", str(tmp_path / "fault_{t}.ts")]) == 0
    written = tmp_path / "fault_-7.25.ts"
    assert f"to {written}" in capsys.readouterr().out
    back = formats.read_one(written)
    assert back.name is not None and back.name.endswith(" at t = -7.25 Ma")
    assert "name:" in written.read_text() and "at t = -7.25 Ma" in written.read_text()
    for ext in ("vtu", "vtp", "vtk"):
        assert main(["--dsn", db_dsn, "at", str(fid), "-2", str(tmp_path / f"f.{ext}")]) == 0
        name = formats.read_one(tmp_path / f"f.{ext}").name
        assert name is not None and name.endswith(" at t = -2.0 Ma"), (ext, name)
    folder = tmp_path / "snapshots"
    folder.mkdir()
    assert main(["--dsn", db_dsn, "at", str(fid), "-1", str(folder), "--format", "ply"]) == 0
    assert sorted(p.name for p in folder.iterdir()) == [f"feature_{fid}_t-1.0.ply"]
    same_surface(formats.read_one(folder / f"feature_{fid}_t-1.0.ply"), fault.at(-1.0))  # type: ignore[arg-type]
    capsys.readouterr()
    assert main(["--dsn", db_dsn, "at", str(fid), "-1", str(folder)]) == 1
    assert "a folder: give --format" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("t", "convention", "index"),
    [
        (0.0, "left", 0),
        (0.0, "right", 0),
        (0.5, "left", 0),
        (0.5, "right", 1),
        (1.0, "left", 1),
        (1.0, "right", 1),
        (2.0, "left", 1),
        (2.0, "right", 2),
        (2.5, "left", 2),
        (99.0, "right", 2),
    ],
)
def test_at_a_model_2_feature_follows_the_convention(
    db_dsn: str,
    stored: tuple[dict[str, int], EvolvingSurface, SurfaceSeries],
    tmp_path: Path,
    t: float,
    convention: str,
    index: int,
) -> None:
    ids, _, horizon = stored
    out = tmp_path / "horizon.vtu"
    assert main(["--dsn", db_dsn, "at", str(ids["horizon"]), str(t), str(out), "--convention", convention]) == 0
    same_surface(formats.read_one(out), horizon.surfaces[index])  # type: ignore[arg-type]


def test_at_a_time_where_the_object_does_not_exist(
    db_dsn: str,
    stored: tuple[dict[str, int], EvolvingSurface, SurfaceSeries],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    ids, _, _ = stored
    out = tmp_path / "none.ts"
    for fid, t, message, hint in [
        (ids["fault"], "-0.5", "(moving_faults) does not exist at t = -0.5 Ma", "it exists from t = -10.0 to -1.0 Ma"),
        (ids["fault"], "-11", "(moving_faults) does not exist at t = -11.0 Ma", "it exists from t = -10.0 to -1.0 Ma"),
        (ids["late"], "-5", "(moving_faults) does not exist at t = -5.0 Ma", "it exists from t = -4.0 Ma on (alive)"),
        (ids["horizon"], "-0.001", "(horizons) does not exist at t = -0.001", "it exists from t = 0.0 on (alive)"),
    ]:
        assert main(["--dsn", db_dsn, "at", str(fid), t, str(out)]) == 1
        err = capsys.readouterr().err
        assert err.startswith(f"tgsis: error: feature {fid} {message}\nHINT: {hint}"), err
        assert "Traceback" not in err
    assert not out.exists()


def test_at_a_static_surface_is_the_surface(
    db_dsn: str,
    stored: tuple[dict[str, int], EvolvingSurface, SurfaceSeries],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    ids, _, _ = stored
    with pytest.raises(SystemExit):  # argparse takes -1e9 for an option: `--` before it (see docs/cli.md)
        main(["--dsn", db_dsn, "at", str(ids["static"]), "-1e9", str(tmp_path / "s.obj")])
    capsys.readouterr()
    assert main(["--dsn", db_dsn, "at", str(ids["static"]), "--", "-1e9", str(tmp_path / "s.obj")]) == 0
    assert formats.read_one(tmp_path / "s.obj").n_vertices == 3


def test_at_bad_arguments(
    db_dsn: str,
    stored: tuple[dict[str, int], EvolvingSurface, SurfaceSeries],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    fid, out = str(stored[0]["fault"]), str(tmp_path / "x.ts")
    check_errors(
        db_dsn,
        capsys,
        ["at"],
        [
            ([fid, "nan", out], "tgsis: error: T must be a finite number, got nan\n"),
            ([fid, "inf", out], "tgsis: error: T must be a finite number, got inf\n"),
            (["987654", "0", out], "tgsis: error: no feature class has a feature 987654\n"),
            ([fid, "-5", str(tmp_path / "x.xyz")], "x.xyz: unknown file extension '.xyz'"),
            ([fid, "-5", str(tmp_path / "x.pvd")], "a .pvd is a time series\nHINT: tgsis series writes a .pvd"),
        ],
    )
    for argv in ([fid, "soon", out], [fid, "0", out, "--convention", "middle"], ["x", "0", out], [fid, "0"]):
        with pytest.raises(SystemExit) as info:
            main(["--dsn", db_dsn, "at", *argv])
        assert info.value.code == 2
        assert "usage: tgsis at" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


# --------------------------------------------------------------------------- tgsis series


def test_series_of_an_evolving_fault(
    db_dsn: str,
    stored: tuple[dict[str, int], EvolvingSurface, SurfaceSeries],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    ids, fault, _ = stored
    fid = ids["fault"]
    out = tmp_path / "new" / "folder"
    assert main(["--dsn", db_dsn, "series", str(fid), "--from", "-11", "--to", "0", "--steps", "12", str(out)]) == 0
    times = [float(t) for t in range(-11, 1)]
    pvd = out / f"feature_{fid}.pvd"
    lines = capsys.readouterr().out.splitlines()
    assert lines[-1] == (
        f"wrote {pvd}: feature {fid} (moving_faults) at 12 times from -11.0 to 0.0 Ma, 2 without the object"
    )
    assert lines[0] == "t\tfile\tvertices\ttriangles"
    assert lines[1] == f"-11.0\t{out}/feature_{fid}/feature_{fid}_000000.vtu\tno object (empty grid)\t"
    first = fault.at(-10.0)
    assert first is not None
    assert lines[2] == (f"-10.0\t{out}/feature_{fid}/feature_{fid}_000001.vtu\t{first.n_vertices}\t{first.n_cells}")
    back = read_pvd(pvd)
    assert [t for t, _ in back] == times
    for t, geometry in back:
        expected = fault.at(t)
        if expected is None:
            assert geometry is None and t in (-11.0, 0.0)
        else:
            assert isinstance(geometry, Surface)
            same_surface(geometry, expected)
    # the topology changes at -2: that frame holds the third period's triangles
    assert dict(back)[-2.0].n_cells == fault.periods[2].n_triangles  # type: ignore[union-attr]


def test_series_at_own_instants_with_a_name(
    db_dsn: str,
    stored: tuple[dict[str, int], EvolvingSurface, SurfaceSeries],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    ids, fault, horizon = stored
    assert main(["--dsn", db_dsn, "series", str(ids["fault"]), str(tmp_path), "--name", "history.pvd"]) == 0
    assert (
        capsys.readouterr()
        .out.splitlines()[-1]
        .startswith(
            f"wrote {tmp_path / 'history.pvd'}: feature {ids['fault']} (moving_faults) at "
            f"{len(fault.geometry_instants)} times from -10.0 to -1.0 Ma"
        )
    )
    back = read_pvd(tmp_path / "history.pvd")
    assert [t for t, _ in back] == fault.geometry_instants.tolist()
    for t, geometry in back:
        same_surface(geometry, fault.at(t))  # type: ignore[arg-type]

    assert main(["--dsn", db_dsn, "series", str(ids["horizon"]), str(tmp_path), "--name", "horizon"]) == 0
    back = read_pvd(tmp_path / "horizon.pvd")
    assert [t for t, _ in back] == INSTANTS
    for (_, geometry), surface in zip(back, horizon.surfaces):
        same_surface(geometry, surface)  # type: ignore[arg-type]


@pytest.mark.parametrize("convention", ["left", "right"])
def test_series_of_a_model_2_feature_between_instants(
    db_dsn: str,
    stored: tuple[dict[str, int], EvolvingSurface, SurfaceSeries],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    convention: str,
) -> None:
    ids, _, horizon = stored
    hid = ids["horizon"]
    assert (
        main(
            [
                "--dsn",
                db_dsn,
                "series",
                str(hid),
                "--from=-0.5",
                "--to",
                "3",
                "--steps",
                "8",
                "--convention",
                convention,
                str(tmp_path),
            ]
        )
        == 0
    )
    assert capsys.readouterr().out.splitlines()[-1] == (
        f"wrote {tmp_path / f'feature_{hid}.pvd'}: feature {hid} (horizons) at 8 times from -0.5 to 3.0, "
        "1 without the object"
    )
    back = read_pvd(tmp_path / f"feature_{hid}.pvd")
    assert [t for t, _ in back] == np.linspace(-0.5, 3.0, 8).tolist()
    for t, geometry in back:
        expected = horizon.at(t, convention)  # type: ignore[arg-type]
        if expected is None:
            assert geometry is None and t == -0.5
        else:
            same_surface(geometry, expected)  # type: ignore[arg-type]


def test_series_bad_arguments(
    db_dsn: str,
    stored: tuple[dict[str, int], EvolvingSurface, SurfaceSeries],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    ids = stored[0]
    fid, out = str(ids["fault"]), str(tmp_path / "out")
    check_errors(
        db_dsn,
        capsys,
        ["series", fid, out],
        [
            (["--from", "0", "--to", "1", "--steps", "0"], "--steps must be an integer >= 1, got 0"),
            (["--from", "2", "--to", "1", "--steps", "3"], "--from (2.0) must not be after --to (1.0)"),
            (["--from", "nan", "--to", "1", "--steps", "3"], "--from must be a finite number, got nan"),
            (["--from", "0", "--to", "inf", "--steps", "3"], "--to must be a finite number, got inf"),
            (
                ["--from", "0", "--to", "1", "--steps", "1"],
                "--steps 1 gives one time, so --from and --to must be equal",
            ),
            (["--from", "1", "--to", "1", "--steps", "4"], "--steps 4 needs --from before --to: both are 1.0"),
            (["--from", "0", "--steps", "3"], "--from, --to and --steps go together"),
            (["--name", "a/b"], "--name 'a/b' must be a file name without folders"),
            (["--name", ".pvd"], "--name '.pvd' must be a file name without folders"),
        ],
    )
    assert main(["--dsn", db_dsn, "series", "987654", out]) == 1
    assert capsys.readouterr().err == (
        "tgsis: error: no feature class has a feature 987654\nHINT: `tgsis ls` lists the features\n"
    )
    assert main(["--dsn", db_dsn, "series", str(ids["static"]), out]) == 1
    assert (
        f"feature {ids['static']} (plain) is static: it has no instants of its own\nHINT: give --from, --to and --steps"
    ) in capsys.readouterr().err
    assert not (tmp_path / "out").exists()  # nothing written, no folder made
    (tmp_path / "file").write_text("")
    assert main(["--dsn", db_dsn, "series", fid, str(tmp_path / "file")]) == 1
    assert "cannot create the folder" in capsys.readouterr().err
    for argv in (["--steps", "many"], ["--from", "early"], []):
        with pytest.raises(SystemExit) as info:
            main(["--dsn", db_dsn, "series", *([fid] if argv else []), *argv])
        assert info.value.code == 2
        capsys.readouterr()


def test_series_of_a_static_surface_with_steps(
    db_dsn: str, stored: tuple[dict[str, int], EvolvingSurface, SurfaceSeries], tmp_path: Path
) -> None:
    ids, _, _ = stored
    assert (
        main(["--dsn", db_dsn, "series", str(ids["static"]), str(tmp_path), "--from", "0", "--to", "0", "--steps", "1"])
        == 0
    )
    [(t, geometry)] = read_pvd(tmp_path / f"feature_{ids['static']}.pvd")
    assert t == 0.0 and isinstance(geometry, Surface) and geometry.n_vertices == 3


def test_at_and_series_in_a_version(
    db_dsn: str,
    stored: tuple[dict[str, int], EvolvingSurface, SurfaceSeries],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """--in: the snapshot of the version's rows (a moved node in the version, the stored one in DEFAULT)."""
    ids, fault, _ = stored
    fid = ids["fault"]
    assert main(["--dsn", db_dsn, "versioning", "enable", "features"]) == 0
    assert main(["--dsn", db_dsn, "version", "create", "moved"]) == 0
    with psycopg.connect(db_dsn) as conn:
        with tgsis.in_version(conn, "moved"):
            conn.execute("UPDATE tgsis.d4dvrtx SET z = z + 1000 WHERE geoid = %s", (fid,))
        conn.commit()
    capsys.readouterr()
    assert main(["--dsn", db_dsn, "--in", "moved", "at", str(fid), "-7.25", str(tmp_path / "moved.vtu")]) == 0
    assert main(["--dsn", db_dsn, "at", str(fid), "-7.25", str(tmp_path / "default.vtu")]) == 0
    expected = fault.at(-7.25)
    assert expected is not None
    same_surface(formats.read_one(tmp_path / "default.vtu"), expected)  # type: ignore[arg-type]
    moved = formats.read_one(tmp_path / "moved.vtu")
    np.testing.assert_allclose(moved.vertices[:, 2], expected.vertices[:, 2] + 1000, rtol=0, atol=1e-9)
    assert main(["--dsn", db_dsn, "--in", "moved", "series", str(fid), str(tmp_path), "--name", "moved"]) == 0
    back = read_pvd(tmp_path / "moved.pvd")
    np.testing.assert_allclose(
        back[0][1].vertices[:, 2],  # type: ignore[union-attr]
        fault.periods[0].positions[0][:, 2] + 1000,
        rtol=0,
        atol=1e-9,
    )


def test_class_create_temporal(db_dsn: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert (
        main(
            [
                "--dsn",
                db_dsn,
                "class",
                "create",
                "growth",
                "--geotype",
                "SURFACE",
                "--time-model",
                "evolving",
                "--time-unit",
                "Ma",
                "--instant-property",
                "throw:float8",
                "--property",
                "porosity:float8",
            ]
        )
        == 0
    )
    assert (
        "created feature class growth (SURFACE, EVOLVING in Ma) in schema public: tables growth, growth_cellpros, "
        "growth_pros, view growth_v" in capsys.readouterr().out
    )
    assert main(["--dsn", db_dsn, "class", "list"]) == 0
    assert (
        capsys.readouterr()
        .out.rstrip("\n")
        .endswith("\tevolving in Ma\t-\tvertex: porosity double precision\tthrow double precision")
    )
    assert (
        main(["--dsn", db_dsn, "class", "create", "wells", "--geotype", "MULTILINESTRING", "--time-model", "INSTANTS"])
        == 1
    )
    assert "holds SURFACE features" in capsys.readouterr().err
    assert (
        main(["--dsn", db_dsn, "class", "create", "x", "--geotype", "SURFACE", "--instant-property", "a:float8"]) == 1
    )
    assert "static feature class x takes no time unit or per-instant properties" in capsys.readouterr().err


def test_import_at_adds_model_2_instants_from_files(
    db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`tgsis import FILE --class C --at T [--feature ID]`: a new feature known from T, then more instants."""
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "tops", "SURFACE", time_model="INSTANTS", time_unit="Ma")
    flat = Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2], [1, 3, 2]], name="top A")
    formats.write(flat, tmp_path / "a0.ts")
    formats.write(Surface(flat.vertices + [0, 0, -5], flat.cells, name="top A"), tmp_path / "a1.ts")
    dsn = ["--dsn", db_dsn]
    assert main([*dsn, "import", str(tmp_path / "a0.ts"), "--class", "tops", "--at", "-10", "--json"]) == 0
    stored = json.loads(capsys.readouterr().out)
    assert stored["instants"] == [-10.0]
    fid = str(stored["id"])
    assert main([*dsn, "import", str(tmp_path / "a1.ts"), "--class", "tops", "--at", "-5", "--feature", fid]) == 0
    assert "its instants: -10.0, -5.0" in capsys.readouterr().out
    with psycopg.connect(db_dsn) as conn:
        assert [t for t, _ in tgsis.instants(conn, int(fid))] == [-10.0, -5.0]
        at = tgsis.get_at(conn, int(fid), -7.0)
        assert at is not None and np.array_equal(at.vertices, flat.vertices)  # the step keeps t = -10's shape
    # refused, in the command's terms, with nothing stored
    assert main([*dsn, "import", str(tmp_path / "a1.ts"), "--class", "tops"]) == 1
    assert "give --at T" in capsys.readouterr().err
    assert main([*dsn, "import", str(tmp_path / "a1.ts"), "--class", "tops", "--at", "-5", "--feature", fid]) == 1
    assert "-5" in capsys.readouterr().err  # that instant exists already
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "still", "SURFACE")
    assert main([*dsn, "import", str(tmp_path / "a1.ts"), "--class", "still", "--at", "1"]) == 1
    assert "take a class of surfaces at instants (INSTANTS)" in capsys.readouterr().err
    with psycopg.connect(db_dsn) as conn:
        assert conn.execute("SELECT count(*) FROM tops").fetchone() == (1,)
        assert conn.execute("SELECT count(*) FROM still").fetchone() == (0,)


def test_import_at_stores_not_alive_like_a_series_from_python_unless_alive(
    db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One default for `alive`: a surface known at T is not claimed to exist after its last instant, from the command
    line as from Python (SurfaceSeries(alive=False)); `--alive` says it does."""
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "tops", "SURFACE", time_model="INSTANTS", time_unit="Ma")
    flat = Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2], [1, 3, 2]], name="top A")
    formats.write(flat, tmp_path / "a0.ts")
    dsn = ["--dsn", db_dsn]
    assert main([*dsn, "import", str(tmp_path / "a0.ts"), "--class", "tops", "--at", "-10", "--json"]) == 0
    plain = json.loads(capsys.readouterr().out)["id"]
    assert main([*dsn, "import", str(tmp_path / "a0.ts"), "--class", "tops", "--at", "-10", "--alive", "--json"]) == 0
    alive = json.loads(capsys.readouterr().out)["id"]
    with psycopg.connect(db_dsn) as conn:
        python = tgsis.insert_feature(conn, "tops", tgsis.SurfaceSeries([-10.0], [flat]), name="from python")
        rows: dict[int, bool] = dict(
            conn.execute(
                "SELECT geoid, alive FROM tgsis.geometry WHERE geoid = ANY (%s)", ([plain, alive, python],)
            ).fetchall()
        )
        assert rows == {plain: False, alive: True, python: False}
        assert tgsis.get_at(conn, plain, 0.0) is None
        at = tgsis.get_at(conn, alive, 0.0)
        assert at is not None and np.array_equal(at.vertices, flat.vertices)
    assert (
        main(
            [
                *dsn,
                "import",
                str(tmp_path / "a0.ts"),
                "--class",
                "tops",
                "--at",
                "-5",
                "--feature",
                str(plain),
                "--alive",
            ]
        )
        == 1
    )
    assert "--alive does not go with --feature" in capsys.readouterr().err
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "still", "SURFACE")
    assert main([*dsn, "import", str(tmp_path / "a0.ts"), "--class", "still", "--alive"]) == 1
    assert "--alive goes with --at T" in capsys.readouterr().err
    with psycopg.connect(db_dsn) as conn:
        assert conn.execute("SELECT count(*) FROM still").fetchone() == (0,)
        assert conn.execute("SELECT count(*) FROM tops").fetchone() == (3,)  # two from the CLI, one from Python

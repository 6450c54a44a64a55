"""Surfaces in time written as ParaView .pvd time series: from numpy (tgsis.temporal) and from the database."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.temporal_data import evolving, series
from tgsis.formats.pvd import read_pvd
from tgsis.mesh import Surface
from tgsis.temporal import EvolvingSurface, SurfaceSeries, even_times, own_instants, series_frames, write_series_pvd

Conn = psycopg.Connection[Any]
STARTS = [-10.0, -6.5, -2.0]  # three topology periods; the surface exists -10 .. -1 (not alive)


def check_against(
    pvd: Path, obj: EvolvingSurface | SurfaceSeries, times: list[float], convention: tgsis.temporal.Convention = "left"
) -> int:
    """Times read back exactly, geometry bit-identical to obj.at(t); return how many frames hold a surface."""
    back = read_pvd(pvd)
    assert [t for t, _ in back] == times
    present = 0
    for t, geometry in back:
        expected = obj.at(t, convention) if isinstance(obj, SurfaceSeries) else obj.at(t)
        if expected is None:
            assert geometry is None, t
            continue
        assert isinstance(geometry, Surface), t
        assert geometry.vertices.tobytes() == expected.vertices.tobytes(), t
        np.testing.assert_array_equal(geometry.triangles, expected.triangles)
        present += 1
    return present


def test_numpy_evolving_surface_to_pvd(tmp_path: Path) -> None:
    surface = evolving(np.random.default_rng(11), STARTS, instants_per_period=4, with_properties=True)
    times = even_times(-12.0, 0.0, 25).tolist()  # before, through the three periods, after
    written = write_series_pvd(surface, tmp_path / "fault.pvd", times)
    assert written.pvd == tmp_path / "fault.pvd"
    assert [f.name for f in written.files] == [f"fault_{i:06d}.vtu" for i in range(25)]
    assert written.missing == [t for t in times if t < -10.0 or t > -1.0] and len(written.missing) == 6
    assert check_against(written.pvd, surface, times) == 19
    # vertex properties are interpolated with the nodes, and written
    mid = read_pvd(written.pvd)[10]
    expected = surface.at(mid[0])
    assert isinstance(mid[1], Surface) and expected is not None
    np.testing.assert_array_equal(mid[1].vertex_properties["porosity"], expected.vertex_properties["porosity"])


def test_numpy_default_times_are_the_own_instants(tmp_path: Path) -> None:
    surface = evolving(np.random.default_rng(12), STARTS, alive=True)
    written = write_series_pvd(surface, tmp_path / "own.pvd")
    assert [t for t, _ in written.frames] == surface.geometry_instants.tolist() == own_instants(surface).tolist()
    assert written.missing == []
    assert check_against(written.pvd, surface, surface.geometry_instants.tolist()) == len(surface.geometry_instants)
    # at a topology change the frame holds the new period's triangles
    frames = dict(written.frames)
    changed = frames[STARTS[1]]
    assert changed is not None and changed.n_cells == surface.periods[1].n_triangles


@pytest.mark.parametrize("convention", ["left", "right"])
def test_numpy_surface_series_to_pvd(convention: str, tmp_path: Path) -> None:
    steps = series(np.random.default_rng(13), [0.0, 1.0, 2.5], with_properties=True)
    times = [-1.0, 0.0, 0.5, 1.0, 1.75, 2.5, 3.0]
    written = write_series_pvd(steps, tmp_path / "steps.pvd", times, convention=convention)  # type: ignore[arg-type]
    assert check_against(written.pvd, steps, times, convention) == 5  # type: ignore[arg-type]
    back = dict(read_pvd(written.pvd))
    half = back[0.5]
    assert isinstance(half, Surface)
    chosen = steps.surfaces[0 if convention == "left" else 1]
    assert half.n_vertices == chosen.n_vertices
    np.testing.assert_array_equal(half.vertex_properties["porosity"], chosen.vertex_properties["porosity"])
    assert written.missing == [-1.0, 3.0]
    own = write_series_pvd(steps, tmp_path / "own.pvd")
    assert [t for t, _ in read_pvd(own.pvd)] == [0.0, 1.0, 2.5]


def test_even_times() -> None:
    assert even_times(-2.0, 0.0, 5).tolist() == [-2.0, -1.5, -1.0, -0.5, 0.0]
    times = even_times(0.1, 0.7, 7)
    assert times[0] == 0.1 and times[-1] == 0.7 and len(times) == 7  # both ends exactly
    assert even_times(3.0, 3.0, 1).tolist() == [3.0]
    for args, message in [
        ((0.0, 1.0, 0), "steps must be an integer >= 1, got 0"),
        ((0.0, 1.0, 2.5), "steps must be an integer >= 1, got 2.5"),
        ((1.0, 0.0, 3), r"start \(1.0\) must not be after end \(0.0\)"),
        ((float("nan"), 1.0, 3), "start must be a finite number, got nan"),
        ((0.0, float("inf"), 3), "end must be a finite number, got inf"),
        ((0.0, 1.0, 1), "steps 1 gives one time"),
        ((1.0, 1.0, 2), "steps 2 needs start before end"),
        ((0.0, 5e-324, 3), "equal neighbouring times"),
    ]:
        with pytest.raises(tgsis.InvalidInputError, match=message):
            even_times(*args)  # type: ignore[arg-type]
    with pytest.raises(tgsis.InvalidInputError, match="--steps must be"):
        even_times(0.0, 1.0, -1, labels=("--from", "--to", "--steps"))


def test_series_frames_refuses_bad_times() -> None:
    surface = evolving(np.random.default_rng(14), [0.0])
    with pytest.raises(tgsis.InvalidInputError, match="strictly increasing"):
        series_frames(surface, [0.0, 0.0])
    with pytest.raises(tgsis.InvalidInputError, match="finite"):
        series_frames(surface, [0.0, float("nan")])
    with pytest.raises(tgsis.InvalidInputError, match="convention"):
        series_frames(surface, [0.0], "middle")  # type: ignore[arg-type]
    with pytest.raises(tgsis.InvalidInputError, match="SurfaceSeries or an EvolvingSurface"):
        own_instants(Surface(np.zeros((3, 3)), [[0, 1, 2]]))  # type: ignore[arg-type]


# --------------------------------------------------------------------------- from the database


@pytest.fixture
def stored(conn: Conn) -> tuple[EvolvingSurface, int]:
    fc = tgsis.create_feature_class(
        conn,
        "moving_faults",
        "SURFACE",
        time_model="EVOLVING",
        time_unit="Ma",
        cell_properties=[("porosity", "double precision")],
        instant_properties=[("throw", "double precision"), ("note_code", "integer")],
    )
    surface = evolving(np.random.default_rng(15), STARTS, instants_per_period=4, with_properties=True)
    fid = tgsis.insert_feature(conn, fc, surface)
    conn.commit()
    return surface, fid


def test_database_evolving_surface_to_pvd(conn: Conn, stored: tuple[EvolvingSurface, int], tmp_path: Path) -> None:
    surface, fid = stored
    written = tgsis.export_series(conn, fid, tmp_path / "db.pvd", start=-12.0, end=0.0, steps=25)
    times = even_times(-12.0, 0.0, 25).tolist()
    assert check_against(written.pvd, surface, times) == 19
    assert written.missing == [t for t in times if t < -10.0 or t > -1.0]
    # the same frames as the numpy path, geometry for geometry
    local = write_series_pvd(surface, tmp_path / "numpy.pvd", times)
    for (t, a), (u, b) in zip(read_pvd(written.pvd), read_pvd(local.pvd)):
        assert t == u and (a is None) == (b is None)
        if isinstance(a, Surface) and isinstance(b, Surface):
            assert a.vertices.tobytes() == b.vertices.tobytes()
            np.testing.assert_array_equal(a.triangles, b.triangles)
    assert conn.info.transaction_status == psycopg.pq.TransactionStatus.IDLE  # its snapshot transaction is over


def test_database_default_times_are_the_own_instants(
    conn: Conn, stored: tuple[EvolvingSurface, int], tmp_path: Path
) -> None:
    surface, fid = stored
    written = tgsis.export_series(conn, fid, tmp_path / "own.pvd")
    assert check_against(written.pvd, surface, surface.geometry_instants.tolist()) == len(surface.geometry_instants)
    assert tgsis.frames_at(conn, fid, [-10.5, -1.0])[0] == (-10.5, None)
    assert tgsis.lifespan(conn, fid) == (-10.0, -1.0, False)


def test_database_series_of_a_surface_series(tx: Conn, tmp_path: Path) -> None:
    fc = tgsis.create_feature_class(
        tx,
        "horizons",
        "SURFACE",
        time_model="INSTANTS",
        cell_properties=[("porosity", "double precision")],
        instant_properties=[("throw", "double precision")],
    )
    steps = series(np.random.default_rng(16), [0.0, 1.0, 2.5], with_properties=True, alive=True)
    fid = tgsis.insert_feature(tx, fc, steps)
    for convention in ("left", "right"):  # -1, -0.5, 0, 0.5, ... 3: before, at, between and after the instants
        written = tgsis.export_series(
            tx, fid, tmp_path / f"{convention}.pvd", start=-1.0, end=3.0, steps=9, convention=convention
        )
        assert check_against(written.pvd, steps, even_times(-1.0, 3.0, 9).tolist(), convention) == 7
    own = tgsis.export_series(tx, fid, tmp_path / "own.pvd")
    assert check_against(own.pvd, steps, [0.0, 1.0, 2.5]) == 3
    assert tgsis.lifespan(tx, fid) == (0.0, 2.5, True)


def test_database_export_errors(tx: Conn, tmp_path: Path) -> None:
    fc = tgsis.create_feature_class(tx, "plain", "SURFACE")
    fid = tgsis.insert_feature(tx, fc, Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]))
    assert tgsis.lifespan(tx, fid) is None
    with tx.transaction():
        with pytest.raises(tgsis.InvalidInputError, match="is static"):
            tgsis.export_series(tx, fid, tmp_path / "static.pvd")
    static = tgsis.export_series(tx, fid, tmp_path / "static.pvd", start=0.0, end=1.0, steps=3)
    assert static.missing == [] and len(read_pvd(static.pvd)) == 3
    with tx.transaction():
        with pytest.raises(tgsis.InvalidInputError, match="together"):
            tgsis.export_series(tx, fid, tmp_path / "x.pvd", start=0.0)
    with tx.transaction():
        with pytest.raises(tgsis.NotFoundError, match="feature 987654 does not exist"):
            tgsis.export_series(tx, 987654, tmp_path / "x.pvd")
    with tx.transaction():
        with pytest.raises(tgsis.NotFoundError, match="feature 987654 does not exist"):
            tgsis.export_series(tx, 987654, tmp_path / "x.pvd", start=0.0, end=1.0, steps=2)
    assert not (tmp_path / "x.pvd").exists() and not (tmp_path / "x").exists()

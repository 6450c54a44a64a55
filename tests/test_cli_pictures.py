"""Pictures from the command line: ``--png`` on ``at`` and ``export``, ``--gif`` on ``series`` (issue 18, part 3)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import psycopg
import pytest
from PIL import Image

import tgsis
from tests.temporal_data import evolving
from tgsis.cli import main
from tgsis.mesh import PointSet, Surface


@pytest.fixture
def stored(db_dsn: str) -> dict[str, int]:
    """An evolving fault (three topology periods), a static surface and a point set, committed."""
    fault = evolving(np.random.default_rng(21), [-10.0, -6.5, -2.0], instants_per_period=4)
    with psycopg.connect(db_dsn) as conn:
        faults = tgsis.create_feature_class(conn, "faults", "SURFACE", time_model="EVOLVING", time_unit="Ma")
        plain = tgsis.create_feature_class(conn, "plain", "SURFACE")
        picks = tgsis.create_feature_class(conn, "picks", "MULTIPOINT")
        return {
            "fault": tgsis.insert_feature(conn, faults, fault),
            "static": tgsis.insert_feature(
                conn, plain, Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], name="a static triangle")
            ),
            "points": tgsis.insert_feature(conn, picks, PointSet([[0, 0, 0], [1, 1, 1]])),
        }


def _png(path: Path) -> tuple[int, int]:
    with Image.open(path) as picture:
        assert picture.format == "PNG"
        return picture.size


def test_at_draws_the_structure_at_t(
    db_dsn: str, stored: dict[str, int], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    png = tmp_path / "at.png"
    assert (
        main(
            [
                "--dsn",
                db_dsn,
                "at",
                str(stored["fault"]),
                "-5",
                str(tmp_path / "at.ts"),
                "--png",
                str(png),
                "--with",
                str(stored["static"]),
            ]
        )
        == 0
    )
    assert "drew 2 surface(s) to" in capsys.readouterr().out
    assert _png(png) == (800, 600)


def test_series_draws_an_animation(
    db_dsn: str, stored: dict[str, int], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    gif = tmp_path / "fault.gif"
    assert (
        main(
            [
                "--dsn",
                db_dsn,
                "series",
                str(stored["fault"]),
                str(tmp_path / "series"),
                "--from",
                "-10",
                "--to",
                "-3",
                "--steps",
                "8",
                "--gif",
                str(gif),
            ]
        )
        == 0
    )
    assert "drew 8 frames to" in capsys.readouterr().out
    with Image.open(gif) as movie:
        assert movie.format == "GIF" and movie.n_frames == 8  # type: ignore[attr-defined]  # PIL: only multi-frame formats


def test_export_draws_a_surface_and_refuses_points(
    db_dsn: str, stored: dict[str, int], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    png = tmp_path / "static.png"
    assert main(["--dsn", db_dsn, "export", str(stored["static"]), str(tmp_path / "static.ts"), "--png", str(png)]) == 0
    assert _png(png) == (800, 600)
    capsys.readouterr()
    assert (
        main(
            [
                "--dsn",
                db_dsn,
                "export",
                str(stored["points"]),
                str(tmp_path / "points.vs"),
                "--png",
                str(tmp_path / "points.png"),
            ]
        )
        == 1
    )
    assert "is no surface: --png draws surfaces" in capsys.readouterr().err
    assert not (tmp_path / "points.png").exists() and not (tmp_path / "points.vs").exists()  # nothing written


def test_version_diff_draws_what_moved(db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    triangle = Surface([[0, 0, 0], [10, 0, 0], [0, 10, 0]], [[0, 1, 2]], name="t")
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "plain", "SURFACE")
        fid = tgsis.insert_feature(conn, "plain", triangle)
        other = tgsis.insert_feature(conn, "plain", triangle)
        tgsis.enable_feature_versioning(conn)
        tgsis.create_version(conn, "v1")
        with tgsis.in_version(conn, "v1"):
            moved = triangle.copy()
            moved.vertices[2, 2] = 3.0
            tgsis.save_feature(conn, "plain", fid, moved)
            tgsis.delete_feature(conn, "plain", other)
            conn.commit()
    assert main(["--dsn", db_dsn, "version", "diff", "DEFAULT", "v1", "--png", str(tmp_path / "diff")]) == 0
    out = capsys.readouterr().out
    assert f"drew feature {fid} to" in out and f"drew feature {other} to" in out
    assert _png(tmp_path / "diff" / f"diff_{fid}.png") == (800, 600)
    assert _png(tmp_path / "diff" / f"diff_{other}.png") == (800, 600)  # only in DEFAULT: drawn as it was


def test_checkin_draws_the_edit(db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from tgsis import formats

    u, v = np.meshgrid(np.arange(6, dtype=float), np.arange(5, dtype=float))
    idx = np.arange(30).reshape(5, 6)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    grid = Surface(
        np.stack([u.ravel() * 100, v.ravel() * 100, np.zeros(30)], 1),
        np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]),
        name="grid",
    )
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "plain", "SURFACE")
        fid = tgsis.insert_feature(conn, "plain", grid)
        tgsis.enable_feature_versioning(conn)
    path = tmp_path / "grid.ts"
    assert main(["--dsn", db_dsn, "checkout", str(fid), str(path)]) == 0
    edited = formats.read_one(path)
    edited.vertices[14, 2] = 40.0
    formats.write(edited, path)
    png = tmp_path / "edit.png"
    assert main(["--dsn", db_dsn, "checkin", str(path), "--png", str(png)]) == 0
    assert f"drew the edit to {png}" in capsys.readouterr().out
    assert _png(png) == (800, 600)

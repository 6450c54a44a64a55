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
        return {"fault": tgsis.insert_feature(conn, faults, fault),
                "static": tgsis.insert_feature(conn, plain, Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]],
                                                                    name="a static triangle")),
                "points": tgsis.insert_feature(conn, picks, PointSet([[0, 0, 0], [1, 1, 1]]))}


def _png(path: Path) -> tuple[int, int]:
    with Image.open(path) as picture:
        assert picture.format == "PNG"
        return picture.size


def test_at_draws_the_structure_at_t(db_dsn: str, stored: dict[str, int], tmp_path: Path,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    png = tmp_path / "at.png"
    assert main(["--dsn", db_dsn, "at", str(stored["fault"]), "-5", str(tmp_path / "at.ts"), "--png", str(png),
                 "--with", str(stored["static"])]) == 0
    assert "drew 2 surface(s) to" in capsys.readouterr().out
    assert _png(png) == (800, 600)


def test_series_draws_an_animation(db_dsn: str, stored: dict[str, int], tmp_path: Path,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    gif = tmp_path / "fault.gif"
    assert main(["--dsn", db_dsn, "series", str(stored["fault"]), str(tmp_path / "series"), "--from", "-10",
                 "--to", "-3", "--steps", "8", "--gif", str(gif)]) == 0
    assert "drew 8 frames to" in capsys.readouterr().out
    with Image.open(gif) as movie:
        assert movie.format == "GIF" and movie.n_frames == 8


def test_export_draws_a_surface_and_refuses_points(db_dsn: str, stored: dict[str, int], tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    png = tmp_path / "static.png"
    assert main(["--dsn", db_dsn, "export", str(stored["static"]), str(tmp_path / "static.ts"), "--png", str(png)]) == 0
    assert _png(png) == (800, 600)
    capsys.readouterr()
    assert main(["--dsn", db_dsn, "export", str(stored["points"]), str(tmp_path / "points.vs"),
                 "--png", str(tmp_path / "points.png")]) == 1
    assert "is no surface: --png draws surfaces" in capsys.readouterr().err
    assert not (tmp_path / "points.png").exists() and not (tmp_path / "points.vs").exists()   # nothing written

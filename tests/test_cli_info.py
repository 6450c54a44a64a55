"""``tgsis info ID``: what the source design's plugin showed as "surface information" (issue 18, part 2)."""

from __future__ import annotations

import numpy as np
import psycopg
import pytest

import tgsis
from tests.temporal_data import evolving, series
from tgsis.cli import main
from tgsis.mesh import Surface


@pytest.fixture
def stored(db_dsn: str) -> dict[str, int]:
    """A static surface with a property (versioned, changed in v1, copied in v2) and an evolving fault."""
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(
            conn, "plain", "SURFACE", feature_properties={"release": "text"}, cell_properties={"porosity": "float8"}
        )
        tgsis.create_feature_class(conn, "faults", "SURFACE", time_model="EVOLVING", time_unit="Ma")
        triangle = Surface(
            [[0, 0, -5], [10, 0, -5], [0, 20, 1]],
            [[0, 1, 2]],
            name="a triangle",
            vertex_properties={"porosity": [0.1, 0.2, 0.3]},
        )
        ids = {
            "plain": tgsis.insert_feature(conn, "plain", triangle, {"release": "5.3"}),
            "fault": tgsis.insert_feature(
                conn, "faults", evolving(np.random.default_rng(3), [-10.0, -4.0]), drop_extra_properties=True
            ),
        }
        tgsis.enable_feature_versioning(conn)
        tgsis.create_version(conn, "v1")
        tgsis.create_version(conn, "v2")
        with tgsis.in_version(conn, "v1"):
            moved = triangle.copy()
            moved.vertices[2, 2] = 2.0
            tgsis.save_feature(conn, "plain", ids["plain"], moved)
            conn.commit()
    return ids


def test_info_of_a_static_versioned_surface(
    db_dsn: str, stored: dict[str, int], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["--dsn", db_dsn, "info", str(stored["plain"])]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines == [
        f"feature {stored['plain']}: a triangle, class plain (SURFACE), in version DEFAULT",
        "  3 vertices, 1 cells",
        "  box: x [0.0, 10.0], y [0.0, 20.0], z [-5.0, 1.0]",
        "  static: the same at every time",
        "  properties: release = '5.3'",
        "  vertex properties: porosity",
        "  versions where it differs from DEFAULT: v1 (2 rows differ)",
    ]


def test_info_of_an_evolving_surface_in_a_version(
    db_dsn: str, stored: dict[str, int], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["--dsn", db_dsn, "--in", "v1", "info", str(stored["fault"])]) == 0
    out = capsys.readouterr().out
    assert f"feature {stored['fault']}: " in out and "class faults (SURFACE, EVOLVING in Ma), in version v1" in out
    assert "  exists from t = -10.0 to " in out and "topology (re)defined at -10.0, -4.0" in out
    assert "  versions where it differs from v1: none" in out


def test_info_of_an_unknown_feature(db_dsn: str, stored: dict[str, int], capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--dsn", db_dsn, "info", "999999"]) == 1
    assert "999999" in capsys.readouterr().err


def test_info_of_surfaces_in_time_counts_per_instant_not_summed(
    db_dsn: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """Model 2 stores each instant's vertices; model 3 each topology period's nodes: info says how many one shape has,
    not the rows of every instant or period added up."""
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "tops", "SURFACE", time_model="INSTANTS", time_unit="Ma")
        tgsis.create_feature_class(conn, "faults", "SURFACE", time_model="EVOLVING", time_unit="Ma")
        flat = Surface([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2], [1, 3, 2]])
        same = tgsis.insert_feature(conn, "tops", tgsis.SurfaceSeries([0.0, 1.0, 2.0], [flat, flat, flat]))
        growing = tgsis.insert_feature(
            conn, "tops", series(np.random.default_rng(1), [0.0, 1.0, 2.0]), drop_extra_properties=True
        )
        moving = tgsis.insert_feature(
            conn, "faults", evolving(np.random.default_rng(3), [-10.0, -4.0]), drop_extra_properties=True
        )
        conn.commit()
    assert main(["--dsn", db_dsn, "info", str(same)]) == 0
    assert capsys.readouterr().out.splitlines()[1] == "  4 vertices, 2 cells at each of its 3 instants"
    assert main(["--dsn", db_dsn, "info", str(growing)]) == 0  # grids of 3x3, 4x4 and 5x5 vertices
    assert capsys.readouterr().out.splitlines()[1] == "  9 to 25 vertices, 8 to 32 cells per instant (3 instants)"
    assert main(["--dsn", db_dsn, "info", str(moving)]) == 0  # 5x5 then 6x6 nodes
    assert (
        capsys.readouterr().out.splitlines()[1]
        == "  25 to 81 vertices, 32 to 128 cells per topology period (2 periods)"
    )

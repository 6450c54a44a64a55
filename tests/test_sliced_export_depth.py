"""``tgsis version conflicts --export DIR`` of a model-2/3 slice of a depth-positive object keeps the depth sign.

An object imported from a GOCAD file with ``ZPOSITIVE Depth`` is stored as
elevation with its convention beside it (docs/meshes.md, "Depth or
elevation"); every export gives it back: GOCAD files say ``ZPOSITIVE Depth``
and hold depths, formats without a z convention hold elevation. The files a
conflict's export writes for each slice of a surface at instants (model 2) or
of an evolving surface (model 3) must do as the other exports do: the oracle is
``tgsis at ID T FILE`` of the same instant in the version.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.merge_data import curved_surface
from tests.test_merge_instants import CHILD_SHIFT, NORTH, PARENT_SHIFT, TIMES, move, move3
from tgsis import formats
from tgsis.cli import main
from tgsis.temporal import EvolvingSurface, SurfaceSeries, TopologyPeriod

Conn = psycopg.Connection[Any]


def _depths(i: int) -> np.ndarray:
    """The curved grid as depths (z positive down, 1,000 m and deeper), a little other at each instant."""
    xyz = curved_surface().vertices.copy()
    xyz[:, 2] = 1000.0 - xyz[:, 2] + i / 3.0
    return xyz


def _depth_object(conn: Conn, model: int) -> int:
    cells = curved_surface().cells
    if model == 2:
        tgsis.create_feature_class(conn, "horizons", "SURFACE", time_model="INSTANTS")
        tgsis.enable_feature_versioning(conn)
        surfaces = [tgsis.Surface(_depths(i), cells, metadata={"zpositive": "Depth"}) for i in range(len(TIMES))]
        geoid = tgsis.insert_feature(conn, "horizons", SurfaceSeries(np.asarray(TIMES), surfaces, name="deep"))
    else:
        tgsis.create_feature_class(conn, "evolving", "SURFACE", time_model="EVOLVING")
        tgsis.enable_feature_versioning(conn)
        # stored elevation (the depths negated), the convention beside it, as an import of a Depth file stores them
        positions = np.stack([_depths(i) * [1.0, 1.0, -1.0] for i in range(len(TIMES))])
        period = TopologyPeriod(np.asarray(TIMES), cells, positions)
        geoid = tgsis.insert_feature(conn, "evolving", EvolvingSurface([period], name="deep"))
        conn.execute("UPDATE tgsis.geometry SET zpositive = 'Depth' WHERE geoid = %s", (geoid,))
    conn.commit()
    assert conn.execute("SELECT zpositive FROM tgsis.geometry WHERE geoid = %s", (geoid,)).fetchone() == ("Depth",)
    tgsis.create_version(conn, "e1")
    conn.commit()
    shift = move if model == 2 else move3
    shift(conn, "e1", geoid, 2.0, NORTH, CHILD_SHIFT)
    shift(conn, "DEFAULT", geoid, 2.0, NORTH[:5], PARENT_SHIFT)
    return geoid


def _rows(mesh: Any) -> np.ndarray:
    """The vertices of a file read back, in the order of their coordinates (files of two writers compared)."""
    xyz = np.asarray(mesh.vertices, dtype=np.float64)
    return xyz[np.lexsort(xyz.T[::-1])]


@pytest.mark.parametrize("model", [2, 3])
@pytest.mark.parametrize("ext", ["ts", "vtu"])
def test_the_exported_slices_keep_the_depth_sign(
    conn: Conn, db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], model: int, ext: str
) -> None:
    geoid = _depth_object(conn, model)
    out = tmp_path / "conflicts"
    args = ["--dsn", db_dsn, "version", "conflicts", "e1", "--export", str(out), "--format", ext]
    assert main(args) == 0
    capsys.readouterr()
    tag = "t2.0" if model == 2 else "m1.0_t2.0"
    [child_file] = sorted(out.glob(f"{geoid}_*{tag}_child.{ext}"))
    [child] = formats.read(child_file)
    # the other export of the same slice: the version's surface at t = 2
    snapshot_file = tmp_path / f"at.{ext}"
    assert main(["--dsn", db_dsn, "--in", "e1", "at", str(geoid), "2", str(snapshot_file)]) == 0
    [snapshot] = formats.read(snapshot_file)
    assert child.metadata.get("zpositive") == snapshot.metadata.get("zpositive")
    assert child.metadata.get("zpositive") == "Depth"  # read back by tgsis: the mesh as it was (depths)
    assert np.all(child.vertices[:, 2] > 800.0)
    if ext == "ts":
        assert "ZPOSITIVE Depth" in child_file.read_text()  # GOCAD says it, and holds depths
    else:  # a format without a z convention holds elevation, the convention beside it
        import meshio

        assert np.all(meshio.read(child_file).points[:, 2] < -800.0)
    np.testing.assert_array_equal(_rows(child), _rows(snapshot))
    # the base file of the slice: the depths the object was stored with
    [base] = formats.read(sorted(out.glob(f"{geoid}_*{tag}_base.{ext}"))[0])
    np.testing.assert_array_equal(_rows(base), _rows(tgsis.Surface(_depths(1), curved_surface().cells)))

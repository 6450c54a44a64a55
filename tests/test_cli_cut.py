"""``tgsis cut``: cutting a surface along vertex paths as a utility (issue 18, part 2)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tgsis import formats
from tgsis.cli import main
from tgsis.mesh import Surface


def _grid(nx: int, ny: int) -> Surface:
    u, v = np.meshgrid(np.arange(nx, dtype=float), np.arange(ny, dtype=float))
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return Surface(
        np.stack([u.ravel(), v.ravel(), np.zeros(u.size)], 1),
        np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]),
        name="grid",
    )


def test_a_border_to_border_cut_splits_the_surface(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    formats.write(_grid(5, 4), tmp_path / "grid.ts")
    column = "2,7,12,17"  # x = 2, from the y = 0 border to the y = 3 border
    assert main(["cut", str(tmp_path / "grid.ts"), str(tmp_path / "cut.ts"), "--path", column]) == 0
    assert "20 vertices, 4 copied (24 now), 24 triangles" in capsys.readouterr().out
    cut = formats.read_one(tmp_path / "cut.ts")
    assert isinstance(cut, Surface) and cut.n_vertices == 24 and cut.n_cells == 24
    # two pieces now: no triangle uses both a copy and its original
    copies = np.arange(20, 24)
    for tri in cut.cells:
        assert not (set(tri) & set(copies.tolist()) and set(tri) & {2, 7, 12, 17})


def test_a_bad_path_is_refused_naming_it_and_nothing_is_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    formats.write(_grid(5, 4), tmp_path / "grid.ts")
    assert main(["cut", str(tmp_path / "grid.ts"), str(tmp_path / "cut.ts"), "--path", "2,13"]) == 1
    err = capsys.readouterr().err
    assert "--path 2,13" in err and "Traceback" not in err
    assert not (tmp_path / "cut.ts").exists()
    with pytest.raises(SystemExit):
        main(["cut", str(tmp_path / "grid.ts"), str(tmp_path / "cut.ts"), "--path", "2;7"])
    assert "vertex indices separated by commas" in capsys.readouterr().err

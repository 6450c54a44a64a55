"""The recipe of docs/meshes.md runs as written: a model's surfaces into tgsis, versioned, out to ParaView files.

The Python block is taken from the page and run against a fresh database
(``TGSIS_DSN``, which ``tgsis.connect()`` reads), in a temporary folder; then
the files it wrote are read by pyvista: each version has its own horizons.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import pyvista as pv

DOC = Path(__file__).resolve().parents[1] / "docs" / "meshes.md"


def recipe() -> str:
    text = DOC.read_text(encoding="utf-8")
    section = text[text.index("## Recipe") :]
    [block] = re.findall(r"```python\n(.*?)```", section, re.S)
    return str(block)


def test_the_recipe_runs_and_each_version_has_its_horizons(
    db_dsn: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("TGSIS_DSN", db_dsn)
    monkeypatch.chdir(tmp_path)
    exec(compile(recipe(), str(DOC), "exec"), {"__name__": "recipe"})  # noqa: S102 - our own documentation
    written = sorted(p.name for p in tmp_path.glob("*.vtp"))
    assert written == [
        "top_sandstone_DEFAULT.vtp",
        "top_sandstone_run2.vtp",
        "top_shale_DEFAULT.vtp",
        "top_shale_run2.vtp",
    ]
    before, after = pv.read(tmp_path / "top_shale_DEFAULT.vtp"), pv.read(tmp_path / "top_shale_run2.vtp")
    assert isinstance(before, pv.PolyData) and isinstance(after, pv.PolyData)
    assert np.allclose(after.points[:, 2], before.points[:, 2] - 25.0)
    assert np.array_equal(before["values"], np.full(before.n_points, 1800.0))
    same = pv.read(tmp_path / "top_sandstone_DEFAULT.vtp"), pv.read(tmp_path / "top_sandstone_run2.vtp")
    assert np.array_equal(same[0].points, same[1].points)

"""tgsis.pictures.scene with boxes (the regions of a merge, issue 39): drawn, and a bad box refused before any file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from tgsis import pictures
from tgsis._cfm import synthetic_release
from tgsis.errors import InvalidInputError
from tgsis.mesh import Surface


def _fault() -> Surface:
    fault = synthetic_release(0)[0].mesh
    assert isinstance(fault, Surface)
    return fault


def test_a_scene_draws_labelled_boxes(tmp_path: Path) -> None:
    fault = _fault()
    low, high = fault.vertices.min(axis=0), fault.vertices.max(axis=0)
    plain = pictures.scene([fault], tmp_path / "plain.png", title="fault")
    boxed = pictures.scene(
        [fault], tmp_path / "boxed.png", title="fault", boxes=[(np.stack([low, (low + high) / 2]), "region 0", "red")]
    )
    with Image.open(plain) as a, Image.open(boxed) as b:
        assert a.size == b.size
        red = np.asarray(b.convert("RGB"), dtype=int)
        red_pixels = (red[..., 0] > 200) & (red[..., 1] < 60) & (red[..., 2] < 60)
        assert red_pixels.sum() > 50 and not np.array_equal(np.asarray(a), np.asarray(b))


@pytest.mark.parametrize(
    "bounds",
    [[[0, 0, 0], [1, 1]], [[1, 0, 0], [0, 1, 1]], [[0, 0, np.nan], [1, 1, 1]]],
    ids=["shape", "min above max", "nan"],
)
def test_a_bad_box_is_refused_naming_it_and_nothing_is_written(tmp_path: Path, bounds: list[list[float]]) -> None:
    with pytest.raises(InvalidInputError, match="the box 'region 3'"):
        pictures.scene([_fault()], tmp_path / "x.png", title="fault", boxes=[(bounds, "region 3", "red")])
    assert not (tmp_path / "x.png").exists()

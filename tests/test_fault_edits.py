"""The fault edits of the scenario ``merge`` (tgsis.scenarios._fault_edits): smooth, local, as stated (issue 39)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import numpy.typing as npt
import pytest

from tgsis._cfm import synthetic_release
from tgsis.scenarios._fault_edits import FaultFrame, bend_tip, deepen_tip, lengthen_tip


def _fault() -> npt.NDArray[np.float64]:
    """A synthetic fault of the demos' stand-in: 20 km along x (wavy in y), 10 km deep, dipping."""
    return synthetic_release(0)[1].mesh.vertices


def test_the_frame_finds_strike_ends_and_depth() -> None:
    vertices = _fault()
    frame = FaultFrame.of(vertices)
    assert frame.strike[2] == 0.0 and abs(np.linalg.norm(frame.strike) - 1.0) < 1e-12
    # the "northern" end (+1) is the one of larger northing along strike: here the western (the trace rises north-west)
    assert frame.strike[1] > 0 and (frame.end_name(1), frame.end_name(-1)) == ("west", "east")
    ends = frame.along.argmax(), frame.along.argmin()
    assert vertices[ends[0], 1] > vertices[ends[1], 1]
    assert frame.down_dip[2] < 0 and abs(frame.down_dip @ frame.normal) < 1e-12
    assert frame.depth.min() == 0.0 and frame.depth.max() == 1.0
    assert 20_000 <= np.ptp(frame.along) <= 20_500  # 20 km along x, the wavy trace a little longer along strike


@pytest.mark.parametrize(
    ("edit", "size"),
    [(lengthen_tip, 400.0), (deepen_tip, 700.0), (bend_tip, 300.0)],
    ids=["lengthen", "deepen", "bend"],
)
@pytest.mark.parametrize("end", [1, -1])
def test_an_edit_moves_one_end_only_smoothly_and_leaves_the_rest_bit_for_bit(
    edit: Callable[..., tuple[npt.NDArray[np.float64], npt.NDArray[np.bool_]]], size: float, end: int
) -> None:
    vertices = _fault()
    frame = FaultFrame.of(vertices)
    zone = 5_000.0
    moved_to, moved = edit(vertices, frame, end, size, zone)
    assert moved_to.tobytes() != vertices.tobytes()
    assert moved_to[~moved].tobytes() == vertices[~moved].tobytes()  # untouched rows: the same bits
    reach = end * frame.along
    assert np.all(reach[moved] > reach.max() - zone)  # only the zone next to that end
    shift = np.linalg.norm(moved_to - vertices, axis=1)
    if edit is deepen_tip:  # the stated size where the tip meets the base; the vertex nearest there has a little less
        assert 0.95 * size < shift.max() <= size * (1 + 1e-9)
    else:  # the stated size at the tip
        assert shift.max() == pytest.approx(size, rel=1e-9) and shift[np.argmax(reach)] == shift.max()
    # smooth: along the vertices nearest the end, the shift grows with the reach (a half cosine of it)
    top = frame.depth == frame.depth.max() if edit is deepen_tip else frame.depth == 0.0
    row = np.argsort(reach[top])
    assert np.all(np.diff(shift[top][row]) >= -1e-9)

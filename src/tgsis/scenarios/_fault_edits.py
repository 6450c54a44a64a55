"""Smooth, geologically plausible edits of one end of a fault surface (the scenario ``merge``).

Pure numpy. A fault is located by its mean plane (:class:`FaultFrame`): the
strike (the horizontal direction of its longest extent), the down-dip
direction in that plane, each vertex's position along strike and its depth
below the fault's top. Each edit moves only the vertices within ``zone``
metres (along strike) of one end, by a displacement that grows smoothly
(a half cosine) from zero at the zone's inner edge to its full size at the
end: the rest of the fault is left bit for bit as it was.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

_COMPASS = ("east", "north-east", "north", "north-west", "west", "south-west", "south", "south-east")


@dataclass(frozen=True)
class FaultFrame:
    """Where a fault's vertices lie: along strike, down dip, and its two ends.

    Attributes
    ----------
    strike : (3,) float64
        Horizontal unit vector of the longest extent, pointing to the end with the larger northing
        (the "northern" end).
    normal : (3,) float64
        Unit normal of the mean plane, z >= 0.
    down_dip : (3,) float64
        Unit vector in the mean plane, horizontal component normal to strike, pointing down.
    along : (n,) float64
        Each vertex's position along strike (m) from the centroid.
    depth : (n,) float64
        0 at the fault's highest vertex, 1 at its deepest.
    """

    strike: FloatArray
    normal: FloatArray
    down_dip: FloatArray
    along: FloatArray
    depth: FloatArray

    @staticmethod
    def of(vertices: FloatArray) -> FaultFrame:
        """The frame of a fault's (n, 3) vertices (z up)."""
        centred = vertices - vertices.mean(axis=0)
        horizontal = np.linalg.svd(centred[:, :2], full_matrices=False)[2][0]
        if horizontal[1] < 0 or (horizontal[1] == 0 and horizontal[0] < 0):
            horizontal = -horizontal
        strike = np.array([horizontal[0], horizontal[1], 0.0])
        normal = np.linalg.svd(centred, full_matrices=False)[2][2]
        normal = normal if normal[2] >= 0 else -normal
        down = np.array([0.0, 0.0, -1.0]) - normal * -normal[2]  # -z projected into the plane
        top, bottom = float(vertices[:, 2].max()), float(vertices[:, 2].min())
        return FaultFrame(
            strike,
            normal,
            down / np.linalg.norm(down),
            centred @ strike,
            (top - vertices[:, 2]) / max(top - bottom, 1e-9),
        )

    def end_name(self, end: int) -> str:
        """The compass name of end +1 (the northern) or -1 (the southern): ``"north-west"``."""
        x, y = end * self.strike[:2]
        return _COMPASS[int(np.round(np.degrees(np.arctan2(y, x)) / 45.0)) % 8]

    def side_name(self, sign: int) -> str:
        """The compass name of the horizontal direction normal to strike, ``sign`` +1 to the left of the strike."""
        x, y = sign * np.array([-self.strike[1], self.strike[0]])
        return _COMPASS[int(np.round(np.degrees(np.arctan2(y, x)) / 45.0)) % 8]

    def taper(self, end: int, zone: float) -> FloatArray:
        """(n,) weights: 1 at the end (+1 northern, -1 southern), 0 from ``zone`` metres inwards, a half cosine between."""
        reach = end * self.along
        t = np.clip((reach - (reach.max() - zone)) / zone, 0.0, 1.0)
        return np.asarray(0.5 * (1.0 - np.cos(np.pi * t)), dtype=np.float64)


def _moved(vertices: FloatArray, displacement: FloatArray) -> tuple[FloatArray, BoolArray]:
    """``vertices`` plus ``displacement`` where it is not zero (elsewhere the same bits); and which moved."""
    moved = np.any(displacement != 0.0, axis=1)
    result = vertices.copy()
    result[moved] += displacement[moved]
    moved &= np.any(result != vertices, axis=1)  # a displacement below the coordinates' resolution moves nothing
    return result, moved


def lengthen_tip(
    vertices: FloatArray, frame: FaultFrame, end: int, length: float, zone: float
) -> tuple[FloatArray, BoolArray]:
    """The end stretched ``length`` metres outwards along strike (new mapping of the trace beyond the old tip)."""
    weights = frame.taper(end, zone)
    return _moved(vertices, (length * weights)[:, None] * (end * frame.strike)[None, :])


def deepen_tip(
    vertices: FloatArray, frame: FaultFrame, end: int, slide: float, zone: float
) -> tuple[FloatArray, BoolArray]:
    """The end's vertices slid down dip, up to ``slide`` metres at the base, none at the top (a deeper base)."""
    weights = frame.taper(end, zone) * frame.depth
    return _moved(vertices, (slide * weights)[:, None] * frame.down_dip[None, :])


def bend_tip(
    vertices: FloatArray, frame: FaultFrame, end: int, offset: float, zone: float
) -> tuple[FloatArray, BoolArray]:
    """The end bent ``offset`` metres sideways: horizontal, normal to strike, positive to the left of :attr:`strike`."""
    side = np.array([-frame.strike[1], frame.strike[0], 0.0])
    weights = frame.taper(end, zone)
    return _moved(vertices, (offset * weights)[:, None] * side[None, :])

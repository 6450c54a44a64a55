"""The set-up of an interpolation, saved to and loaded from a JSON file.

The thesis's tool kept all set-up data in files for later reuse; so does
tgsis (``tgsis interpolate SOURCE TARGET --setup setup.json``). Vertex
indices are 0-based indices into the source and target meshes as read from
their files (cutting appends copies after them, so the indices stay valid).
Controlling surfaces are named files, resolved relative to the JSON file.

Example::

    {
      "source_controls": [0, 99, 9999, 9900],
      "target_controls": [0, 49, 2499, 2450],
      "source_fences": [[0, 1, 2, ...]], "target_fences": [],
      "cuts": [{"path": [512, 513, 514], "name": "crack"}],
      "controlling_surfaces": {"east": "east_wall.ts"},
      "attachments": [{"vertex": 99, "surfaces": ["east"]}],
      "steps": 10, "tolerance": 0.5
    }
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tgsis.errors import FileFormatError
from tgsis.interpolation.errors import InterpolationSetupError

__all__ = ["Attachment", "CutPath", "InterpolationSetup"]

_KEYS = {
    "source_controls",
    "target_controls",
    "source_fences",
    "target_fences",
    "fence_names",
    "cuts",
    "controlling_surfaces",
    "attachments",
    "steps",
    "tolerance",
}


@dataclass(frozen=True)
class CutPath:
    """A cutting path of the source (vertex indices, consecutive ones sharing an edge) and its name."""

    path: tuple[int, ...]
    name: str | None = None


@dataclass(frozen=True)
class Attachment:
    """A source border vertex glued to one controlling surface, or to two (then it follows their intersection)."""

    vertex: int
    surfaces: tuple[str, ...]


@dataclass(frozen=True)
class InterpolationSetup:
    """Everything the user sets for one interpolation, apart from the two meshes and the times.

    Attributes
    ----------
    source_controls, target_controls : tuple of int
        Control vertices; position i of one corresponds to position i of the other.
    source_fences, target_fences : tuple of tuple of int
        Fence paths (edge paths between two control vertices).
    fence_names : tuple of str, optional
        Names of the source fence paths, for messages.
    cuts : tuple of CutPath
        Cutting paths of the source.
    controlling_surfaces : mapping of str to str
        Name -> mesh file of each controlling surface.
    attachments : tuple of Attachment
    steps : int
        Number m >= 2 of geometry instants from t0 to t1.
    tolerance : float
        ε > 0: largest distance allowed between the compatible target and the target.
    """

    source_controls: tuple[int, ...]
    target_controls: tuple[int, ...]
    source_fences: tuple[tuple[int, ...], ...] = ()
    target_fences: tuple[tuple[int, ...], ...] = ()
    fence_names: tuple[str, ...] | None = None
    cuts: tuple[CutPath, ...] = ()
    controlling_surfaces: Mapping[str, str] = field(default_factory=dict)
    attachments: tuple[Attachment, ...] = ()
    steps: int = 10
    tolerance: float = math.inf

    def __post_init__(self) -> None:
        problems = []
        if len(self.source_controls) != len(self.target_controls):
            problems.append(
                f"{len(self.source_controls)} source control vertices but {len(self.target_controls)} "
                "target ones: they pair up by position"
            )
        if not isinstance(self.steps, int) or self.steps < 2:
            problems.append(f"steps must be an integer >= 2, got {self.steps!r}")
        if not (isinstance(self.tolerance, (int, float)) and self.tolerance > 0):
            problems.append(f"tolerance must be a number > 0, got {self.tolerance!r}")
        for i, attachment in enumerate(self.attachments):
            if not 1 <= len(attachment.surfaces) <= 2:
                problems.append(
                    f"attachment {i} (vertex {attachment.vertex}) names {len(attachment.surfaces)} "
                    "controlling surfaces: one or two"
                )
            unknown = [s for s in attachment.surfaces if s not in self.controlling_surfaces]
            if unknown:
                problems.append(
                    f"attachment {i} (vertex {attachment.vertex}) names unknown controlling surfaces "
                    f"{unknown}; known: {sorted(self.controlling_surfaces)}"
                )
            if len(attachment.surfaces) == 2 and attachment.vertex not in self.source_controls:
                problems.append(
                    f"attachment {i}: vertex {attachment.vertex} follows the intersection of two "
                    "surfaces, so it must be a source control vertex"
                )
        if self.fence_names is not None and len(self.fence_names) != len(self.source_fences):
            problems.append(f"{len(self.fence_names)} fence names for {len(self.source_fences)} source fences")
        if problems:
            raise InterpolationSetupError.collect("the interpolation set-up", problems)

    # ---- JSON

    def to_dict(self) -> dict[str, Any]:
        """The set-up as JSON-ready data."""
        return {
            "source_controls": list(self.source_controls),
            "target_controls": list(self.target_controls),
            "source_fences": [list(p) for p in self.source_fences],
            "target_fences": [list(p) for p in self.target_fences],
            **({"fence_names": list(self.fence_names)} if self.fence_names is not None else {}),
            "cuts": [{"path": list(c.path), **({"name": c.name} if c.name else {})} for c in self.cuts],
            "controlling_surfaces": dict(self.controlling_surfaces),
            "attachments": [{"vertex": a.vertex, "surfaces": list(a.surfaces)} for a in self.attachments],
            "steps": self.steps,
            **({"tolerance": self.tolerance} if math.isfinite(self.tolerance) else {}),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], *, where: str = "the set-up") -> InterpolationSetup:
        """A set-up from :meth:`to_dict` data; unknown keys and bad values are errors naming them."""
        if not isinstance(data, Mapping):
            raise FileFormatError(f"{where}: a set-up is a JSON object, not {type(data).__name__}")
        unknown = sorted(set(data) - _KEYS)
        if unknown:
            raise FileFormatError(f"{where}: unknown keys {unknown}", hint=f"known keys: {sorted(_KEYS)}")
        for required in ("source_controls", "target_controls"):
            if required not in data:
                raise FileFormatError(f"{where}: {required!r} is missing")
        try:
            return cls(
                source_controls=_indices(data["source_controls"], "source_controls"),
                target_controls=_indices(data["target_controls"], "target_controls"),
                source_fences=tuple(
                    _indices(p, f"source_fences[{i}]") for i, p in enumerate(data.get("source_fences", []))
                ),
                target_fences=tuple(
                    _indices(p, f"target_fences[{i}]") for i, p in enumerate(data.get("target_fences", []))
                ),
                fence_names=tuple(str(n) for n in data["fence_names"]) if "fence_names" in data else None,
                cuts=tuple(
                    CutPath(_indices(c["path"], f"cuts[{i}].path"), c.get("name"))
                    for i, c in enumerate(data.get("cuts", []))
                ),
                controlling_surfaces={str(k): str(v) for k, v in dict(data.get("controlling_surfaces", {})).items()},
                attachments=tuple(
                    Attachment(int(a["vertex"]), tuple(str(s) for s in a["surfaces"]))
                    for a in data.get("attachments", [])
                ),
                steps=int(data.get("steps", 10)),
                tolerance=float(data.get("tolerance", math.inf)),
            )
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise FileFormatError(f"{where}: {type(exc).__name__}: {exc}") from None

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the set-up as JSON; returns the path."""
        target = Path(path)
        target.write_text(json.dumps(self.to_dict(), indent=2) + "\n")
        return target

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> InterpolationSetup:
        """Read a set-up written by :meth:`save` (or by hand); controlling surfaces resolve beside the file."""
        source = Path(path)
        try:
            data = json.loads(source.read_text())
        except OSError as exc:
            raise FileFormatError(f"{source}: cannot read the set-up: {exc.strerror or exc}") from None
        except json.JSONDecodeError as exc:
            raise FileFormatError(f"{source}: not JSON: {exc}") from None
        setup = cls.from_dict(data, where=str(source))
        resolved = {name: str((source.parent / file).resolve()) for name, file in setup.controlling_surfaces.items()}
        return cls(**{**setup.__dict__, "controlling_surfaces": resolved})


def _indices(values: Sequence[Any], what: str) -> tuple[int, ...]:
    """Vertex indices: non-negative integers (JSON numbers like 3.0 are refused, they are not indices)."""
    if isinstance(values, (str, bytes)) or not isinstance(values, Sequence):
        raise ValueError(f"{what} must be a list of vertex indices")
    out = []
    for value in values:
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            raise ValueError(f"{what} holds {value!r}, not a vertex index")
        out.append(value)
    return tuple(out)

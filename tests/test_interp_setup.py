"""The interpolation set-up: JSON round trip and the mistakes it names."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import tgsis
from tgsis.interpolation import InterpolationSetupError
from tgsis.interpolation.setup import Attachment, CutPath, InterpolationSetup


def _setup() -> InterpolationSetup:
    return InterpolationSetup(
        source_controls=(0, 9, 99, 90),
        target_controls=(0, 4, 24, 20),
        source_fences=((0, 11, 22),),
        target_fences=((0, 6, 12),),
        fence_names=("diagonal",),
        cuts=(CutPath((45, 46, 47), "crack"),),
        controlling_surfaces={"east": "east.ts", "top": "top.ts"},
        attachments=(Attachment(9, ("east",)), Attachment(99, ("east", "top"))),
        steps=7,
        tolerance=0.25,
    )


def test_round_trip_through_a_file(tmp_path: Path) -> None:
    setup = _setup()
    path = setup.save(tmp_path / "setup.json")
    loaded = InterpolationSetup.load(path)
    assert loaded.controlling_surfaces == {"east": str(tmp_path / "east.ts"), "top": str(tmp_path / "top.ts")}
    assert {**loaded.__dict__, "controlling_surfaces": setup.controlling_surfaces} == setup.__dict__
    assert json.loads(path.read_text())["cuts"] == [{"path": [45, 46, 47], "name": "crack"}]
    # no tolerance means no refinement limit, and is left out of the file
    plain = InterpolationSetup((0, 1, 2), (0, 1, 2))
    assert "tolerance" not in plain.to_dict() and InterpolationSetup.from_dict(plain.to_dict()) == plain


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"target_controls": (0, 4, 24)}, "4 source control vertices but 3 target ones"),
        ({"steps": 1}, "steps must be an integer >= 2"),
        ({"tolerance": 0.0}, "tolerance must be a number > 0"),
        ({"attachments": (Attachment(9, ("west",)),)}, "attachment 0 (vertex 9) names unknown controlling surfaces"),
        ({"attachments": (Attachment(45, ("east", "top")),)}, "vertex 45 follows the intersection of two surfaces"),
        ({"attachments": (Attachment(9, ()),)}, "names 0 controlling surfaces"),
        ({"fence_names": ("a", "b")}, "2 fence names for 1 source fences"),
    ],
)
def test_mistakes_are_named(change: dict[str, object], message: str) -> None:
    with pytest.raises(InterpolationSetupError, match=message.replace("(", r"\(").replace(")", r"\)")):
        InterpolationSetup(**{**_setup().__dict__, **change})


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[1, 2]", "a set-up is a JSON object"),
        ('{"source_controls": [0, 1, 2]}', "'target_controls' is missing"),
        ('{"source_controls": [0, 1, 2], "target_controls": [0, 1, 2], "fences": []}', "unknown keys \\['fences'\\]"),
        ('{"source_controls": [0, 1.0, 2], "target_controls": [0, 1, 2]}', "source_controls holds 1.0"),
        ('{"source_controls": [0, 1, 2], "target_controls": [0, 1, -2]}', "target_controls holds -2"),
        ('{"source_controls": [0, 1, 2], "target_controls": [0, 1, 2], "cuts": [{"name": "x"}]}', "KeyError"),
        ("{not json", "not JSON"),
    ],
)
def test_bad_files(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "bad.json"
    path.write_text(text)
    with pytest.raises(tgsis.FileFormatError, match=message):
        InterpolationSetup.load(path)

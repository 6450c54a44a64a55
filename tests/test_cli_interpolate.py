"""`tgsis interpolate` and `tgsis corners`: files in, a model-3 feature and previews out."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import psycopg
import pytest

import tgsis
from tests.test_interp_end_to_end import _dome, _flat, _flat_corners
from tgsis import formats
from tgsis.cli import main
from tgsis.interpolation import InterpolationSetup


def test_interpolate_from_files_into_a_class(db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    source, (target, corners) = _flat(13, 7), _dome()
    formats.write(source, tmp_path / "flat.ts")
    formats.write(target, tmp_path / "dome.ts")
    # the corners command proposes the control vertices of both
    assert main(["corners", str(tmp_path / "flat.ts")]) == 0
    proposed = json.loads(capsys.readouterr().out)
    assert sorted(proposed) == sorted(_flat_corners(13, 7))
    assert main(["corners", str(tmp_path / "dome.ts"), "--count", "4"]) == 0
    assert sorted(json.loads(capsys.readouterr().out)) == sorted(corners)
    InterpolationSetup(tuple(_flat_corners(13, 7)), tuple(corners), steps=4, tolerance=0.1).save(tmp_path / "s.json")
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "domes", "SURFACE", time_model="EVOLVING", time_unit="Ma")
    argv = [
        "--dsn",
        db_dsn,
        "interpolate",
        str(tmp_path / "flat.ts"),
        str(tmp_path / "dome.ts"),
        "--setup",
        str(tmp_path / "s.json"),
        "--t0=-5",
        "--t1",
        "0",
        "--class",
        "domes",
        "--preview",
        str(tmp_path / "png"),
        "--frames",
        "3",
    ]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "interpolated flat:" in out and "m = 4" in out and "3 previews in" in out
    assert (
        "stored as feature 1 of class domes: the source (flat) at t = -5 Ma, the target at t = 0 Ma; it exists "
        "from t = -5 to 0 Ma" in out
    )
    pngs = sorted((tmp_path / "png").glob("*.png"))
    assert len(pngs) == 3 and all(p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for p in pngs)
    with psycopg.connect(db_dsn) as conn:
        end = tgsis.get_at(conn, 1, 0.0)
    assert end is not None and np.abs(end.vertices[:, 2]).max() > 0.5  # the dome at t1


def test_interpolate_split_chooses_the_refinement(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`--split centroid` is the design's refinement (more vertices here than the default edge bisection)."""
    source, (target, corners) = _flat(13, 7), _dome()
    formats.write(source, tmp_path / "flat.ts")
    formats.write(target, tmp_path / "dome.ts")
    InterpolationSetup(tuple(_flat_corners(13, 7)), tuple(corners), steps=2, tolerance=0.05).save(tmp_path / "s.json")
    argv = [
        "interpolate",
        str(tmp_path / "flat.ts"),
        str(tmp_path / "dome.ts"),
        "--setup",
        str(tmp_path / "s.json"),
        "--t0",
        "0",
        "--t1",
        "1",
    ]
    assert main(argv) == 0
    assert "interpolated flat: 99 vertices" in capsys.readouterr().out
    assert main([*argv, "--split", "centroid"]) == 0
    assert "interpolated flat: 103 vertices" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main([*argv, "--split", "middle"])
    assert "--split" in capsys.readouterr().err


def test_a_backward_interpolation_says_when_the_feature_exists(
    db_dsn: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--t0 1 --t1 0 (the source is the later shape): said as given, and the span it exists in, earlier time first."""
    source, (target, corners) = _flat(13, 7), _dome()
    formats.write(source, tmp_path / "flat.ts")
    formats.write(target, tmp_path / "dome.ts")
    InterpolationSetup(tuple(_flat_corners(13, 7)), tuple(corners), steps=2, tolerance=0.1).save(tmp_path / "s.json")
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "domes", "SURFACE", time_model="EVOLVING", time_unit="Ma")
    assert (
        main(
            [
                "--dsn",
                db_dsn,
                "interpolate",
                str(tmp_path / "flat.ts"),
                str(tmp_path / "dome.ts"),
                "--setup",
                str(tmp_path / "s.json"),
                "--t0",
                "1",
                "--t1",
                "0",
                "--class",
                "domes",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert (
        "stored as feature 1 of class domes: the source (flat) at t = 1 Ma, the target at t = 0 Ma; it exists "
        "from t = 0 to 1 Ma"
    ) in out
    with psycopg.connect(db_dsn) as conn:
        span = tgsis.lifespan(conn, 1)
        assert span is not None and span[:2] == (0.0, 1.0)


def test_interpolate_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    formats.write(_flat(5, 4), tmp_path / "flat.ts")
    formats.write(tgsis.LineSet([[0, 0, 0], [1, 0, 0]], [[0, 1]]), tmp_path / "line.pl")
    (tmp_path / "s.json").write_text('{"source_controls": [0, 4, 19], "target_controls": [0, 4]}')
    cases = [
        (
            [
                "interpolate",
                str(tmp_path / "line.pl"),
                str(tmp_path / "flat.ts"),
                "--setup",
                str(tmp_path / "s.json"),
                "--t0",
                "0",
                "--t1",
                "1",
            ],
            "holds a LineSet",
        ),
        (
            [
                "interpolate",
                str(tmp_path / "flat.ts"),
                str(tmp_path / "flat.ts"),
                "--setup",
                str(tmp_path / "s.json"),
                "--t0",
                "0",
                "--t1",
                "1",
            ],
            "3 source control vertices but 2 target ones",
        ),
        (
            [
                "interpolate",
                str(tmp_path / "flat.ts"),
                str(tmp_path / "flat.ts"),
                "--setup",
                str(tmp_path / "no.json"),
                "--t0",
                "0",
                "--t1",
                "1",
            ],
            "cannot read the set-up",
        ),
    ]
    for argv, message in cases:
        assert main(argv) == 1, argv
        err = capsys.readouterr().err
        assert err.startswith("tgsis: error: ") and message in err and "Traceback" not in err, (argv, err)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["corners", "{file}", "--count", "0"], "--count must be >= 1, got 0"),
        (["corners", "{file}", "--min-angle", "nan"], "--min-angle must be from 0 to 180 degrees, got nan"),
        (
            [
                "interpolate",
                "{file}",
                "{file}",
                "--setup",
                "{file}",
                "--t0",
                "0",
                "--t1",
                "1",
                "--preview",
                "{dir}",
                "--frames",
                "-1",
            ],
            "--frames must be from 1 to 1000, got -1",
        ),
    ],
)
def test_bad_option_values_name_the_flag(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], message: str
) -> None:
    # before: --count 0 and --min-angle nan gave corners anyway, --frames -1 a numpy traceback after the work
    surface = tmp_path / "flat.ts"
    formats.write(_flat(5, 4), surface)
    assert main([a.format(file=surface, dir=tmp_path / "previews") for a in argv]) == 1
    assert message in capsys.readouterr().err
    assert not (tmp_path / "previews").exists()

"""The `tgsis` command in a pipe and on a terminal: `| head`, progress bars, full coordinates."""

from __future__ import annotations

import fcntl
import os
import pty
import select
import signal
import struct
import subprocess
import sys
import termios
from pathlib import Path

import numpy as np
import psycopg
import pytest

import tgsis
from tests.local_helpers import child_env
from tests.temporal_data import evolving
from tgsis.cli import main

TGSIS = str(Path(sys.executable).parent / "tgsis")
FLAGGED = Path(__file__).parent / "data" / "gocad" / "flagged.ts"


def test_a_checkin_piped_into_head_exits_0_and_keeps_its_record(db_dsn: str, tmp_path: Path) -> None:
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "faults", "SURFACE")
        fid = tgsis.insert_feature(conn, "faults", tgsis.formats.read(FLAGGED)[1])
    path = tmp_path / "f.ts"
    env = child_env()
    assert (
        subprocess.run(
            [TGSIS, "--dsn", db_dsn, "checkout", str(fid), str(path)], env=env, capture_output=True, check=False
        ).returncode
        == 0
    )
    mesh = tgsis.formats.read_one(path)
    mesh.vertices[0, 2] += 1.0
    tgsis.formats.write(mesh, path)
    # a real pipe whose reader is gone before the command writes: every line is a broken pipe
    read, write = os.pipe()
    os.close(read)
    result = subprocess.run(
        [TGSIS, "--dsn", db_dsn, "checkin", str(path)],
        env=env,
        stdout=write,
        stderr=subprocess.PIPE,
        text=True,
        check=False,
    )
    os.close(write)
    assert result.returncode == 0 and "Traceback" not in result.stderr and "BrokenPipe" not in result.stderr, (
        result.stderr
    )
    # the record followed the check-in: a second edit checks in without a conflict
    mesh.vertices[1, 2] += 1.0
    tgsis.formats.write(mesh, path)
    again = subprocess.run(
        [TGSIS, "--dsn", db_dsn, "checkin", str(path)], env=env, capture_output=True, text=True, check=False
    )
    assert again.returncode == 0, again.stderr
    # and `ls | head -1` with many lines
    with psycopg.connect(db_dsn) as conn:
        for _ in range(300):
            tgsis.insert_feature(conn, "faults", tgsis.formats.read(FLAGGED)[1])
    shell = subprocess.run(
        f"set -o pipefail; '{TGSIS}' --dsn '{db_dsn}' ls | head -1",
        shell=True,
        executable="/bin/bash",
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert (
        shell.returncode == 0
        and shell.stdout == "id\tclass\tname\tgeotype\tvertices\tcells\tmembers\tdarts\tproperties\n"
    )
    assert shell.stderr == ""


def _on_a_terminal(argv: list[str]) -> tuple[int, str, str]:
    """Run tgsis with stderr on a pseudo-terminal; return its exit status, stdout and what the terminal got."""
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))  # a terminal 100 columns wide
    run = subprocess.Popen([TGSIS, *argv], env=child_env(), stdout=subprocess.PIPE, stderr=slave)
    os.close(slave)
    seen = b""
    while True:
        ready, _, _ = select.select([master], [], [], 60)
        if not ready:
            break
        try:
            chunk = os.read(master, 65536)
        except OSError:
            break
        if not chunk:
            break
        seen += chunk
    out = run.stdout.read().decode() if run.stdout else ""
    os.close(master)
    return run.wait(60), out, seen.decode(errors="replace")


def test_progress_on_a_terminal_and_none_in_a_pipe(db_dsn: str, tmp_path: Path) -> None:
    moving = evolving(np.random.default_rng(3), [-10.0, -6.5], instants_per_period=3, with_properties=True)
    with psycopg.connect(db_dsn) as conn:
        fc = tgsis.create_feature_class(
            conn,
            "moving",
            "SURFACE",
            time_model="EVOLVING",
            time_unit="Ma",
            cell_properties=[("porosity", "double precision")],
            instant_properties=[("throw", "double precision"), ("note_code", "integer")],
        )
        fid = tgsis.insert_feature(conn, fc, moving)
    argv = ["--dsn", db_dsn, "series", str(fid), str(tmp_path / "s"), "--from", "-10", "--to", "-7", "--steps", "40"]
    code, out, terminal = _on_a_terminal(argv)
    assert code == 0, terminal
    assert "writing frames" in terminal and "40/40" in terminal  # tqdm's bar
    piped = subprocess.run([TGSIS, *argv], env=child_env(), capture_output=True, text=True, check=False)
    assert piped.returncode == 0 and piped.stderr == ""  # nothing extra when not a terminal
    assert piped.stdout == out  # stdout is the same either way


def test_corners_print_every_digit(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """UTM-scale coordinates: 6 significant digits would be ~10 m off; repr gives the float back exactly."""
    n = 6
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    vertices = np.column_stack(
        [x.ravel() * 1234.567 + 326126.2968812, y.ravel() * 987.6543 + 3762345.123456789, np.full(n * n, -1234.56789)]
    )
    cells = [[i * n + j, i * n + j + 1, (i + 1) * n + j] for i in range(n - 1) for j in range(n - 1)] + [
        [i * n + j + 1, (i + 1) * n + j + 1, (i + 1) * n + j] for i in range(n - 1) for j in range(n - 1)
    ]
    path = tmp_path / "grid.ts"
    tgsis.formats.write(tgsis.Surface(vertices, cells), path)
    stored = tgsis.formats.read_one(path).vertices
    assert main(["corners", str(path)]) == 0
    out, err = capsys.readouterr()
    corners = [int(v) for v in out.strip("[]\n").split(",")]
    lines = err.splitlines()
    assert len(lines) == len(corners) >= 3
    for vertex, line in zip(corners, lines):
        label, coordinates = line.split(": ")
        assert label == f"vertex {vertex}"
        assert [float(c) for c in coordinates.split()] == stored[vertex].tolist()  # bit for bit
    assert main(["corners", str(path), "--json"]) == 0
    import json

    doc = json.loads(capsys.readouterr().out)
    assert [c["vertex"] for c in doc["corners"]] == corners and doc["corners"][0]["xyz"] == stored[corners[0]].tolist()


def test_the_command_called_in_a_program_gives_its_sigterm_handler_back(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``main`` stops on SIGTERM while it runs, then leaves the caller's handler (pytest's: CI's timeout stops it)."""

    def callers(signum: int, frame: object) -> None:
        raise AssertionError("not called")

    before = signal.signal(signal.SIGTERM, callers)
    try:
        path = tmp_path / "one.ts"
        tgsis.formats.write(tgsis.Surface([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [[0, 1, 2]]), path)
        assert main(["corners", str(path)]) == 0
        assert signal.getsignal(signal.SIGTERM) is callers
    finally:
        signal.signal(signal.SIGTERM, before)
    capsys.readouterr()


def test_interpolation_and_import_show_progress_on_a_terminal(db_dsn: str, tmp_path: Path) -> None:
    from tests.test_interp_end_to_end import _dome, _flat, _flat_corners
    from tgsis.interpolation import InterpolationSetup, interpolate

    source, (target, corners) = _flat(13, 7), _dome()
    setup = InterpolationSetup(tuple(_flat_corners(13, 7)), tuple(corners), steps=4, tolerance=0.1)
    calls: list[tuple[int, int]] = []
    interpolate(source, target, setup, 0.0, 1.0, progress=lambda done, total: calls.append((done, total)))
    assert [done for done, _ in calls] == list(range(1, len(calls) + 1)) and calls[-1][0] == calls[-1][1] >= 5
    tgsis.formats.write(source, tmp_path / "flat.ts")
    tgsis.formats.write(target, tmp_path / "dome.ts")
    setup.save(tmp_path / "s.json")
    code, out, terminal = _on_a_terminal(
        [
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
    )
    assert code == 0, terminal
    assert "interpolating flat" in terminal and f"{calls[-1][0]}/{calls[-1][1]}" in terminal
    assert "interpolated flat:" in out
    with psycopg.connect(db_dsn) as conn:
        tgsis.create_feature_class(conn, "faults", "SURFACE")
    code, out, terminal = _on_a_terminal(["--dsn", db_dsn, "import", str(FLAGGED), "--class", "faults"])
    assert code == 0, terminal
    assert "uploading objects" in terminal and "2/2" in terminal

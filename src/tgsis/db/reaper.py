"""Stop a local PostgreSQL server when the process that started it goes away.

Run as a script (``python reaper.py ...``, never imported by tgsis) in a
session of its own, so that Ctrl-C in the terminal does not reach it. Its
standard input is a pipe whose write end only the owning process holds: the
read returns end-of-file when the owner closes it (normal release) or dies
(Ctrl-C, SIGTERM, SIGKILL, a crash). Then:

* ``--mode throwaway``: stop the server at once and remove its whole folder
  (test clusters);
* ``--mode lease``: under the transition lock, if no other process holds a
  lease on the server (an exclusive ``flock`` on the lease file succeeds) and
  the server was started implicitly, stop it; a server started by
  ``tgsis local start`` stays up.

A dying owner releases its files in the order the kernel chooses: the pipe
may reach end-of-file a moment *before* the owner's ``flock`` on the lease
file is gone, and a look at the lease file then would see the dead owner as
another user and leave the server running (1 run in 3 under load). So the
reaper tells the two ends apart: an owner that lets go normally writes
:data:`RELEASED` first (it has closed its lease file already); without it the
owner died, and the reaper waits until it has been re-parented (the kernel
re-parents children after it has closed every file of the dead process, flock
locks included) before it looks.

Standard library only: it must start fast and must not import tgsis.
"""

from __future__ import annotations

import argparse
import contextlib
import fcntl
import json
import os
import shutil
import signal
import subprocess
import sys
import time

#: What an owner writes to the pipe before closing it when it lets go normally.
RELEASED = b"released\n"

#: Longest wait for a dead owner to be re-parented (its files released), in seconds.
OWNER_EXIT_WAIT = 30.0


def _stop(pg_ctl: str, data: str, mode: str, uid: int | None, gid: int | None) -> None:
    """``pg_ctl stop`` in ``mode``; a fast shutdown that fails or times out is followed by an immediate one."""
    if not os.path.exists(os.path.join(data, "postmaster.pid")):
        return
    done = subprocess.run(  # noqa: S603 - fixed argument list
        [pg_ctl, "stop", "-D", data, "-m", mode, "-w", "-t", "60"],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        cwd="/",
        check=False,
        user=uid,
        group=gid,
        extra_groups=[] if uid is not None else None,
    )
    if done.returncode != 0 and mode != "immediate":
        _stop(pg_ctl, data, "immediate", uid, gid)


def _wait_for_owner_exit(owner: int | None) -> None:
    """Return once the dead ``owner`` no longer is our parent: by then its files, flocks included, are closed."""
    if owner is None:
        return
    deadline = time.monotonic() + OWNER_EXIT_WAIT
    while os.getppid() == owner and time.monotonic() < deadline:
        time.sleep(0.005)


def _implicitly_started(state_file: str) -> bool:
    try:
        with open(state_file, encoding="utf-8") as handle:
            return bool(json.load(handle).get("started_by") == "implicit")
    except (OSError, ValueError):
        return False


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--pg-ctl", required=True)
    parser.add_argument("--data", required=True)
    parser.add_argument("--root", required=True)
    parser.add_argument("--mode", choices=("throwaway", "lease"), required=True)
    parser.add_argument("--lock-file")
    parser.add_argument("--transition-lock-file")
    parser.add_argument("--state-file")
    parser.add_argument("--uid", type=int)
    parser.add_argument("--gid", type=int)
    parser.add_argument("--owner-pid", type=int, help="the process whose end the reaper waits for (its parent)")
    args = parser.parse_args(argv)

    for sig in (signal.SIGINT, signal.SIGHUP, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)

    tail = b""
    while chunk := sys.stdin.buffer.read(65536):
        tail = (tail + chunk)[-len(RELEASED) :]
    if tail != RELEASED:  # the owner died: its lease may outlive the pipe for a moment
        _wait_for_owner_exit(args.owner_pid)

    if args.mode == "throwaway":
        _stop(args.pg_ctl, args.data, "immediate", args.uid, args.gid)
        shutil.rmtree(args.root, ignore_errors=True)
        return 0

    # The same protocol as LocalServer: decide inside the transition lock, stop
    # only when no other process holds the lease file.
    transition = os.open(args.transition_lock_file, os.O_RDWR | os.O_CREAT, 0o644)
    lease = os.open(args.lock_file, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(transition, fcntl.LOCK_EX)
        try:
            fcntl.flock(lease, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return 0  # another process still uses the server; the last one stops it
        if _implicitly_started(args.state_file):
            _stop(args.pg_ctl, args.data, "fast", args.uid, args.gid)
            with contextlib.suppress(FileNotFoundError):
                os.unlink(args.state_file)
    finally:
        os.close(lease)
        os.close(transition)
    return 0


if __name__ == "__main__":
    sys.exit(main())

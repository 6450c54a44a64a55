"""Progress of the ``tgsis`` command on standard error: a bar over counted steps, a spinner over one long step.

Both are shown only when standard error is a terminal (:func:`on_terminal`);
in a pipe or a log file nothing is printed. Bars are removed when the work ends.
"""

from __future__ import annotations

import contextlib
import sys
import threading
from collections.abc import Callable, Iterator
from typing import Any


def on_terminal() -> bool:
    """Whether standard error is a terminal (progress is shown only then)."""
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


@contextlib.contextmanager
def progress(description: str, total: int | None, unit: str = "it") -> Iterator[Callable[[int, int], None]]:
    """A callback ``(done, total)`` that moves a progress bar on standard error, when it is a terminal.

    Not on a terminal, the callback does nothing and nothing is printed. The
    bar is removed when the work ends.
    """
    if not on_terminal():
        yield lambda done, count: None
        return
    from tqdm import tqdm

    bar = tqdm(total=total, desc=description, unit=unit, file=sys.stderr, leave=False, dynamic_ncols=True)
    lock = threading.Lock()

    def moved(done: int, count: int) -> None:
        with lock:
            if bar.total != count:
                bar.total = count
            bar.n = done
            bar.refresh()

    try:
        with _ticking(bar, lock):  # the time elapsed moves on during one long step too
            yield moved
    finally:
        bar.close()


@contextlib.contextmanager
def _ticking(bar: Any, lock: threading.Lock) -> Iterator[None]:
    """Refresh ``bar`` a few times a second while the block runs."""
    stop = threading.Event()

    def tick() -> None:
        while not stop.wait(0.2):
            with lock:
                bar.refresh()

    ticker = threading.Thread(target=tick, daemon=True)
    ticker.start()
    try:
        yield
    finally:
        stop.set()
        ticker.join()


@contextlib.contextmanager
def busy(description: str) -> Iterator[None]:
    """A spinner with the time elapsed on standard error while one long step runs (terminal only)."""
    if not on_terminal():
        yield
        return
    from tqdm import tqdm

    bar = tqdm(total=None, desc=description, file=sys.stderr, leave=False, bar_format="{desc}: {elapsed}")
    try:
        with _ticking(bar, threading.Lock()):
            yield
    finally:
        bar.close()

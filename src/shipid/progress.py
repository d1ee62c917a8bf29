"""Progress bars (rich) for anything that may take more than a second.

Bars go to stderr, so ``--json`` output on stdout stays clean, and are hidden
when stderr is not a terminal (CI logs, pipes) or ``SHIPID_NO_PROGRESS`` is set.
"""

from __future__ import annotations

import os
import sys
from contextlib import contextmanager
from typing import Iterator

from rich.console import Console
from rich.progress import (BarColumn, MofNCompleteColumn, Progress, ProgressColumn, TaskProgressColumn,
                           TextColumn, TimeElapsedColumn, TimeRemainingColumn)
from rich.text import Text


class RateColumn(ProgressColumn):
    """Items per second (rich's own speed column formats bytes)."""

    def render(self, task) -> Text:
        speed = task.finished_speed or task.speed
        if speed is None:
            return Text("-/s", style="progress.data.speed")
        return Text(f"{speed:.3g}/s" if speed < 1000 else f"{speed:,.0f}/s", style="progress.data.speed")


def _enabled() -> bool:
    return sys.stderr.isatty() and not os.environ.get("SHIPID_NO_PROGRESS")


@contextmanager
def progress_bar(total: int, description: str, completed: int = 0) -> Iterator:
    """Yield ``advance(k=1)``; shows a bar with count, rate and ETA when interactive.

    ``completed`` items (e.g. runs resumed from a store) count as done without
    entering the rate and ETA.
    """
    if not _enabled():
        yield lambda k=1: None
        return
    prog = Progress(TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
                    TaskProgressColumn(), RateColumn(), TimeElapsedColumn(), TimeRemainingColumn(),
                    console=Console(stderr=True), transient=False)
    with prog:
        task = prog.add_task(description, total=total, completed=completed)
        yield lambda k=1: prog.advance(task, k)

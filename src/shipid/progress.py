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
from rich.progress import (BarColumn, MofNCompleteColumn, Progress, TaskProgressColumn, TextColumn,
                           TimeElapsedColumn, TimeRemainingColumn)


def _enabled() -> bool:
    return sys.stderr.isatty() and not os.environ.get("SHIPID_NO_PROGRESS")


@contextmanager
def progress_bar(total: int, description: str) -> Iterator:
    """Yield ``advance(k=1)``; shows a bar with count, rate and ETA when interactive."""
    if not _enabled():
        yield lambda k=1: None
        return
    prog = Progress(TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
                    TaskProgressColumn(), TimeElapsedColumn(), TimeRemainingColumn(),
                    console=Console(stderr=True), transient=False)
    with prog:
        task = prog.add_task(description, total=total)
        yield lambda k=1: prog.advance(task, k)

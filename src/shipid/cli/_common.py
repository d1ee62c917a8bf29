"""Loud failures on the command line: one mechanism for every command.

Whatever a user must not miss about a result — the estimator did not converge, an
estimate is implausible or flagged, a coefficient the data do not determine, a
repair made to the input data, any Python warning raised inside a method — is

* printed as one line on stderr, ``shipid: warning: <text>`` (never Python's
  ``file.py:123: RuntimeWarning: ...`` with a source path and a code line),
* recorded in the result's JSON (``result.diagnostics["warnings"]``, or the
  ``"warnings"`` list of a command whose output is a plain table), and
* under ``shipid --strict CMD ...`` (an option of ``shipid`` itself, not of a
  command) turned into exit status 3 once the command has written its output.

:func:`shipid.cli.main` records every Python warning of the command
(:func:`recording`); a command hands its :class:`~shipid.result.Result` to
:func:`loud` before it writes or prints it, which moves the warnings recorded so
far into the result, adds those the result itself implies and prints each one
once. Warnings recorded but never claimed by a command are printed by ``main``
at the end, in the same format.

Outputs follow one convention (:func:`out_options`): ``--json`` prints the result as JSON
on stdout, ``-o/--out FILE`` writes it atomically (:mod:`shipid.outputs`) and refuses
to overwrite an existing FILE without ``--force`` (one line, exit status 2, checked
before any work is done); :func:`emit` does both.
"""

from __future__ import annotations

import functools
import json
import warnings
from pathlib import Path
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Iterator

import click

# the lines themselves are the library's (every face of a method reports the same ones)
from shipid.warning_lines import QUIET as _QUIET  # noqa: F401
from shipid.warning_lines import (UNDETERMINED, collect, implied_warnings, one_line,  # noqa: F401
                                      python_warnings, repair_warnings)

#: Exit status of a command that warned under ``--strict``.
STRICT_EXIT = 3
PREFIX = "shipid: warning: "


@dataclass
class _Session:
    strict: bool = False
    emitted: list[str] = field(default_factory=list)
    recorded: list | None = None
    claimed: int = 0


_S = _Session()


def set_strict(ctx: click.Context | None = None, param: Any = None, value: bool = True) -> bool:
    """Turn ``--strict`` on for this invocation (the click callback of ``shipid --strict``)."""
    if value:
        _S.strict = True
    return value


#: Spellings no command accepts, each with the option that replaces it: ``shipid`` answers
#: them with one line saying what to type instead (:func:`moved_option`).
MOVED_OPTIONS = {
    "--strict": "--strict is an option of shipid itself: put it before the command",
    "--output": "write -o/--out FILE",
    "--jsonl": "write --json",
    "--seconds": "write --duration S",
}


def moved_option(err: click.NoSuchOption) -> str | None:
    """The one-line error for an option of :data:`MOVED_OPTIONS` given where no command takes it, else ``None``.

    For ``--strict`` after a command the line shows where it goes (``shipid --strict validate ...``).
    """
    name = err.option_name
    if name not in MOVED_OPTIONS:
        return None
    cmd = err.ctx.command_path.partition(" ")[2] if err.ctx is not None else ""
    text = f"no such option{f' of {cmd!r}' if cmd else ''}: {name}; {MOVED_OPTIONS[name]}"
    if name == "--strict" and cmd:
        text += f" (shipid --strict {cmd} ...)"
    return text


def warn(text: str) -> None:
    """Print ``shipid: warning: text`` on stderr (once per distinct text) and count it for ``--strict``."""
    line = one_line(text)
    if line in _S.emitted:
        return
    _S.emitted.append(line)
    click.echo(PREFIX + line, err=True)


@contextmanager
def recording() -> Iterator[None]:
    """Record every Python warning raised inside (used by :func:`shipid.cli.main` around a command)."""
    prev, prev_claimed = _S.recorded, _S.claimed
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        for cat in _QUIET:
            warnings.simplefilter("ignore", cat)
        _S.recorded, _S.claimed = rec, 0
        try:
            yield
        finally:
            _S.recorded, _S.claimed = prev, prev_claimed


def take_python_warnings() -> list[str]:
    """The Python warnings recorded since the last call, as distinct one-line texts (counts appended)."""
    rec = _S.recorded
    if rec is None:
        return []
    new = rec[_S.claimed:]
    _S.claimed = len(rec)
    return python_warnings(new)


def loud(res, *, trials: Iterable = (), extra: Iterable[str] = ()) -> list[str]:
    """Move recorded Python warnings, implied warnings and data repairs into ``res`` and print them.

    Call it before the result is written or printed, so that its JSON carries every
    warning. Returns the full warning list of the result.
    """
    lst = collect(res, trials=trials, extra=extra, python=take_python_warnings())
    for w in lst:
        warn(w)
    return lst


def loud_lines(lines: Iterable[str], *, trials: Iterable = ()) -> list[str]:
    """:func:`loud` for a command whose output is not a Result: returns the list for its JSON."""
    lst: list[str] = []
    for w in [*take_python_warnings(), *repair_warnings(trials), *lines]:
        w = one_line(w)
        if w not in lst:
            lst.append(w)
    for w in lst:
        warn(w)
    return lst


def begin(strict: bool = False) -> None:
    """Reset the per-invocation state (``main`` calls it first)."""
    _S.strict = bool(strict)
    _S.emitted = []


def finish(rv: int) -> int:
    """Print the Python warnings no command claimed; exit 3 under ``--strict`` if anything warned."""
    for w in take_python_warnings():
        warn(w)
    if rv == 0 and _S.strict and _S.emitted:
        n = len(_S.emitted)
        click.echo(f"shipid: error: {n} warning{'s' if n > 1 else ''} and --strict: exit status {STRICT_EXIT}",
                   err=True)
        return STRICT_EXIT
    return rv


def emitted() -> list[str]:
    """The warning lines printed so far in this invocation."""
    return list(_S.emitted)


# ----------------------------------------------------------------------------- reading trials
CHANNELS_HELP = ("Map the files' columns onto standard channels, NAME=COLUMN,... (e.g. "
                 "'t=Time,psi=Heading,U=Speed'); COLUMN as in the header, with or without its unit; "
                 "'psi=hdg[deg]' gives a unit the header lacks. Applies to every trial file of the command.")


def channels_option(f: Callable | None = None, *, help: str = CHANNELS_HELP):
    """Click decorator: ``--channels MAP`` (``channels``), the column map of every command that reads trials.

    The value is the text :func:`shipid.io.files.read_trial` takes as ``channel_map``
    (:func:`shipid.io.mapping.parse_channel_map`); one syntax on every command.
    """
    opt = click.option("--channels", "channels", default=None, metavar="MAP", help=help)
    return opt(f) if f is not None else opt


# ----------------------------------------------------------------------------- outputs
OUT_HELP = "Write the result as JSON to FILE (atomically; an existing FILE needs --force)."
JSON_HELP = "Print the result as JSON on stdout."


def refuse_existing(*paths, force: bool = False) -> None:
    """Raise :class:`~shipid.errors.OutputExistsError` (exit 2) for the first existing path unless ``force``."""
    from shipid.errors import OutputExistsError

    for p in paths:
        if p is not None and not force and Path(p).exists():
            raise OutputExistsError(str(p))


def out_options(f: Callable | None = None, *, json_flag: bool = True, json_help: str = JSON_HELP,
                out_help: str = OUT_HELP, metavar: str = "FILE", required: bool = False,
                force_help: str = "Overwrite an existing --out file."):
    """Click decorator: ``--json`` (``as_json``), ``-o/--out FILE`` (``out``) and ``--force`` (``force``).

    Before the command runs, an existing ``--out`` without ``--force`` is refused
    (:func:`refuse_existing`): the error comes before a long computation, never after it,
    and never clobbers the file. Use it as ``@out_options`` or
    ``@out_options(out_help=...)``; write the result with :func:`emit`.
    """

    def decorate(func):
        @functools.wraps(func)
        def wrapper(*args, out=None, force=False, **kw):
            refuse_existing(out, force=force)
            return func(*args, out=out, force=force, **kw)

        opts = []
        if json_flag:
            opts.append(click.option("--json", "as_json", is_flag=True, help=json_help))
        opts.append(click.option("-o", "--out", "out", type=click.Path(dir_okay=False), default=None,
                                 required=required, metavar=metavar, help=out_help))
        opts.append(click.option("--force", is_flag=True, help=force_help))
        for opt in reversed(opts):
            wrapper = opt(wrapper)
        return wrapper

    return decorate(f) if f is not None else decorate


def json_text(payload: Any, indent: int | None = 2) -> str:
    """The JSON text of a result: a :class:`~shipid.result.Result` (its ``to_json``), a dict or a JSON string."""
    if isinstance(payload, str):
        return payload
    if hasattr(payload, "to_json"):
        return payload.to_json(indent=indent)
    return json.dumps(payload, indent=indent, allow_nan=True)


def emit(payload: Any, *, as_json: bool, out: str | None, force: bool, text: Callable[[], None] | None = None,
         indent: int | None = 2):
    """Write ``payload`` to ``out`` (atomically, see :func:`out_options`), print it with ``--json``, else ``text()``.

    Returns the written path (``None`` without ``--out``).
    """
    from shipid.outputs import atomic_write_text

    body = json_text(payload, indent)
    path = atomic_write_text(out, body if body.endswith("\n") else body + "\n", force=force) if out else None
    if as_json:
        click.echo(body)
    elif text is not None:
        text()
    return path


class ManyValues(click.Option):
    """An option that takes every following argument up to the next option: ``--surge a.csv b.csv``.

    It may also be repeated (``--surge a.csv --surge b.csv``); all files are collected.
    """

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("multiple", True)
        super().__init__(*args, **kwargs)
        self._prev = None
        self._parser_opt = None

    def add_to_parser(self, parser, ctx):
        ret = super().add_to_parser(parser, ctx)
        for name in self.opts:
            opt = parser._long_opt.get(name) or parser._short_opt.get(name)
            if opt is not None:
                self._parser_opt = opt
                self._prev = opt.process
                prefixes = tuple(parser._opt_prefixes) if hasattr(parser, "_opt_prefixes") else ("-",)

                def process(value, state, _prev=self._prev, _prefixes=prefixes):
                    vals = [value]
                    while state.rargs and not state.rargs[0].startswith(_prefixes):
                        vals.append(state.rargs.pop(0))
                    for v in vals:
                        _prev(v, state)

                opt.process = process
                break
        return ret

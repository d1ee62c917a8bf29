"""The ``shipid`` command.

The top-level group and its sub-groups (``identify``, ``study``, ``analyse``,
``design``) live here. Commands live in the sibling modules of this package, one
module per topic, and in each method's ``cli*`` modules; :func:`load_all_commands`
finds and imports them all, so adding a command never needs an edit to this file. A
module registers its commands on the groups below with the usual click decorators,
e.g.::

    from shipid.cli import identify

    @identify.command("mass-cm")
    ...

Start-up. The command modules import the methods, and the methods numba, which costs
seconds; so a command's module is imported only when that command runs (or its help
is asked for). The names, modules and one-line summaries of all commands are in the
generated index :data:`shipid.cli._index.INDEX`, from which every group lists its
commands without importing them. The index records a hash of the command modules it
was built from (:func:`sources_key`); when a command module has been added or edited
since, the index is not used and every command module is imported at start-up, as
without an index (correct, only slow). Refresh it after such an edit with
``python -c "import shipid.cli as c; c.write_index()"`` (``tests/cli/test_lazy.py``
fails until then).

Errors: anything derived from :class:`shipid.errors.ShipidError` is printed as one
line on stderr (``shipid: error: ...``) and the process exits with status 2.
Warnings (non-convergence, implausible or undetermined estimates, data repairs,
Python warnings of a method) are one line each, ``shipid: warning: ...``, and in
the JSON; with ``shipid --strict CMD ...`` a command that warned exits with status 3
(:mod:`shipid.cli._common`). ``--strict`` is an option of ``shipid`` itself, given before
the command; no command has its own.
"""

from __future__ import annotations

import hashlib
import importlib
import os
import pkgutil
import sys
from pathlib import Path
from typing import Iterator

import click

import shipid
from shipid.cli import _common
from shipid.cli import _index
from shipid.errors import ShipidError

CONTEXT = {"help_option_names": ["-h", "--help"], "max_content_width": 100}
#: The command index (path -> module, summary, hidden): :data:`shipid.cli._index.INDEX`.
INDEX = _index.INDEX


def summary(cmd: click.Command) -> str:
    """The one-line summary of ``cmd`` that its group's help shows: ``short_help``, else the first paragraph."""
    return cmd.short_help or " ".join((cmd.help or "").split("\b")[0].split("\n\n")[0].split())


class Group(click.Group):
    """A click group whose commands are imported when used, and whose command list shows each summary whole.

    The commands not yet imported are known from :data:`INDEX` (name, module, summary): listing
    them, or the group's help, imports nothing; resolving one (to run it or show its help)
    imports its module, which registers it. Summaries are shown whole (click cuts them at 45
    characters, and at the first '. ', which turned "Fig. 4 ..." into "Fig.").
    """

    group_class = type      # sub-groups made with @cli.group are of this class too (not a change to click's Group)

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.parent: tuple[Group, str] | None = None

    @property
    def path(self) -> tuple[str, ...]:
        """The names from the top-level group down to this one (``()`` for ``shipid`` itself)."""
        return () if self.parent is None else (*self.parent[0].path, self.parent[1])

    def add_command(self, cmd: click.Command, name: str | None = None) -> None:
        super().add_command(cmd, name)
        if isinstance(cmd, Group):
            cmd.parent = (self, name or cmd.name)

    def indexed(self) -> dict[str, tuple[str, str, bool]]:
        """This group's commands in :data:`INDEX`: name -> (module, summary, hidden)."""
        p = self.path
        return {k[-1]: v for k, v in INDEX.items() if k[:-1] == p}

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(set(self.commands) | set(self.indexed()))

    def get_command(self, ctx: click.Context, name: str) -> click.Command | None:
        if name not in self.commands:
            entry = self.indexed().get(name)
            if entry is not None:
                importlib.import_module(entry[0])
                if name not in self.commands:       # the index is out of date: import every command module
                    load_all_commands()
        return self.commands.get(name)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        indexed = self.indexed()
        rows = []
        for name in self.list_commands(ctx):
            cmd = self.commands.get(name)
            text, hidden = (summary(cmd), cmd.hidden) if cmd is not None else indexed[name][1:]
            if not hidden:
                rows.append((name, text))
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)


def _print_version(ctx: click.Context, param: click.Parameter, value: bool) -> None:
    if value and not ctx.resilient_parsing:
        click.echo(f"shipid, version {shipid.__version__}")
        ctx.exit()


@click.group(cls=Group, context_settings=CONTEXT)
@click.option("-V", "--version", is_flag=True, expose_value=False, is_eager=True, callback=_print_version,
              help="Show the version and exit.")
@click.option("--strict", is_flag=True, expose_value=False, callback=_common.set_strict,
              help="Exit with status 3 if the command warns (non-convergence, implausible or undetermined "
                   "estimates, data repairs). Before the command: shipid --strict identify ...")
def cli() -> None:
    """Identify ship dynamics from motion data.

    Mass and centre of mass from an IMU and the rudder (Linder et al. 2015), online
    too; DP low-frequency models (Fossen, Sagatun & Sørensen 1996); manoeuvring
    coefficients by Estimation-Before-Modelling (Yoon & Rhee 2003), of the Abkowitz
    model and of an MMG model from real runs. Warnings are one 'shipid: warning:'
    line each; 'shipid --strict CMD ...' exits with status 3 when any was raised.
    """


@cli.group(context_settings=CONTEXT)
def identify() -> None:
    """Identify a model from trial files."""


@cli.group(context_settings=CONTEXT)
def study() -> None:
    """Run a study: paper reproductions and Monte Carlo campaigns."""


@cli.group(context_settings=CONTEXT)
def analyse() -> None:
    """Analyse an experiment before running it (Cramér–Rao bounds, identifiability)."""


@cli.group(context_settings=CONTEXT)
def design() -> None:
    """Design inputs for identification (D-optimal manoeuvres)."""


def command_files() -> dict[str, Path]:
    """Every module that defines commands, with its file: this package's public modules, then each
    method's ``cli*`` modules. Found on disk (nothing is imported to list them)."""
    here = Path(__file__).parent
    out = {f"{__name__}.{m.name}": here / f"{m.name}.py" for m in pkgutil.iter_modules([str(here)])
           if not m.name.startswith("_") and not m.ispkg}
    methods = here.parent / "methods"
    for pkg in pkgutil.iter_modules([str(methods)]):
        if pkg.ispkg:
            out.update({f"shipid.methods.{pkg.name}.{m.name}": methods / pkg.name / f"{m.name}.py"
                        for m in pkgutil.iter_modules([str(methods / pkg.name)])
                        if (m.name == "cli" or m.name.startswith("cli_")) and not m.ispkg})
    return out


def command_modules() -> list[str]:
    """The names of :func:`command_files`, in the order :func:`load_all_commands` imports them."""
    return list(command_files())


def sources_key() -> str:
    """First 16 hex digits of the SHA-256 of the names and contents of every command module.

    The index records the key of the sources it was built from; at start-up a different key
    means the index is out of date, and every command module is imported instead.
    """
    h = hashlib.sha256()
    for name, path in command_files().items():
        h.update(name.encode() + b"\0")
        try:
            h.update(path.read_bytes())
        except OSError:
            h.update(b"(unreadable)")
    return h.hexdigest()[:16]


def load_all_commands() -> None:
    """Import every command module (:func:`command_modules`), so that every group holds all its commands."""
    for name in command_modules():
        importlib.import_module(name)


def walk(group: click.Group, path: tuple[str, ...] = ()) -> Iterator[tuple[tuple[str, ...], click.Command]]:
    """Every command and sub-group registered below ``group`` so far, with its path, sorted by name."""
    for name, cmd in sorted(group.commands.items()):
        yield (*path, name), cmd
        if isinstance(cmd, click.Group):
            yield from walk(cmd, (*path, name))


def build_index() -> dict[tuple[str, ...], tuple[str, str, bool]]:
    """The index of every command below the groups of this file: path -> (module, summary, hidden).

    Imports every command module. The module of a command is the one its function is defined
    in, which must be one of :func:`command_modules` (importing it registers the command).
    """
    load_all_commands()
    modules = set(command_modules())
    index = {}
    for path, cmd in walk(cli):
        mod = getattr(cmd.callback, "__module__", None)
        if mod == __name__:
            continue                        # the groups defined above: always there
        if mod not in modules:
            raise RuntimeError(f"shipid {' '.join(path)}: defined in {mod}, which is not a command module "
                               f"(a cli.py or cli_*.py of a method, or a module of shipid.cli)")
        index[path] = (mod, summary(cmd), bool(cmd.hidden))
    return index


def write_index(path: str | Path | None = None) -> Path:
    """Write :func:`build_index` as ``shipid/cli/_index.py`` (or to ``path``); returns the path written."""
    out = Path(path) if path is not None else Path(__file__).with_name("_index.py")
    lines = ['"""The index of ``shipid``\'s commands: what every group lists without importing its commands.',
             "",
             'Generated by :func:`shipid.cli.write_index` (``python -c "import shipid.cli as c; c.write_index()"``);',
             "do not edit by hand. ``tests/cli/test_lazy.py`` checks it is current.",
             '"""',
             "",
             "#: :func:`shipid.cli.sources_key` of the command modules this index was built from",
             f"SOURCES = {sources_key()!r}",
             "",
             "#: command path -> (module whose import registers the command, summary its group shows, hidden)",
             "INDEX: dict[tuple[str, ...], tuple[str, str, bool]] = {"]
    for key, val in build_index().items():
        lines += [f"    {key!r}:", f"        {val!r},"]
    lines += ["}", ""]
    out.write_text("\n".join(lines), encoding="utf-8")
    return out


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script: run the CLI, turning known errors into one line."""
    _common.begin()
    with _common.recording():
        rv = dispatch(argv)
        return _common.finish(rv)


def dispatch(argv: list[str] | None) -> int:
    """Run the command of ``argv``; each known error becomes one line on stderr and its exit status.

    :func:`main` is this inside the warning recording of :mod:`shipid.cli._common`.
    """
    try:
        rv = cli.main(args=argv, prog_name="shipid", standalone_mode=False)
    except click.exceptions.NoArgsIsHelpError as err:     # bare `shipid` or `shipid study`: the help, not an error
        click.echo(err.ctx.get_help() if err.ctx is not None else cli.get_help(click.Context(cli)))
        return 0
    except ShipidError as err:
        click.echo(f"shipid: error: {err}", err=True)
        return err.exit_code
    except click.exceptions.Abort:
        click.echo("shipid: aborted", err=True)
        return 130
    except click.ClickException as err:
        moved = _common.moved_option(err) if isinstance(err, click.NoSuchOption) else None
        click.echo(f"shipid: error: {moved or ' '.join(err.format_message().split())}", err=True)
        return err.exit_code
    except click.exceptions.Exit as err:
        return err.exit_code
    except KeyboardInterrupt:
        click.echo("shipid: interrupted", err=True)
        return 130
    except OSError as err:  # unreadable file, full disk ...: one line, not a traceback
        name = f"{err.filename}: " if getattr(err, "filename", None) else ""
        click.echo(f"shipid: error: {name}{err.strerror or err}", err=True)
        return 2
    except Exception as err:  # a bug: still one line, the traceback on request
        if os.environ.get("SHIPID_DEBUG"):
            raise
        click.echo(f"shipid: internal error: {type(err).__name__}: {' '.join(str(err).split())} "
                   "(set SHIPID_DEBUG=1 for the traceback)", err=True)
        return 1
    return rv if isinstance(rv, int) else 0


def run() -> None:  # pragma: no cover - console script shim
    exit_now(main())


def exit_now(rc: int | None) -> None:
    """End the ``shipid`` process with status ``rc``: the atexit handlers run, the interpreter's teardown does not.

    After a command that ran compiled code, freeing numba's and LLVM's objects at interpreter exit costs about a
    quarter of a second of CPU (``benchmarks/bench_cli_startup.py``), more than many commands take. Output is
    flushed and every ``atexit`` handler (temporary files, campaign clean-up, logging) runs first. Where another
    thread is still alive, or flushing fails, the ordinary exit is taken.
    """
    import atexit
    import threading

    code = int(rc or 0)
    if threading.active_count() > 1:
        sys.exit(code)
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        atexit._run_exitfuncs()
        sys.stdout.flush()
        sys.stderr.flush()
    except BaseException:  # a closed pipe or a failing handler: let Python exit (and report) as usual
        sys.exit(code)
    os._exit(code)


#: True when :data:`INDEX` was built from the command modules on disk; otherwise (a command module was
#: added or edited since ``write_index``) every command module is imported now, as without an index.
INDEX_CURRENT = sources_key() == getattr(_index, "SOURCES", None)
if not INDEX_CURRENT:
    INDEX = {}
    load_all_commands()

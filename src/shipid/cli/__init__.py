"""The ``shipid`` command.

The top-level group and its sub-groups (``identify``, ``study``, ``analyse``,
``design``) live here. Commands live in the sibling modules of this package, one
module per topic; every module is imported by :func:`_load_commands`, so adding a
command never needs an edit to this file. A module registers its commands on the
groups below with the usual click decorators, e.g.::

    from shipid.cli import identify

    @identify.command("mass-cm")
    ...

Errors: anything derived from :class:`shipid.errors.ShipidError` is printed as one
line on stderr (``shipid: error: ...``) and the process exits with status 2.
Warnings (non-convergence, implausible or undetermined estimates, data repairs,
Python warnings of a method) are one line each, ``shipid: warning: ...``, and in
the JSON; with ``--strict`` a command that warned exits with status 3
(:mod:`shipid.cli._common`).
"""

from __future__ import annotations

import importlib
import os
import pkgutil
import sys

import click

import shipid
from shipid.cli import _common
from shipid.errors import ShipidError

CONTEXT = {"help_option_names": ["-h", "--help"], "max_content_width": 100}


class Group(click.Group):
    """A click group whose command list shows each summary whole (click cuts them at 45 characters,
    and at the first '. ', which turned "Fig. 4 ..." into "Fig.")."""

    group_class = type      # sub-groups made with @cli.group are of this class too (not a change to click's Group)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        rows = []
        for name in self.list_commands(ctx):
            cmd = self.get_command(ctx, name)
            if cmd is None or cmd.hidden:
                continue
            text = cmd.short_help or " ".join((cmd.help or "").split("\b")[0].split("\n\n")[0].split())
            rows.append((name, text))
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)




@click.group(cls=Group, context_settings=CONTEXT)
@click.version_option(shipid.__version__, "-V", "--version", prog_name="shipid")
@click.option("--strict", is_flag=True, expose_value=False, callback=_common.set_strict,
              help="Exit with status 3 if the command warns (non-convergence, implausible or undetermined "
                   "estimates, data repairs).")
def cli() -> None:
    """Identify ship dynamics from motion data.

    Mass and centre of mass from an IMU and the rudder (Linder et al. 2015), DP
    low-frequency models (Fossen, Sagatun & Sørensen 1996), manoeuvring
    coefficients by Estimation-Before-Modelling (Yoon & Rhee 2003).
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


def _load_commands() -> None:
    """Import the shared command modules of this package, then each method's ``cli*`` modules."""
    for mod in pkgutil.iter_modules(__path__):
        if not mod.name.startswith("_"):
            importlib.import_module(f"{__name__}.{mod.name}")
    import shipid.methods as methods_pkg

    for pkg in pkgutil.iter_modules(methods_pkg.__path__):
        if not pkg.ispkg:
            continue
        sub = importlib.import_module(f"shipid.methods.{pkg.name}")
        for mod in pkgutil.iter_modules(sub.__path__):
            if mod.name == "cli" or mod.name.startswith("cli_"):
                importlib.import_module(f"shipid.methods.{pkg.name}.{mod.name}")


_load_commands()


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script: run the CLI, turning known errors into one line."""
    _common.begin()
    with _common.recording():
        rv = _run(argv)
        return _common.finish(rv)


def _run(argv: list[str] | None) -> int:
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
        click.echo(f"shipid: error: {' '.join(err.format_message().split())}", err=True)
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
    sys.exit(main())

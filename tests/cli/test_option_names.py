"""One name per concept on the command line (docs/cli.md, "Option conventions"), checked over the click tree.

Every command's options are walked: an option of the conventions table has the same kind everywhere (``--seed``
an integer, ``--dt`` and ``--duration`` seconds as floats, ``--json`` and ``--force`` flags, ``-o/--out`` and
``--trial`` paths, ``--channels`` one string), ``--out`` always comes with ``-o``, and no visible option uses a
synonym of a conventional name (a hidden alias kept for old scripts is allowed). ``--input`` is not one: here it
names the rudder input (standard manoeuvres or a PRBS), not a file.
"""

from __future__ import annotations

import click
import pytest

from shipid.cli import cli, load_all_commands, walk

#: conventional option -> the click parameter types it may have
KINDS = {
    "--seed": (click.types.IntParamType, click.types.IntRange),
    "--workers": (click.types.IntParamType, click.types.IntRange),
    "--dt": (click.types.FloatParamType, click.types.FloatRange),
    "--duration": (click.types.FloatParamType, click.types.FloatRange),
    "--out": (click.Path,),
    "--trial": (click.Path,),
    "--channels": (click.types.StringParamType,),
}
FLAGS = ("--json", "--force")
#: spellings that name a conventional concept under another name
SYNONYMS = {
    "--output": "-o/--out", "--outfile": "-o/--out", "--out-file": "-o/--out",
    "--file": "--trial", "--run": "--trial", "--n-workers": "--workers", "--jobs": "--workers", "-j": "--workers",
    "--random-seed": "--seed", "--rng-seed": "--seed", "--time": "--duration", "--length": "--duration",
    "--step": "--dt", "--timestep": "--dt", "--sample-time": "--dt", "--ship": "--vessel",
    "--channel-map": "--channels", "--map": "--channels",
}


def _options():
    load_all_commands()
    for path, cmd in walk(cli):
        for p in cmd.params:
            if isinstance(p, click.Option):
                yield " ".join(path), p


OPTIONS = list(_options())


def test_the_walk_sees_the_commands():
    assert len({c for c, _ in OPTIONS}) >= 20


@pytest.mark.parametrize("name", sorted(KINDS))
def test_a_conventional_option_has_one_kind(name):
    bad = [f"{c}: {type(p.type).__name__}" for c, p in OPTIONS if name in p.opts
           and not isinstance(p.type, KINDS[name])]
    assert not bad, f"{name} has another kind in: {bad}"


@pytest.mark.parametrize("name", FLAGS)
def test_json_and_force_are_flags(name):
    bad = [c for c, p in OPTIONS if name in p.opts and not p.is_flag]
    assert not bad, f"{name} is not a flag in: {bad}"


def test_out_always_has_its_short_form():
    bad = [c for c, p in OPTIONS if "--out" in p.opts and "-o" not in p.opts]
    assert not bad, f"--out without -o in: {bad}"


def test_no_visible_synonym_of_a_conventional_name():
    bad = [f"{c}: {o} (use {SYNONYMS[o]})" for c, p in OPTIONS if not p.hidden
           for o in (*p.opts, *p.secondary_opts) if o in SYNONYMS]
    assert not bad, "synonyms of the conventional names:\n" + "\n".join(bad)

"""One name per concept on the command line (docs/cli.md, "Option conventions"), checked over the click tree.

Every command's options are walked: an option of the conventions table has the same kind everywhere (``--seed``
an integer, ``--dt`` and ``--duration`` seconds as floats, ``--json`` and ``--force`` flags, ``-o/--out`` and
``--trial`` paths, ``--channels`` one string), ``--out`` always comes with ``-o``, no option uses a synonym of a
conventional name and none is hidden (no alias kept for old scripts: ``shipid`` answers an old spelling with one
line naming the new one), ``--strict`` is an option of ``shipid`` itself and of no command, no command is
registered twice, every option has a help text, and an option name takes one kind of value (flag, int, float,
path or text) on every command that has it. ``--input`` is not a synonym: here it names the rudder input (standard manoeuvres or a PRBS),
not a file.
"""

from __future__ import annotations

import click
import pytest

from shipid.cli import _common, cli, load_all_commands, main, walk

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
    "--output": "-o/--out", "--jsonl": "--json", "--json-out": "--json", "--outfile": "-o/--out", "--out-file": "-o/--out",
    "--file": "--trial", "--run": "--trial", "--n-workers": "--workers", "--jobs": "--workers", "-j": "--workers",
    "--random-seed": "--seed", "--rng-seed": "--seed", "--time": "--duration", "--length": "--duration", "--seconds": "--duration",
    "--step": "--dt", "--timestep": "--dt", "--sample-time": "--dt", "--ship": "--vessel",
    "--channel-map": "--channels", "--map": "--channels",
}


def _options():
    load_all_commands()
    for path, cmd in [((), cli), *walk(cli)]:
        for p in cmd.params:
            if isinstance(p, click.Option):
                yield " ".join(path), p


OPTIONS = list(_options())


def test_the_walk_sees_the_commands():
    assert len({c for c, _ in OPTIONS}) >= 20
    assert any(c == "" and "--strict" in p.opts for c, p in OPTIONS)        # the root group's own options too


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


def test_no_synonym_of_a_conventional_name():
    bad = [f"{c}: {o} (use {SYNONYMS[o]})" for c, p in OPTIONS
           for o in (*p.opts, *p.secondary_opts) if o in SYNONYMS]
    assert not bad, "synonyms of the conventional names:\n" + "\n".join(bad)


def test_no_hidden_option():
    """Every option a command takes is in its --help: no alias kept out of sight."""
    bad = [f"{c}: {'/'.join(p.opts)}" for c, p in OPTIONS if p.hidden]
    assert not bad, f"hidden options: {bad}"


def test_each_option_has_one_long_name():
    """One spelling per option (``--json``, not ``--json/--jsonl``); ``-o``/``-V`` are the only short forms."""
    bad = [f"{c}: {p.opts}" for c, p in OPTIONS if len([o for o in p.opts if o.startswith("--")]) != 1]
    assert not bad, f"options with several long names: {bad}"
    shorts = {(o, tuple(sorted(p.opts))) for c, p in OPTIONS for o in (*p.opts, *p.secondary_opts)
              if not o.startswith("--")}
    assert shorts <= {("-o", ("--out", "-o")), ("-V", ("--version", "-V"))}, shorts


def _kind(p: click.Option) -> str:
    """The kind of value an option takes: flag, int, float, path or text (a choice is text)."""
    if p.is_flag:
        return "flag"
    for kind, types in (("int", (click.types.IntParamType,)), ("float", (click.types.FloatParamType,)),
                        ("path", (click.Path, click.File)), ("text", (click.types.StringParamType, click.Choice))):
        if isinstance(p.type, types):
            return kind
    return type(p.type).__name__


def _kinds_by_name() -> dict[str, dict[str, list[str]]]:
    out: dict[str, dict[str, list[str]]] = {}
    for c, p in OPTIONS:
        for o in p.opts:
            if o.startswith("--"):
                out.setdefault(o, {}).setdefault(_kind(p), []).append(c)
    return out


#: one name on two concepts, left for the owners of those commands (each fails the test below once fixed:
#: then take it off this list)
TWO_KINDS: dict[str, str] = {}


@pytest.mark.parametrize("name", sorted({o for _, p in OPTIONS for o in p.opts if o.startswith("--")}))
def test_one_name_one_kind_of_value(name):
    kinds = _kinds_by_name()[name]
    if name in TWO_KINDS:
        assert len(kinds) > 1, f"{name} has one kind now: take it off TWO_KINDS"
        pytest.xfail(TWO_KINDS[name])
    assert len(kinds) == 1, f"{name} takes different kinds of value: {kinds}"


def test_every_option_says_what_it_does():
    bad = [f"{c}: {'/'.join(p.opts)}" for c, p in OPTIONS if not (p.help or "").strip()]
    assert not bad, f"options without a help text: {bad}"


def test_strict_is_an_option_of_shipid_only():
    on_commands = sorted(c for c, p in OPTIONS if c and "--strict" in (*p.opts, *p.secondary_opts))
    assert not on_commands, f"--strict on commands (it belongs to shipid itself): {on_commands}"


def test_no_command_is_registered_twice():
    seen: dict = {}
    for path, cmd in walk(cli):
        key = (getattr(cmd.callback, "__module__", None), getattr(cmd.callback, "__qualname__", None))
        if isinstance(cmd, click.Group) and cmd.callback is None:
            continue
        assert key not in seen, f"{' '.join(path)} and {' '.join(seen[key])} are one command under two names"
        seen[key] = path


@pytest.mark.parametrize("argv,says", [
    (["validate", "published:esso_osaka_3m", "--trial", "run.csv", "--strict"],
     "no such option of 'validate': --strict; --strict is an option of shipid itself: put it before the command "
     "(shipid --strict validate ...)"),
    (["identify", "mmg", "--trial", "run.csv", "--output", "m.json"],
     "no such option of 'identify mmg': --output; write -o/--out FILE"),
    (["monitor", "mass-cm", "--jsonl"], "no such option of 'monitor mass-cm': --jsonl; write --json"),
])
def test_an_old_spelling_is_one_line_naming_the_new_one(argv, says, capsys):
    assert main(argv) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err == f"shipid: error: {says}\n"
    assert set(_common.MOVED_OPTIONS) <= set(SYNONYMS) | {"--strict"}

"""One CLI convention for every result (issue 14).

Every ``identify`` and ``study`` command (and ``design``, ``analyse``, ``imo``, whose output is a
result too) takes ``--json`` (the result as JSON on stdout) and ``-o/--out FILE`` with ``--force``
(the result written atomically; an existing FILE refused before any work, one line, exit 2). Every
``--format`` is a choice; every command has a help text whose summary the group listing shows whole.
The options come from one decorator, :func:`shipid.cli._common.out_options`.
"""

from __future__ import annotations

import json

import click
import pytest

from shipid.cli import cli, load_all_commands, main
from shipid.cli._common import out_options

load_all_commands()         # the commands are imported when used; the walk needs them all

#: Groups whose every command produces a result (JSON and -o/--out) ...
RESULT_GROUPS = ("identify", "study", "design", "analyse")
#: ... and the commands outside them that do (``check``: the summary of a trial; ``monitor mass-cm``: the
#: JSON lines of a monitoring run).
RESULT_COMMANDS = (("imo",), ("check",), ("monitor", "mass-cm"))


def _walk(group: click.Group, path: tuple[str, ...] = ()):
    for name, cmd in sorted(group.commands.items()):
        p = (*path, name)
        if isinstance(cmd, click.Group):
            yield from _walk(cmd, p)
        else:
            yield p, cmd


ALL = list(_walk(cli))
RESULTS = [(p, c) for p, c in ALL if p[0] in RESULT_GROUPS or p in RESULT_COMMANDS]
IDS = [" ".join(p) for p, _ in RESULTS]


def _option(cmd: click.Command, flag: str) -> click.Option | None:
    return next((o for o in cmd.params if isinstance(o, click.Option) and flag in o.opts + o.secondary_opts), None)


def test_the_walk_finds_every_method_command():
    names = {" ".join(p) for p, _ in RESULTS}
    for expected in ("identify mass-cm", "identify dp", "identify ebm", "identify mmg", "study mass-cm-contour",
                     "study dp-supply", "study ebm-esso-osaka", "study mmg-coverage", "design prbs",
                     "analyse crlb mass-cm", "imo", "check", "monitor mass-cm"):
        assert expected in names


@pytest.mark.parametrize("path,cmd", RESULTS, ids=IDS)
def test_json_out_force(path, cmd):
    js = _option(cmd, "--json")
    assert js is not None and js.is_flag and js.name == "as_json", f"{' '.join(path)}: no --json flag"
    out = _option(cmd, "--out")
    assert out is not None, f"{' '.join(path)}: no -o/--out"
    assert out.name == "out" and set(out.opts) == {"-o", "--out"} and not out.hidden
    force = _option(cmd, "--force")
    assert force is not None and force.is_flag and force.name == "force"


def test_every_format_option_is_a_choice():
    seen = 0
    for path, cmd in ALL:
        opt = _option(cmd, "--format")
        if opt is not None:
            seen += 1
            assert isinstance(opt.type, click.Choice), f"{' '.join(path)}: --format is {opt.type!r}"
    assert seen >= 4          # check, convert, identify mmg / realdata, validate


def _summary(cmd: click.Command) -> str:
    return " ".join((cmd.help or "").split("\b")[0].split("\n\n")[0].split())


@pytest.mark.parametrize("group", ["", "identify", "study", "design", "analyse", "analyse crlb"])
def test_group_help_shows_each_summary_whole(group, capsys):
    assert main([*group.split(), "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    g = cli
    for part in group.split():
        g = g.commands[part]
    for name, cmd in g.commands.items():
        if cmd.hidden:
            continue
        s = _summary(cmd)
        assert s, f"{group} {name}: no help text"
        assert f"{name} {s}" in text, f"{group} {name}: summary cut in the group help"


def _dummy_args(cmd: click.Command) -> list[str]:
    """Values for the required arguments and options (never read: the --out check comes first)."""
    args: list[str] = []
    for p in cmd.params:
        if not p.required or p.name == "out":
            continue
        if isinstance(p.type, click.Choice):
            val = p.type.choices[0]
        elif isinstance(p.type, (click.types.IntParamType, click.types.FloatParamType)):
            val = "1"
        else:
            val = "no-such-input.csv"
        args += [val] if isinstance(p, click.Argument) else [p.opts[-1], val]
    return args


@pytest.mark.parametrize("path,cmd", RESULTS, ids=IDS)
def test_existing_out_is_refused_before_any_work(path, cmd, tmp_path, capsys):
    target = tmp_path / "result.json"
    target.write_text("keep me\n", encoding="utf-8")
    rc = main([*path, *_dummy_args(cmd), "-o", str(target)])
    err = capsys.readouterr().err
    assert rc == 2
    lines = err.strip().splitlines()
    assert lines == [f"shipid: error: {target}: output file exists (use --force to overwrite)"], err
    assert target.read_text(encoding="utf-8") == "keep me\n"


def test_toy_study_writes_out_refuses_clobber_and_force_overwrites(tmp_path, capsys):
    out = tmp_path / "toy.json"
    assert main(["study", "toy", "--runs", "3", "--workers", "1", "--json", "-o", str(out)]) == 0
    printed = json.loads(capsys.readouterr().out)
    written = json.loads(out.read_text(encoding="utf-8"))
    assert written == printed and written["ok"] == 3 and written["runs"] == 3
    assert abs(written["mean_slope"] - 2.0) < 0.1        # the toy fits y = 1 + 2 x + noise
    first = out.read_text(encoding="utf-8")

    assert main(["study", "toy", "--runs", "5", "--workers", "1", "-o", str(out)]) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and len(cap.err.strip().splitlines()) == 1 and "--force" in cap.err
    assert out.read_text(encoding="utf-8") == first

    assert main(["study", "toy", "--runs", "5", "--workers", "1", "-o", str(out), "--force"]) == 0
    assert json.loads(out.read_text(encoding="utf-8"))["runs"] == 5
    assert "mean slope" in capsys.readouterr().out     # without --json: the text table on stdout
    assert [p.name for p in tmp_path.iterdir()] == ["toy.json"]   # no temporary file left behind


def test_store_info_and_export_follow_the_convention(tmp_path, capsys):
    store = tmp_path / "s.sqlite"
    assert main(["study", "toy", "--runs", "4", "--workers", "1", "--store", str(store), "--json"]) == 0
    capsys.readouterr()
    info = tmp_path / "info.json"
    assert main(["study", "store-info", str(store), "-o", str(info)]) == 0
    assert "4/4 runs done" in capsys.readouterr().out
    d = json.loads(info.read_text(encoding="utf-8"))
    assert d["campaigns"][0]["done"] == 4
    table = tmp_path / "runs.csv"
    assert main(["study", "export", str(store), "-o", str(table), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["runs"] == 4
    assert len(table.read_text(encoding="utf-8").strip().splitlines()) == 5      # header + 4 runs
    assert main(["study", "export", str(store), "-o", str(table)]) == 2


def test_output_is_refused_with_the_option_to_use(tmp_path, capsys):
    rc = main(["identify", "mmg", "--trial", "x.csv", "--output", str(tmp_path / "b.json")])
    assert rc == 2 and "--output; write -o/--out FILE" in capsys.readouterr().err
    assert not (tmp_path / "b.json").exists()


def test_out_options_is_one_decorator():
    @click.command()
    @out_options
    def cmd(as_json, out, force):
        click.echo(f"{as_json} {out} {force}")

    names = {p.name for p in cmd.params}
    assert names == {"as_json", "out", "force"}


def test_a_method_command_writes_the_json_it_prints(tmp_path, capsys):
    """`analyse crlb mass-cm` (a short record): -o writes what --json prints; the text table otherwise."""
    out = tmp_path / "crlb.json"
    args = ["analyse", "crlb", "mass-cm", "--duration", "30", "--fs", "20"]
    assert main([*args, "--json", "-o", str(out)]) == 0
    printed = json.loads(capsys.readouterr().out)
    written = json.loads(out.read_text(encoding="utf-8"))
    assert written == printed
    assert set(written["bounds"]) >= {"m", "zm_bar", "rho"} and written["bounds"]["m"]["std"] > 0
    assert main([*args, "-o", str(out)]) == 2                  # refused, unchanged
    assert json.loads(out.read_text(encoding="utf-8")) == written
    capsys.readouterr()
    assert main([*args, "-o", str(out), "--force"]) == 0
    assert "Cramér–Rao bounds" in capsys.readouterr().out

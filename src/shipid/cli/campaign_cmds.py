"""Shared campaign options for ``shipid study`` commands, and the store commands.

Any study that repeats work should run through :func:`shipid.campaign.engine.run_campaign`
and take its execution options from :func:`campaign_options`::

    import click
    from shipid.cli import study
    from shipid.cli.campaign_cmds import campaign_options, echo_campaign_summary

    @study.command("mass-cm-sensitivity")
    @click.option("--runs", type=click.IntRange(min=1), default=10_000, show_default=True)
    @click.option("--json", "as_json", is_flag=True)
    @campaign_options
    def mass_cm_sensitivity(runs, as_json, campaign):
        res = campaign.run("shipid.methods.masscm.estimator:sensitivity_run", runs,
                           kwargs={...}, name="mass-cm-sensitivity")
        ...  # res.outputs (run order, None where failed), res.failed, res.wall_s

The decorator adds ``--seed S`` (default 0), ``--workers W``, ``--dask-local N``,
``--scheduler tcp://HOST:PORT``, ``--store FILE``, ``--resume`` and ``--retry-failed``, and hands the
command one keyword argument ``campaign``, a
:class:`shipid.campaign.engine.CampaignOptions` (``campaign.seed``,
``campaign.run(...)``, ``campaign.engine_kwargs()``). Use
``@campaign_options(seed_default=S)`` for another default seed.

Commands here:

* ``shipid study toy --runs N [--json] [-o R.json]`` — a cheap seeded toy campaign (smoke test of a cluster);
* ``shipid study export STORE -o FILE.parquet|FILE.csv [--json]`` — one row per run;
* ``shipid study store-info STORE [--json] [-o R.json]`` — campaigns in a store and their progress.
"""

from __future__ import annotations

import functools
import json
import math
from typing import TYPE_CHECKING

import click

from shipid.cli import study
from shipid.cli._common import emit, loud_lines, out_options
from shipid.errors import ShipidError

if TYPE_CHECKING:   # the engine (multiprocessing, rich) is imported when a campaign command runs
    from shipid.campaign.engine import CampaignResult


def campaign_options(f=None, *, seed_default: int = 0):
    """Click decorator adding the campaign options; the command receives ``campaign: CampaignOptions``."""

    def decorate(func):
        @functools.wraps(func)
        def wrapper(*args, seed, workers, dask_local, scheduler, store, resume, retry_failed, **kw):
            from shipid.campaign.engine import CampaignOptions

            kw["campaign"] = CampaignOptions(seed=seed, workers=workers, dask_local=dask_local,
                                             scheduler=scheduler, store=store, resume=resume,
                                             retry_failed=retry_failed)
            return func(*args, **kw)

        opts = [
            click.option("--seed", type=click.IntRange(min=0), default=seed_default, show_default=True,
                         help="Campaign seed; run i draws from SeedSequence([seed, i]) only."),
            click.option("--workers", type=click.IntRange(min=1), default=None, metavar="W",
                         help="Local worker processes [default: all CPUs; 1 = in this process]."),
            click.option("--dask-local", "dask_local", type=click.IntRange(min=1), default=None, metavar="N",
                         help="Run on a Dask LocalCluster of N worker processes on loopback."),
            click.option("--scheduler", default=None, metavar="tcp://HOST:PORT",
                         help="Run on an existing Dask cluster (its workers need shipid installed)."),
            click.option("--store", type=click.Path(dir_okay=False), default=None, metavar="FILE",
                         help="SQLite store: one row per run, committed as chunks finish."),
            click.option("--resume", is_flag=True,
                         help="Continue the campaign in --store (same definition), skipping finished runs."),
            click.option("--retry-failed", "retry_failed", is_flag=True,
                         help="With --resume: run the stored failed runs again."),
        ]
        for opt in reversed(opts):
            wrapper = opt(wrapper)
        return wrapper

    return decorate(f) if f is not None else decorate


def echo_campaign_summary(res: CampaignResult) -> None:
    """Print a one-paragraph human summary of a campaign to stderr (keeps --json stdout clean)."""
    where = f", store {res.store}" if res.store else ""
    reused = f", {res.reused} resumed from the store" if res.reused else ""
    how = ("nothing left to run" if res.workers == 0 else
           f"on {res.executor} ({res.workers} worker{'s' if res.workers != 1 else ''})")
    click.echo(f"{res.name}: {res.n_runs} runs ({res.n_ok} ok, {res.n_failed} failed{reused}) in "
               f"{res.wall_s:.2f} s, {how}{where}", err=True)


def failure_lines(res: CampaignResult) -> list[str]:
    """The warning line for the failed runs of ``res`` (none when every run succeeded).

    One line: how many runs failed and were left out of the summary, and the first three errors
    (run index and ``Type: message``, as the store records them). Every study command adds it to its
    warnings (:func:`shipid.cli._common.loud_lines`), so a failed run is on stderr and in the JSON, in
    text and ``--json`` mode alike, and ``--strict`` exits 3.
    """
    if not res.n_failed:
        return []
    return [f"{res.name}: {res.n_failed} of {res.n_runs} runs failed and are left out of the summary "
            f"({res.failed_text()})"]


@study.command("toy")
@click.option("--runs", type=click.IntRange(min=0), default=100, show_default=True, help="Number of runs.")
@click.option("--points", type=click.IntRange(min=2), default=200, show_default=True,
              help="Points per toy line fit.")
@click.option("--fail-every", type=click.IntRange(min=0), default=0, show_default=True,
              help="Make every K-th run fail (tests error recording).")
@click.option("--sleep", type=click.FloatRange(min=0), default=0.0, show_default=True,
              help="Seconds each run sleeps.")
@out_options(json_help="Print one JSON object on stdout.")
@campaign_options
def toy(runs, points, fail_every, sleep, as_json, out, force, campaign):
    """A cheap seeded toy campaign (a least-squares line fit per run).

    Useful as a smoke test of an executor or a cluster: the same --seed gives the
    same numbers with --workers, --dask-local or --scheduler.
    """
    res = campaign.run("shipid.campaign.toy:toy_run", runs, name="toy",
                       kwargs={"n": points, "fail_every": fail_every, "sleep": sleep})
    slopes = [o["b"] for o in res.outputs if o is not None]
    mean = math.fsum(slopes) / len(slopes) if slopes else None
    summary = {**res.summary(), "mean_slope": mean, "warnings": loud_lines(failure_lines(res))}

    def text():
        echo_campaign_summary(res)
        if mean is not None:
            click.echo(f"mean slope {mean:.6f} over {len(slopes)} runs (true 2)")

    emit(summary, as_json=as_json, out=out, force=force, indent=None, text=text)


@study.command("export")
@click.argument("store", type=click.Path(dir_okay=False))
@out_options(required=True, json_help="Print what was written (file, campaign, runs) as JSON on stdout.",
             out_help="Output table, one row per run: .parquet or .csv (atomically; an existing FILE needs --force).",
             force_help="Overwrite FILE.")
@click.option("--campaign", default=None, help="Campaign name (needed when the store holds several).")
def export(store, as_json, out, force, campaign):
    """Export a campaign store to Parquet or CSV, one row per run."""
    from shipid.campaign.store import export_store

    path, n = export_store(store, out, campaign=campaign, force=force)
    click.echo(f"wrote {n} runs to {path}", err=True)
    if as_json:
        click.echo(json.dumps({"store": store, "campaign": campaign, "out": str(path), "runs": n}))


@study.command("store-info")
@click.argument("store", type=click.Path(dir_okay=False))
@out_options(json_help="Print one JSON object on stdout.")
def store_info(store, as_json, out, force):
    """List the campaigns in a store with their definition and progress."""
    from pathlib import Path

    from shipid.campaign.store import CampaignStore

    if not Path(store).is_file():
        raise ShipidError(f"{store}: no such store")
    with CampaignStore(store) as st:
        info = []
        for name in st.campaign_names():
            meta = st.metadata(name)
            recs = st.records(name)
            meta.update(done=len(recs), failed=sum(r.status != "ok" for r in recs))
            info.append(meta)
    emit({"store": store, "campaigns": info}, as_json=as_json, out=out, force=force, indent=None,
         text=lambda: _print_info(info))


def _print_info(info: list) -> None:
    for m in info:
        click.echo(f"{m['name']}: {m['done']}/{m['n_runs']} runs done ({m['failed']} failed); task {m['task']}, "
                   f"seed {m['seed']}, kwargs {m['kwargs']}, shipid {m['shipid_version']}")

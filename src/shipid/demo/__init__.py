"""``shipid demo``: a list of demonstration steps that any module can add to.

A step is a function ``step(ctx: DemoContext) -> list[dict]`` returning rows of
its summary table (each row a mapping column → text, printed as an aligned table); it writes its files into
``ctx.out_dir`` and may print a line with ``ctx.echo``. Register it with the
decorator::

    from shipid.demo import demo_step

    @demo_step("mass-cm", order=20, description="mass and CoM from a simulated trial")
    def _demo(ctx):
        ...
        return [{"vessel": "fishing-vessel", "m [kg]": "22.1 ± 0.3"}]

Steps run in ``order`` (ties by name). Modules are discovered by importing every
module of :mod:`shipid.methods` and every command module of :mod:`shipid.cli`
(:func:`shipid.cli.load_all_commands`), so a method registers its step simply by
being in the package. Every step must be quick (see ``shipid demo --help`` for the measured time). A step that
leaves out a part of its work (real data missing, an optional package absent)
says so with ``ctx.skip(what, why)``; the demo lists every skipped part at the end.

The first step, ``simulate`` (order 0), simulates every packaged vessel on a
representative manoeuvre (:data:`DEMO_MANOEUVRES`).
"""

from __future__ import annotations

import importlib
import pkgutil
import textwrap
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from shipid import summary as _summary
from shipid.io.files import write_trial
from shipid.errors import InputError, ShipidError
from shipid.simulate.manoeuvres import parse_manoeuvre, run_manoeuvre
from shipid.simulate.metrics import turning_metrics, zigzag_metrics
from shipid.simulate.registry import get_ship_model, list_vessels

DemoFn = Callable[["DemoContext"], list[dict]]


@dataclass
class DemoContext:
    """What a demo step gets: where to write, whether to overwrite, the seed, a printer."""

    out_dir: Path
    force: bool = False
    seed: int = 0
    echo: Callable[[str], None] = print
    files: list[Path] = field(default_factory=list)
    #: (what, why) of every part a step did not run; ``shipid demo`` lists them at the end.
    skipped: list[tuple[str, str]] = field(default_factory=list)
    #: What each result of the run says of itself (:func:`result_findings`); listed at the end.
    findings: list[str] = field(default_factory=list)

    def skip(self, what: str, why: str) -> None:
        """Record that ``what`` was not run and why (printed in the demo's summary, never silent)."""
        self.skipped.append((what, " ".join(str(why).split())))


@dataclass(frozen=True)
class DemoStep:
    name: str
    fn: DemoFn
    order: int = 100
    description: str = ""


_STEPS: dict[str, DemoStep] = {}


def demo_step(name: str, *, order: int = 100, description: str = "") -> Callable[[DemoFn], DemoFn]:
    """Decorator registering ``fn`` as the demo step ``name`` (re-registering replaces it)."""
    def register(fn: DemoFn) -> DemoFn:
        _STEPS[name] = DemoStep(name, fn, order, description or (fn.__doc__ or "").strip().split("\n")[0])
        return fn
    return register


#: Modules whose demo steps could not be loaded for a missing optional dependency: name → reason.
SKIPPED: dict[str, str] = {}


def discover() -> None:
    """Import every module of :mod:`shipid.methods` (and the CLI) so their steps register.

    A module that needs an optional third-party package which is not installed
    (dask, say) is listed in :data:`SKIPPED` instead of failing the whole demo;
    any other import error is a bug and propagates.
    """
    methods = importlib.import_module("shipid.methods")       # plug-in discovery
    for mod in pkgutil.walk_packages(methods.__path__, "shipid.methods.",
                                     onerror=lambda name: None):
        try:
            importlib.import_module(mod.name)
        except ModuleNotFoundError as err:
            if not err.name or err.name.split(".")[0] == "shipid":
                raise
            SKIPPED[mod.name] = f"needs the optional package {err.name!r}"
    importlib.import_module("shipid.cli").load_all_commands()     # the command modules load lazily otherwise


def demo_steps() -> list[DemoStep]:
    """All registered steps, in order."""
    discover()
    return sorted(_STEPS.values(), key=lambda s: (s.order, s.name))


#: Representative manoeuvre per vessel for the demo: (manoeuvre, duration s, dt s).
DEMO_MANOEUVRES: dict[str, tuple[str, float, float]] = {
    "esso-osaka": ("zigzag-20", 600.0, 0.5),
    "supply": ("dp-sway-yaw", 600.0, 0.5),
    "fishing-vessel": ("zigzag-10", 60.0, 0.05),
    "nomoto": ("turning-35", 300.0, 0.2),
}
DEFAULT_DEMO_MANOEUVRE = ("zigzag-20", 600.0, 0.5)


@demo_step("simulate", order=0, description="simulate every packaged vessel on a typical manoeuvre")
def simulate_vessels(ctx: DemoContext) -> list[dict]:
    """Simulate every packaged vessel (and the generic Nomoto ship) and write the trials as CSV."""
    rows = []
    for entry in list_vessels():
        man, duration, dt = DEMO_MANOEUVRES.get(entry.name, DEFAULT_DEMO_MANOEUVRE)
        row: dict = {"vessel": entry.name, "manoeuvre": man}
        try:
            model = get_ship_model(entry.name)
        except ShipidError as err:
            row["file"] = f"skipped: {err}"
            ctx.skip(f"simulate {entry.name}", str(err))
            rows.append(row)
            continue
        trial = run_manoeuvre(model, man, duration=duration, dt=dt, seed=ctx.seed)
        path = ctx.out_dir / f"{entry.name}_{man}.csv"
        write_trial(trial, path, force=ctx.force)
        ctx.files.append(path)
        row.update(summarise(trial))
        row["manoeuvre measures"] = manoeuvre_measures(trial, man)
        row["file"] = path.name
        rows.append(row)
    return rows


def summarise(trial) -> dict[str, str]:
    """What a simulated trial did: duration, final heading, peak yaw rate, rudder and roll, track length."""
    out = {"duration [s]": f"{trial.duration:.0f}"}
    deg = np.rad2deg
    out["final psi [deg]"] = f"{deg(trial['psi'][-1]):.1f}" if "psi" in trial else "-"
    out["max |r| [deg/s]"] = f"{deg(np.max(np.abs(trial['r']))):.2f}" if "r" in trial else "-"
    out["max |delta| [deg]"] = f"{deg(np.max(np.abs(trial['delta']))):.1f}" if "delta" in trial else "-"
    out["max |phi| [deg]"] = f"{deg(np.max(np.abs(trial['phi']))):.1f}" if "phi" in trial else "-"
    if "x" in trial and "y" in trial:
        out["track [m]"] = f"{np.sum(np.hypot(np.diff(trial['x']), np.diff(trial['y']))):.0f}"
    else:
        out["track [m]"] = "-"
    return out


def manoeuvre_measures(trial, manoeuvre: str) -> str:
    """Overshoot angles of a zig-zag or the diameters of a turning circle, as text ("-" if none)."""
    spec = parse_manoeuvre(manoeuvre)
    try:
        if spec.kind == "zigzag":
            zm = zigzag_metrics(trial, float(spec.params["psi"]))
            return "overshoots " + "/".join(f"{np.rad2deg(o):.1f}" for o in zm.overshoots[:2]) + " deg"
        if spec.kind == "turning":
            tm = turning_metrics(trial)
            return f"tactical D {tm.tactical_diameter:.0f} m, steady D {tm.steady_diameter:.0f} m"
    except InputError:
        pass
    return "-"


def result_row(res) -> dict[str, str]:
    """Summary-table cells of one result: converged, how many quantities were determined, how many
    were not, how many warnings (the verdict of :func:`shipid.summary.verdict`, as its report shows it)."""
    v = _summary.verdict(res)
    det, und = len(v.determined), len(v.not_determined)
    return {"converged": {True: "yes", False: "NO"}.get(v.converged, "-"),
            "determined": f"{det} of {det + und}", "not determined": str(und), "warnings": str(len(v.warnings))}


def result_findings(name: str, res, width: int = 100) -> list[str]:
    """Lines naming what ``res`` did not determine and every warning it raised (empty when neither)."""
    v = _summary.verdict(res)
    if not v.not_determined and not v.warnings and v.converged is not False:
        return []
    det, und = len(v.determined), len(v.not_determined)
    out = [f"{name} ({res.method}): {det} of {det + und} estimated quantities determined"
           + ("; DID NOT CONVERGE" if v.converged is False else "")]
    if und:
        out += textwrap.wrap(f"not determined ({und}, not estimates): {', '.join(v.not_determined)}", width,
                             initial_indent="    ", subsequent_indent="        ", break_on_hyphens=False)
    for w in v.warnings:
        text = f"    warning: {' '.join(str(w).split())}"
        out.append(text if len(text) <= 2 * width else text[:2 * width - 1] + "…")
    return out


def closing_line(ctx: DemoContext, seconds: float, target) -> str:
    """The last line of ``shipid demo``: time, files, and whether anything was skipped or found wanting."""
    n = len(ctx.skipped)
    bits = [f"demo done in {seconds:.1f} s; {len(ctx.files)} files in {target}"]
    flagged = sum(1 for x in ctx.findings if not x.startswith(" "))
    if flagged:
        bits.append(f"{flagged} result{'s' if flagged > 1 else ''} with undetermined quantities or warnings "
                    "(findings above: read their reports before using them)")
    else:
        bits.append("no result has an undetermined quantity or a warning")
    bits.append(f"{n} part{'s' if n > 1 else ''} skipped (listed above)" if n else "every step ran in full")
    return "; ".join(bits)


def format_table(rows: list[dict]) -> list[str]:
    """Rows (dicts) as aligned text lines, columns in first-seen order, missing cells blank."""
    cols: list[str] = []
    for r in rows:
        cols += [k for k in r if k not in cols]
    cells = [[str(r.get(c, "")) for c in cols] for r in rows]
    width = [max([len(c)] + [len(row[i]) for row in cells]) for i, c in enumerate(cols)]
    fmt = lambda vals: "  ".join(v.ljust(w) for v, w in zip(vals, width)).rstrip()
    return [fmt(cols), fmt(["-" * w for w in width])] + [fmt(r) for r in cells]

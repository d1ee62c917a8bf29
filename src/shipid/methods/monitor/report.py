"""HTML report of a monitoring run: the JSON lines of ``shipid monitor mass-cm``.

One self-contained page: m(t), zm_bar(t) and rho(t) with their ±2 std bands, the detector statistic with
its threshold, the alarms and the located change times, and the truth when the stream was simulated
(the ``*.truth.json`` sidecar of ``shipid simulate fishing-vessel mass-cm-stream``), with the detection
delay and the coverage of the ±2 std intervals from 300 s after the change computed from them.
"""

from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np

from shipid.errors import InputError, OutputExistsError
from shipid.methods.monitor.estimator import MonitorOptions
from shipid.models.roll_reduced import KnownParams
from shipid.report.figures import new_figure, to_data_uri
from shipid.report.page import page as report_page
from shipid.simulate.masscm_stream import truth_at

_KEYS = ("t", "m", "m_std", "zm_bar", "zm_bar_std", "rho", "rho_std", "converged", "alarm", "change_at")


def is_monitor_jsonl(path: str | Path) -> bool:
    """Whether the first non-empty line of ``path`` is a monitor update (a JSON object with ``t`` and ``alarm``)."""
    try:
        with open(path, encoding="utf-8") as fh:
            for line in fh:
                if line.strip():
                    obj = json.loads(line)
                    return isinstance(obj, dict) and "t" in obj and "alarm" in obj and "method" not in obj
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return False
    return False


def read_updates(path: str | Path) -> list[dict]:
    """The updates of a JSONL file; a bad line is an :class:`InputError` naming the file and the line."""
    out = []
    with open(path, encoding="utf-8") as fh:
        for k, line in enumerate(fh, start=1):
            if not line.strip():
                continue
            try:
                obj = json.loads(line)
            except json.JSONDecodeError as err:
                raise InputError(f"line {k}: not valid JSON ({err.msg})", file=str(path)) from None
            missing = [key for key in _KEYS if key not in obj]
            if missing:
                raise InputError(f"line {k}: not a monitor update (missing {', '.join(missing)})", file=str(path))
            out.append(obj)
    if not out:
        raise InputError("no updates in the file", file=str(path))
    return out


def _col(ups, key) -> np.ndarray:
    return np.array([np.nan if u.get(key) is None else float(u[key]) for u in ups])


def summary(ups: list[dict], truth: dict | None, settle: float = 300.0) -> dict:
    """Alarms, located changes and, with the truth, detection delay and coverage of ±2 std from change + settle."""
    t = _col(ups, "t")
    alarms = [float(u["t"]) for u in ups if u["alarm"]]
    located = [u["change_at"] for u in ups if u["alarm"]]
    out = {"updates": len(ups), "t_end": float(t[-1]), "alarms": alarms, "located": located}
    if truth is not None:
        ca = truth.get("change_at")
        out["true_change_at"] = ca
        out["false_alarms"] = [a for a in alarms if ca is None or a <= ca]
        after = [a for a in alarms if ca is not None and a > ca]
        out["detection_delay"] = after[0] - ca if after else None
        t0 = (ca or 0.0) + settle
        sel = [u for u in ups if u["m"] is not None and u["t"] >= t0]
        if sel:
            mt, zt = truth_at(truth, [u["t"] for u in sel])
            out["coverage_from"] = t0
            out["coverage_m"] = float(np.mean([abs(u["m"] - a) <= 2 * u["m_std"] for u, a in zip(sel, mt)]))
            out["coverage_zm_bar"] = float(np.mean([abs(u["zm_bar"] - a) <= 2 * u["zm_bar_std"]
                                                    for u, a in zip(sel, zt)]))
    return out


def figure(ups: list[dict], truth: dict | None, threshold: float | None = None):
    """m, zm_bar, rho with ±2 std bands and the detector statistic against stream time."""
    fig = new_figure(height=8.0)
    axs = fig.subplots(4, 1, sharex=True)
    t = _col(ups, "t")
    alarms = [u["t"] for u in ups if u["alarm"]]
    located = sorted({u["change_at"] for u in ups if u["alarm"]})
    tt = None
    if truth is not None:
        tt = np.linspace(0.0, float(np.nanmax(t)), 2000)
        mt, zt = truth_at(truth, tt)
        kn_rho = None
        try:
            kn = KnownParams.from_vessel(truth.get("vessel", "fishing-vessel"))
            zf = float(truth["z_f"])
            kn_rho = mt * (zt + zf) / (kn.m_c * (kn.zc_bar + zf))
        except Exception:  # no rho truth for an unknown vessel: only m and zm_bar are drawn
            kn_rho = None
    for ax, key, label, tr in ((axs[0], "m", "m [kg]", None if tt is None else mt),
                               (axs[1], "zm_bar", "zm_bar [m]", None if tt is None else zt),
                               (axs[2], "rho", "rho [-]", None if tt is None else kn_rho)):
        v, s = _col(ups, key), _col(ups, key + "_std")
        ax.fill_between(t, v - 2 * s, v + 2 * s, color="C0", alpha=0.25, lw=0, label="±2 std")
        ax.plot(t, v, color="C0", lw=1.2, label="estimate")
        if tr is not None:
            ax.plot(tt, tr, color="k", lw=1.0, ls="--", label="truth (simulated)")
        fin = v[np.isfinite(v)]
        if fin.size:
            lo, hi = np.percentile(fin, [2, 98])
            pad = 0.5 * (hi - lo) + 1e-12
            ax.set_ylim(lo - pad, hi + pad)
        ax.set_ylabel(label)
    T = _col(ups, "statistic") if any("statistic" in u for u in ups) else None
    if T is not None:
        axs[3].semilogy(t, np.maximum(T, 1e-3), color="C2", lw=1.0, label="detector T")
        if threshold is not None:
            axs[3].axhline(threshold, color="C3", lw=0.8, ls=":", label=f"threshold {threshold:g}")
    axs[3].set_ylabel("Wald T [-]")
    axs[3].set_xlabel("stream time t [s]")
    for ax in axs:
        for a in alarms:
            ax.axvline(a, color="C3", lw=1.0)
        for c in located:
            ax.axvline(c, color="C3", lw=0.8, ls="--")
    axs[0].legend(loc="best", fontsize=7)
    axs[3].legend(loc="best", fontsize=7)
    axs[0].set_title("red: alarm (solid) and located change (dashed)", fontsize=8)
    return fig


def _s(x) -> str:
    return "—" if x is None else f"{float(x):.0f} s"


def _times(xs) -> str:
    return ", ".join(_s(x) for x in xs) if xs else "none"


def summary_rows(summ: dict) -> list[tuple[str, str]]:
    """The :func:`summary` as labelled rows with units (seconds of stream time, coverage in %)."""
    rows = [("updates", f"{summ['updates']}"), ("stream end", _s(summ["t_end"])),
            ("alarms at", _times(summ["alarms"])), ("located change times", _times(summ["located"]))]
    if "true_change_at" in summ:
        rows += [("true change at (simulated)", _s(summ["true_change_at"])),
                 ("false alarms (before the change)", _times(summ.get("false_alarms", []))),
                 ("detection delay", _s(summ.get("detection_delay")) if summ.get("detection_delay") is not None
                  else "no alarm after the change")]
    if "coverage_from" in summ:
        rows.append((f"±2 std intervals holding the truth from t = {_s(summ['coverage_from'])}",
                     f"m {100 * summ['coverage_m']:.0f} %, zm_bar {100 * summ['coverage_zm_bar']:.0f} % "
                     "(nominal 95 %)"))
    return rows


def monitor_page(jsonl, ups: list[dict], summ: dict, uri: str, warn: list[str], truth_path=None) -> str:
    """The HTML page (the style of every shipid report, :mod:`shipid.report.page`)."""
    esc = html.escape
    last = ups[-1]
    alarms, located = summ["alarms"], summ["located"]
    if alarms:
        head = (f"{len(alarms)} alarm{'s' if len(alarms) != 1 else ''} (first at {_s(alarms[0])}, change located "
                f"at {_s(located[0])}): the loading changed.")
        cls = "warn"
    else:
        head, cls = f"No alarm in {_s(last['t'])} of stream: no change of loading detected.", "ok"
    trust = []
    if "true_change_at" in summ:
        fa = summ.get("false_alarms") or []
        trust.append(("bad" if fa else "ok", f"{len(fa)} false alarm{'s' if len(fa) != 1 else ''} against the "
                                             "simulated truth."))
        d = summ.get("detection_delay")
        trust.append(("ok" if d is not None else "bad", f"Detection delay {_s(d)}." if d is not None else
                      "The change was not detected."))
    if "coverage_from" in summ:
        trust.append(("", f"±2 std intervals held the truth in {100 * summ['coverage_m']:.0f} % (m) and "
                          f"{100 * summ['coverage_zm_bar']:.0f} % (zm_bar) of the updates from "
                          f"{_s(summ['coverage_from'])} (nominal 95 %)."))
    trust.append(("bad" if warn else "ok", f"{len(warn)} warning{'s' if len(warn) != 1 else ''}"
                  + (" (listed below)." if warn else ".")))
    nxt = ("After an alarm, the estimates settle on the new loading within about 300 s: read m, zm_bar and rho "
           "from the last updates, not from those just after the alarm." if alarms else
           "Nothing to do: keep monitoring.")
    li = "".join(f'<li class="{c}">{t}</li>' for c, t in trust)
    est = [(f"{k} at t = {last['t']:g} s", f"{last[k]:.4g} ± {last[k + '_std']:.2g} {u}".rstrip())
           for k, u in (("m", "kg"), ("zm_bar", "m"), ("rho", "")) if last.get(k) is not None
           and last.get(k + "_std") is not None]
    rows = "".join(f'<tr><th scope="row">{esc(k)}</th><td>{esc(v)}</td></tr>' for k, v in est + summary_rows(summ))
    warns = ('<section class="warnings" id="warnings"><h2>Warnings (' + str(len(warn)) + ")</h2><ul>"
             + "".join(f"<li>{esc(w)}</li>" for w in warn) + "</ul></section>") if warn else ""
    src = f"Truth from <code>{esc(Path(truth_path).name)}</code> (simulated stream)." if truth_path else \
        "No truth given."
    body = f"""<header class="top"><h1>Online mass and centre-of-mass monitoring</h1>
<div class="sub">run <b>{esc(Path(jsonl).name)}</b> · {len(ups)} updates to t = {last['t']:g} s · after Linder et al.
(2015), Algorithm 1 on a sliding window · {src}</div></header>
<section class="verdict" id="verdict"><h2>Verdict</h2><p class="headline {cls}">{esc(head)}</p>
<div class="vcols"><div><h3>What was found</h3><table class="kv"><tbody>{rows}</tbody></table></div>
<div><h3>How far to trust it</h3><ul>{li}</ul><h3>What to do next</h3><ul><li>{esc(nxt)}</li></ul></div></div>
</section>{warns}
<h2>Estimates against time</h2>
<figure><img src="{uri}" alt="m, zm_bar, rho and the detector statistic against time">
<figcaption>m [kg], zm_bar [m] and rho [-] with ±2 std bands; alarms (red, solid) and located change times
(red, dashed); the detector's Wald statistic T with the default threshold.</figcaption></figure>"""
    return report_page(f"shipid report — monitor mass-cm — {Path(jsonl).name}", body)


def write_monitor_report(jsonl: str | Path, out: str | Path, *, truth_path: str | Path | None = None,
                         force: bool = False) -> Path:
    """Write the HTML page of a monitoring run (atomically; an existing ``out`` needs ``force``)."""
    out = Path(out)
    if out.exists() and not force:
        raise OutputExistsError(str(out))
    ups = read_updates(jsonl)
    truth = None
    if truth_path is not None:
        try:
            truth = json.loads(Path(truth_path).read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError) as err:
            raise InputError(f"cannot read the truth sidecar ({err})", file=str(truth_path)) from None
        if not isinstance(truth, dict) or "before" not in truth:
            raise InputError("not a truth sidecar of shipid simulate ... mass-cm-stream", file=str(truth_path))
    summ = summary(ups, truth)
    fig = figure(ups, truth, MonitorOptions().threshold)
    uri = to_data_uri(fig)
    import matplotlib.pyplot as plt
    plt.close(fig)
    warn = sorted({w for u in ups for w in u.get("warnings", [])})
    page = monitor_page(jsonl, ups, summ, uri, warn, truth_path if truth else None)
    tmp = out.with_name(out.name + ".tmp")
    tmp.write_text(page, encoding="utf-8")
    tmp.replace(out)
    return out


__all__ = ["is_monitor_jsonl", "read_updates", "summary", "figure", "write_monitor_report"]

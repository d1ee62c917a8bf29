"""Fixtures for the report tests: a headless Chromium driven over the DevTools Protocol.

The browser is Debian's ``chromium`` (``.ci/run`` installs it). It is started with
``--remote-debugging-port=0``; the port it picked is read from
``<user-data-dir>/DevToolsActivePort`` and the page is driven over a websocket on
127.0.0.1 with ``websocket-client`` (the ``test`` extra). Tests that need it skip
cleanly when the ``chromium`` executable is absent.
"""

from __future__ import annotations

import base64
import itertools
import json
import os
import shutil
import subprocess
import tempfile
import time
import urllib.request
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
ARTIFACTS = REPO / "test-artifacts"

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-extensions", "--disable-default-apps", "--mute-audio", "--hide-scrollbars",
         "--remote-debugging-address=127.0.0.1", "--remote-debugging-port=0", "--remote-allow-origins=*"]


def chromium_path() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        p = shutil.which(name)
        if p:
            return p
    return None


class Page:
    """One browser tab driven over the Chrome DevTools Protocol (a tiny synchronous client)."""

    def __init__(self, ws_url: str):
        import websocket  # websocket-client

        self.ws = websocket.create_connection(ws_url, timeout=60, suppress_origin=True)
        self._ids = itertools.count(1)
        self.events: list[dict] = []

    def send(self, method: str, **params):
        mid = next(self._ids)
        self.ws.send(json.dumps({"id": mid, "method": method, "params": params}))
        while True:
            msg = json.loads(self.ws.recv())
            if msg.get("id") == mid:
                if "error" in msg:
                    raise RuntimeError(f"CDP {method}: {msg['error']}")
                return msg.get("result", {})
            self.events.append(msg)

    def wait_event(self, method: str, timeout: float = 60.0) -> dict:
        for ev in self.events:
            if ev.get("method") == method:
                return ev
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            msg = json.loads(self.ws.recv())
            if "method" in msg:
                self.events.append(msg)
                if msg["method"] == method:
                    return msg
        raise TimeoutError(method)

    def evaluate(self, expr: str):
        res = self.send("Runtime.evaluate", expression=expr, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in res:
            raise RuntimeError(f"JS error: {res['exceptionDetails']}")
        return res["result"].get("value")

    def errors(self) -> list[str]:
        """Console errors, uncaught exceptions and error log entries (failed loads ...)."""
        out = []
        for ev in self.events:
            m, p = ev.get("method"), ev.get("params", {})
            if m == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
                out.append("console: " + " ".join(str(a.get("value", a.get("description", "")))
                                                  for a in p.get("args", [])))
            elif m == "Runtime.exceptionThrown":
                out.append("exception: " + json.dumps(p.get("exceptionDetails", {}))[:300])
            elif m == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
                e = p["entry"]
                out.append(f"log: {e.get('source')}: {e.get('text')} {e.get('url', '')}")
        return out

    def close(self) -> None:
        try:
            self.ws.close()
        except Exception:  # noqa: BLE001
            pass


class Browser:
    def __init__(self, exe: str):
        self.tmp = tempfile.mkdtemp(prefix="shipid-chromium-")
        self.proc = subprocess.Popen([exe, *FLAGS, f"--user-data-dir={self.tmp}", "about:blank"],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        port_file = Path(self.tmp) / "DevToolsActivePort"
        end = time.monotonic() + 60
        while not (port_file.exists() and port_file.read_text().strip()):
            if self.proc.poll() is not None:
                raise RuntimeError(f"chromium exited with status {self.proc.returncode}")
            if time.monotonic() > end:
                self.quit()
                raise RuntimeError("chromium did not open its DevTools port within 60 s")
            time.sleep(0.1)
        self.port = int(port_file.read_text().split()[0])

    def new_page(self) -> Page:
        req = urllib.request.Request(f"http://127.0.0.1:{self.port}/json/new?about:blank", method="PUT")
        with urllib.request.urlopen(req, timeout=30) as resp:
            target = json.loads(resp.read())
        page = Page(target["webSocketDebuggerUrl"])
        for domain in ("Page", "Runtime", "Log"):
            page.send(f"{domain}.enable")
        return page

    def check(self, html_path: Path, screenshot: Path, width: int = 1100) -> dict:
        """See :func:`open_and_check`."""
        return open_and_check(self, html_path, screenshot, width)

    def quit(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(10)
        shutil.rmtree(self.tmp, ignore_errors=True)


def open_and_check(browser: Browser, html_path: Path, screenshot: Path, width: int = 1100) -> dict:
    """Load ``html_path``; return errors, image states and a full-page screenshot path."""
    page = browser.new_page()
    try:
        page.send("Emulation.setDeviceMetricsOverride", width=width, height=900, deviceScaleFactor=1,
                  mobile=False)
        page.events.clear()
        page.send("Page.navigate", url=html_path.resolve().as_uri())
        page.wait_event("Page.loadEventFired")
        info = page.evaluate("""JSON.stringify({
            title: document.title,
            images: Array.from(document.images).map(i => ({complete: i.complete, w: i.naturalWidth,
                                                            h: i.naturalHeight, src: i.src.slice(0, 30)})),
            tables: document.querySelectorAll('table').length,
            external: Array.from(document.querySelectorAll('[src],[href]')).map(e => e.getAttribute('src') ||
                      e.getAttribute('href')).filter(u => /^(https?:)?\\/\\//.test(u)),
            overflow: (() => {
                const main = document.querySelector('main') || document.body;
                const right = main.getBoundingClientRect().right + 1;
                const out = [];
                for (const e of main.querySelectorAll('*')) {
                    if (e.closest('.scroll')) continue;      // scrolls on purpose, inside its box
                    const r = e.getBoundingClientRect();
                    const what = e.tagName + ' "' + (e.textContent || '').trim().slice(0, 60) + '"';
                    if (r.width > 0 && r.right > right) out.push(what + ' runs past the right edge');
                    else if (e.clientWidth > 0 && e.scrollWidth > e.clientWidth + 1 &&
                             getComputedStyle(e).overflowX === 'visible') out.push(what + ' overflows its box');
                }
                return out; })(),
            height: document.documentElement.scrollHeight,
            width: document.documentElement.scrollWidth, viewport: window.innerWidth})""")
        info = json.loads(info)
        first = page.evaluate("""JSON.stringify({
            verdict_top: (() => { const v = document.querySelector('.verdict');
                                  return v ? v.getBoundingClientRect().top : null; })(),
            headline: (() => { const h = document.querySelector('.verdict .headline');
                               return h ? {top: h.getBoundingClientRect().top, text: h.textContent} : null; })(),
            sideways: Array.from(document.querySelectorAll('body *')).filter(e => {
                const r = e.getBoundingClientRect();
                return r.top < window.innerHeight && r.width > 0 && r.right > window.innerWidth + 1; })
                .map(e => e.tagName + ' "' + (e.textContent || '').trim().slice(0, 60) + '"'),
            scroll_x: document.documentElement.scrollWidth - window.innerWidth})""")
        info["first_screen"] = json.loads(first)
        shot = page.send("Page.captureScreenshot", format="png")
        first_png = screenshot.with_name(screenshot.stem + "-first.png")
        first_png.parent.mkdir(parents=True, exist_ok=True)
        first_png.write_bytes(base64.b64decode(shot["data"]))
        info["first_screenshot"] = str(first_png)
        height = min(int(info["height"]), 30000)
        page.send("Emulation.setDeviceMetricsOverride", width=width, height=height, deviceScaleFactor=1,
                  mobile=False)
        shot = page.send("Page.captureScreenshot", format="png", captureBeyondViewport=True)
        screenshot.parent.mkdir(parents=True, exist_ok=True)
        screenshot.write_bytes(base64.b64decode(shot["data"]))
        info["errors"] = page.errors()
        info["screenshot"] = str(screenshot)
        return info
    finally:
        page.close()


@pytest.fixture(scope="session")
def browser():
    exe = os.environ.get("SHIPID_CHROMIUM") or chromium_path()
    if not exe:
        pytest.skip("chromium is not installed (apt-get install chromium); browser test skipped")
    pytest.importorskip("websocket", reason="websocket-client not installed (pip install -e '.[test]')")
    b = Browser(exe)
    try:
        yield b
    finally:
        b.quit()


@pytest.fixture(scope="session")
def artifacts() -> Path:
    """``test-artifacts/`` at the repository root (git-ignored): screenshots are kept there."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    return ARTIFACTS


@pytest.fixture(scope="session")
def example_reports(tmp_path_factory):
    """The HTML reports of the three example results, built once: method -> (Result, html, path)."""
    from report.examples import EXAMPLES

    return _build_reports(EXAMPLES, tmp_path_factory.mktemp("reports"))


#: The results as the methods returned them (numpy arrays inside), before the JSON round trip.
RAW: dict = {}


def _build_reports(makers: dict, folder: Path) -> dict:
    """name -> (Result, html, path) for each ``make()`` in ``makers``: the Result goes through its JSON
    (as ``shipid report RESULT.json`` reads it) and the HTML is written to ``folder/report-NAME.html``."""
    from shipid.report import build_report
    from shipid.result import Result

    out = {}
    for name, make in makers.items():
        raw = make()
        RAW[name] = raw
        r = Result.from_json(raw.to_json())
        html = build_report(r)
        path = folder / f"report-{name}.html"
        path.write_text(html, encoding="utf-8")
        out[name] = (r, html, path)
    return out


def _masscm_result():
    from shipid.methods.masscm.estimator import fit_mass_cm
    from shipid.methods.masscm.series import with_series
    from shipid.models.roll_reduced import KnownParams
    from shipid.models.roll_sim import simulate_datasets
    from shipid.vessels import load_vessel

    d = simulate_datasets("fishing-vessel", seed=0)
    z_f = float(load_vessel("fishing-vessel").value("general", "z_f"))
    return with_series(fit_mass_cm(list(d.items()), KnownParams.from_vessel("fishing-vessel"), z_f=z_f), cost_map=True)


def _spread_result():
    from shipid.methods.masscm.series import spread_result
    from shipid.methods.masscm.study import run_one, summarise

    outs = [run_one(i, 1) for i in range(4)]
    s = summarise(outs)
    s.update({"seed": 1, "data_seed": 0, "init": "given"})
    return spread_result(s, outs, command="test: 4 runs")


def _dp_result():
    from shipid.methods.dp.estimator import fit_dp
    from shipid.methods.dp.series import with_series
    from shipid.methods.dp.trials import TrialNoise, simulate_dp_trials
    from shipid.models.dp import dp_vessel
    from shipid.vessels import load_vessel

    v = dp_vessel(load_vessel("supply"))
    trials = simulate_dp_trials(v, 0, duration=300.0, n_per_kind=1, noise=TrialNoise())
    return with_series(fit_dp(trials["surge"], trials["sway-yaw"], trials["azimuth"], v, theta_true=v.theta))


def _ebm_result():
    from shipid.methods.ebm.design import prbs_grid
    from shipid.methods.ebm import estimator as ebm
    from shipid.methods.ebm import series as ebm_series
    from shipid.methods.ebm.trials import simulate_trial

    res = ebm_series.with_series(ebm.identify_run([simulate_trial("zigzag-20", 300.0, seed=11)]))
    # the opt-in extras, small: held-out validation (Figs 6, 10) and a 2 x 2 D-optimal map (Fig. 7)
    res.series["overlays"].update(ebm_series.validation_overlays(res, duration=100.0))
    res.series["contours"] = {"d_optimal": ebm_series.d_optimal_contour(
        prbs_grid((10.0, 35.0), (30.0, 105.0), duration=200.0, seeds=(0,), dt=2.0))}
    return res


#: Real method runs (small, seeded) whose reports the figure and browser tests check.
METHOD_RUNS = {"mass-cm": _masscm_result, "mass-cm-spread": _spread_result, "dp": _dp_result,
               "ebm": _ebm_result}


@pytest.fixture(scope="session")
def method_reports(tmp_path_factory):
    """Reports of real (small) runs of the three methods, built once: name -> (Result, html, path).

    The Result goes through its JSON (as ``shipid report RESULT.json`` reads it).
    """
    return _build_reports(METHOD_RUNS, tmp_path_factory.mktemp("method-reports"))


@pytest.fixture(scope="session")
def raw_results(method_reports):
    """name -> the in-memory Result of each real method run (as ``shipid demo`` passes them to the report)."""
    return {k: RAW[k] for k in method_reports}


@pytest.fixture(scope="session")
def esso_mmg_report(tmp_path_factory):
    """``shipid identify mmg`` on two real Esso Osaka zig-zags, then its report: (Result, html, path, runs).

    Skips when the shared data folder is absent.
    """
    import subprocess
    import sys

    from shipid.cli.report_cmds import load_result
    from shipid.io.paths import data_root
    from shipid.report import build_report

    root = data_root()
    zz = (root / "esso_osaka_3m" / "data" / "zigzag") if root else None
    if zz is None or not zz.is_dir():
        pytest.skip("the shared Esso Osaka data are not available")
    runs = sorted(zz.glob("*.csv"))[:2]
    folder = tmp_path_factory.mktemp("esso")
    model = folder / "model.json"
    cmd = [sys.executable, "-m", "shipid", "identify", "mmg", "--format", "esso", "--structure",
           "hull+rudder+thrust", "-o", str(model)]
    for r in runs:
        cmd += ["--trial", str(r)]
    subprocess.run(cmd, check=True, capture_output=True, cwd=folder)
    res = load_result(model)
    html = build_report(res)
    path = folder / "report-esso-mmg.html"
    path.write_text(html, encoding="utf-8")
    return res, html, path, runs

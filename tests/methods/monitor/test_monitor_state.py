"""``shipid monitor mass-cm --state FILE``: output lines written as produced, the state saved atomically at
every update; after ``kill -9`` at a random update the same command resumes without the start-up, and its
output equals an uninterrupted run's."""

import json
import random
import signal
import subprocess
import time

import pytest
from monitor_procs import env, monitor_args, run, shipid_cmd

from shipid.cli import main


def _lines(p):
    return p.read_text(encoding="utf-8").splitlines() if p.exists() else []


@pytest.mark.parametrize("seed", [1])
def test_kill9_at_a_random_update_then_resume_equals_uninterrupted(stream300, tmp_path, seed, monkeypatch, capsys):
    d = stream300
    ref = _lines(d / "ref.jsonl")
    assert len(ref) == 30
    out, state = tmp_path / "run.jsonl", tmp_path / "state.bin"
    target = random.Random(seed).randint(13, 27)       # after the start-up (its first estimate at update 12)
    args = monitor_args(d, "--stream", str(d / "s.csv"), "-o", str(out), "--state", str(state))
    proc = subprocess.Popen(shipid_cmd(*args), env=env(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    t_end = time.monotonic() + 120
    while len(_lines(out)) < target and proc.poll() is None and time.monotonic() < t_end:
        time.sleep(0.005)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL
    written = _lines(out)
    assert target <= len(written) < 30 and state.exists()
    assert written[:len(written) - 1] == ref[:len(written) - 1]       # as produced, not at the end
    # resume in this process: the start-up must not run again
    from shipid.methods.monitor import estimator as E

    def no_start(self):
        raise AssertionError("the start-up ran again")
    monkeypatch.setattr(E.MassCMMonitor, "_start", no_start)
    assert main(args) == 0
    cap = capsys.readouterr()
    assert "resumed from" in cap.err
    assert _lines(out) == ref
    printed = cap.out.splitlines()
    assert printed == ref[-len(printed):] and 0 < len(printed) <= 30 - target + 1


def test_state_of_other_inputs_is_refused(stream300, tmp_path):
    d = stream300
    state = tmp_path / "st.bin"
    assert main(monitor_args(d, "--stream", str(d / "s.csv"), "--state", str(state), "--every", "10")) == 0
    assert state.exists()
    r = run(*monitor_args(d, "--stream", str(d / "s.csv"), "--state", str(state), "--window", "200"))
    assert r.returncode == 2 and r.stderr.strip().splitlines()[-1] == (
        f"shipid: error: {state}: the state was saved with other inputs (nominal, calibration, known or "
        "options); use another --state file")
    state.write_bytes(b"\x80\x04garbage")
    r = run(*monitor_args(d, "--stream", str(d / "s.csv"), "--state", str(state)))
    assert r.returncode == 2 and "not a readable monitor state" in r.stderr and "Traceback" not in r.stderr


def test_a_finished_state_resumes_to_nothing_new(stream300, tmp_path, capsys):
    d = stream300
    out, state = tmp_path / "o.jsonl", tmp_path / "s.bin"
    args = monitor_args(d, "--stream", str(d / "s.csv"), "-o", str(out), "--state", str(state))
    assert main(args) == 0
    first = _lines(out)
    capsys.readouterr()
    assert main(args) == 0
    assert capsys.readouterr().out == "" and _lines(out) == first == _lines(d / "ref.jsonl")
    assert json.loads(first[-1])["t"] == 300.0


def test_state_file_runs_no_foreign_code(tmp_path):
    """The state is a pickle read by a restricted unpickler: only numpy arrays, deques and shipid classes."""
    import os
    import pickle

    from shipid.errors import InputError
    from shipid.methods.monitor.session import load_state

    class Evil:
        def __reduce__(self):
            return (os.system, ("touch " + str(tmp_path / "pwned"),))

    p = tmp_path / "evil.bin"
    p.write_bytes(pickle.dumps({"version": 1, "fingerprint": "x", "session": Evil()}))
    with pytest.raises(InputError, match="not a readable monitor state"):
        load_state(str(p), "x")
    assert not (tmp_path / "pwned").exists()

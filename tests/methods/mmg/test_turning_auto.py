"""The automatic turning selection's guard and heading constraint (shipid.methods.mmg.turning_auto)."""

from types import SimpleNamespace

from shipid.methods.mmg import turning_auto as N


def _runs(*names):
    return [SimpleNamespace(meta={"source": f"/x/HSVA_CPMC_KVLCC2_Z_{n}.dat"}) for n in names]


def test_guard_counts_runs_with_switch_of_5_deg_or_more_at_distinct_angles():
    assert not N.guard(_runs("10_05", "15_05"))[0]                       # two runs
    assert not N.guard(_runs("10_05", "10_10_P", "10_10_S", "10_05"))[0]  # one angle
    assert not N.guard(_runs("10_01", "15_01", "10_05", "15_05", "20_05"))[0]  # 1-deg runs do not count: 3
    assert N.guard(_runs("10_05", "10_10_P", "15_05", "20_05"))[0]
    assert not N.guard(_runs("10_01", "15_01", "10_05", "15_05"))[0]     # only 2 count


def _tables(monkeypatch, peak, psi, horizon):
    names = list(peak)

    def fake_default(trials, runs, prior, cands, config=None, folds=None):
        t = {c: {"score": horizon[c]} for c in cands}
        return min(t, key=lambda c: t[c]["score"]), t

    def fake_turning(trials, runs, prior, cands, config=None, folds=None, *, criterion="peak"):
        t = {c: {"score": peak[c], "psi_rms": psi[c]} for c in names}
        return min(t, key=lambda c: t[c]["score"]), t, "m"

    monkeypatch.setattr(N, "select_structure", fake_default)
    monkeypatch.setattr(N.TS, "select_for_turning", fake_turning)
    monkeypatch.setattr(N, "CANDIDATES", {"s": {"a": {}, "b": {}}})
    return {c: {} for c in names}


def test_select_auto_takes_lowest_peak_within_heading_limit(monkeypatch):
    # default (horizons) chooses 'a' (heading 4); 'c' has the lowest peak error but heading 6.5 > 1.5 x 4
    cands = _tables(monkeypatch, peak={"a": 6.0, "b": 5.0, "c": 3.0}, psi={"a": 4.0, "b": 5.9, "c": 6.5},
                    horizon={"a": 1.0, "b": 2.0})
    prior = SimpleNamespace(structure="s")
    trials = _runs("10_05", "10_10_P", "15_05", "20_05")
    name, table, method = N.select_auto(trials, None, prior, cands)
    assert name == "b"
    assert table["c"]["within_heading_limit"] is False and "6.00 deg" in method


def test_select_auto_falls_back_to_default_on_few_runs(monkeypatch):
    cands = _tables(monkeypatch, peak={"a": 6.0, "b": 1.0}, psi={"a": 4.0, "b": 4.0}, horizon={"a": 2.0, "b": 1.0})
    name, table, method = N.select_auto(_runs("10_05", "15_05"), None, SimpleNamespace(structure="s"), cands)
    assert name == "b" and "not used" in method and set(table) == {"a", "b"}

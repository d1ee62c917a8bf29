"""Validation at the door (shipid.io.validate): errors with rows, and the explicit repairs."""

import numpy as np
import pytest

from shipid.io.validate import UNIFORM_RTOL, interpolate, validate_arrays
from shipid.errors import InputError


def ramp(n=11, dt=0.1):
    t = dt * np.arange(n)
    return t, {"x": 2.0 * t + 1.0, "u": np.full(n, 2.0)}


def test_clean_input_passes_unchanged():
    t, ch = ramp()
    t2, ch2, repairs = validate_arrays(t, ch)
    np.testing.assert_array_equal(t2, t)
    np.testing.assert_array_equal(ch2["x"], ch["x"])
    assert repairs == []


def test_float_drift_of_long_records_is_uniform():
    # t accumulated as a running sum over an hour at 10 Hz, as loggers do
    t = np.cumsum(np.full(40000, 0.1)) + 1176.0
    validate_arrays(t, {"x": np.zeros_like(t)})


def test_duplicate_timestamp_names_row():
    t, ch = ramp()
    t[5] = t[4]
    with pytest.raises(InputError, match=r"channel 't', row 6: duplicated timestamp t=0\.4 s \(same as row 5\)"):
        validate_arrays(t, ch, file="f.csv")


def test_backwards_time_names_row_given_by_caller():
    t, ch = ramp()
    t[3], t[4] = t[4], t[3]
    rows = np.arange(10, 21)
    with pytest.raises(InputError, match=r"row 14: time not increasing"):
        validate_arrays(t, ch, rows=rows)


def test_missing_value_is_error_without_repair():
    t, ch = ramp()
    ch["x"][4] = np.nan
    with pytest.raises(InputError, match=r"channel 'x', row 5: missing value"):
        validate_arrays(t, ch)


def test_infinite_value_is_error():
    t, ch = ramp()
    ch["u"][2] = -np.inf
    with pytest.raises(InputError, match=r"channel 'u', row 3: infinite value"):
        validate_arrays(t, ch)


def test_missing_values_interpolated_within_limit():
    t, ch = ramp()
    ch["x"][4:6] = np.nan                # gap from t=0.3 to t=0.6: 0.3 s
    t2, ch2, repairs = validate_arrays(t, ch, interpolate_gaps=0.3 + 1e-9)
    np.testing.assert_allclose(ch2["x"], 2.0 * t + 1.0, rtol=0, atol=1e-12)
    assert repairs[0]["kind"] == "interpolated" and repairs[0]["channel"] == "x"
    assert (repairs[0]["first_row"], repairs[0]["last_row"], repairs[0]["samples"]) == (5, 6, 2)
    assert repairs[0]["seconds"] == pytest.approx(0.3)
    with pytest.raises(InputError, match=r"row 5: .*gap of 0\.3 s \(rows 5-6\) is longer"):
        validate_arrays(t, ch, interpolate_gaps=0.25)


def test_missing_values_at_the_ends_cannot_be_interpolated():
    t, ch = ramp()
    ch["x"][-2:] = np.nan
    with pytest.raises(InputError, match=r"row 10: .*at the end of the record"):
        validate_arrays(t, ch, interpolate_gaps=100.0)


def test_missing_time_stamp_interpolated_by_index():
    t, ch = ramp()
    t[3] = np.nan
    t2, _, repairs = validate_arrays(t, ch, interpolate_gaps=0.2 + 1e-9)
    np.testing.assert_allclose(t2, 0.1 * np.arange(11), atol=1e-12)
    assert repairs[0]["channel"] == "t"


def test_angle_interpolated_across_wrap():
    t = np.array([0.0, 0.1, 0.2])
    psi = np.array([2 * np.pi - 0.1, np.nan, 0.1])
    _, ch, _ = validate_arrays(t, {"psi": psi}, units={"psi": "rad"}, interpolate_gaps=1.0)
    # the short way round through 0 (= 2*pi), not through pi
    assert np.cos(ch["psi"][1]) == pytest.approx(1.0)
    assert ch["psi"][0] == psi[0] and ch["psi"][2] == psi[2]


def test_interpolate_angle_keeps_samples():
    t = np.linspace(0, 1, 11)
    psi = np.mod(np.linspace(0, 10, 11), 2 * np.pi)
    np.testing.assert_array_equal(interpolate(t, t, psi, angle=True), psi)


def test_time_gap_is_error_and_fill_on_request():
    t, ch = ramp(11)
    keep = np.ones(11, bool)
    keep[[4, 5]] = False                  # two samples lost: step 0.3 s
    t, ch = t[keep], {k: v[keep] for k, v in ch.items()}
    with pytest.raises(InputError, match=r"row 5: time gap of 0\.3 s \(t=0\.3 s to 0\.6 s.* after row 4"):
        validate_arrays(t, ch)
    t2, ch2, repairs = validate_arrays(t, ch, interpolate_gaps=0.31)
    np.testing.assert_allclose(t2, 0.1 * np.arange(11), atol=1e-12)
    np.testing.assert_allclose(ch2["x"], 2.0 * t2 + 1.0, atol=1e-12)
    assert repairs[0]["kind"] == "filled_time_gap" and repairs[0]["samples"] == 2
    with pytest.raises(InputError, match="longer than --interpolate-gaps"):
        validate_arrays(t, ch, interpolate_gaps=0.29)


def test_gap_that_is_not_whole_steps_needs_resample():
    t = np.array([0.0, 0.1, 0.2, 0.45, 0.55, 0.65])
    ch = {"x": t.copy()}
    with pytest.raises(InputError, match="non-uniform sampling"):
        validate_arrays(t, ch, interpolate_gaps=1.0)
    t2, ch2, _ = validate_arrays(t, ch, interpolate_gaps=1.0, resample=0.1)
    np.testing.assert_allclose(np.diff(t2), 0.1, rtol=1e-12)
    np.testing.assert_allclose(ch2["x"], t2, atol=1e-12)


def test_non_uniform_is_error_and_resample_on_request():
    t, ch = ramp()
    t[5] += 0.02
    ch["x"] = 2.0 * t + 1.0
    with pytest.raises(InputError, match=r"row 6: non-uniform sampling: step of 0\.12 s after row 5"):
        validate_arrays(t, ch)
    t2, ch2, repairs = validate_arrays(t, ch, resample=0.05)
    assert t2.size == 21
    np.testing.assert_allclose(ch2["x"], 2.0 * t2 + 1.0, atol=1e-12)  # linear data is reproduced
    assert repairs[-1]["kind"] == "resampled"


def test_jitter_below_tolerance_is_accepted():
    t, ch = ramp()
    t[5] += 0.5 * UNIFORM_RTOL * 0.1
    validate_arrays(t, ch)


def test_required_channel_missing():
    t, ch = ramp()
    with pytest.raises(InputError, match=r"channel 'r': required channel missing \(has: x, u\)"):
        validate_arrays(t, ch, required=["t", "x", "r"])


def test_trim_only_on_request_and_only_at_ends():
    t, ch = ramp()
    t[-3:] = np.nan
    for v in ch.values():
        v[-3:] = np.nan
    with pytest.raises(InputError, match=r"channel 't', row 9: missing value .*--trim-empty"):
        validate_arrays(t, ch)
    t2, ch2, repairs = validate_arrays(t, ch, trim_empty_rows=True)
    assert t2.size == 8
    assert repairs == [{"kind": "trimmed_empty_rows", "first_row": 9, "last_row": 11, "samples": 3,
                        "text": "removed 3 empty rows 9-11 at the end"}]


def test_too_short_and_bad_options():
    with pytest.raises(InputError, match="only one data row"):
        validate_arrays([0.0], {"x": [1.0]})
    t, ch = ramp()
    with pytest.raises(InputError, match="interpolate-gaps must be a positive"):
        validate_arrays(t, ch, interpolate_gaps=-1)
    with pytest.raises(InputError, match="resample must be a positive"):
        validate_arrays(t, ch, resample=0.0)


def test_required_message_names_the_method():
    t, ch = ramp()
    with pytest.raises(InputError, match=r"channel 'delta': required by identify ebm but missing"):
        validate_arrays(t, ch, required=["delta"], method="identify ebm")


def test_concat_trials_reports_gap_between_parts():
    from shipid.io import Trial
    from shipid.io.combine import concat_trials
    t = 0.1 * np.arange(10)
    a = Trial(t[:4], {"x": t[:4]}, meta={"source": "a.csv"})
    b = Trial(t[4:], {"x": t[4:]}, meta={"source": "b.csv"})
    c = Trial(t[6:], {"x": t[6:]}, meta={"source": "c.csv"})
    joined = concat_trials([a, b])
    np.testing.assert_array_equal(joined.t, t)
    assert joined.meta["parts"] == ["a.csv", "b.csv"]
    with pytest.raises(InputError, match=r"a\.csv \+ c\.csv, channel 't', row 5: time gap of 0\.3 s"):
        concat_trials([a, c])
    filled = concat_trials([a, c], interpolate_gaps=0.35)
    np.testing.assert_allclose(filled["x"], t, atol=1e-12)
    with pytest.raises(InputError, match="time not increasing"):
        concat_trials([b, a])

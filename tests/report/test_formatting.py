"""Rounding of estimates in the report: digits follow the standard error (2 significant digits)."""

import math

import pytest

from shipid.report.formatting import fmt_fixed, fmt_num, format_estimate


@pytest.mark.parametrize("value, std, expect_value, expect_std", [
    (1234.567, 12.3, "1235", "12"),            # SE 12.3 -> 2 digits: units
    (0.5, 0.0123, "0.500", "0.012"),           # SE 0.0123 -> 3 decimals
    (-0.36812, 0.06, "−0.368", "0.060"),
    (14430.2, 420.0, "14430", "420"),
    (271234.0, 23875.0, "271000", "24000"),    # SE 2.4e4 -> rounded to thousands
])
def test_digits_follow_standard_error(value, std, expect_value, expect_std):
    f = format_estimate(value, std)
    assert (f.value, f.std, f.scale) == (expect_value, expect_std, "")


def test_large_values_share_a_power_of_ten():
    f = format_estimate(5.234e6, 4.6e5)
    assert f.scale == "×10⁶"
    assert (f.value, f.std, f.ci_low, f.ci_high) == ("5.23", "0.46", "4.33", "6.14")


def test_interval_is_value_plus_minus_1_96_se():
    f = format_estimate(10.0, 1.0)
    lo, hi = 10.0 - 1.959963984540054, 10.0 + 1.959963984540054
    assert f.ci_low == fmt_fixed(lo, 1) == "8.0" and f.ci_high == fmt_fixed(hi, 1) == "12.0"
    assert f.rel == "10 %"


def test_missing_and_infinite_standard_errors():
    assert format_estimate(3.14159, float("nan")).std == "—"
    assert format_estimate(3.14159, float("nan")).value == "3.142"   # 4 significant digits
    assert format_estimate(3.0e4, math.inf).std == "not identifiable"
    assert format_estimate(float("nan"), 1.0).value == "—"


@pytest.mark.parametrize("x, text", [(0.0, "0"), (1, "1"), (-12345678.0, "−1.235×10⁷"), (0.000123456, "1.235×10⁻⁴"),
                                     (0.012, "0.012"), (True, "yes"), (float("inf"), "∞"), (42.0, "42")])
def test_fmt_num(x, text):
    assert fmt_num(x) == text


def test_no_negative_zero():
    assert fmt_fixed(-0.0001, 2) == "0.00"


_SUP_BACK = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")


def _parse(text: str, scale: str) -> tuple[float, float]:
    """(number, half of its last digit) of a formatted cell, shared power of ten applied."""
    s = text.replace("−", "-")
    k = 10.0 ** int(scale.replace("×10", "").translate(_SUP_BACK)) if scale else 1.0
    decimals = len(s.split(".")[1]) if "." in s else 0
    trailing = 0 if "." in s else len(s) - len(s.rstrip("0"))
    half = 0.5 * 10.0 ** (-decimals) if "." in s else 0.5 * 10.0 ** trailing
    return float(s) * k, half * k


from hypothesis import given, settings, strategies as st  # noqa: E402


@settings(max_examples=300, deadline=None)
@given(st.floats(-1e9, 1e9, allow_nan=False).filter(lambda v: v == 0 or abs(v) > 1e-9),
       st.floats(1e-7, 1e8, allow_nan=False))
def test_rounding_is_faithful_and_keeps_two_se_digits(value, std):
    if abs(value) > 1e12 * std:  # beyond what float64 can show with two SE digits
        return
    f = format_estimate(value, std)
    unit = 10.0 ** (math.floor(math.log10(std)) - 1)   # second significant digit of the SE
    for text, true in ((f.value, value), (f.std, std)):
        shown, half = _parse(text, f.scale)
        # rounded at the SE's second significant digit: faithful to half that unit ...
        assert abs(shown - true) <= 0.5 * unit * (1 + 1e-6) + 1e-12 * abs(true)
        # ... and a decimal string shows exactly down to that digit
        if "." in text:
            assert math.isclose(half, 0.5 * unit, rel_tol=1e-6)

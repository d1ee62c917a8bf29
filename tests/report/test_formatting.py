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

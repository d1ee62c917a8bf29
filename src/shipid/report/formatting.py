"""Rounding numbers for the report: digits follow the standard error.

An estimate is shown with as many decimals as the second significant digit of
its standard error (``1234.567 ± 12.3`` → ``1235 ± 12``); very large or small
values use a power of ten shared by value, SE and interval
(``1.234×10⁶ ± 1.2×10⁴`` is shown as ``1.234 ± 0.012 ×10⁶``). Output is HTML.
"""

from __future__ import annotations

import html
import math
from dataclasses import dataclass

Z95 = 1.959963984540054  # two-sided 95 % normal quantile

_SUP = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _pow10(e: int) -> str:
    return f"×10{str(e).translate(_SUP)}"


def _isfinite(x) -> bool:
    try:
        return math.isfinite(float(x))
    except (TypeError, ValueError):
        return False


def _minus(s: str) -> str:
    return s.replace("-", "−")


def fmt_fixed(x: float, decimals: int) -> str:
    """``x`` rounded to ``decimals`` decimals (negative: tens, hundreds ...), with a true minus sign."""
    if decimals >= 0:
        s = f"{x:.{decimals}f}"
    else:
        q = 10.0 ** (-decimals)
        s = f"{round(x / q) * q:.0f}"
    if s.lstrip("-").strip("0.") == "":  # "-0.00" -> "0.00"
        s = s.lstrip("-")
    return _minus(s)


def fmt_num(x, sig: int = 4) -> str:
    """A number with ``sig`` significant digits (ints exact, bools as yes/no), as HTML text."""
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, int):
        return _minus(f"{x:d}")
    try:
        v = float(x)
    except (TypeError, ValueError):
        return html.escape(str(x))
    if math.isnan(v):
        return "—"
    if math.isinf(v):
        return "∞" if v > 0 else "−∞"
    if v == 0:
        return "0"
    e = math.floor(math.log10(abs(v)))
    if -3 <= e < 6:
        decimals = max(sig - 1 - e, 0)
        s = fmt_fixed(v, decimals)
        if "." in s:
            s = s.rstrip("0").rstrip(".")
        return s
    m = v / 10.0 ** e
    if round(abs(m), sig - 1) >= 10:
        m, e = m / 10, e + 1
    return f"{fmt_fixed(m, sig - 1)}{_pow10(e)}"


@dataclass(frozen=True)
class FormattedEstimate:
    """HTML strings for one table row; ``scale`` is a shared ``×10ⁿ`` or ``""``."""

    value: str
    std: str
    ci_low: str
    ci_high: str
    rel: str
    scale: str


def format_estimate(value: float, std: float) -> FormattedEstimate:
    """Round ``value``, its SE and its 95 % interval consistently.

    The number of decimals is set by the SE: two significant digits of ``std``.
    With no SE (NaN or 0) the value gets four significant digits; an infinite SE
    means the parameter is not identifiable from the data.
    """
    if not _isfinite(value):
        return FormattedEstimate(fmt_num(value), "—", "—", "—", "—", "")
    v = float(value)
    s = float(std) if std is not None else float("nan")
    if math.isinf(s):
        return FormattedEstimate(fmt_num(v), "not identifiable", "—", "—", "—", "")
    if math.isnan(s) or s <= 0:
        return FormattedEstimate(fmt_num(v), "—", "—", "—", "—", "")
    lo, hi = v - Z95 * s, v + Z95 * s
    rel = f"{fmt_num(100 * s / abs(v), 2)} %" if v != 0 else "—"
    big = max(abs(v), abs(lo), abs(hi))
    e_big = math.floor(math.log10(big)) if big > 0 else 0
    e_std = math.floor(math.log10(s))
    if -3 <= e_big < 6 and e_std >= -6:
        d = 1 - e_std  # decimals for 2 significant digits of the SE
        return FormattedEstimate(fmt_fixed(v, d), fmt_fixed(s, max(d, 0) if d >= 0 else d),
                                 fmt_fixed(lo, d), fmt_fixed(hi, d), rel, "")
    # shared power of ten, chosen from the largest magnitude
    E = e_big
    k = 10.0 ** E
    d = max(1 - (e_std - E), 0)
    d = min(d, 15)  # float64 carries ~16 significant digits
    return FormattedEstimate(fmt_fixed(v / k, d), fmt_fixed(s / k, d), fmt_fixed(lo / k, d),
                             fmt_fixed(hi / k, d), rel, _pow10(E))

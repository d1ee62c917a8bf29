"""Helpers shared by the default sections."""

from __future__ import annotations

from typing import Mapping

from shipid.report.registry import Claim


def entries(result, kind: str, *, names=(), prefixes=(), where=None) -> list[tuple[str, Mapping]]:
    """Entries of ``result.series[kind]`` selected by exact name, name prefix or predicate."""
    s = (result.series or {}).get(kind) or {}
    if not isinstance(s, Mapping):
        return []
    out = []
    for n, e in s.items():
        if not isinstance(e, Mapping):
            continue
        if n in names or any(n.startswith(p) for p in prefixes) or (where is not None and where(n, e)):
            out.append((n, e))
    return out


def fig_and_claim(kind: str, name: str, fig, caption: str) -> list:
    return [(fig, caption), Claim(kind, name)]


def caption(entry: Mapping, paper: str, default: str) -> str:
    ref = entry.get("paper") or paper
    return f"{ref} — {entry.get('title') or default}"

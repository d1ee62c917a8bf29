"""Suite-wide checks.

With ``CI`` set to a true value (``.ci/run`` sets ``CI=true``), a missing real-data folder
(``../shared/data`` or ``$SHIPID_DATA``, see :func:`shipid.data.paths.data_root`) stops the run
at once instead of letting the real-data tests skip: a CI run that skipped them would stay green
while checking less than it claims.
"""

from __future__ import annotations

import os

import pytest

from shipid.data.paths import data_root


def _ci() -> bool:
    return os.environ.get("CI", "").strip().lower() in {"1", "true", "yes", "on"}


def pytest_sessionstart(session):
    if _ci() and data_root() is None:
        where = os.environ.get("SHIPID_DATA") or "../shared/data"
        pytest.exit(f"CI: the real data are missing ({where} not found); set SHIPID_DATA or place "
                    "../shared/data beside the checkout", returncode=4)

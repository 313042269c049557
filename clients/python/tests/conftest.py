"""Shared fixtures: the package's protocol description."""
from __future__ import annotations

import pytest

from osc_client import PROTOCOL_JSON, Protocol


@pytest.fixture(scope="session")
def protocol() -> Protocol:
    """The package's description (not $OSC_PROTOCOL: the tests are the default arm's)."""
    return Protocol(PROTOCOL_JSON)


@pytest.fixture(autouse=True)
def default_arm(monkeypatch: pytest.MonkeyPatch) -> None:
    """No $OSC_PROTOCOL of the caller's: the command line reads the package's description too."""
    monkeypatch.delenv("OSC_PROTOCOL", raising=False)

"""Shared fixtures: the package's protocol description."""
from __future__ import annotations

import pytest

from osc_client import PROTOCOL_JSON, Protocol


@pytest.fixture(scope="session")
def protocol() -> Protocol:
    """The package's description (not $OSC_PROTOCOL: the tests are the default arm's)."""
    return Protocol(PROTOCOL_JSON)

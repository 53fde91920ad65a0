"""colour-science is the independent estimator of these tests (installed for tests and the data
generator; the extension never imports it). Its import warnings about optional packages are muted."""

from __future__ import annotations

import warnings

import pytest


@pytest.fixture(scope="session")
def colour():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import colour as colour_module
        import colour.recovery  # noqa: F401
    return colour_module

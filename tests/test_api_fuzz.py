"""Property-based fuzz of the API's own OpenAPI schema (schemathesis): never an undocumented 5xx.

Bounded (half the hypothesis profile's examples per operation: 20 in CI, 150 with
``--hypothesis-profile=dev``; no deadline; a 2 s budget per request) so that CI stays quick.
Every answer must match the documented response schema, with a status code the schema declares
for that operation (400 unreadable body, 413, 415, 422 invalid input, 503...). The one 5xx the API
documents is 503 (with ``Retry-After``): a request over its time budget, a busy server or a
server stopping. A loaded machine can send a fuzzed request over its budget, so a 503 passes
when, and only when, the operation documents it, it carries Retry-After and its detail is one of
the budget or busy messages (:mod:`app.api.budget`); any other 5xx fails.
"""

from __future__ import annotations

import re

import pytest
import schemathesis
from hypothesis import HealthCheck, settings
from schemathesis.checks import not_a_server_error
from schemathesis.specs.openapi.checks import response_schema_conformance, status_code_conformance

from app.api import ApiSettings, create_api
from app.api.budget import RETRY_AFTER_S

EXAMPLES = max(10, settings.default.max_examples // 2)  # the profile in force (tests/conftest.py)


@pytest.fixture(scope="module")
def api_schema():
    """The API's own schema, read when the test runs: building its tests costs ~2 s, which every
    pytest-xdist worker would pay again at collection (each collects every file)."""
    return schemathesis.openapi.from_asgi("/openapi.json", create_api(ApiSettings(time_budget_s=2.0, max_batch=50)))


schema = schemathesis.pytest.from_fixture("api_schema")
"""One test; each operation of the schema is a subtest of its own, reported by name."""

UNAVAILABLE = re.compile(
    r"^(analysis )?stopped[ :]"  # a budget stop: where, and why (app.api.budget, app.workers)
    r"|^all \d+ workers are busy( and \d+ requests are waiting)?; retry in a moment$"
    r"|^waited [\d.]+ s in the queue for one of the \d+ workers; retry in a moment$"
)


def check_unavailable(case, response) -> None:
    """A 503 is the documented answer of a budget stop or a busy server, never a bare failure."""
    assert "503" in case.operation.definition.raw.get("responses", {}), f"undocumented 503\n{case.as_curl_command()}"
    assert response.headers.get("retry-after") == [str(RETRY_AFTER_S)], response.headers
    detail = response.json()["detail"]
    assert isinstance(detail, str) and UNAVAILABLE.search(detail), detail


@schema.parametrize()
@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
def test_no_server_error(case):
    response = case.call()
    if response.status_code == 503:
        check_unavailable(case, response)
        case.validate_response(response, checks=[response_schema_conformance, status_code_conformance])
        return
    assert response.status_code < 500, f"{response.status_code}: {response.text[:500]}\n{case.as_curl_command()}"
    case.validate_response(response, checks=[not_a_server_error, response_schema_conformance, status_code_conformance])


def test_the_503_check_accepts_only_the_documented_answer():
    """The check above can fail: a 503 without Retry-After, or with another message, is refused."""

    class Op:
        definition = type("D", (), {"raw": {"responses": {"503": {}}}})()

    class Case:
        operation = Op()

        def as_curl_command(self) -> str:
            return "curl ..."

    class Response:
        def __init__(self, headers, detail):
            self.headers, self._detail = headers, detail

        def json(self):
            return {"detail": self._detail}

    ok = [str(RETRY_AFTER_S)]
    check_unavailable(Case(), Response({"retry-after": ok}, "stopped after 3 of 9 pairs: over the time budget of 5 s per request"))
    check_unavailable(Case(), Response({"retry-after": ok}, "all 2 workers are busy and 16 requests are waiting; retry in a moment"))
    for headers, detail in [({}, "stopped: x"), ({"retry-after": ok}, "Internal Server Error"), ({"retry-after": ok}, "boom")]:
        try:
            check_unavailable(Case(), Response(headers, detail))
        except AssertionError:
            continue
        raise AssertionError(f"accepted {headers} {detail!r}")

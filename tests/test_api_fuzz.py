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

import schemathesis
from hypothesis import HealthCheck, given, settings
from schemathesis import GenerationMode
from schemathesis.checks import not_a_server_error
from schemathesis.specs.openapi.checks import response_schema_conformance, status_code_conformance

from app.api import ApiSettings, create_api
from app.api.budget import RETRY_AFTER_S

EXAMPLES = max(10, settings.default.max_examples // 2)  # the profile in force (tests/conftest.py)


def api_operations():
    """The operations of the API's own schema, read when the test runs (not at collection, where
    every pytest-xdist worker would pay for it)."""
    schema = schemathesis.openapi.from_asgi("/openapi.json", create_api(ApiSettings(time_budget_s=2.0, max_batch=50)))
    return [result.ok() for result in schema.get_all_operations()]


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


def check_case(case) -> None:
    """One generated request: a documented answer, never an undocumented 5xx."""
    response = case.call()
    if response.status_code == 503:
        check_unavailable(case, response)
        case.validate_response(response, checks=[response_schema_conformance, status_code_conformance])
        return
    assert response.status_code < 500, f"{response.status_code}: {response.text[:500]}\n{case.as_curl_command()}"
    case.validate_response(response, checks=[not_a_server_error, response_schema_conformance, status_code_conformance])


def fuzz_operations(operations, check=check_case) -> dict[str, str]:
    """Valid and invalid requests of every operation (schemathesis' strategies driven by Hypothesis
    here, through its public API only: its pytest plugin reaches into pytest's internals, which
    pytest 9.2 changed); the failing operations, by label, with Hypothesis' smallest example."""
    failures = {}
    for operation in operations:
        strategy = operation.as_strategy(GenerationMode.POSITIVE) | operation.as_strategy(GenerationMode.NEGATIVE)

        @settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck), database=None)
        @given(case=strategy)
        def run(case):
            check(case)

        try:
            run()
        except Exception as error:  # noqa: BLE001 - every operation is fuzzed; all failures are reported
            failures[operation.label] = f"{type(error).__name__}: {error}"
    return failures


def test_no_server_error():
    operations = api_operations()
    assert len(operations) >= 13, [op.label for op in operations]  # every route of the API is fuzzed
    failures = fuzz_operations(operations)
    assert not failures, "\n\n".join(f"{label}:\n{text}" for label, text in failures.items())


def test_the_fuzz_reports_a_failing_operation_by_name():
    """The loop above can fail: an operation whose check fails is reported, the others still run."""
    operations = api_operations()[:3]
    seen = []

    def check(case):
        seen.append(case.operation.label)
        if case.operation.label == operations[1].label:
            raise AssertionError("planted")

    failures = fuzz_operations(operations, check)
    assert list(failures) == [operations[1].label] and "planted" in failures[operations[1].label]
    assert {op.label for op in operations} <= set(seen)


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

"""Property-based fuzz of the API's own OpenAPI schema (schemathesis): never a 5xx.

Bounded (30 examples per operation, no deadline) so it stays well under a minute on 2 cores.
Successful answers must also match the documented response schema.
"""

from __future__ import annotations

import schemathesis
from hypothesis import HealthCheck, settings
from schemathesis.checks import not_a_server_error
from schemathesis.specs.openapi.checks import response_schema_conformance

from app.api import ApiSettings, create_api

app = create_api(ApiSettings(time_budget_s=5.0, max_batch=50))
schema = schemathesis.openapi.from_asgi("/openapi.json", app)


@schema.parametrize()
@settings(max_examples=30, deadline=None, suppress_health_check=list(HealthCheck))
def test_no_server_error(case):
    response = case.call()
    assert response.status_code < 500, f"{response.status_code}: {response.text[:500]}\n{case.as_curl_command()}"
    case.validate_response(response, checks=[not_a_server_error, response_schema_conformance])

"""Schemathesis against the served OpenAPI spec: generated requests (valid and invalid) never get a 5xx,
and every answer matches the spec (status codes, content types, bodies)."""

import hypothesis
import pytest
import schemathesis
from schemathesis import checks

from tests.conftest import API_KEY

EXAMPLES_PER_OPERATION = 30  # x 19 operations; `docs/reliability.md` has a longer run's figures


@pytest.fixture(scope="session")
def api_schema(server_url):
    return schemathesis.openapi.from_url(f"{server_url}/openapi.json")


schema = schemathesis.pytest.from_fixture("api_schema")


@schema.parametrize()
@hypothesis.settings(max_examples=EXAMPLES_PER_OPERATION, deadline=None,
                     suppress_health_check=list(hypothesis.HealthCheck))
def test_no_request_gets_a_server_error(case):
    case.call_and_validate(headers={"X-API-Key": API_KEY}, timeout=30, checks=[
        checks.not_a_server_error, checks.status_code_conformance, checks.content_type_conformance,
        checks.response_schema_conformance])

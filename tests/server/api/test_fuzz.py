"""Schemathesis against the served OpenAPI spec: generated requests never get a 5xx, and every answer
matches the spec (status codes, content types, bodies). Both modes: data that fits the schema and
data that does not (every number just outside its range, wrong types); the coverage phase adds each
number's boundary values."""

import hypothesis
import pytest
import schemathesis
from schemathesis import checks
from schemathesis.generation import GenerationMode

from tests.conftest import API_KEY

EXAMPLES_PER_OPERATION = 30  # x 19 operations; `docs/reliability.md` has a longer run's figures


@pytest.fixture(scope="session")
def api_schema(server_url):
    schema = schemathesis.openapi.from_url(f"{server_url}/openapi.json")
    schema.config.generation.update(modes=[GenerationMode.POSITIVE, GenerationMode.NEGATIVE])
    schema.config.phases.update(phases=["examples", "coverage", "fuzzing"])
    return schema


schema = schemathesis.pytest.from_fixture("api_schema")


@schema.parametrize()
@hypothesis.settings(max_examples=EXAMPLES_PER_OPERATION, deadline=None,
                     suppress_health_check=list(hypothesis.HealthCheck))
def test_no_request_gets_a_server_error(case):
    case.call_and_validate(headers={"X-API-Key": API_KEY}, timeout=30, checks=[
        checks.not_a_server_error, checks.status_code_conformance, checks.content_type_conformance,
        checks.response_schema_conformance])

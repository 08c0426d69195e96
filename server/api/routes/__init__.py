"""One router per resource."""

from __future__ import annotations

from typing import Any

from shared_schemas import ErrorBody

# Declared on the routes that read a stored map, profile or sample by name (docs/reliability.md).
DAMAGED_RESPONSES: dict[int | str, dict[str, Any]] = {
    409: {"model": ErrorBody, "description": "the stored map, profile or sample is damaged: the message names its file"}
}

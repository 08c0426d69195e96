"""What every `lumipose` command shares: its exit codes and how it reports a request it cannot read.

A command that cannot read its input exits 2 with an `ErrorBody` (the contract's error object):
printed as JSON on stdout when the user asked for `--json`, as `error: ...` on stderr otherwise.
"""

from __future__ import annotations

import sys
from pathlib import Path

from shared_schemas.models import BeaconMap, ErrorBody

EXIT_OK, EXIT_NO_FIX, EXIT_BAD_INPUT = 0, 1, 2


class BadInput(Exception):
    """Input a command cannot use: a missing or unreadable file, a bad flag value, an unknown name."""

    def __init__(self, message: str, field: str | None = None, error: str = "bad_input"):
        super().__init__(message)
        self.body = ErrorBody(error=error, field=field, message=message)


def read_map_argument(value: str, data_dir: Path | None = None) -> BeaconMap:
    """The map a `--map` value means: a file if one is there, else a map of that name (stored in
    `data_dir`, or bundled); BadInput (field `map`) naming both readings when neither exists."""
    from shared_schemas import find_map_file, load_map

    try:
        path = find_map_file(value, data_dir)
    except ValueError as error:
        raise BadInput(str(error), field="map") from None
    try:
        return load_map(path)
    except (OSError, ValueError) as error:  # a pydantic ValidationError is a ValueError
        raise BadInput(f"cannot read map {path}: {error}", field="map") from None


def report_bad_input(problem: BadInput | ErrorBody, as_json: bool = False) -> int:
    """Print `problem` the way the user asked for output and return exit code 2."""
    body = problem.body if isinstance(problem, BadInput) else problem
    if as_json:
        print(body.model_dump_json(indent=2))
    else:
        where = f" (field {body.field})" if body.field and body.field not in body.message else ""
        print(f"error: {body.message}{where}", file=sys.stderr)
    return EXIT_BAD_INPUT

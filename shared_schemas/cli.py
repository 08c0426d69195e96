"""What every `lumipose` command shares: its exit codes and how it reports a request it cannot read.

A command that cannot read its input exits 2 with an `ErrorBody` (the contract's error object):
printed as JSON on stdout when the user asked for `--json`, as `error: ...` on stderr otherwise.
"""

from __future__ import annotations

import sys
from pathlib import Path

from pydantic import ValidationError

from shared_schemas.models import BeaconMap, ErrorBody

EXIT_OK, EXIT_NO_FIX, EXIT_BAD_INPUT = 0, 1, 2


class BadInput(Exception):
    """Input a command cannot use: a missing or unreadable file, a bad flag value, an unknown name."""

    def __init__(self, message: str, field: str | None = None, error: str = "bad_input"):
        super().__init__(message)
        self.body = ErrorBody(error=error, field=field, message=message)


def report_bad_input(problem: BadInput | ErrorBody, as_json: bool = False) -> int:
    """Print `problem` the way the user asked for output and return exit code 2."""
    body = problem.body if isinstance(problem, BadInput) else problem
    if as_json:
        print(body.model_dump_json(indent=2))
    else:
        where = f" (field {body.field})" if body.field and body.field not in body.message else ""
        print(f"error: {body.message}{where}", file=sys.stderr)
    return EXIT_BAD_INPUT


def describe_validation_error(error: ValidationError, source: str | Path | None = None) -> str:
    """A pydantic ValidationError in one short line: `map.json: beacons.0.side_m: Input should be greater
    than 0 (got -1)`, the first problem and how many more there are (no pydantic dump with links)."""
    problems = error.errors(include_url=False)
    first = problems[0]
    where = ".".join(str(part) for part in first["loc"])
    message = first["msg"].removeprefix("Value error, ")
    given = first.get("input")
    shown = isinstance(given, int | float | str) and not isinstance(given, bool) and len(str(given)) <= 40
    if where and shown and str(given) not in message:
        message += f" (got {given!r})"
    more = len(problems) - 1
    parts = [str(source) if source is not None else "", where, message]
    text = ": ".join(part for part in parts if part)
    return text + (f" (and {plural(more, 'more problem')})" if more else "")


def describe_file_error(path: str | Path, error: Exception) -> str:
    """Why the file at `path` could not be used, naming the file and (for a model) the field."""
    if isinstance(error, ValidationError):
        return describe_validation_error(error, path)
    if isinstance(error, OSError) and error.strerror:
        return f"{path}: {error.strerror}"
    if isinstance(error, UnicodeDecodeError):
        return f"{path}: not a text file"
    return f"{path}: {error}"


def plural(count: int, noun: str, plural_form: str | None = None) -> str:
    """`1 beacon`, `2 beacons` (`plural_form` for irregular nouns)."""
    return f"{count} {noun if count == 1 else plural_form or noun + 's'}"


def number(value: float, decimals: int = 2, digits: int = 2) -> str:
    """`value` with `decimals` decimals, or `digits` significant ones where the decimals would hide it
    (an ambiguity ratio of 0.0031 prints as 0.0031, not 0.00)."""
    if value == 0 or abs(value) >= 10 ** (digits - 1 - decimals):
        return f"{value:.{decimals}f}"
    return f"{value:.{digits}g}"


def check_beacon_id(beacon_id: int | None, beacon_map: BeaconMap) -> None:
    """`--beacon-id` must name a beacon of the map the frames are located in."""
    if beacon_id is not None and beacon_map.beacon(beacon_id) is None:
        known = ", ".join(str(beacon.id) for beacon in beacon_map.beacons)
        raise BadInput(
            f"beacon {beacon_id} is not in map '{beacon_map.name}' (its beacons: {known})",
            field="beacon_id",
            error="unknown_beacon",
        )

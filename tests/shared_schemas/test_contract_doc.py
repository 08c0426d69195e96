"""docs/contract.md says what the models in shared_schemas/models.py say.

Each model and enum of the contract has a section whose heading names it in backticks
(`### `FrameMeta`: the frame JSON`); the first table of that section lists its fields
(field | type | unit | range | required | meaning) or its values (value | meaning). These tests
fail when a field, a range, a required flag, a default or an enum value drifts between the two.
"""

from __future__ import annotations

import inspect
import json
import re
from enum import Enum
from pathlib import Path

import pytest
from pydantic import BaseModel, ValidationError

from shared_schemas import calibration, models, survey

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "contract.md"

BASES = {models.Strict, models.Open}
CONTRACT_MODULES = (models, calibration, survey)  # the contract's models; api.py's bodies are the HTTP API's
CONTRACT_MODELS = {
    name: cls for module in CONTRACT_MODULES for name, cls in vars(module).items()
    if inspect.isclass(cls) and issubclass(cls, BaseModel) and cls.__module__ == module.__name__
    and cls not in BASES
}
CONTRACT_ENUMS = {
    name: cls for module in CONTRACT_MODULES for name, cls in vars(module).items()
    if inspect.isclass(cls) and issubclass(cls, Enum) and cls.__module__ == module.__name__
}
TOP_LEVEL = (models.FrameMeta, models.BeaconMap, models.DeviceProfile, models.LocateResult, models.ErrorBody)

HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*$")
CODE = re.compile(r"`([^`]+)`")
DEFAULT = re.compile(r"default\s+`([^`]*)`")


def _cells(line: str) -> list[str]:
    return [cell.strip() for cell in line.strip().strip("|").split("|")]


def parse_sections(text: str) -> dict[str, list[dict[str, str]]]:
    """Heading's first backticked name -> rows of the first table under that heading."""
    sections: dict[str, list[dict[str, str]]] = {}
    current: str | None = None
    header: list[str] | None = None
    in_code = False
    for line in text.splitlines():
        if line.startswith("```"):
            in_code = not in_code
            continue
        if in_code:
            continue
        heading = HEADING.match(line)
        if heading:
            names = CODE.findall(heading[2])
            current = names[0] if names else None
            header = None
            if current is not None:
                assert current not in sections, f"two sections of the contract doc name `{current}`"
                sections[current] = []
            continue
        if current is None:
            continue
        if line.lstrip().startswith("|"):
            cells = _cells(line)
            if header is None:
                header = [c.lower() for c in cells]
            elif not all(set(c) <= set("-: ") for c in cells):
                assert len(cells) == len(header), f"`{current}`: row {line!r} has {len(cells)} cells, not {len(header)}"
                sections[current].append(dict(zip(header, cells)))
        elif header is not None and sections[current]:
            current = None  # the first table of the section is over: later tables are prose
    return sections


DOC_TEXT = DOC.read_text()
SECTIONS = parse_sections(DOC_TEXT)


def _name(cell: str) -> str:
    names = CODE.findall(cell)
    assert len(names) == 1, f"the first cell {cell!r} must hold one `name`"
    return names[0]


def _json_field_names(model: type[BaseModel]) -> dict[str, str]:
    """JSON name (alias) -> attribute name."""
    return {(info.alias or name): name for name, info in model.model_fields.items()}


def _rendered(value) -> str:
    if isinstance(value, Enum):
        value = value.value
    if isinstance(value, bool) or value is None or isinstance(value, (list, dict)):
        return json.dumps(value)
    return str(value)


def test_every_contract_model_and_enum_has_a_section_with_a_table():
    missing = sorted((set(CONTRACT_MODELS) | set(CONTRACT_ENUMS)) - set(SECTIONS))
    assert not missing, f"docs/contract.md has no section for {missing}"
    empty = sorted(name for name in set(CONTRACT_MODELS) | set(CONTRACT_ENUMS) if not SECTIONS[name])
    assert not empty, f"docs/contract.md has no table under {empty}"


@pytest.mark.parametrize("name", sorted(CONTRACT_MODELS))
def test_field_table_lists_exactly_the_models_fields(name):
    rows = SECTIONS.get(name, [])
    listed = [_name(row["field"]) for row in rows]
    assert len(listed) == len(set(listed)), f"`{name}` lists a field twice: {listed}"
    fields = _json_field_names(CONTRACT_MODELS[name])
    assert not set(fields) - set(listed), f"`{name}` fields missing from docs/contract.md: {sorted(set(fields) - set(listed))}"
    assert not set(listed) - set(fields), f"docs/contract.md lists fields `{name}` does not have: {sorted(set(listed) - set(fields))}"


@pytest.mark.parametrize("name", sorted(CONTRACT_MODELS))
def test_required_and_defaults_match_the_model(name):
    model = CONTRACT_MODELS[name]
    fields = _json_field_names(model)
    for row in SECTIONS.get(name, []):
        json_name = _name(row["field"])
        if json_name not in fields:
            continue  # reported by the field test
        info = model.model_fields[fields[json_name]]
        cell = row["required"]
        said_required = cell.lower().startswith("yes")
        assert said_required or cell.lower().startswith("no"), f"`{name}.{json_name}`: required is {cell!r}, not yes/no"
        assert said_required == info.is_required(), (
            f"`{name}.{json_name}` is {'required' if info.is_required() else 'optional'} in the model "
            f"but {cell!r} in docs/contract.md")
        if info.is_required():
            continue
        default = info.get_default(call_default_factory=True)
        said = DEFAULT.search(cell)
        if default is None:
            assert said is None, f"`{name}.{json_name}` has no default in the model, docs/contract.md says {said[1]!r}"
        else:
            assert said is not None, f"`{name}.{json_name}`: docs/contract.md must give its default `{_rendered(default)}`"
            assert said[1] == _rendered(default), (
                f"`{name}.{json_name}` defaults to {_rendered(default)} in the model, {said[1]} in docs/contract.md")


# A range cell: `[1, 1e6]`, `(0, 1]`, `[0, 2^63)` (brackets include, parentheses exclude), `>= 0`,
# or either prefixed by `each` for the items of a list; empty when the model sets no bound.
INTERVAL = re.compile(r"^(each\s+)?([\[(])\s*([^,\s]+)\s*,\s*([^,\s]+)\s*([\])])$")
ONE_SIDED = re.compile(r"^(each\s+)?(>=|>|<=|<)\s*(\S+)$")
Bounds = tuple[bool, tuple[float, bool] | None, tuple[float, bool] | None]  # each, (lower, inclusive), (upper, ...)


def _number(text: str) -> float:
    base, caret, power = text.partition("^")
    return float(base) ** int(power) if caret else float(text)


def _doc_bounds(cell: str) -> Bounds | None:
    """What a range cell says, or None when it is empty."""
    cell = cell.strip()
    if not cell:
        return None
    interval = INTERVAL.match(cell)
    if interval:
        each, left, low, high, right = interval.groups()
        return bool(each), (_number(low), left == "["), (_number(high), right == "]")
    one_sided = ONE_SIDED.match(cell)
    assert one_sided, f"range {cell!r} is neither [a, b] (brackets or parentheses), '>= a' nor empty"
    each, operator, value = one_sided.groups()
    bound = (_number(value), "=" in operator)
    return (bool(each), bound, None) if operator.startswith(">") else (bool(each), None, bound)


def _schema_bounds(prop: dict) -> Bounds | None:
    """The bounds of a property of a model's JSON Schema (of its innermost items for lists), or None."""
    branches = [branch for branch in prop.get("anyOf", [prop]) if branch.get("type") != "null"]
    if len(branches) != 1:
        return None  # a choice of models: each has its own section
    schema, each = branches[0], False
    while schema.get("type") == "array" and "items" in schema:
        schema, each = schema["items"], True
    lower = (schema["minimum"], True) if "minimum" in schema else None
    lower = (schema["exclusiveMinimum"], False) if "exclusiveMinimum" in schema else lower
    upper = (schema["maximum"], True) if "maximum" in schema else None
    upper = (schema["exclusiveMaximum"], False) if "exclusiveMaximum" in schema else upper
    return None if lower is None and upper is None else (each, lower, upper)


@pytest.mark.parametrize("name", sorted(CONTRACT_MODELS))
def test_range_column_says_the_models_bounds(name):
    """Every field table has a range column, and it says exactly the bounds of the model's JSON Schema."""
    rows = SECTIONS.get(name, [])
    assert rows and "range" in rows[0], f"`{name}`: the field table of docs/contract.md has no range column"
    properties = CONTRACT_MODELS[name].model_json_schema(by_alias=True)["properties"]
    for row in rows:
        json_name = _name(row["field"])
        if json_name not in properties:
            continue  # reported by the field test
        said, bounds = _doc_bounds(row["range"]), _schema_bounds(properties[json_name])
        assert said == bounds, f"`{name}.{json_name}`: docs/contract.md says range {row['range']!r}, the model {bounds}"


@pytest.mark.parametrize("name", sorted(CONTRACT_ENUMS))
def test_enum_table_lists_exactly_the_enums_values(name):
    listed = [_name(row["value"]) for row in SECTIONS.get(name, [])]
    values = [member.value for member in CONTRACT_ENUMS[name]]
    assert sorted(listed) == sorted(values), f"`{name}`: docs/contract.md lists {listed}, the model has {values}"


def test_schema_identifiers_are_named():
    for schema in (models.FRAME_SCHEMA, models.MAP_SCHEMA, models.RESULT_SCHEMA):
        assert f"`{schema}`" in DOC_TEXT


def test_json_examples_in_the_doc_are_valid_contract_documents():
    blocks = re.findall(r"```json\n(.*?)```", DOC_TEXT, flags=re.DOTALL)
    for block in blocks:
        data = json.loads(block)
        errors = []
        for model in TOP_LEVEL:
            try:
                model.model_validate(data)
                break
            except ValidationError as error:
                errors.append(f"{model.__name__}: {error.error_count()} errors")
        else:
            pytest.fail(f"this example of docs/contract.md is no contract document ({'; '.join(errors)}):\n{block}")


def _slug(heading: str) -> str:
    """GitHub's anchor of a heading."""
    text = heading.strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def _anchors(path: Path) -> set[str]:
    return {_slug(m[2]) for m in map(HEADING.match, path.read_text().splitlines()) if m}


def test_links_in_the_doc_resolve():
    for target in re.findall(r"\]\(([^)\s]+)\)", DOC_TEXT):
        if re.match(r"[a-z]+://", target):
            continue
        file_part, _, anchor = target.partition("#")
        path = (DOC.parent / file_part).resolve() if file_part else DOC
        assert path.exists(), f"docs/contract.md links to {target}, which does not exist"
        if anchor:
            assert path.suffix == ".md" and anchor in _anchors(path), f"docs/contract.md links to a missing anchor {target}"


OLD_DRAFT = "shared/" + "spec"  # split so that this file does not match itself
SEARCHED = ("README.md", "docs", "shared_schemas", "server", "simulator", "lumipose_client", "tests",
            "android_client/core/src", "android_client/app/src", "scripts", "docker")


def test_nothing_points_to_the_old_draft_outside_the_repository():
    offenders = []
    for entry in SEARCHED:
        root = ROOT / entry
        paths = [root] if root.is_file() else [p for p in root.rglob("*") if p.is_file()] if root.exists() else []
        for path in paths:
            if path.suffix not in {".py", ".md", ".java", ".json", ".sh", ".yaml", ".yml", ".txt", ""}:
                continue
            try:
                if OLD_DRAFT in path.read_text(errors="ignore"):
                    offenders.append(str(path.relative_to(ROOT)))
            except OSError:
                continue
    assert not offenders, f"these files still point to ../{OLD_DRAFT}/contract.md instead of docs/contract.md: {offenders}"

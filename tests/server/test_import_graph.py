"""The modules of `server/` import each other one way only (docs/architecture.md).

Every import counts, also those inside functions: a lazy import that closes a circle is still a
circle (the one-panel pipeline and the room code used to call each other that way).
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def server_imports() -> dict[str, set[str]]:
    """Each module of server/ and the server modules it imports anywhere in its body."""
    modules = {module_name(p): p for p in (ROOT / "server").rglob("*.py")}
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        targets: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                targets.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    base = ".".join(package.split(".")[: len(package.split(".")) - node.level + 1] + [base]).strip(".")
                targets.add(base)
                targets.update(f"{base}.{alias.name}" for alias in node.names)  # `from pkg import module`
        graph[name] = {t for t in targets if t in modules and t != name}
    return graph


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        for target in sorted(graph[node]):
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def test_there_is_no_import_circle_inside_server():
    assert circles(server_imports()) == []


def test_the_circle_finder_finds_one():
    assert circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_only_the_api_and_the_command_line_call_the_dispatcher():
    callers = sorted(name for name, targets in server_imports().items() if "server.locator" in targets)
    assert callers and all(name.startswith(("server.api", "server.cli", "server.locate_cli")) for name in callers), callers


def test_the_stages_do_not_import_the_layers_above_them():
    above = ("server.pipeline", "server.rooms", "server.tracking", "server.options", "server.locator", "server.api",
             "server.cli", "server.store")
    graph = server_imports()
    stages = [name for name in graph if name.startswith(("server.vision", "server.pose", "server.vlc"))]
    upward = {name: sorted(t for t in graph[name] if t.startswith(above)) for name in stages}
    assert {name: targets for name, targets in upward.items() if targets} == {}

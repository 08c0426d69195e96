"""The packages layer one way: shared_schemas <- lumipose_client, shared_schemas <- server,
and only simulator/ and the `lumipose` command (lumipose_cli/) sit above both.

Every import counts, also those inside functions (a lazy import is still a dependency). The
client is what a user installs on a laptop: importing it must not load OpenCV, scipy,
matplotlib, the server or the simulator.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

FORBIDDEN = {
    "server": {"lumipose_client", "simulator", "lumipose_cli"},
    "lumipose_client": {"server", "simulator", "lumipose_cli"},
    "shared_schemas": {"server", "simulator", "lumipose_client", "lumipose_cli"},
}
# What the client may import besides the standard library and itself; numpy only to cut frames.
CLIENT_DEPENDENCIES = {"shared_schemas", "httpx", "zstandard", "pydantic"}
CLIENT_NUMPY_MODULES = {"lumipose_client/crop.py"}


def absolute_imports(path: Path) -> list[tuple[int, str]]:
    """(line, module) of every absolute import anywhere in a file (relative ones stay in its package)."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.append((node.lineno, node.module))
    return found


def package_files(package: str) -> list[Path]:
    return sorted((ROOT / package).rglob("*.py"))


def test_packages_import_no_layer_above_them():
    wrong = [f"{path.relative_to(ROOT)}:{line} imports {module}"
             for package, forbidden in FORBIDDEN.items() for path in package_files(package)
             for line, module in absolute_imports(path) if module.split(".")[0] in forbidden]
    assert not wrong, "imports across the layers:\n" + "\n".join(wrong)


def test_the_client_needs_only_the_contract_httpx_zstandard_and_pydantic():
    allowed = set(sys.stdlib_module_names) | CLIENT_DEPENDENCIES | {"lumipose_client"}
    wrong = []
    for path in package_files("lumipose_client"):
        name = path.relative_to(ROOT).as_posix()
        extra = allowed | ({"numpy"} if name in CLIENT_NUMPY_MODULES else set())
        wrong += [f"{name}:{line} imports {module}" for line, module in absolute_imports(path)
                  if module.split(".")[0] not in extra]
    assert not wrong, "the client imports more than it may:\n" + "\n".join(wrong)


def test_the_checks_see_lazy_imports(tmp_path):
    source = tmp_path / "lazy.py"
    source.write_text("from . import sibling\n\ndef later():\n    import server.cli\n    from simulator import reports\n")
    assert absolute_imports(source) == [(4, "server.cli"), (5, "simulator")]


def test_importing_the_client_and_its_cli_loads_no_server_simulator_or_heavy_library():
    code = ("import lumipose_client, lumipose_client.cli; import sys; print(sorted(m for m in sys.modules "
            "if m.split('.')[0] in {'cv2', 'scipy', 'matplotlib', 'server', 'simulator'}))")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "[]"

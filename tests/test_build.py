"""`scripts/setup.sh`'s editable install says nothing but that it installed (issue 31).

pip (>= 25) shows every warning its build backend raised as a BuildBackendWarning box. The hook is run
here the way pip runs it (its vendored pyproject_hooks, the backend in a subprocess), without build
isolation, so offline: on a copy of the project, with the setuptools the test environment holds.
"""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ["server", "shared_schemas", "simulator", "lumipose_client", "lumipose_cli"]


def project_copy(target: Path) -> Path:
    """pyproject.toml, the readme it names and the packages it finds, without caches."""
    target.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / name, target / name)
    for package in PACKAGES:
        shutil.copytree(ROOT / package, target / package, ignore=shutil.ignore_patterns("__pycache__"))
    return target


def test_the_editable_build_raises_no_backend_warning(tmp_path):
    # setuptools before 70.1 needs the `wheel` package for an editable build, which only build isolation brings
    pytest.importorskip("setuptools", minversion="70.1")
    hooks = pytest.importorskip("pip._vendor.pyproject_hooks")
    source = project_copy(tmp_path / "project")
    caller = hooks.BuildBackendHookCaller(str(source), "setuptools.build_meta", runner=hooks.quiet_subprocess_runner)
    (tmp_path / "wheel").mkdir()
    with warnings.catch_warnings(record=True) as raised:
        warnings.simplefilter("always")
        wheel = caller.build_editable(str(tmp_path / "wheel"))
    assert [f"{w.category.__name__}: {w.message}" for w in raised] == []
    assert (tmp_path / "wheel" / wheel).exists()

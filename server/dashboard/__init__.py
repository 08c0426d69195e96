"""The operator's web page (`/dashboard/`): static files in `static/`, no build step, no external requests."""

from pathlib import Path

STATIC_DIR = Path(__file__).parent / "static"

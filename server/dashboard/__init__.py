"""The operator's web page (issue 16): static files in `static/` (index.html, ES modules, style.css).

No build step and no external requests: the service serves the folder as it is shipped in the package.
"""

from __future__ import annotations

from pathlib import Path

STATIC_DIR = Path(__file__).parent / "static"

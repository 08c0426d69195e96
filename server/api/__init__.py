"""The Lumipose HTTP service (FastAPI). `create_app` in `server.api.main` builds it."""

from importlib.metadata import PackageNotFoundError, version

try:
    VERSION = version("lumipose")
except PackageNotFoundError:  # running from a source tree that was not installed
    VERSION = "0+unknown"

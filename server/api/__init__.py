"""The Lumipose HTTP service (FastAPI). `create_app` in `server.api.main` builds it."""

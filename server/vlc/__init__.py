"""Beacon identification by visible-light communication (seed paper, Section IV-D)."""

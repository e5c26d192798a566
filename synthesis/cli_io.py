"""File-conversion subcommands of the command line (model files, DXF)."""

from __future__ import annotations


def register(sub) -> None:
    """Add the file-conversion subcommands to the ``cspace-tol`` sub-parser."""
    return None

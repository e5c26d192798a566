"""The command line ``cspace-tol`` (also ``python -m synthesis``) and what it writes.

Index
-----
main           the parser and the ``analyze`` and ``synthesize`` subcommands
convert        file-conversion subcommands: ``import-dxf``, ``export-dxf``
yield_command  the ``yield`` subcommand
report         the output folder of a run: report.md, report.json, geometry, figures
plotting       figures of a run and of the statistics (matplotlib imported on first use)
outlock        one writer per output folder (a lock file)

``main(argv)`` runs the command line and returns its exit status.
"""

from .main import build_parser, main

__all__ = ["main", "build_parser"]

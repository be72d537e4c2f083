"""The command line ``impact-harness``: argument parsing, error reporting and exit codes
(:mod:`.main`), and the subcommands simulate, strobe, sweep and jacobian (:mod:`.commands`);
``reproduce`` and ``windows`` are registered from :mod:`harness.reproduce`.

Layer: the top (beside :mod:`harness.reproduce`); may import everything below.
"""
from .main import main  # noqa: F401  (the console script: harness.cli:main)

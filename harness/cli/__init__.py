"""The command line ``impact-harness``: argument parsing, error reporting and exit codes
(:mod:`.main`), the options the subcommands share (:mod:`.options`, :mod:`.experiment_args`,
:mod:`.resumable`), and one module per subcommand: :mod:`.simulate`, :mod:`.strobe`,
:mod:`.sweep`, :mod:`.jacobian`, :mod:`.basins`, :mod:`.continue_`, :mod:`.reproduce`,
:mod:`.windows`, :mod:`.chart`.

Layer: the top; may import everything below (:mod:`harness.reproduce`, :mod:`harness.analysis`
and the library); nothing imports it.
"""
from .main import main  # noqa: F401  (the console script: harness.cli:main)

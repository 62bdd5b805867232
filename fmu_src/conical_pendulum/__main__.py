"""`python -m conical_pendulum`: the `conical-pendulum` command."""

import sys

from conical_pendulum.cli import main

sys.exit(main(prog="python -m conical_pendulum"))

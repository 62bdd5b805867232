"""The one error class for what a user can act on, raised by library code and turned into a
message and an exit status by the command line alone (cli.py).

Library code (builder/, analysis/, viz/, demos/) raises UserError and never exits: a
program that imports it keeps control. `conical-pendulum` prints it as
`<command>: <message>` and exits with its `status`.
"""

from __future__ import annotations


class UserError(Exception):
    """A mistake the user can fix (a bad option or value, a missing or unreadable file), a
    missing optional package or tool (the message says what to install), or work that was
    tried and failed for a reason the message gives.

    `status` is the command's exit status: 2 (the default) for what was asked wrongly or
    cannot be done here, 1 for work that ran and failed."""

    def __init__(self, message: str, status: int = 2):
        super().__init__(message)
        self.status = status

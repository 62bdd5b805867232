"""The subcommands of `conical-pendulum`, one module each (build, check, linearize, show, page,
sweep, demo, system; common.py what build, check, linearize and page share), each with `add_arguments(parser)` and `run(args) -> int`: options parsed into calls
of the library (builder/, analysis/, viz/, demos/), results printed.

Only cli.py imports them, and only the chosen one; they raise errors.UserError for what
the user can fix, and cli.py alone turns it into one line and an exit status. Library
code imports nothing from here.
"""

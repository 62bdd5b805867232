"""Build dist/ConicalPendulum.fmu for a scene, then run it with fmpy against the native integrator.

    python build_fmu.py                       # the seed scene: 3 links with bobs
    python build_fmu.py --native              # dist/ConicalPendulum_native.fmu (--fmi 3: _fmi3.fmu)
    python build_fmu.py --links 5 --no-bobs --output dist/Chain5.fmu
    python build_fmu.py --scene scenes/seed.toml
    python build_fmu.py --coupling --output dist/Coupled.fmu   # a moving support: a_pivot in, F_pivot out

The same as `conical-pendulum build` (conical_pendulum/commands/build.py), which the
package installs; `python build_fmu.py --help` lists the options.
"""

import sys

from conical_pendulum.cli import run_command

if __name__ == "__main__":
    sys.exit(run_command("build", prog="build_fmu.py"))

"""Build dist/ConicalPendulum.fmu for a scene, then run it with fmpy against the native integrator.

    python build_fmu.py                       # the seed scene: 3 links with bobs
    python build_fmu.py --links 5 --no-bobs --output dist/Chain5.fmu
    python build_fmu.py --scene scenes/seed.toml
    python build_fmu.py --coupling --output dist/Coupled.fmu   # a moving support: a_pivot in, F_pivot out
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from conical_pendulum import Scene, SceneError
from conical_pendulum.scene import KINEMATICS, MAX_LINKS, load_scene


def parse(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", type=Path, help="a scene file (TOML or JSON, see scenes/seed.toml)")
    parser.add_argument("--links", type=int, help=f"number of links, 1 to {MAX_LINKS} (3)")
    parser.add_argument("--massless-links", action="store_true", help="links without mass or inertia")
    parser.add_argument("--no-bobs", action="store_true", help="no bobs at the joints")
    parser.add_argument("--kinematics", choices=KINEMATICS,
                        help="'pydy-example' reproduces the published (energy-violating) equations")
    parser.add_argument("--coupling", action="store_true",
                        help="inputs a_pivot_x/y/z (the support's acceleration) and outputs "
                             "F_pivot_x/y/z (the force on it)")
    parser.add_argument("--output", type=Path, default=Path("dist/ConicalPendulum.fmu"))
    parser.add_argument("--no-check", action="store_true",
                        help="only build; skip the fmpy run against the native integrator, "
                             "its plot and its animation")
    return parser.parse_args(argv)


def choose_scene(args) -> Scene:
    options = [name for name, given in [("--links", args.links is not None),
                                        ("--massless-links", args.massless_links),
                                        ("--no-bobs", args.no_bobs),
                                        ("--kinematics", args.kinematics is not None),
                                        ("--coupling", args.coupling)] if given]
    if args.scene:
        if options:
            raise SceneError(f"--scene describes the whole scene; drop {', '.join(options)}")
        return load_scene(args.scene)
    return Scene.uniform(3 if args.links is None else args.links,
                         massless_links=args.massless_links, bobs=not args.no_bobs,
                         kinematics=args.kinematics or "consistent", coupling=args.coupling)


def main(argv=None) -> int:
    args = parse(argv)
    try:
        scene = choose_scene(args)
    except SceneError as exc:
        print(f"build_fmu.py: {exc}", file=sys.stderr)
        return 2
    from conical_pendulum.build.fmu import build_fmu

    try:
        build = build_fmu(scene, args.output)
    except ValueError as exc:
        print(f"build_fmu.py: {exc}", file=sys.stderr)
        return 2
    how = "from cache" if build.core.cached else "compiled " + ", ".join(
        f"{k} {v:.1f} s" for k, v in build.core.seconds.items())
    print(f"built {build.path} ({build.path.stat().st_size / 1024:.0f} KiB) in {build.seconds:.1f} s: "
          f"{scene.n} links, {len(scene.parameter_names())} parameters, {len(scene.input_names())} inputs, "
          f"{len(scene.output_names())} calculated outputs; core {how}")
    if args.no_check:
        return 0
    from conical_pendulum.analysis.compare import compare

    start = time.perf_counter()
    comparison = compare(build.path, scene)
    print(f"fmpy.simulate_fmu, 10 s at 60 outputs/s, DOP853 rtol = atol = 1e-12, against native "
          f"scipy DOP853 ({time.perf_counter() - start:.1f} s):")
    print(comparison.report())
    ok = comparison.angle_error() < 1e-8
    print(f"angles agree to {comparison.angle_error():.2e} rad: {'OK' if ok else 'FAILED'}")
    show(comparison.result, args.output.parent)
    return 0 if ok else 1


def show(result, folder: Path) -> None:
    """The run as CSV, a plot and an animation, next to the FMU."""
    from fmpy.util import write_csv

    from conical_pendulum.viz import plots as viz

    csv = folder / "results.csv"
    write_csv(str(csv), result)
    results = viz.load_results(csv)
    viz.plot(results, folder / "pendulum.png")
    seconds = viz.animate(results, folder / "pendulum.gif")
    print(f"wrote {csv}, {folder / 'pendulum.png'} and {folder / 'pendulum.gif'} "
          f"(animation rendered in {seconds:.1f} s)")


if __name__ == "__main__":
    sys.exit(main())

"""`conical-pendulum build` (and `build_fmu.py`): a scene's FMU, checked against the native
reference, its run drawn."""

from __future__ import annotations

import argparse
from pathlib import Path

from fmpy.util import write_csv

from ..builder import fmu as fmus
from ..errors import UserError
from ..runtime.rules import LINK_RULES, RULES, satisfies
from ..scene import KINEMATICS, MAX_LINKS, Scene, SceneError, load_scene
from ..viz import plots
from .common import CHECK_BOUND, compare


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description += (
        "\n\nWithout --scene, the options describe a uniform chain (3 links with bobs by default).\n"
        "After the build, unless --no-check, the FMU runs with fmpy (10 s, an output every 1/60 s,\n"
        "DOP853 at 1e-12) against the native scipy integration of the same scene; the run goes to\n"
        "a CSV, a plot and an animation named after the FMU (dist/ConicalPendulum.csv, .png, .gif).\n"
        f"Exit status 1 when the angles disagree by more than the check's bound:\n{CHECK_BOUND}.\n"
        "\nWithout --output, the FMU is named after the scene (its file's name; ConicalPendulum\n"
        "without --scene) and the kind of FMU, so that no build overwrites another scene's or kind's:\n"
        + "\n".join(f"  {flavour:<26} {default_output(kind, 'SCENE')}" for flavour, kind in KINDS.items())
        + "\nA build that replaces an FMU of another scene says so."
    )
    scene = parser.add_argument_group("the scene")
    scene.add_argument(
        "--scene",
        type=Path,
        metavar="FILE",
        help="a scene file (TOML or JSON, see scenes/seed.toml), instead of the options below",
    )
    scene.add_argument("--links", type=int, metavar="N", help=f"number of links, 1 to {MAX_LINKS} (3)")
    scene.add_argument("--massless-links", action="store_true", help="links without mass or inertia")
    scene.add_argument("--no-bobs", action="store_true", help="no bobs at the joints")
    scene.add_argument(
        "--kinematics",
        choices=KINEMATICS,
        help="'pydy-example' reproduces the published (energy-violating) equations (default: consistent)",
    )
    scene.add_argument(
        "--coupling",
        action="store_true",
        help="inputs a_pivot_x/y/z (the support's acceleration) and outputs "
        "F_pivot_x/y/z (the force on it), with its split F_free_x/y/z, M_pivot_xx..zz",
    )
    scene.add_argument(
        "--joint-damping",
        type=float,
        metavar="C",
        help="a viscous torque -C w_rel at every joint [N m s/rad]: parameters c0.. (start C) and "
        "the state W_damping, its work, so that energy - W_damping stays constant",
    )
    scene.add_argument(
        "--air-drag",
        action="store_true",
        help="the air's quadratic drag on every bob, -1/2 rho C_d A |v_air| v_air: parameters rho, "
        "C_d0.., A0.. (a sphere's: 0.47 and pi r^2), inputs wind_x/y/z (with --coupling also "
        "v_pivot_x/y/z, the support's velocity) and the state W_drag, its work",
    )
    parser.add_argument(
        "--output",
        type=Path,
        metavar="PATH",
        help="the FMU to write, ending in .fmu (default: named after the scene and the kind of FMU, "
        "as listed above; dist/ConicalPendulum.fmu for the seed's pythonfmu FMU)",
    )
    parser.add_argument(
        "--native",
        action="store_true",
        help="the native FMU: FMI glue in C, no Python at run time (docs/native.md)",
    )
    parser.add_argument(
        "--fmi",
        type=int,
        choices=(2, 3),
        default=2,
        help="with --native: the FMI version, 2 (2.0) or 3 (3.0; Co-Simulation and Model Exchange) (2)",
    )
    parser.add_argument(
        "--scalars",
        action="store_true",
        help="with --native --fmi 3: per-link quantities as scalars with FMI 2.0's names (alpha0, ...) "
        "instead of arrays, for tools that read no FMI 3.0 arrays (OMSimulator)",
    )
    parser.add_argument(
        "--win64",
        action="store_true",
        help="with --native: also a Windows binary, cross-compiled (needs mingw-w64)",
    )
    parser.add_argument(
        "--aarch64",
        action="store_true",
        help="with --native --fmi 3: also a Linux binary for 64-bit ARM (binaries/aarch64-linux), "
        "cross-compiled (needs gcc-aarch64-linux-gnu)",
    )
    parser.add_argument(
        "--no-check",
        action="store_true",
        help="only build; skip the fmpy run against the native integrator, its plot and its animation",
    )


DEFAULT_NAME = "ConicalPendulum"  # the FMU of a scene the options describe (the seed's, by default)
# each kind of FMU's suffix to the scene's name: the README's builds, in turn, leave all four
KINDS = {
    "pythonfmu (default)": "",
    "--native": "_native",
    "--native --fmi 3": "_fmi3",
    "--native --fmi 3 --scalars": "_fmi3_scalars",
}


def kind_of(native: bool, fmi: int, scalars: bool = False) -> str:
    """The suffix of a build's kind of FMU (KINDS)."""
    if not native:
        return KINDS["pythonfmu (default)"]
    if fmi == 2:
        return KINDS["--native"]
    return KINDS["--native --fmi 3 --scalars" if scalars else "--native --fmi 3"]


def default_output(kind: str, scene_file: Path | str | None = None) -> Path:
    """Where a build writes without --output: dist/, named after the scene file (DEFAULT_NAME
    without one) and the kind of FMU."""
    name = Path(scene_file).stem if scene_file else DEFAULT_NAME
    return Path("dist") / f"{name}{kind}.fmu"


def replaced_scene(output: Path, scene: Scene) -> str | None:
    """What a build to `output` replaces, when that is an FMU of another scene (or no FMU of
    this package); None when nothing or the same scene's FMU is there."""
    if not output.exists():
        return None
    try:
        if fmus.fmu_scene(output) == scene:
            return None
    except ValueError:
        return f"{output}: replacing a file that is no pendulum FMU of this package"
    return f"{output}: replacing the FMU of another scene (--output names a file of its own)"


def run_files(fmu: Path) -> tuple[Path, Path, Path]:
    """The CSV, plot and animation of an FMU's checked run: named after the FMU, next to it."""
    return fmu.with_suffix(".csv"), fmu.with_suffix(".png"), fmu.with_suffix(".gif")


def choose_scene(args) -> Scene:
    """The scene of --scene, or of the options describing a uniform chain (not both)."""
    options = [
        name
        for name, given in [
            ("--links", args.links is not None),
            ("--massless-links", args.massless_links),
            ("--no-bobs", args.no_bobs),
            ("--kinematics", args.kinematics is not None),
            ("--coupling", args.coupling),
            ("--joint-damping", args.joint_damping is not None),
            ("--air-drag", args.air_drag),
        ]
        if given
    ]
    damping_rule = RULES[LINK_RULES["damping"]]
    if args.joint_damping is not None and not satisfies(LINK_RULES["damping"], args.joint_damping):
        raise UserError(f"--joint-damping: must be {damping_rule.wanted}, got {args.joint_damping!r}")
    if args.scene:
        if options:
            raise UserError(f"--scene describes the whole scene; drop {', '.join(options)}")
        return load_scene(args.scene)
    return Scene.uniform(
        3 if args.links is None else args.links,
        massless_links=args.massless_links,
        bobs=not args.no_bobs,
        kinematics=args.kinematics or "consistent",
        coupling=args.coupling,
        damping=args.joint_damping,
        air_drag=args.air_drag,
    )


def platforms(args) -> tuple[str, ...]:
    """The platforms whose binaries the FMU carries: Linux x86-64, and those the options add."""
    extra = {"win64": args.win64, "aarch64-linux": args.aarch64}
    return ("linux64", *(platform for platform, wanted in extra.items() if wanted))


def run(args) -> int:
    try:
        scene = choose_scene(args)
    except SceneError as exc:
        raise UserError(str(exc)) from None
    if args.win64 and not args.native:
        raise UserError("--win64: only the native FMU carries a Windows binary; add --native")
    if args.fmi == 3 and not args.native:
        raise UserError("--fmi 3: only the native FMU is FMI 3.0; add --native")
    if args.aarch64 and args.fmi != 3:
        raise UserError(
            "--aarch64: only the FMI 3.0 FMU carries an ARM binary (FMI 2.0 tools disagree on its "
            "folder: docs/native.md#platforms); add --native --fmi 3"
        )
    if args.scalars and args.fmi != 3:
        raise UserError("--scalars: only the FMI 3.0 FMU has arrays; add --native --fmi 3")
    output = args.output or default_output(kind_of(args.native, args.fmi, args.scalars), args.scene)
    replacing = replaced_scene(output, scene)  # before the build replaces it
    try:
        build = fmus.build_fmu(
            scene,
            output,
            backend="native" if args.native else "pythonfmu",
            platforms=platforms(args),
            fmi_version=args.fmi,
            arrays=not args.scalars,
        )
    except ValueError as exc:
        raise UserError(str(exc)) from None
    how = (
        "from cache"
        if build.core.cached
        else "compiled " + ", ".join(f"{k} {v:.1f} s" for k, v in build.core.seconds.items())
    )
    print(
        f"built {build.path} ({build.path.stat().st_size / 1024:.0f} KiB) in {build.seconds:.1f} s: "
        f"{scene.n} links, {len(scene.parameter_names())} parameters, {len(scene.input_names())} inputs, "
        f"{len(scene.output_names())} calculated outputs; {'native, ' if args.native else ''}{'FMI 3.0, ' if args.fmi == 3 else ''}core {how}"
    )
    if replacing:
        print(replacing)
    if args.no_check:
        return 0
    comparison, ok = compare(build.path, scene)
    draw(comparison.result, build.path)
    return 0 if ok else 1


def draw(result, fmu: Path) -> None:
    """The run as CSV, a plot and an animation named after the FMU (run_files): as much of
    them as the scene's outputs allow, and one line saying what was left out and why."""
    csv, png, gif = run_files(fmu)
    write_csv(str(csv), result)
    results = plots.load_results(csv)
    lacking = plots.missing(results)
    plots.plot(results, png)
    if "the animation" in lacking:
        gif.unlink(missing_ok=True)  # an earlier build's, of another scene: not this run
        print(f"wrote {csv} and {png}")
    else:
        seconds = plots.animate(results, gif)
        print(f"wrote {csv}, {png} and {gif} (animation rendered in {seconds:.1f} s)")
    if lacking:
        print(plots.left_out(lacking))

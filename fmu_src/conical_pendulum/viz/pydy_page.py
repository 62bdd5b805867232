"""The seed's own viewer for FMU results: pydy.viz's static page, fed our trajectories.

Builds the scene's frames and points with sympy.physics.mechanics (analysis time, not FMU
run time), gives each link a cylinder and each bob a sphere as the seed does, and lets
pydy.viz write its scene description and simulation data (a 4x4 matrix per object per
step) next to its HTML. Needs pydy (`pip install -e .[test]`).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..scene import Scene

PREFIX = "conical_pendulum"
FOV = 45.0  # pydy's default field of view, degrees (vertical)
ELEVATION = 20.0  # the camera looks down at the pivot from this many degrees above the horizon


def write_pydy_page(scene: Scene, results: dict, directory) -> tuple[Path, str]:
    """Write pydy.viz's static page for these results into directory/pydy-resources.

    Returns that folder and the page's address in it: serve the folder as the web root
    (pydy's page fetches the simulation data from "/"), e.g. `python -m http.server`
    there, and open `http://127.0.0.1:8000/<address>`."""
    import sympy.physics.mechanics as me
    from pydy.viz.scene import Scene as PydyScene
    from pydy.viz.shapes import Cylinder, Sphere
    from pydy.viz.visualization_frame import VisualizationFrame

    times = np.asarray(results["time"], dtype=float)
    steps = np.diff(times)
    if len(times) < 2 or np.ptp(steps) > 1e-9 * max(times[-1] - times[0], 1.0):
        raise ValueError("results: pydy.viz needs at least two samples on a uniform time grid")
    names = scene.state_names()
    missing = [name for name in names if name not in results]
    if missing:
        raise ValueError(f"results: the state {missing} is missing; pydy.viz draws from it")
    n = scene.n
    q = me.dynamicsymbols(f"alpha0:{n}") + me.dynamicsymbols(f"beta0:{n}")
    u = me.dynamicsymbols(f"omega0:{n}") + me.dynamicsymbols(f"delta0:{n}")
    inertial, pivot = me.ReferenceFrame("I"), me.Point("O")
    parent, joint, shown = inertial, pivot, []
    for i, link in enumerate(scene.links):
        frame = me.ReferenceFrame(f"F{i}")
        frame.orient(parent, "Space", [q[i], q[n + i], 0], "ZXY")
        centre = joint.locatenew(f"G{i}", -link.length / 2 * frame.y)
        end = joint.locatenew(f"P{i}", -link.length * frame.y)
        shown.append(
            VisualizationFrame(
                f"link{i}",
                frame,
                centre,
                Cylinder(name=f"cylinder{i}", radius=link.radius, length=link.length, color="red"),
            )
        )
        if link.has_bob:
            shown.append(
                VisualizationFrame(
                    f"bob{i}", frame, end, Sphere(name=f"sphere{i}", radius=link.bob_radius, color="blue")
                )
            )
        parent, joint = frame, end
    viz = PydyScene(inertial, pivot, *shown, cameras=[_camera(scene, inertial, pivot)])
    viz.times = times
    viz.constants = {}
    viz.states_symbols = q + u
    viz.states_trajectories = np.column_stack([results[name] for name in names])
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    cwd = os.getcwd()
    os.chdir(directory)
    try:
        viz.create_static_html(overwrite=True, silent=True, prefix=PREFIX)
    finally:
        os.chdir(cwd)
    return directory / viz.pydy_directory, f"index.html?load={PREFIX}_scene_desc.json"


def _camera(scene: Scene, inertial, pivot):
    """pydy's camera, framing every place the chain can reach.

    The bobs move anywhere in the sphere of radius reach = sum of link lengths + the
    largest bob radius around the pivot. The page cannot aim the camera elsewhere: each
    frame its TrackballControls turn the camera to look at their target, the origin (the
    pivot), with Y (up, against gravity) up on the screen, whatever orientation it was
    given. A sphere of radius `reach` centred on the line of sight fits the vertical field
    of view `FOV` (the narrower one while the canvas is wider than tall) from the distance
    reach / sin(FOV / 2); 10 % more leaves a margin (pydy's default camera, 10 m from the
    pivot, sits inside the seed's 30 m chain). The camera is raised by `ELEVATION` above the
    horizontal, on the +Z side, so a bob's cone shows as an ellipse, not a line, and is
    oriented as the controls will turn it (its -z towards the pivot). The near and far
    planes keep the chain and zooming in or out with the mouse in view. pydy's
    `workspaceSize` is not set: its page never reads it (the axes are 100 m whatever it is).
    """
    from pydy.viz.camera import PerspectiveCamera

    reach = sum(link.length for link in scene.links) + max(
        link.bob_radius if link.has_bob else link.radius for link in scene.links
    )
    distance = 1.1 * reach / np.sin(np.radians(FOV / 2))
    tilt = np.radians(ELEVATION)
    frame = inertial.orientnew("C", "Axis", [-tilt, inertial.x])  # its z points at the camera
    eye = pivot.locatenew("E", distance * frame.z)
    return PerspectiveCamera("camera", frame, eye, fov=FOV, near=distance / 100, far=distance * 10)

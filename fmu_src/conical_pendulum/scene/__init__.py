"""What a user wants simulated: links, bobs, outputs, kinematics, the forces on the chain.

The scene is the single input of the build pipeline (scene.py); its links and their parts
(links.py: where a new kind of link is added), the names of its variables (variables.py) and
its files (files.py). This package imports no sympy: the FMU and the native simulation use it
too. Its value rules are runtime.rules', the same the FMU applies.
"""

from .files import load_scene, scene_from_dict
from .links import SPHERE_DRAG, Link, SceneError
from .scene import (
    AIR_DENSITY,
    FORMULATIONS,
    KINEMATICS,
    MAX_EXPANDED_LINKS,
    MAX_LINKS,
    MAX_PUBLISHED_LINKS,
    OUTPUT_GROUPS,
    RECURSIVE_FROM,
    Scene,
)
from .variables import (
    APPARENT_MASS,
    ELASTIC_OUTPUTS,
    FREE_FORCE,
    PIVOT_INPUTS,
    PIVOT_OUTPUTS,
    PIVOT_VELOCITY,
    ROPE_EVENTS,
    ROPE_OUTPUTS,
    SEED_ANGLE,
    WIND,
    WORKS,
    Scalar,
)

__all__ = [
    "AIR_DENSITY",
    "APPARENT_MASS",
    "ELASTIC_OUTPUTS",
    "FORMULATIONS",
    "FREE_FORCE",
    "KINEMATICS",
    "MAX_EXPANDED_LINKS",
    "MAX_LINKS",
    "MAX_PUBLISHED_LINKS",
    "OUTPUT_GROUPS",
    "PIVOT_INPUTS",
    "PIVOT_OUTPUTS",
    "PIVOT_VELOCITY",
    "RECURSIVE_FROM",
    "ROPE_EVENTS",
    "ROPE_OUTPUTS",
    "SEED_ANGLE",
    "SPHERE_DRAG",
    "WIND",
    "WORKS",
    "Link",
    "Scalar",
    "Scene",
    "SceneError",
    "load_scene",
    "scene_from_dict",
]

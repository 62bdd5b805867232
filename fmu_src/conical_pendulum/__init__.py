"""An n-link conical pendulum as an FMI 2.0 co-simulation FMU, from a sympy model to compiled C."""

from .scene import Link, Scene, SceneError

__all__ = ["Link", "Scene", "SceneError"]

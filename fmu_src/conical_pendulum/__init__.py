"""An n-link conical pendulum as FMI 2.0 and 3.0 FMUs (a pythonfmu slave, native C), from a sympy model to compiled C."""

from .scene import Link, Scene, SceneError

__all__ = ["Link", "Scene", "SceneError"]

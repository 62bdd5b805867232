"""Cart: a mass on a spring and damper along X, the support of the coupled demo (FMI 2.0 CS).

It carries the pendulum, whose force on it answers the cart's acceleration a at once:
F_pivot_x = F_free_x - M_pivot_xx a. Its inputs are a force F_x and the apparent mass M_x
of what it carries, and it moves by (m_cart + M_x) a = F_x - k_cart x - c_cart v; its output
`a` is the pendulum's a_pivot_x. Two exchanges (demos/coupled.py):

- explicit: F_x = F_pivot_x held over the step, M_x = 0: the force as computed at the last
  acceleration exchanged; unstable when the cart is light against M_pivot_xx (the
  added-mass effect);
- apparent-mass: F_x = F_free_x and M_x = M_pivot_xx, so the part of the force that
  answers the cart's own acceleration is solved with the cart's step (implicitly); F_free_x
  depends on the pendulum's state only, smoothly, so it can be extrapolated (F_x_order = 1).

Over a step the force is held (F_x_order = 0) or extrapolated linearly through the last
two communication points (1); either way the step is solved exactly, with the matrix
exponential: all the error of the coupled demo is the coupling's. Needs numpy only.
"""

import math

import numpy as np
from pythonfmu import Fmi2Slave, Integer, Real
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Causality, Fmi2Initial, Fmi2Status, Fmi2Variability

from .rules import BadValue, check_value

PARAMETERS = {
    "m_cart": ("mass of the cart [kg]", 100.0),
    "k_cart": ("stiffness of the spring from the ground to the cart [N/m]", 150.0),
    "c_cart": ("damping from the ground to the cart [N s/m]", 20.0),
}
START = {"x": 1.0, "v": 0.0}  # the cart's state at t = 0 [m, m/s]


def expm(A: np.ndarray) -> np.ndarray:
    """exp(A) by scaling and squaring with a Taylor series: to rounding for the small
    matrices of a step (scipy's expm costs milliseconds at this size)."""
    norm = np.abs(A).sum(axis=1).max()
    squarings = max(0, math.ceil(math.log2(norm / 0.25))) if norm > 0.25 else 0
    X = A / 2.0**squarings
    term = result = np.eye(len(A))
    for k in range(1, 16):  # 0.25^16 / 16! < 1e-22
        term = term @ X / k
        result = result + term
    for _ in range(squarings):
        result = result @ result
    return result


class Cart(Fmi2Slave):
    author = "conical-pendulum-fmu"
    description = (
        "cart on a spring and damper along X carrying an apparent mass M_x; inputs "
        "F_x (held or extrapolated) and M_x (held) over each communication step, "
        "solved exactly"
    )
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=10.0, step_size=0.01)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        for name, (_, value) in PARAMETERS.items():
            setattr(self, name, value)
        self.F_x_order = 0
        self.x, self.v, self.M_x = START["x"], START["v"], 0.0
        self._input = 0.0  # F_x as last set
        self._force = 0.0  # the force in effect now: F_x as set, or as extrapolated to now
        self._last_input = None  # (time, F_x) at the last step, for the extrapolation
        fixed, continuous = Fmi2Variability.fixed, Fmi2Variability.continuous
        for name, (text, _) in PARAMETERS.items():
            self.register_variable(
                Real(name, causality=Fmi2Causality.parameter, variability=fixed, description=text)
            )
        self.register_variable(
            Integer(
                "F_x_order",
                causality=Fmi2Causality.parameter,
                variability=fixed,
                description="the force over a step: 0 held at its value, 1 "
                "extrapolated linearly through the last two "
                "communication points (for F_free_x only: F_pivot_x "
                "answers the acceleration and diverges so)",
            )
        )
        self.register_variable(
            Real(
                "F_x",
                causality=Fmi2Causality.input,
                variability=continuous,
                getter=lambda: self._input,
                setter=self._set_force,
                description="force on the cart along X [N]: the pendulum's F_pivot_x, or F_free_x with M_x",
            )
        )
        self.register_variable(
            Real(
                "M_x",
                causality=Fmi2Causality.input,
                variability=continuous,
                description="apparent mass along X of what the cart carries [kg] "
                "(the pendulum's M_pivot_xx), moved with the cart: "
                "(m_cart + M_x) a = F_x - k_cart x - c_cart v; 0 for "
                "an explicit exchange; held over each step",
            )
        )
        for name, text in (
            ("x", "position of the cart along X [m]"),
            ("v", "velocity of the cart along X [m/s]"),
        ):
            self.register_variable(
                Real(
                    name,
                    causality=Fmi2Causality.output,
                    variability=continuous,
                    initial=Fmi2Initial.exact,
                    description=text,
                )
            )
        self.register_variable(
            Real(
                "a",
                causality=Fmi2Causality.output,
                variability=continuous,
                initial=Fmi2Initial.calculated,
                getter=self._acceleration,
                description="acceleration of the cart along X [m/s2] (the "
                "pendulum's a_pivot_x); depends at once on F_x and M_x",
            )
        )

    def _set_force(self, value):
        self._input = self._force = value

    def _acceleration(self):
        return (self._force - self.k_cart * self.x - self.c_cart * self.v) / (self.m_cart + self.M_x)

    def _problem(self):
        """What makes the cart unsolvable, or None."""
        try:
            for name in ("m_cart", "k_cart", "c_cart", "F_x_order", "x", "v", "M_x"):
                check_value(name, getattr(self, name))
            check_value("F_x", self._input)
        except BadValue as exc:
            return str(exc)
        return None

    def do_step(self, current_time, step_size):
        problem = self._problem()
        if problem is None and not (step_size >= 0 and math.isfinite(step_size)):
            problem = f"communication step {step_size!r}: must be a non-negative finite number"
        if problem:
            self.log(f"do_step at t = {current_time:.9g} s: {problem}; the state is kept", Fmi2Status.error)
            return False
        slope = 0.0
        if self.F_x_order == 1 and self._last_input and current_time > self._last_input[0]:
            slope = (self._input - self._last_input[1]) / (current_time - self._last_input[0])
        self._last_input = (current_time, self._input)
        # (x, v, F, F') with x' = v, m v' = F - k x - c v, F' = slope: exact over the step
        mass, k, c = self.m_cart + self.M_x, self.k_cart, self.c_cart
        system = np.zeros((4, 4))
        system[0, 1], system[1, :3], system[2, 3] = 1.0, (-k / mass, -c / mass, 1.0 / mass), 1.0
        self.x, self.v, self._force, _ = expm(system * step_size) @ (self.x, self.v, self._input, slope)
        return True


SLAVE = Cart  # what the FMU's entry module exports (runtime/entry.py)

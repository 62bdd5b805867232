"""Cart: a mass on a spring and damper along X, the support of the coupled demo (FMI 2.0 CS).

It carries the pendulum: its input is the force the pendulum exerts on it (F_pivot_x),
its output `a` is its acceleration (the pendulum's a_pivot_x). The input is held over a
communication step, so the step is solved exactly with the matrix exponential: all the
error of the coupled demo is the coupling's. At run time it needs numpy and scipy.
"""
import math

import numpy as np
from pythonfmu import Fmi2Slave, Real
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Causality, Fmi2Initial, Fmi2Status, Fmi2Variability

from .rules import BadValue, check_value

PARAMETERS = {"m_cart": ("mass of the cart [kg]", 100.0),
              "k_cart": ("stiffness of the spring from the ground to the cart [N/m]", 150.0),
              "c_cart": ("damping from the ground to the cart [N s/m]", 20.0)}
START = {"x": 1.0, "v": 0.0}  # the cart's state at t = 0 [m, m/s]


class Cart(Fmi2Slave):
    author = "conical-pendulum-fmu"
    description = ("cart on a spring and damper along X; input F_x held constant over each "
                   "communication step, solved exactly")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=10.0, step_size=0.01)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        for name, (_, value) in PARAMETERS.items():
            setattr(self, name, value)
        self.x, self.v, self.F_x = START["x"], START["v"], 0.0
        self._propagators = {}
        fixed, continuous = Fmi2Variability.fixed, Fmi2Variability.continuous
        for name, (text, _) in PARAMETERS.items():
            self.register_variable(Real(name, causality=Fmi2Causality.parameter, variability=fixed,
                                        description=text))
        self.register_variable(Real("F_x", causality=Fmi2Causality.input, variability=continuous,
                                    description="force on the cart along X [N] (the pendulum's "
                                                "F_pivot_x); held constant over each communication step"))
        for name, text in (("x", "position of the cart along X [m]"),
                           ("v", "velocity of the cart along X [m/s]")):
            self.register_variable(Real(name, causality=Fmi2Causality.output, variability=continuous,
                                        initial=Fmi2Initial.exact, description=text))
        self.register_variable(Real("a", causality=Fmi2Causality.output, variability=continuous,
                                    initial=Fmi2Initial.calculated, getter=self._acceleration,
                                    description="acceleration of the cart along X [m/s2] (the "
                                                "pendulum's a_pivot_x); depends at once on F_x"))

    def _acceleration(self):
        return (self.F_x - self.k_cart * self.x - self.c_cart * self.v) / self.m_cart

    def _problem(self):
        """What makes the cart unsolvable, or None."""
        try:
            for name in ("m_cart", "k_cart", "c_cart", "x", "v", "F_x"):
                check_value(name, getattr(self, name))
        except BadValue as exc:
            return str(exc)
        return None

    def _propagator(self, dt):
        """exp(dt [[A, B], [0, 0]]): the exact step of (x, v) under a constant force."""
        if dt not in self._propagators:
            from scipy.linalg import expm

            m, k, c = self.m_cart, self.k_cart, self.c_cart
            system = np.array([[0.0, 1.0, 0.0], [-k / m, -c / m, 1.0 / m], [0.0, 0.0, 0.0]])
            self._propagators[dt] = expm(system * dt)
        return self._propagators[dt]

    def exit_initialization_mode(self):
        self._propagators.clear()  # parameters are fixed from here on

    def do_step(self, current_time, step_size):
        problem = self._problem()
        if problem is None and not (step_size >= 0 and math.isfinite(step_size)):
            problem = f"communication step {step_size!r}: must be a non-negative finite number"
        if problem:
            self.log(f"do_step at t = {current_time:.9g} s: {problem}; the state is kept",
                     Fmi2Status.error)
            return False
        step = self._propagator(step_size)
        self.x, self.v = step[:2, :2] @ (self.x, self.v) + step[:2, 2] * self.F_x
        return True


SLAVE = Cart  # what the FMU's entry module exports (runtime/entry.py)

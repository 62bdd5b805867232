"""A trivial pythonfmu FMU: `count` constant outputs with pythonfmu's default getters, a do_step
that does nothing. benchmarks/fmu_overhead.py builds it with as many outputs as the seed FMU
(pythonfmu's `newargs` sets count's default) as the floor of a pythonfmu FMU through fmpy."""

from pythonfmu import Fmi2Causality, Fmi2Slave, Real


class Trivial(Fmi2Slave):
    def __init__(self, count=1, **kwargs):
        super().__init__(**kwargs)
        for i in range(count):
            setattr(self, f"y{i}", float(i))
            self.register_variable(Real(f"y{i}", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        return True

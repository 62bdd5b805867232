"""The model contract (runtime/csrc/fmi/fmu_model.h) driven directly, with no FMI layer: a native
FMU's own sources but its FMI glue compiled into a library, and its functions called through
ctypes. What an FMI 3.0 layer builds on (the adjoint, the early-returning step) is tested here
at the model level."""

from __future__ import annotations

import ctypes
import functools
import math
import subprocess
import zipfile
from pathlib import Path

import numpy as np
from fmpy import read_model_description

from conical_pendulum.builder.packaging.native import LAYER_SOURCES

MODEL_OK, MODEL_DISCARD, MODEL_REFUSED, MODEL_NO_VARIABLE = range(4)
GLUES = {name for layer in LAYER_SOURCES.values() for name in layer}  # both FMI layers and their body


class ModelSizes(ctypes.Structure):
    _fields_ = [
        ("data_size", ctypes.c_size_t),
        ("scratch_size", ctypes.c_size_t),
        ("n_real", ctypes.c_int),
        ("n_integer", ctypes.c_int),
        ("n_state", ctypes.c_int),
        ("n_event_indicator", ctypes.c_int),
        ("vr_state", ctypes.c_uint),
        ("vr_derivative", ctypes.c_uint),
    ]


def compile_model(fmu: Path, folder: Path) -> Path:
    """The library of the FMU's model sources (every C file it ships but the FMI layers)."""
    sources = folder / "sources"
    with zipfile.ZipFile(fmu) as archive:
        for name in archive.namelist():
            if name.startswith("sources/"):
                archive.extract(name, folder)
    library = folder / "model.so"
    files = [str(p) for p in sorted(sources.glob("*.c")) if p.name not in GLUES]
    command = ["cc", "-std=c99", "-O2", "-shared", "-fPIC", "-Wall", "-Wextra", "-Werror"]
    subprocess.run([*command, f"-I{sources}", *files, "-o", str(library), "-lm"], check=True)
    return library


@functools.lru_cache
def description(fmu: Path):
    return read_model_description(str(fmu))


def _array(kind, values):
    return (kind * max(len(values), 1))(*values)


class Model:
    """One ModelData, initialized, with the model description's names and ModelStructure."""

    def __init__(self, library: Path, fmu: Path, start: dict | None = None, integers: dict | None = None):
        self.lib = lib = ctypes.CDLL(str(library))
        self.sizes = ModelSizes.in_dll(lib, "model_sizes")
        self.md = description(fmu)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.name = {v.valueReference: v.name for v in self.md.modelVariables}
        # the data and, after it, the model's own scratch (fmu_model.h)
        self.data = (ctypes.c_double * math.ceil((self.sizes.data_size + self.sizes.scratch_size) / 8))()
        self.message = ctypes.create_string_buffer(4096)
        lib.model_set_states.restype = ctypes.c_char_p
        lib.model_reset(self.data)
        for name, value in (integers or {}).items():
            self.check(lib.model_check_integer(self.data, self.vr[name], value, 0, self.message, 4096))
            lib.model_set_integer(self.data, self.vr[name], value)
        for name, value in (start or {}).items():
            self.set(name, value, initialized=0)
        lib.model_initialize(self.data)
        structure = list(self.md.derivatives) + list(self.md.outputs)
        self.unknowns = [u.variable.valueReference for u in structure]
        n = self.sizes.n_state
        self.states = list(range(self.sizes.vr_state, self.sizes.vr_state + n))
        self.inputs = [v.valueReference for v in self.md.modelVariables if v.causality == "input"]
        self.knowns = self.states + self.inputs
        self.depends = np.array(
            [[k in {d.valueReference for d in u.dependencies} for k in self.knowns] for u in structure]
        )

    def check(self, status):
        if status != MODEL_OK:
            raise AssertionError((status, self.message.value.decode()))

    def set(self, name, value, initialized=1):
        vr = self.vr[name] if isinstance(name, str) else name
        self.check(
            self.lib.model_check_real(
                self.data, ctypes.c_uint(vr), ctypes.c_double(value), initialized, self.message, 4096
            )
        )
        self.lib.model_set_real(self.data, ctypes.c_uint(vr), ctypes.c_double(value))

    def get(self, *names):
        value, out = ctypes.c_double(), []
        for name in names:
            vr = self.vr[name] if isinstance(name, str) else name
            status = self.lib.model_get_real(
                self.data, ctypes.c_uint(vr), ctypes.byref(value), ctypes.c_double(0.0), self.message, 4096
            )
            self.check(status)
            out.append(value.value)
        return out

    def set_point(self, x, a=()):
        """The states (model_set_states) and the inputs."""
        x = np.asarray(x, dtype=float)
        refused = self.lib.model_set_states(self.data, _array(ctypes.c_double, x), self.message, 4096)
        assert refused is None, refused
        for vr, value in zip(self.inputs, a):
            self.set(vr, float(value))

    def state(self):
        x = (ctypes.c_double * self.sizes.n_state)()
        self.lib.model_get_states(self.data, x)
        return np.array(x[:])

    def values(self, unknowns=None):
        return np.array(self.get(*(self.unknowns if unknowns is None else unknowns)))

    def _derivative(self, function, unknowns, knowns, seed, n_out):
        out = (ctypes.c_double * max(n_out, 1))()
        status = function(
            self.data,
            _array(ctypes.c_uint, unknowns),
            ctypes.c_size_t(len(unknowns)),
            _array(ctypes.c_uint, knowns),
            ctypes.c_size_t(len(knowns)),
            _array(ctypes.c_double, [float(s) for s in seed]),
            out,
            ctypes.c_double(0.0),
            self.message,
            ctypes.c_size_t(4096),
        )
        return status, np.array(out[:n_out])

    def directional(self, unknowns, knowns, seed):
        """(status, J seed) by model_directional_derivative."""
        return self._derivative(self.lib.model_directional_derivative, unknowns, knowns, seed, len(unknowns))

    def adjoint(self, unknowns, knowns, seed):
        """(status, seed^T J) by model_adjoint_derivative."""
        return self._derivative(self.lib.model_adjoint_derivative, unknowns, knowns, seed, len(knowns))

    def step(self, t, dt, early=True):
        """(status, last successful time, message) of model_do_step_early."""
        reached = ctypes.c_double(-1.0)
        status = self.lib.model_do_step_early(
            self.data,
            ctypes.c_double(t),
            ctypes.c_double(dt),
            int(early),
            ctypes.byref(reached),
            self.message,
            ctypes.c_size_t(4096),
        )
        return status, reached.value, self.message.value.decode() if status else ""

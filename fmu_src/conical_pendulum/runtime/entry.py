"""The module pythonfmu loads: a few lines that hand it the slave class of this FMU.

Shipped in an FMU's resources as `<slave module>_<digest>.py`, next to the package
`cp_runtime_<digest>` (this runtime's sources under a name unique to them); it exports
that package's `<slave module>.SLAVE`.

pythonfmu 0.7 compiles and executes this module again at every instantiation to find
the slave class (findClass), with the module's dict as globals and a fresh dict as
locals; it never releases the classes it finds in those locals, and it releases the
module's dict once without having taken a reference. So the module stays tiny
(compiled per instance), imports the class only once, and afterwards only names it
and gives the dict its reference back.
"""

if "SLAVE" in globals():  # executed again by pythonfmu, at each instantiation
    locals()[SLAVE.__name__] = SLAVE  # noqa: F821 - defined by the import below
    __import__("ctypes").pythonapi.Py_IncRef(__import__("ctypes").py_object(globals()))
else:
    import importlib
    import os
    import sys

    _slave_module, _, _digest = __name__.rpartition("_")
    _package = f"cp_runtime_{_digest}"
    if _package in sys.modules:  # imported by another FMU, whose files may be gone by now:
        _here = os.path.join(os.path.dirname(os.path.abspath(__file__)), _package)
        if _here not in sys.modules[_package].__path__:  # the same sources, from this FMU
            sys.modules[_package].__path__.insert(0, _here)
    SLAVE = importlib.import_module(f"{_package}.{_slave_module}").SLAVE
    globals()[SLAVE.__name__] = SLAVE

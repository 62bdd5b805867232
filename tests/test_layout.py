"""The package's layout: its import graph has no cycle and its layers point one way.

The graph is read from the sources (ast), not by importing them: every `import` and
`from ... import` at any level (a module's top, or inside a function), resolved to this
package's modules. An import inside a function still counts, so a cycle cannot hide in
one; such imports are for optional or heavy packages (pydy, dask, ecospy, scipy), never
for the package's own modules to dodge a cycle.

The layers, from the bottom: runtime/ (shipped inside the FMUs) imports nothing of the
build or the host side; builder/ nothing of analysis/, viz/, demos/ or the command
line, and inside it each role (core/, fmi/, packaging/, models/, then fmu.py) only the
roles below it; library code nothing of the command line (commands/ and cli.py), which
alone turns errors into a line and an exit status.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

PACKAGE = "conical_pendulum"
ROOT = Path(__file__).parents[1] / "fmu_src" / PACKAGE

# what each part may not import (a part is a subpackage, or a top-level module by name)
FORBIDDEN = {
    "runtime": {"builder", "analysis", "viz", "demos", "commands", "cli"},
    "builder": {"analysis", "viz", "demos", "commands", "cli"},
    "analysis": {"commands", "cli"},
    "viz": {"commands", "cli"},
    "demos": {"commands", "cli"},
    "scene": {"commands", "cli", "builder", "analysis", "viz", "demos"},
    "errors": {"commands", "cli", "builder", "analysis", "viz", "demos", "runtime"},
    "progress": {"commands", "cli", "builder", "analysis", "viz", "demos", "runtime"},
    "commands": {"cli"},
}


def module_names() -> dict[str, Path]:
    """Every module of the package by dotted name (a package by its own name)."""
    modules = {}
    for path in sorted(ROOT.rglob("*.py")):
        parts = (PACKAGE, *path.relative_to(ROOT).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        modules[".".join(parts)] = path
    return modules


def imports_of(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The package's modules that `name` (at `path`) imports, anywhere in its source."""
    is_package = path.name == "__init__.py"
    found = set()

    def resolve(target: str) -> str | None:
        """The module itself, or the innermost package holding it."""
        while target and target not in modules:
            target = target.rpartition(".")[0]
        return target or None

    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".")[: len(name.split(".")) - node.level + is_package]
                origin = ".".join(base + ([node.module] if node.module else []))
            else:
                origin = node.module or ""
            # `from a import b`: b is a module of a, or a name in a
            targets = [
                f"{origin}.{alias.name}" if f"{origin}.{alias.name}" in modules else origin
                for alias in node.names
            ]
        else:
            continue
        for target in targets:
            if target == PACKAGE or target.startswith(PACKAGE + "."):
                module = resolve(target)
                if module and module != name:
                    found.add(module)
    return found


def import_graph() -> dict[str, set[str]]:
    modules = module_names()
    return {name: imports_of(name, path, modules) for name, path in modules.items()}


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Every module's shortest import cycle, as a path back to the module it starts from,
    each cycle once (from its first module in sorted order)."""
    found = []
    for start in sorted(graph):
        cycle = _shortest_cycle(graph, start)
        if cycle and min(cycle) == start and cycle[1:] not in [c[1:] for c in found]:
            found.append(cycle)
    return found


def _shortest_cycle(graph: dict[str, set[str]], start: str) -> list[str] | None:
    """A shortest path of imports from `start` back to it (breadth first), or None."""
    paths = {start: [start]}
    queue = [start]
    while queue:
        node = queue.pop(0)
        for other in sorted(graph.get(node, ())):
            if other == start:
                return paths[node] + [start]
            if other not in paths:
                paths[other] = paths[node] + [other]
                queue.append(other)
    return None


def part(module: str) -> str:
    """runtime, builder, ..., or a top-level module's own name (cli, scene, ...)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else PACKAGE


def test_the_graph_sees_the_package():
    graph = import_graph()
    assert f"{PACKAGE}.cli" in graph and f"{PACKAGE}.builder.fmu" in graph
    assert f"{PACKAGE}.scene" in graph[f"{PACKAGE}.builder.fmu"]
    assert f"{PACKAGE}.errors" in graph[f"{PACKAGE}.builder.packaging.native"]


def test_no_import_cycles():
    found = cycles(import_graph())
    lines = [" -> ".join(m.removeprefix(PACKAGE + ".") for m in cycle) for cycle in found]
    print("import cycles:", *(lines or ["none"]), sep="\n  ")
    assert not found, "import cycles:\n" + "\n".join(" -> ".join(cycle) for cycle in found)


@pytest.mark.parametrize("layer", sorted(FORBIDDEN))
def test_layers_point_one_way(layer):
    wrong = sorted(
        f"{module} imports {target}"
        for module, targets in import_graph().items()
        if part(module) == layer
        for target in targets
        if part(target) in FORBIDDEN[layer]
    )
    assert not wrong, "\n".join(wrong)


# builder/ by role, from the bottom: what each role may import of the others (c_literals, the C
# text written one way, serves them all; builder.fmu, the entry, drives them all)
BUILDER_ROLES = {
    "core": set(),  # scene -> equations, dependencies, generated C, the cache's place: no FMI
    "fmi": {"core"},  # what an FMU declares, per FMI version (the records list core's dependencies)
    "packaging": {"core", "fmi"},  # the native FMU compiled and packed; pythonfmu's binary and description
    "models": {"core", "fmi", "packaging"},  # the models behind fmu_model.h: pendulum, cart
    # the compiled core: the scene's numerics with the pendulum's model and its variable table
    "compiler": {"core", "fmi", "packaging", "models"},
    "fmu": {"core", "fmi", "packaging", "models", "compiler"},
}
BUILDER_SHARED = {"c_literals"}


def builder_role(module: str) -> str | None:
    """core, fmi, packaging, models, compiler, fmu or c_literals for a module of builder/, else None."""
    parts = module.split(".")
    return parts[2] if len(parts) > 2 and parts[1] == "builder" else None


def test_builder_holds_its_roles_and_nothing_flat():
    found = {builder_role(module) for module in import_graph()} - {None}
    assert found == set(BUILDER_ROLES) | BUILDER_SHARED


@pytest.mark.parametrize("role", sorted(BUILDER_ROLES))
def test_builder_roles_import_only_the_roles_below(role):
    wrong = sorted(
        f"{module} imports {target}"
        for module, targets in import_graph().items()
        if builder_role(module) == role
        for target in targets
        if builder_role(target) not in {None, role, *BUILDER_SHARED, *BUILDER_ROLES[role]}
    )
    assert not wrong, "\n".join(wrong)


def test_a_cycle_is_found_and_written_out():
    graph = {"a": {"b"}, "b": {"c", "d"}, "c": {"a"}, "d": {"b"}, "e": {"a"}}
    assert cycles(graph) == [["a", "b", "c", "a"], ["b", "d", "b"]]


# ---- an FMU ships only what it runs

RUNTIME = ROOT / "runtime"


def runtime_imports(source: str) -> set[str]:
    """The runtime modules a runtime module's source imports (relative, within the package)."""
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            found |= {node.module} if node.module else {alias.name for alias in node.names}
    return found


def shipped(fmu) -> tuple[str, dict[str, str]]:
    """The runtime package an FMU ships (cp_runtime_<digest>) and its modules' sources by name."""
    import zipfile

    with zipfile.ZipFile(fmu) as archive:
        names = [n for n in archive.namelist() if n.startswith("resources/cp_runtime_")]
        packages = {n.split("/")[1] for n in names}
        assert len(packages) == 1, packages
        return packages.pop(), {
            n.rsplit("/", 1)[1].removesuffix(".py"): archive.read(n).decode()
            for n in names
            if n.endswith(".py")
        }


def test_an_fmu_ships_exactly_the_runtime_its_slave_imports(seed_fmu):
    from conical_pendulum.builder.fmu import runtime_digest, runtime_modules

    package, sources = shipped(seed_fmu)
    assert package == f"cp_runtime_{runtime_digest()}"
    assert set(sources) == {"__init__", "slave", "files"} == set(runtime_modules("slave"))
    # what is shipped is closed under the runtime's imports, and is the runtime's own source
    for name, source in sources.items():
        assert runtime_imports(source) <= set(sources), name
        assert source == (RUNTIME / f"{name}.py").read_text()


def test_each_fmu_still_runs_in_fmpy(seed_fmu, cart_fmu):
    from conical_pendulum.analysis.fmpy_runs import simulate_fmu

    pendulum = simulate_fmu(str(seed_fmu), stop_time=0.5, output_interval=0.1)
    assert abs(pendulum["energy"][-1] - pendulum["energy"][0]) < 1e-6 * abs(pendulum["energy"][0])
    cart = simulate_fmu(str(cart_fmu), stop_time=1.0, output_interval=0.1)
    assert cart["x"][0] == 1.0 and 0 < cart["x"][-1] < 1.0  # the spring pulls it back to 0


def test_each_subcommand_is_a_module_of_its_own():
    """cli.py is the entry point only; commands/<name>.py has the command's options and run."""
    from conical_pendulum.cli import COMMANDS

    for name, command in COMMANDS.items():
        assert command.module == f"{PACKAGE}.commands.{name}"
        tree = ast.parse((ROOT / "commands" / f"{name}.py").read_text())
        defined = {node.name for node in tree.body if isinstance(node, ast.FunctionDef)}
        assert {"add_arguments", "run"} <= defined, name
    cli = ast.parse((ROOT / "cli.py").read_text())
    assert not {node.name for node in cli.body if isinstance(node, ast.FunctionDef)} & {
        "add_arguments",
        "run",
    }


# runtime/csrc by role, and what each role's C may include: core/ (the model's numerics) knows
# neither FMI nor a model behind the contract, but for core.pyx, the compiled core's module, which
# holds the pendulum's model for the pythonfmu slave through fmu_model.h; fmi/ (the FMI layers and
# the contract) knows a model only through fmu_model.h; models/ implement fmu_model.h on the core.
# Generated files (the core's model.h and model.c, an FMU's fmu_config.h and fmi3_arrays.h) may be
# included anywhere.
CSRC = ROOT / "runtime" / "csrc"
GENERATED_C = {"model.h", "model.c", "fmu_config.h", "fmi3_arrays.h"}
FMI_HEADERS = {"fmi2Functions.h", "fmi3Functions.h"}


def test_csrc_is_laid_out_by_role_and_its_includes_point_one_way():
    files = [path for path in CSRC.rglob("*") if path.is_file()]
    role = {path.name: path.parent.name for path in files}
    assert {path.parent for path in files} == {CSRC / "core", CSRC / "fmi", CSRC / "models"}
    assert len(role) == len(files)  # names unique: an FMU's sources/ holds them side by side
    of = {name: {file for file, its in role.items() if its == name} for name in ("core", "fmi", "models")}
    may_include = {
        "core": of["core"],
        "fmi": of["fmi"] | FMI_HEADERS,
        "models": of["core"] | {"fmu_model.h"},
    }
    for path in files:
        included = set(re.findall(r'(?:#include|cdef extern from) "([^"<]+)"', path.read_text()))
        allowed = may_include[role[path.name]] | ({"fmu_model.h"} if path.name == "core.pyx" else set())
        assert included - GENERATED_C <= allowed, path.relative_to(CSRC)

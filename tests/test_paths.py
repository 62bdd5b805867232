"""Every path of this repository that the sources and the docs name exists: a file moved or
renamed leaves no comment, docstring, doc line or link pointing at its old place.

A path is named as `folder/.../name` whose first folder is one of the repository's own
(builder/, runtime/csrc/core/, docs/results/, ...; `*` globs allowed): it must be the end of
a tracked path. A Markdown link to a file of the repository must resolve from the page, and
its #anchor must be a heading of the page it points to.
"""

import re
import subprocess
from functools import cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCANNED = (".md", ".py", ".pyx", ".c", ".h", ".in", ".toml")
VENDORED = "fmu_src/conical_pendulum/runtime/pythonfmu_export/"  # pythonfmu's sources, as released
THIS = "tests/test_paths.py"  # names missing paths on purpose, to see that they are found
# a path-like word: folders and a name, each of word characters, dots, hyphens or a glob's *
PATH_WORD = re.compile(r"(?<![\w./*<>-])((?:[\w*.-]+/)+[\w*.-]*)")
LINK = re.compile(r"\]\(([^)\s]+)\)")


@cache
def tracked() -> tuple[str, ...]:
    """The repository's files (git's index, so what a clone has, not what a build left)."""
    listed = subprocess.run(
        ["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, text=True, check=True, timeout=60
    ).stdout
    return tuple(name for name in listed.split("\0") if name and (ROOT / name).exists())


@cache
def tracked_paths() -> frozenset[str]:
    """Every tracked file and every folder above one, as paths from the root."""
    paths = set()
    for name in tracked():
        parts = name.split("/")
        paths.update("/".join(parts[:i]) for i in range(1, len(parts) + 1))
    return frozenset(paths)


@cache
def folder_names() -> frozenset[str]:
    return frozenset(part for name in tracked() for part in name.split("/")[:-1])


def exists(named: str) -> bool:
    """Whether `named` (folders/name, maybe a glob) is the end of a tracked path."""
    pattern = re.compile("(?:.*/)?" + re.escape(named.rstrip("/")).replace(r"\*", "[^/]*"))
    return any(pattern.fullmatch(path) for path in tracked_paths())


def named_paths(text: str):
    """The repository paths a text names: words whose first folder is a folder of the repository."""
    for match in PATH_WORD.finditer(text):
        word = match.group(1).rstrip(".")
        first = word.removeprefix("./").split("/")[0]
        if first in folder_names():
            yield word


def anchors(page: Path) -> set[str]:
    """GitHub's anchors of a Markdown page's headings."""
    found = set()
    for line in page.read_text().splitlines():
        if line.startswith("#"):
            title = line.lstrip("#").strip().lower()
            found.add(re.sub(r"[^\w\- ]", "", title).replace(" ", "-"))
    return found


def scanned_files():
    return [
        name
        for name in tracked()
        if (name.endswith(SCANNED) and not name.startswith(VENDORED) and name != THIS) or name == ".ci/run"
    ]


@pytest.mark.parametrize("name", scanned_files())
def test_every_path_a_file_names_exists(name):
    text = (ROOT / name).read_text()
    missing = sorted({word for word in named_paths(text) if not exists(word)})
    assert not missing, f"{name} names paths that do not exist: {missing}"


def broken_links(page: Path) -> list[str]:
    """A page's links to files that are not there, or to anchors their page does not have."""
    broken = []
    for target in LINK.findall(page.read_text()):
        if re.match(r"[a-z]+:", target):
            continue  # a URL
        path, _, anchor = target.partition("#")
        linked = (page.parent / path).resolve() if path else page
        wrong_anchor = linked.suffix == ".md" and anchor and linked.exists() and anchor not in anchors(linked)
        if not linked.exists() or wrong_anchor:
            broken.append(target)
    return broken


@pytest.mark.parametrize("name", [name for name in tracked() if name.endswith(".md")])
def test_every_link_of_a_page_resolves(name):
    broken = broken_links(ROOT / name)
    assert not broken, f"{name} links to what is not there: {broken}"


def test_the_checks_see_a_missing_path_and_a_wrong_anchor(tmp_path):
    """The two checks fail where they should: an old layout's path, a heading that moved."""
    assert exists("runtime/csrc/core/dynamics.c") and exists("csrc/core/dynamics.c")
    assert not exists("runtime/csrc/dynamics.c") and not exists("csrc/dynamics.c")
    assert exists("csrc/*/*.c") and not exists("csrc/*.pyx")
    assert list(named_paths("see `builder/fmu.py`, dist/x.fmu and ../shared/hosts/x.")) == ["builder/fmu.py"]
    page = tmp_path / "page.md"
    page.write_text("# A page\n\n## Cost per step, FMI 3.0 against FMI 2.0\n")
    assert anchors(page) == {"a-page", "cost-per-step-fmi-30-against-fmi-20"}
    page.write_text(
        page.read_text() + "[a](page.md#a-page) [b](#a-page) [c](#b-page) [d](gone.md) [e](https://x.org/y)\n"
    )
    assert broken_links(page) == ["#b-page", "gone.md"]

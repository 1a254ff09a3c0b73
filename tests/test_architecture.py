"""The shape of the code: no import cycle between modules, no private name imported from another module,
and the README's Layout section lists exactly the project's packages.

Imports are read from the source (``ast``), so an import inside a function or under ``if TYPE_CHECKING:``
counts as much as one at the top of a module.
"""

from __future__ import annotations

import ast
import functools
import re
from pathlib import Path

import networkx as nx
import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("bondgraph", "diagnosis", "prognosis", "bgphm")


def _modules() -> dict[str, tuple[Path, bool]]:
    """Dotted module name -> (file, is a package)."""
    found = {}
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            is_package = parts[-1] == "__init__"
            found[".".join(parts[:-1] if is_package else parts)] = (path, is_package)
    return found


MODULES = _modules()


def _enclosing_module(name: str) -> str | None:
    """The project module that ``name`` (a module or a name inside one) belongs to."""
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name or None


@functools.cache   # the tests read the same files: parse each once
def _imports(module: str) -> list[tuple[str, str | None, int]]:
    """(imported module, imported name or None, line) for every import statement of ``module``."""
    path, is_package = MODULES[module]
    package = module if is_package else module.rpartition(".")[0]
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(alias.name, None, node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module
            found += [(source, alias.name, node.lineno) for alias in node.names]
    return found


def import_graph() -> nx.DiGraph:
    """Module -> module edges of the project, with the line of the first import as ``line``."""
    graph = nx.DiGraph()
    graph.add_nodes_from(MODULES)
    for module in MODULES:
        for source, name, line in _imports(module):
            target = f"{source}.{name}" if name and f"{source}.{name}" in MODULES else _enclosing_module(source)
            if target and target != module and not graph.has_edge(module, target):
                graph.add_edge(module, target, line=line)
    return graph


@pytest.mark.slow
def test_the_walk_sees_every_package_and_imports_inside_functions():
    packages = {"bondgraph", "diagnosis", "prognosis", "bgphm", "prognosis.statespace", "diagnosis.intervals"}
    assert packages <= set(MODULES)
    graph = import_graph()
    # bgphm.commands.detect imports the library inside its run function (lazily); the walk must see those edges
    assert any(target.startswith("diagnosis") for target in graph.successors("bgphm.commands.detect"))


def test_no_import_cycle_between_modules():
    cycles = sorted(nx.simple_cycles(import_graph()), key=len)
    assert not cycles, "import cycles: " + "; ".join(" -> ".join(cycle + cycle[:1]) for cycle in cycles[:10])


def test_data_flows_one_way_between_the_packages():
    order = {package: rank for rank, package in enumerate(PACKAGES)}
    backwards = [(a, b) for a, b in import_graph().edges
                 if order[b.split(".")[0]] > order[a.split(".")[0]]]
    assert not backwards, f"imports against bondgraph -> diagnosis -> prognosis -> bgphm: {backwards}"


def test_no_module_imports_a_private_name_of_another_module():
    offenders = []
    for module in MODULES:
        for source, name, line in _imports(module):
            if not name or not name.startswith("_") or name.startswith("__"):
                continue
            if f"{source}.{name}" in MODULES and source.split(".")[0] == module.split(".")[0]:
                continue  # a package-private module of the same package (e.g. prognosis._linalg)
            offenders.append(f"{module}:{line} imports {name} from {source}")
    assert not offenders, "\n".join(offenders)


def _declared(module: str) -> set[str] | None:
    """The names of ``module``'s ``__all__`` (None without one)."""
    path, _ = MODULES[module]
    for node in ast.parse(path.read_text(), str(path)).body:
        if isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if any(getattr(t, "id", None) == "__all__" for t in targets):
                return set(ast.literal_eval(node.value))
    return None


def _private(module: str) -> bool:
    return any(part.startswith("_") and not part.startswith("__") for part in module.split("."))


def test_every_module_declares_its_public_names():
    missing = sorted(module for module in MODULES if _declared(module) is None)
    assert not missing, f"modules without __all__: {missing}"


def test_no_module_imports_a_private_module_of_another_package():
    offenders = [f"{a}:{data['line']} imports {b}" for a, b, data in import_graph().edges(data=True)
                 if _private(b) and a.split(".")[0] != b.split(".")[0]]
    assert not offenders, "\n".join(offenders)


def _outside_imports() -> list[tuple[str, int, str, str]]:
    """(file, line, module, name) of every ``from <library module> import name`` in bgphm, examples, benchmarks."""
    files = [path for module, (path, _) in MODULES.items() if module.split(".")[0] == "bgphm"]
    files += sorted((ROOT / "examples").rglob("*.py")) + sorted((ROOT / "benchmarks").rglob("*.py"))
    found = []
    for path in files:
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.ImportFrom) and not node.level and node.module \
                    and node.module.split(".")[0] in PACKAGES[:3]:
                found += [(str(path.relative_to(ROOT)), node.lineno, node.module, alias.name) for alias in node.names]
    return found


@pytest.mark.slow   # parses every example and benchmark: 2 s of the fast tier
def test_bgphm_examples_and_benchmarks_use_only_public_names():
    """Each name they import from the library is declared public by the module it comes from (its ``__all__``),
    in no private module: what a user may rely on is what the application and the figures rely on."""
    offenders = []
    for where, line, module, name in _outside_imports():
        if f"{module}.{name}" in MODULES:  # a module: public unless its name is private
            if _private(f"{module}.{name}"):
                offenders.append(f"{where}:{line} imports the private module {module}.{name}")
        elif module not in MODULES or _private(module) or name not in (_declared(module) or set()):
            offenders.append(f"{where}:{line} imports {name} from {module}, which does not declare it public")
    assert not offenders, "\n".join(offenders)


# ------------------------------------------------------------------------------------------------ README


def _readme_layout() -> list[str]:
    text = (ROOT / "README.md").read_text()
    section = re.search(r"^## Layout\n(.*?)(?=^## |\Z)", text, re.S | re.M)
    assert section, "README.md has no '## Layout' section"
    block = re.search(r"```text\n(.*?)```", section.group(1), re.S)
    assert block, "the Layout section has no ```text tree"
    listed, stack = [], []
    for line in block.group(1).splitlines():
        name = line.split("#")[0].strip()
        if not name.endswith("/"):
            continue
        depth = (len(line) - len(line.lstrip())) // 2  # two spaces per level of the tree
        stack[depth:] = [name.rstrip("/")]
        listed.append("/".join(stack))
    return listed


def _packages() -> list[str]:
    return sorted(name.replace(".", "/") for name, (_, is_package) in MODULES.items() if is_package)


def test_readme_layout_lists_exactly_the_packages():
    listed = _readme_layout()
    tops = [entry for entry in listed if "/" not in entry]
    assert sorted(set(listed) - {"examples", "tests", "benchmarks", "docs"}) == _packages()
    assert len(listed) == len(set(listed)), "a package is listed twice"
    assert set(PACKAGES) <= set(tops)


@pytest.mark.parametrize("entry", ["bondgraph", "prognosis/statespace"])
def test_readme_layout_gives_each_package_one_line_of_description(entry):
    text = (ROOT / "README.md").read_text()
    name = entry.rpartition("/")[2]
    line = next(line for line in text.splitlines() if re.match(rf"\s*{re.escape(name)}/\s", line))
    assert len(line.split("#", 1)[1].strip()) > 10


def test_the_lazy_core_package_declares_what_it_loads():
    """``bondgraph`` loads its public names on first use: each one declared resolves, and none is left out."""
    import bondgraph

    assert set(bondgraph.__all__) == set(bondgraph._MODULE_OF)
    for name in bondgraph.__all__:
        assert getattr(bondgraph, name).__module__.startswith("bondgraph."), name

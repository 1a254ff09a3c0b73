"""The packages are layered: no import cycle, no private name imported from another module.

Every import statement counts, also one inside a function or under ``if TYPE_CHECKING:``: a lazy
import hides a cycle from the interpreter, not from the reader.  prognosis is left out here while
it is being restructured.
"""

import ast
from pathlib import Path

import networkx as nx
import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("bondgraph", "diagnosis", "bgphm")


def modules() -> dict[str, tuple[Path, bool]]:
    """Dotted module name -> (file, is a package's __init__)."""
    found = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            is_package = parts[-1] == "__init__"
            found[".".join(parts[:-1] if is_package else parts)] = (path, is_package)
    return found


def imports(name: str, path: Path, is_package: bool, known) -> list[tuple[str, str]]:
    """(imported module of ours, imported name or "") for every import statement of a module."""
    package = name if is_package else name.rpartition(".")[0]

    def ours(dotted: str) -> str | None:
        while dotted and dotted not in known:
            dotted = dotted.rpartition(".")[0]
        return dotted or None

    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found += [(target, "") for alias in node.names if (target := ours(alias.name))]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(parts + ([node.module] if node.module else []))
            for alias in node.names:
                full = f"{base}.{alias.name}"
                target = full if full in known else ours(base)
                if target:
                    found.append((target, "" if full in known else alias.name))
    return found


@pytest.fixture(scope="module")
def edges():
    known = modules()
    return {name: imports(name, path, is_package, known) for name, (path, is_package) in known.items()}


def test_no_import_cycle(edges):
    graph = nx.DiGraph()
    graph.add_nodes_from(edges)
    graph.add_edges_from((source, target) for source, found in edges.items() for target, _ in found
                         if target != source)
    cycles = [" -> ".join(cycle) for cycle in nx.simple_cycles(graph)]
    assert not cycles, f"import cycles: {cycles}"


def test_no_private_name_imported_from_another_module(edges):
    private = [f"{source} imports {name} from {target}" for source, found in edges.items() for target, name in found
               if target != source and name.startswith("_") and not name.startswith("__")]
    assert not private, private

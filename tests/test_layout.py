"""The package's layout: no import circles, layers in pipeline order, modules of one concept.

An AST scan of every ``import`` inside ``dustoptics`` (at module level and inside functions;
``if TYPE_CHECKING:`` blocks aside, since they never run), without importing anything.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "dustoptics"

#: The pipeline, bottom to top: a module may import its own layer and those below it only.
#: Within a layer, the cycle check alone applies.
LAYERS: tuple[tuple[str, ...], ...] = (
    (
        "dustoptics._validation",
        "dustoptics._numba_cache",
        "dustoptics._files",
    ),
    ("dustoptics.table", "dustoptics.colour", "dustoptics.compare"),
    ("dustoptics.particles",),
    ("dustoptics.scattering",),
    ("dustoptics.models", "dustoptics.atmosphere"),
    ("dustoptics.io",),
    ("dustoptics.plot", "dustoptics.sweep", "dustoptics.sky", "dustoptics.retrieve"),
    ("dustoptics.cli",),
)

#: Most lines of a module of the command line, and of a library module whose docstring does not
#: say why it is one concept (issue 25).
CLI_MAX_LINES = 300
LIBRARY_MAX_LINES = 1200
ONE_CONCEPT = "one concept"


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _is_type_checking(node: ast.AST) -> bool:
    return isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)


def _import_nodes(tree: ast.AST) -> list[ast.Import | ast.ImportFrom]:
    """Every import statement of ``tree`` that runs (TYPE_CHECKING blocks aside)."""
    found: list[ast.Import | ast.ImportFrom] = []
    stack: list[ast.AST] = [tree]
    while stack:
        node = stack.pop()
        if _is_type_checking(node):
            stack.extend(getattr(node, "orelse", []))
            continue
        if isinstance(node, ast.Import | ast.ImportFrom):
            found.append(node)
        stack.extend(ast.iter_child_nodes(node))
    return found


def _resolve(name: str, modules: dict[str, Path]) -> str | None:
    """The module of ``modules`` that ``name`` (a module or a name in one) refers to."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name or None


def import_graph() -> dict[str, set[str]]:
    """Module -> the dustoptics modules it imports (a package's ``__init__`` is the package)."""
    modules = _modules()
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        is_package = path.name == "__init__.py"
        deps: set[str] = set()
        for node in _import_nodes(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            else:
                base = node.module or ""
                if node.level:
                    parts = name.split(".") if is_package else name.split(".")[:-1]
                    parts = parts[: len(parts) - (node.level - 1)]
                    base = ".".join(parts + ([base] if base else []))
                targets = [f"{base}.{alias.name}" for alias in node.names]
            for target in targets:
                if target.startswith("dustoptics"):
                    resolved = _resolve(target, modules)
                    if resolved is not None and resolved != name:
                        deps.add(resolved)
        graph[name] = deps
    return graph


def _without_package_edges(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """Drop the edges between a package and its own submodules.

    Importing ``a.b`` runs ``a/__init__`` first, and a package's ``__init__`` gathering its
    submodules is how packages are built: neither is a circle of concepts.
    """
    return {
        m: {d for d in deps if not d.startswith(m + ".") and not m.startswith(d + ".")}
        for m, deps in graph.items()
    }


def find_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on_stack: set[str] = set()
    stack: list[str] = []
    cycles: list[list[str]] = []
    counter = 0
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in graph:
                    continue
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    cycles.append(sorted(component))
    return cycles


def _layer(module: str) -> int | None:
    if module == "dustoptics":
        return None  # the top-level package gathers everything
    for rank, prefixes in enumerate(LAYERS):
        if any(module == p or module.startswith(p + ".") for p in prefixes):
            return rank
    return None


def test_the_scan_finds_a_circle() -> None:
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert find_cycles(graph) == [["a", "b", "c"]]
    assert find_cycles({"a": {"b"}, "b": set()}) == []


def test_the_scan_sees_imports_inside_functions_but_not_type_checking_blocks() -> None:
    tree = ast.parse(
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    from dustoptics.io import x\n"
        "def f():\n    from dustoptics.table import Table\n"
    )
    assert sorted(str(getattr(n, "module", None)) for n in _import_nodes(tree)) == [
        "dustoptics.table",
        "typing",
    ]


def test_no_import_circles() -> None:
    cycles = find_cycles(_without_package_edges(import_graph()))
    assert cycles == [], "import circles inside dustoptics: " + "; ".join(
        " <-> ".join(c) for c in cycles
    )


def test_every_module_has_a_layer() -> None:
    missing = [m for m in _modules() if m != "dustoptics" and _layer(m) is None]
    assert missing == [], f"modules outside LAYERS (add them where they belong): {missing}"


def test_lower_layers_never_import_upper_ones() -> None:
    upward = []
    for module, deps in _without_package_edges(import_graph()).items():
        rank = _layer(module)
        if rank is None:
            continue
        for dep in sorted(deps):
            dep_rank = _layer(dep)
            if dep_rank is not None and dep_rank > rank:
                upward.append(f"{module} -> {dep}")
    assert upward == [], "imports from a lower layer to an upper one: " + ", ".join(upward)


@pytest.mark.parametrize("name", sorted(_modules()))
def test_module_size(name: str) -> None:
    path = _modules()[name]
    lines = len(path.read_text(encoding="utf-8").splitlines())
    if name == "dustoptics.cli" or name.startswith("dustoptics.cli."):
        assert lines <= CLI_MAX_LINES, (
            f"{path}: {lines} lines (a CLI module: at most {CLI_MAX_LINES})"
        )
    elif lines > LIBRARY_MAX_LINES:
        doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
        assert ONE_CONCEPT in doc.lower(), (
            f"{path}: {lines} lines (over {LIBRARY_MAX_LINES}, and its docstring does not say "
            f"why it is {ONE_CONCEPT})"
        )


def test_test_files_have_unique_names() -> None:
    # tests/ has no __init__.py: pytest imports each test file by its base name (rootdir
    # import mode), so two files of one name in different folders fail collection.
    tests = Path(__file__).resolve().parent
    seen: dict[str, Path] = {}
    for path in sorted(tests.rglob("test_*.py")):
        if "node_modules" in path.parts:
            continue
        assert path.name not in seen, f"{path} and {seen[path.name]} share a name"
        seen[path.name] = path

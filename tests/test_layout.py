"""The package's layout: no import circles, layers in pipeline order, short modules, simple functions.

An AST scan of every ``import`` inside ``dustoptics`` (at module level and inside functions;
``if TYPE_CHECKING:`` blocks aside, since they never run), without importing anything.  Module
length and the cyclomatic complexity of public functions are read from the same ASTs; each
exception is listed here with its reason.
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
        "dustoptics._lazy",
    ),
    ("dustoptics.table", "dustoptics.colour", "dustoptics.compare"),
    ("dustoptics.particles",),
    ("dustoptics.scattering",),
    ("dustoptics.models", "dustoptics.atmosphere"),
    ("dustoptics.io",),
    ("dustoptics.plot", "dustoptics.sweep", "dustoptics.sky", "dustoptics.retrieve"),
    ("dustoptics.cli", "dustoptics.__main__"),
)

#: Most lines of a module of the command line, and of a library module (issue 25).
CLI_MAX_LINES = 300
LIBRARY_MAX_LINES = 1200

#: Library modules allowed above LIBRARY_MAX_LINES, each with the reason it stays one module.
LONG_MODULES: dict[str, str] = {
    "dustoptics.scattering.mie": (
        "the compiled Mie kernel: single spheres, the polydisperse sums fused with the angular "
        "sums and the Legendre projections share one flat workspace layout"
    ),
    "dustoptics.scattering.phase": (
        "the analytic phase functions: most of it is each model's docstring and citation"
    ),
    "dustoptics.particles.sizedist": (
        "the analytic size distributions and their shared interface: most of it is each "
        "family's docstring and closed forms"
    ),
    "dustoptics.atmosphere.gases": (
        "the gases' models and their registry: each Rayleigh model's factory with its citation "
        "and notes, and the ozone spectra (Bodhaine et al.'s formulas are atmosphere.bodhaine1999)"
    ),
}

#: Most cyclomatic complexity of a public function (McCabe; counted as radon counts it).
MAX_COMPLEXITY = 20

#: Public functions allowed above MAX_COMPLEXITY ("module:qualified name"), with the reason.
COMPLEX_FUNCTIONS: dict[str, str] = {}


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
    elif name not in LONG_MODULES:
        assert lines <= LIBRARY_MAX_LINES, (
            f"{path}: {lines} lines (at most {LIBRARY_MAX_LINES}: split it, or add it to "
            "LONG_MODULES with the reason it is one module)"
        )


def test_long_modules_are_long() -> None:
    modules = _modules()
    stale = [
        name
        for name in LONG_MODULES
        if name not in modules
        or len(modules[name].read_text(encoding="utf-8").splitlines()) <= LIBRARY_MAX_LINES
    ]
    assert stale == [], f"LONG_MODULES lists modules that are gone or short (remove them): {stale}"


# ------------------------------------------------------------------ complexity

#: Statements and expressions that add a branch, as radon's ComplexityVisitor counts them.
_LOOPS = (ast.For, ast.AsyncFor, ast.While)
_SCOPES = (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Lambda)


def _branches(node: ast.AST) -> int:
    """The branches ``node`` itself adds (not its children)."""
    if isinstance(node, ast.Try):
        return len(node.handlers) + bool(node.orelse)
    if isinstance(node, ast.BoolOp):
        return len(node.values) - 1
    if isinstance(node, ast.If | ast.IfExp | ast.Assert):
        return 1
    if isinstance(node, ast.Match):
        wildcard = any(getattr(case.pattern, "pattern", False) is None for case in node.cases)
        return max(0, len(node.cases) - wildcard)
    if isinstance(node, _LOOPS):
        return 1 + bool(node.orelse)
    if isinstance(node, ast.comprehension):
        return 1 + len(node.ifs)
    return 0


def cyclomatic_complexity(function: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """McCabe's number of a function: 1 plus its branches.

    Counted as radon (``radon cc``) counts it: ``if``/``elif`` and conditional
    expressions, loops (their ``else`` one more), each ``except`` (and a ``try``'s
    ``else``), each ``and``/``or`` operand after the first, each comprehension's ``for``
    and ``if``, ``assert``, and each ``case`` but a final wildcard.  The functions and
    classes defined inside it count on their own; an ``assert``'s expression is not
    looked into.  Lambdas count towards the function that holds them.
    """
    total = 1
    stack: list[ast.AST] = list(function.body)
    while stack:
        node = stack.pop()
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            continue
        total += _branches(node)
        if not isinstance(node, ast.Assert):
            stack.extend(ast.iter_child_nodes(node))
    return total


def _is_public(name: str) -> bool:
    return not name.startswith("_") or (name.startswith("__") and name.endswith("__"))


def public_functions(tree: ast.Module) -> dict[str, ast.FunctionDef | ast.AsyncFunctionDef]:
    """Qualified name -> every public function and method of a module (nested classes too)."""
    found: dict[str, ast.FunctionDef | ast.AsyncFunctionDef] = {}
    stack: list[tuple[str, ast.AST]] = [("", tree)]
    while stack:
        prefix, scope = stack.pop()
        for node in getattr(scope, "body", []):
            if not _is_public(getattr(node, "name", "_")):
                continue
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                found[prefix + node.name] = node
            elif isinstance(node, ast.ClassDef):
                stack.append((f"{prefix}{node.name}.", node))
    return found


def complexities() -> dict[str, int]:
    """ "module:qualified name" -> complexity, for every public function of the package."""
    found = {}
    for module, path in _modules().items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for name, function in public_functions(tree).items():
            found[f"{module}:{name}"] = cyclomatic_complexity(function)
    return found


def test_the_complexity_count_follows_radon() -> None:
    source = (
        "def f(x, ys):\n"
        "    if x and ys or not x:\n"  # if 1, boolean operands 2
        "        return [y for y in ys if y]\n"  # comprehension 1, its if 1
        "    elif x > 1:\n"  # 1
        "        pass\n"
        "    for y in ys:\n"  # loop 1, its else 1
        "        while y:\n"  # 1
        "            y = y - 1 if y > 2 else 0\n"  # 1
        "    else:\n"
        "        pass\n"
        "    try:\n"
        "        pass\n"
        "    except ValueError:\n"  # 1
        "        pass\n"
        "    except TypeError:\n"  # 1
        "        pass\n"
        "    else:\n"  # 1
        "        pass\n"
        "    finally:\n"
        "        pass\n"
        "    assert x or ys\n"  # 1 (its expression is not looked into)
        "    match x:\n"
        "        case 1:\n"  # 1
        "            pass\n"
        "        case _:\n"  # a final wildcard: 0
        "            pass\n"
        "    def inner():\n"  # counts on its own
        "        if x:\n"
        "            pass\n"
        "    with open(x):\n"  # 0
        "        pass\n"
        "    return lambda: 1 if x else 2\n"  # 1
    )
    (function,) = public_functions(ast.parse(source)).values()
    assert cyclomatic_complexity(function) == 17  # radon cc gives 17


def test_public_functions_are_found_in_classes_and_private_names_left_out() -> None:
    tree = ast.parse(
        "def f(): pass\n"
        "def _g(): pass\n"
        "class A:\n"
        "    def __init__(self): pass\n"
        "    def _h(self): pass\n"
        "    class B:\n"
        "        def m(self): pass\n"
        "class _C:\n"
        "    def m(self): pass\n"
    )
    assert sorted(public_functions(tree)) == ["A.B.m", "A.__init__", "f"]


def test_public_functions_are_simple() -> None:
    found = complexities()
    over = {
        name: value
        for name, value in found.items()
        if value > MAX_COMPLEXITY and name not in COMPLEX_FUNCTIONS
    }
    assert over == {}, (
        f"public functions above cyclomatic complexity {MAX_COMPLEXITY} (split them): {over}"
    )
    stale = [
        name for name in COMPLEX_FUNCTIONS if name not in found or found[name] <= MAX_COMPLEXITY
    ]
    assert stale == [], f"COMPLEX_FUNCTIONS lists functions gone or simple (remove them): {stale}"


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

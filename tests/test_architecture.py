"""The layout keeps its promises: imports go one way, no cycles, no core -> builder import, short code.

See docs/architecture.md for the layers and why they are in this order.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
CORE = REPO / "brainpainter"

# Lowest first: a module may import from its own layer or a lower one, never from a higher one.
LAYERS = ["errors", "io", "color", "atlas", "tracts", "table", "maps", "connectome", "layers", "rendering",
          "media", "web", "cli", "testing"]
NOT_CORE = ("brainpainter_builder", "brainpainter_blender", "brainpainter_atlases")
# (module, longest function, longest module) limits
MAX_FUNCTION_LINES = 80
MAX_MODULE_LINES = 500
LONG_MODULES_ALLOWED = {"tools/brainpainter_builder/gcsa.py"}   # FreeSurfer GCSA reader, a file format


def module_name(path: Path) -> str:
    parts = path.relative_to(REPO).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported_modules(path: Path, known: set[str]) -> set[str]:
    """Project modules that `path` imports anywhere in its body (also inside functions)."""
    name = module_name(path)
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            candidates = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            candidates = [base] + [f"{base}.{alias.name}" for alias in node.names]
        else:
            continue
        for candidate in candidates:
            if candidate.startswith(NOT_CORE):
                found.add(candidate.split(".")[0])
            while candidate and candidate not in known:
                candidate = candidate.rpartition(".")[0]
            if candidate and candidate != name:
                found.add(candidate)
    return found


def layer(module: str) -> int | None:
    parts = module.split(".")
    if len(parts) < 2:
        return None                      # the facade brainpainter/__init__.py: lazy public names
    return LAYERS.index("cli" if parts[1] == "__main__" else parts[1])


@pytest.fixture(scope="module")
def graph() -> dict[str, set[str]]:
    paths = sorted(CORE.rglob("*.py"))
    known = {module_name(p) for p in paths}
    return {module_name(p): imported_modules(p, known) for p in paths}


def test_every_core_module_sits_in_a_layer(graph):
    assert all(layer(m) is not None for m in graph if m != "brainpainter"), sorted(graph)


def test_imports_go_down_the_layers_only(graph):
    upward = [f"{m} -> {t}" for m, targets in graph.items() if layer(m) is not None
              for t in targets if t.startswith("brainpainter.") and layer(t) > layer(m)]
    assert upward == []


def test_core_never_imports_the_builder_or_a_plugin(graph):
    assert [f"{m} -> {t}" for m, targets in graph.items() for t in targets if t in NOT_CORE] == []


def test_no_import_cycles(graph):
    cycles: list[list[str]] = []
    state: dict[str, int] = {}

    def visit(node: str, stack: list[str]) -> None:
        state[node] = 1
        for target in sorted(graph.get(node, ())):
            if target == "brainpainter" or target not in graph:
                continue                 # the facade is imported by name only (__version__)
            if state.get(target) == 1:
                cycles.append([*stack[stack.index(target):], target])
            elif target not in state:
                visit(target, [*stack, target])
        state[node] = 2

    for module in sorted(graph):
        if module not in state:
            visit(module, [module])
    assert cycles == []


def python_files() -> list[Path]:
    roots = [CORE, REPO / "tools", REPO / "plugins"]
    return sorted(p for root in roots for p in root.rglob("*.py")
                  if ".venv" not in p.parts and "tests" not in p.parts)


def test_no_function_over_80_lines():
    long = []
    for path in python_files():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = node.end_lineno - node.lineno + 1
                if lines > MAX_FUNCTION_LINES:
                    long.append(f"{path.relative_to(REPO)}:{node.lineno} {node.name} ({lines} lines)")
    assert long == []


def test_no_module_over_500_lines():
    long = [f"{p.relative_to(REPO)} ({n} lines)" for p in python_files()
            if (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES
            and str(p.relative_to(REPO)) not in LONG_MODULES_ALLOWED]
    assert long == []


def test_the_walker_sees_an_upward_import(tmp_path):
    """The check can fail: an upward import written into a fake core module is found."""
    fake = tmp_path / "brainpainter" / "io" / "fake.py"
    fake.parent.mkdir(parents=True)
    fake.write_text("def f():\n    from brainpainter.media.figure import make_figure\n")
    global REPO
    saved, REPO = REPO, tmp_path
    try:
        found = imported_modules(fake, {"brainpainter.io.fake", "brainpainter.media.figure"})
    finally:
        REPO = saved
    assert found == {"brainpainter.media.figure"}
    assert layer("brainpainter.media.figure") > layer("brainpainter.io.fake")

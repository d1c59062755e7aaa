"""The house rules of the package, checked on its source: a thin command line, small modules and
functions, imports that only run down the stack (the import graph has no cycle), and the command
line's libraries (typer, rich) only in the modules that print."""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "excite_cli"
PRINTING = {"excite_cli.cli", "excite_cli.console.tables", "excite_cli.console.progress"}


def _modules() -> dict[str, ast.Module]:
    modules = {}
    for path in PACKAGE.rglob("*.py"):
        name = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts).removesuffix(".__init__")
        modules[name] = ast.parse(path.read_text(), filename=str(path))
    return modules


def _imports(tree: ast.Module) -> set[str]:
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            found.add(node.module)
            found.update(f"{node.module}.{a.name}" for a in node.names)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
    return found


def test_cli_is_thin():
    assert len((PACKAGE / "cli.py").read_text().splitlines()) <= 150


def test_modules_and_functions_are_small():
    long_modules = [p.name for p in PACKAGE.rglob("*.py") if len(p.read_text().splitlines()) > 300]
    long_functions = [(name, node.name, node.end_lineno - node.lineno + 1) for name, tree in _modules().items()
                      for node in ast.walk(tree) if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
                      and node.end_lineno - node.lineno + 1 > 60]
    assert long_modules == [] and long_functions == []


def test_imports_only_run_down_the_stack():
    modules = _modules()
    graph = {name: {m for m in _imports(tree) if m in modules and m != name} for name, tree in modules.items()}
    state: dict[str, int] = {}

    def visit(name: str, path: list[str]) -> None:
        state[name] = 1
        for dep in graph[name]:
            assert state.get(dep) != 1, "import cycle: " + " → ".join(path + [dep])
            if dep not in state:
                visit(dep, path + [dep])
        state[name] = 2

    for name in modules:
        if name not in state:
            visit(name, [name])
    assert graph["excite_cli.cli"]  # the check saw the imports


def test_only_the_printing_modules_use_the_command_line_libraries():
    users = {name for name, tree in _modules().items()
             if any(m.split(".")[0] in ("typer", "rich") for m in _imports(tree))}
    assert users == PRINTING

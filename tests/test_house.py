"""The house rules of the package, checked on its source: a thin command line, small modules and
functions, an import graph without a cycle whose every import runs down the floors (so identification
reaches neither the design nor the search), criteria as records, constraints told apart by their
classes, the command line's libraries (typer, rich) only in the modules that print, modules in role
folders, no command-line flag in a library message, tests that mirror the package's folders with
every module tested in its own, and lower floors handed values, not whole problems (through any path)."""

import ast
import re
from pathlib import Path

TESTS = Path(__file__).resolve().parent
PACKAGE = TESTS.parent / "excite_cli"
PRINTING = {"excite_cli.cli"} | {
    f"excite_cli.console.{m}"
    for m in (
        "app",
        "tables",
        "plans",
        "rehearsal",
        "identification",
        "effect_search",
        "noise_levels",
        "bodies",
        "model_files",
        "progress",
        "errors",
    )
}


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
    """Each command parses, calls one library function and prints: a handful of statements."""
    tree = _modules()["excite_cli.cli"]
    commands = [node for node in tree.body if isinstance(node, ast.FunctionDef)]
    sizes = {
        f.name: sum(1 for s in f.body if not (isinstance(s, ast.Expr) and isinstance(s.value, ast.Constant)))
        for f in commands
    }
    assert len(commands) >= 7 and max(sizes.values()) <= 6, sizes
    assert not [node for node in tree.body if isinstance(node, ast.ClassDef)]
    assert len((PACKAGE / "cli.py").read_text().splitlines()) <= 250


def _code_lines(node: ast.FunctionDef) -> int:
    """Lines of a function without its docstring (as ruff formats it: one argument a line when long)."""
    doc = node.body[0] if ast.get_docstring(node) is not None else None
    return node.end_lineno - node.lineno + 1 - (doc.end_lineno - doc.lineno + 1 if doc else 0)


def test_modules_and_functions_are_small():
    long_modules = [p.name for p in PACKAGE.rglob("*.py") if len(p.read_text().splitlines()) > 300]
    long_functions = [
        (name, node.name, _code_lines(node))
        for name, tree in _modules().items()
        for node in ast.walk(tree)
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and _code_lines(node) > 80
    ]
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
    users = {
        name for name, tree in _modules().items() if any(m.split(".")[0] in ("typer", "rich") for m in _imports(tree))
    }
    assert users == PRINTING


#: The floors of the package from the ground up: the modules every stage shares, then the role folders
#: (and the top-level modules between them) in the order data flows. A module imports only from its
#: own floor or the floors under it (:func:`test_every_import_runs_down_the_floors`).
FLOORS = (
    "kernels",
    "__init__",
    "errors",
    "memo",
    "memory",
    "inputs",
    "atomic",
    "h5",
    "criteria",
    "effects",
    "config",
    "trajectory",
    "dynamics",
    "collision",
    "constraints",
    "stored",
    "identification",
    "config_file",
    "design",
    "search",
    "drafting",
    "storage",
    "rehearsal",
    "plots",
    "workflows",
    "console",
    "cli",
    "__main__",
)
#: The role folders: the floors that are folders.
ROLE_FOLDERS = {name for name in FLOORS if (PACKAGE / name).is_dir()}
#: Modules outside the role folders: the entry points and what every stage shares.
TOP_LEVEL = set(FLOORS) - ROLE_FOLDERS


def _floor(module: str) -> int:
    """The floor (index in :data:`FLOORS`) of an ``excite_cli`` module: its folder's, or its own at the top level."""
    parts = module.split(".")
    return FLOORS.index(parts[1] if len(parts) > 1 else "__init__")


def test_every_import_runs_down_the_floors():
    """No module imports from a floor above its own (so identification, under the design and the
    search, reaches none of them, nor the files or the plots)."""
    modules = _modules()
    upward = sorted(
        (name, dep)
        for name, tree in modules.items()
        for dep in _imports(tree)
        if dep in modules and _floor(dep) > _floor(name)
    )
    assert upward == []
    assert _floor("excite_cli.identification.pipeline") < _floor("excite_cli.design.excitation")


def test_every_module_sits_in_a_role_folder_or_is_a_named_top_level_module():
    misplaced = [
        str(p.relative_to(PACKAGE))
        for p in PACKAGE.rglob("*.py")
        if (p.parent == PACKAGE and p.stem not in TOP_LEVEL)
        or (p.parent != PACKAGE and p.relative_to(PACKAGE).parts[0] not in ROLE_FOLDERS)
    ]
    assert misplaced == []
    assert {p.name for p in PACKAGE.iterdir() if p.is_dir() and p.name != "__pycache__"} == ROLE_FOLDERS


def _messages(tree: ast.Module) -> list[str]:
    """Every string constant and f-string text of a module, docstrings left out."""
    docstrings = {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
        and node.body
        and isinstance(node.body[0], ast.Expr)
        and isinstance(node.body[0].value, ast.Constant)
    }
    return [
        node.value
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings
    ]


def test_no_library_message_names_a_command_line_flag():
    flagged = {
        name: [s for s in _messages(tree) if re.search(r"--[a-z]", s)]
        for name, tree in _modules().items()
        if name != "excite_cli.cli" and not name.startswith("excite_cli.console")
    }
    assert {name: found for name, found in flagged.items() if found} == {}
    assert any(re.search(r"--[a-z]", s) for s in _messages(_modules()["excite_cli.cli"]))  # the check sees flags


def _tested_modules() -> dict[str, set[str]]:
    """For each package module, the test modules that import it (or a name from it)."""
    modules, tested = _modules(), {}
    for test in TESTS.rglob("test_*.py"):
        imports = _imports(ast.parse(test.read_text()))
        for name in modules:
            if name in imports:
                tested.setdefault(name, set()).add(str(test.relative_to(TESTS)))
    return tested


def test_tests_mirror_the_package_and_every_module_is_tested_in_its_own_folder():
    """tests/ has the package's folders; every module (but the entry point and the packages' own
    __init__) is imported by a test module in the folder that mirrors its own."""
    folders = {p.relative_to(PACKAGE) for p in PACKAGE.rglob("*") if p.is_dir() and p.name != "__pycache__"}
    assert folders <= {p.relative_to(TESTS) for p in TESTS.rglob("*") if p.is_dir() and p.name != "__pycache__"}
    tested = _tested_modules()
    untested = []
    for path in PACKAGE.rglob("*.py"):
        if path.name in ("__main__.py", "__init__.py") and path.parent != PACKAGE / "workflows":
            continue
        name = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts).removesuffix(".__init__")
        folder = path.parent.relative_to(PACKAGE)
        if not any(Path(t).parent == folder for t in tested.get(name, ())):
            untested.append(name)
    assert untested == []


#: The optimize problem, as a module can import it: from its package or its own module.
_OPTIMIZE_PROBLEM = {"excite_cli.config.Problem", "excite_cli.config.problem.Problem"}
#: Where the whole optimize problem may be read: the config and its loader, the commands' workflows,
#: and the one module that resolves it into the design (``excite_cli.design.spec.DesignSpec``).
_PROBLEM_READERS = ("excite_cli.config", "excite_cli.config_file", "excite_cli.workflows", "excite_cli.design.resolve")


def test_only_the_config_its_loader_the_workflows_and_the_resolver_read_the_optimize_problem():
    """No module but the config's own, its loader, the workflows and ``design/resolve.py`` imports the
    whole optimize ``Problem``: the design, its search and its storage take a ``DesignSpec`` or the
    sections they use, and a workflow is what reads a config (from a file, a result or a draft) into
    them."""
    offenders = [
        name
        for name, tree in _modules().items()
        if name not in _PROBLEM_READERS
        and not name.startswith(tuple(f"{reader}." for reader in _PROBLEM_READERS))
        and _OPTIMIZE_PROBLEM & _imports(tree)
    ]
    assert offenders == []


def test_lower_floors_take_sections_and_values_not_the_identify_problem():
    """Robots, data, constraints, trajectories, the identification's measured, fitting and choice rooms,
    the design, the search, the plots and the printed tables are handed the identify config's section
    or the value they use, never the whole ``IdentifyProblem`` (the report stores the whole config, so
    the identification's pipeline and reporting may take it)."""
    lower = (
        "dynamics",
        "collision",
        "constraints",
        "trajectory",
        "identification.measured",
        "identification.fitting",
        "identification.choice",
        "design",
        "search",
        "plots",
        "console",
    )
    offenders = [
        name
        for name, tree in _modules().items()
        if name.removeprefix("excite_cli.").startswith(lower)
        and "excite_cli.identification.config.IdentifyProblem" in _imports(tree)
    ]
    assert offenders == []


def _comparisons_with(names: set[str], outside: str) -> list[tuple[str, int]]:
    """(module, line) of every comparison with one of ``names`` (or a tuple, list or set holding one) in
    the modules outside the package ``outside``."""
    return [
        (name, node.lineno)
        for name, tree in _modules().items()
        if not name.startswith(outside)
        for node in ast.walk(tree)
        if isinstance(node, ast.Compare)
        and any(
            isinstance(c, ast.Constant)
            and c.value in names
            or isinstance(c, (ast.Tuple, ast.List, ast.Set))
            and any(isinstance(e, ast.Constant) and e.value in names for e in c.elts)
            for c in [node.left, *node.comparators]
        )
    ]


def test_a_criterion_is_one_record_and_nothing_outside_its_room_branches_on_its_name():
    """Adding a criterion is adding a record to ``excite_cli.criteria.catalogue.CRITERIA``: no module outside
    ``excite_cli/criteria`` compares anything with a criterion's name (that is what the record says),
    nor picks a record by a name written in its code."""
    from excite_cli.criteria import NAMES

    assert _comparisons_with(NAMES, outside="excite_cli.criteria") == []
    keyed = [
        (name, node.lineno)
        for name, tree in _modules().items()
        if not name.startswith("excite_cli.criteria")
        for node in ast.walk(tree)
        if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant) and node.slice.value in NAMES
    ]
    assert keyed == []


def _subclasses(cls: type) -> set[type]:
    return {c for s in cls.__subclasses__() for c in {s} | _subclasses(s)}


def test_a_constraint_s_kind_is_answered_by_its_class_not_by_its_name():
    """What a caller asks of a constraint (its rows in words, the distance it keeps, whether it bounds
    the torques) is a method or an attribute of its class: no module outside ``excite_cli/constraints``
    compares anything with a constraint's name, so adding a constraint touches its own file."""
    import excite_cli.design.excitation  # noqa: F401  (imports every constraint class)
    from excite_cli.constraints import Constraint

    names = {c.name for c in _subclasses(Constraint)}
    assert {"joint_limits", "self_collision", "world_collision", "torque_limits"} <= names
    assert _comparisons_with(names, outside="excite_cli.constraints") == []


def test_test_modules_have_unique_names():
    """pytest imports test modules by their file name (no package __init__ in tests/): two test files
    of one name in different folders fail collection."""
    names = [p.name for p in TESTS.rglob("test_*.py")]
    assert sorted(n for n in set(names) if names.count(n) > 1) == []


def test_restart_ends_and_stop_reasons_are_enum_members_not_strings():
    """A restart's end and stop reason are members of ``End`` and ``Stop``: a string of one of their
    values anywhere else in the package is a kind spelled by hand, which a typo turns into a new kind."""
    from excite_cli.search.kkt import End, Stop

    words = {m.value for m in (*Stop, *End)} - {"none", "start"}  # common words besides
    found = []
    for name, tree in _modules().items():
        definitions = {
            id(c)
            for node in ast.walk(tree)
            if isinstance(node, ast.ClassDef) and node.name in ("Stop", "End")
            for c in ast.walk(node)
        }
        found += [
            f"{name}:{node.lineno} {node.value!r}"
            for node in ast.walk(tree)
            if isinstance(node, ast.Constant) and node.value in words and id(node) not in definitions
        ]
    assert found == []


def test_the_design_wing_and_the_identification_wing_import_nothing_of_each_other():
    """What one run hands the next (a report, its model, prior data) is read in ``stored/``, under both
    wings: the design and its search import nothing of the identification (the floors already keep the
    identification from reaching them)."""
    wing = ("excite_cli.design", "excite_cli.search")
    crossing = sorted(
        (name, dep)
        for name, tree in _modules().items()
        if name.startswith(wing)
        for dep in _imports(tree)
        if dep.startswith("excite_cli.identification")
    )
    assert crossing == []
    assert _floor("excite_cli.stored.report") < _floor("excite_cli.identification.pipeline")


def test_no_module_outside_the_constraints_asks_a_constraint_its_class():
    """The plots and the drafting learn what a constraint draws, keeps apart or leaves idle from its own
    methods (``drawn``, ``capsules``, ``never_apart``, ``always_within``), not from ``isinstance`` at the
    caller: a new constraint class is then drawn and drafted without touching them."""
    import excite_cli.design.excitation  # noqa: F401  (imports every constraint class)
    from excite_cli.constraints import Constraint

    classes = {c.__name__ for c in _subclasses(Constraint)} | {"Constraint"}
    asked = []
    for name, tree in _modules().items():
        if name.startswith("excite_cli.constraints"):
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "isinstance" and len(node.args) == 2:
                named = {n.id for n in ast.walk(node.args[1]) if isinstance(n, ast.Name)}
                if named & classes:
                    asked.append(f"{name}:{node.lineno}")
    assert asked == []


def test_shape_kinds_and_solver_forms_are_enum_members_not_strings_or_classes():
    """A world shape's kind is a ``ShapeKind`` member (never compared with a string), the form the solver
    sees a criterion in is the problem's ``form`` (an ``NlpForm``, never ``isinstance`` on the problem
    classes): a new kind is then a new member that every branch must name."""
    forms = {"Evaluations", "Epigraph", "Smoothed"}
    found = []
    for name, tree in _modules().items():
        for node in ast.walk(tree):
            if isinstance(node, ast.Compare) and any(
                isinstance(side, ast.Attribute)
                and side.attr == "kind"
                and not (isinstance(side.value, ast.Attribute) and side.value.attr == "dtype")  # numpy's
                for side in [node.left, *node.comparators]
            ):
                if any(isinstance(side, ast.Constant) and isinstance(side.value, str) for side in node.comparators):
                    found.append(f"{name}:{node.lineno}")
            if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "isinstance" and len(node.args) == 2:
                if {n.id for n in ast.walk(node.args[1]) if isinstance(n, ast.Name)} & forms:
                    found.append(f"{name}:{node.lineno}")
    assert found == []

"""Make's view of the project: each stage's sources from its real imports, and the cases to build.

    python -m pipeline.deps sources --out build/.deps.mk        SRC_<stage> := every project file
                                                                the stage's command can import
    python -m pipeline.deps case CASE.toml --out MK             CASE_NAMES += <name>,
                                                                CASE_FILE_<name> := CASE.toml
    python -m pipeline.deps fingerprint CASE.toml --name NAME --out FILE
                                                                the case's content fingerprint,
                                                                rewritten only when it changes

Sources: a stage runs `python -m pipeline <command>`: pipeline/__main__.py, the CLI, then the
command module's module-level code, its `register` and the stage function (STAGES). The closure
follows every import statement (ast; lazy imports inside functions too) and every
`import_module(f"{__name__}.x")` of a registry (all modules of its package) through the project
packages; an import by a computed name the walk cannot resolve stops Make with its location; inside the command module only the functions the stage reaches are followed (so the
mesh stage does not depend on the FE solvers of `fem` in the same module), in imported modules
everything is. Package `__init__.py` files count. Make includes the result, so a stage's rule
depends on exactly the code it can run: no hand-written list to drift.

Cases: the build folder is the case's `name` (read and validated by geometry.params, the case
file's one home), whatever the file is called or wherever it lies. The fingerprint file lets Make
rebuild on a change of the case's content (geometry.fingerprint), not of its comments or mtime,
and when a case file of the same name but other content is given.
"""
from __future__ import annotations

import argparse
import ast
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("geometry", "fem", "dynamics", "pipeline")
ENTRY = ("pipeline.__main__",)   # `python -m pipeline` runs this first (it imports the CLI)
# modules whose computed imports are accounted for otherwise, with the reason
DYNAMIC_OK = {"pipeline.cli": "imports the command module of the command asked for: STAGES adds it"}

# stage -> "command module:function the CLI calls" (see each module's register())
STAGES = {
    "geometry": "pipeline.cmd_geometry:_run",
    "mesh": "pipeline.cmd_fem:run_mesh",
    "fem": "pipeline.cmd_fem:run",
    "matrix": "pipeline.cmd_dynamics:cmd_matrix",
    "hysteresis": "pipeline.cmd_dynamics:cmd_hysteresis",
    "simulate": "pipeline.cmd_dynamics:cmd_simulate",
    "fourbar": "pipeline.cmd_fourbar:run_fourbar",
    "tolerance": "pipeline.cmd_fourbar:run_tolerance",
    "signatures": "pipeline.cmd_signatures:cmd_signatures",
    "diagnosis": "pipeline.cmd_diagnose:run",
    "paper001": "pipeline.cmd_diagnose:run_paper001",
    "compensate": "pipeline.cmd_compensate:run",
    "conditions": "pipeline.cmd_conditions:run",
    "report": "pipeline.cmd_report:run",
    "sensitivity": "pipeline.cmd_sensitivity:run",
}
# characters Make cannot carry in a file name or variable name
_MAKE_UNSAFE = re.compile(r"[\s$#:%;=\\*?\[\]]")
_NAME_TOKEN = re.compile(r"^[A-Za-z0-9._-]{1,100}$")   # as geometry.params allows


class DepsError(Exception):
    """The import walk or a case cannot be turned into Make rules (named in the message)."""


# ------------------------------------------------------------------------------------ import walk
def module_file(name: str, root: Path = ROOT) -> Path | None:
    """The file of a project module (dotted name), or None for anything outside the packages."""
    if name.split(".")[0] not in PACKAGES:
        return None
    base = root.joinpath(*name.split("."))
    for p in (base.with_suffix(".py"), base / "__init__.py"):
        if p.is_file():
            return p
    return None


def _is_package(name: str, root: Path) -> bool:
    return (root.joinpath(*name.split(".")) / "__init__.py").is_file()


def _targets(node: ast.AST, module: str, is_package: bool, root: Path) -> list[str]:
    """Project modules one import statement loads (`from a import b` loads a.b when it is one)."""
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names]
    else:
        if node.level:
            base = module.split(".") if is_package else module.split(".")[:-1]
            anchor = base[:len(base) - node.level + 1]
            src = ".".join(anchor + ([node.module] if node.module else []))
        else:
            src = node.module or ""
        names = [src] + [f"{src}.{a.name}" for a in node.names if module_file(f"{src}.{a.name}", root)]
    return [n for n in names if module_file(n, root)]


def _dynamic_targets(call: ast.Call, module: str, is_package: bool, root: Path) -> set[str] | None:
    """Project modules an `import_module(...)` / `__import__(...)` call loads: a constant name, or
    f"{__name__}.{x}" (a registry importing its own package's modules: all of them count).
    None: not an import call; DepsError: one the walk cannot resolve."""
    f = call.func
    name = f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else None
    if name not in ("import_module", "__import__") or not call.args:
        return None
    arg = call.args[0]
    if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
        return {arg.value} if module_file(arg.value, root) else set()
    if (isinstance(arg, ast.JoinedStr) and len(arg.values) >= 2 and isinstance(arg.values[0], ast.FormattedValue)
            and isinstance(arg.values[0].value, ast.Name) and arg.values[0].value.id == "__name__"
            and isinstance(arg.values[1], ast.Constant) and arg.values[1].value == "."):
        pkg = module if is_package else module.rsplit(".", 1)[0]
        folder = root.joinpath(*pkg.split("."))
        return {f"{pkg}.{p.stem}" for p in folder.glob("*.py") if p.stem != "__init__"}
    if module in DYNAMIC_OK:
        return set()
    raise DepsError(f"{module} (line {call.lineno}): {name}() with a computed name: Make cannot see what it "
                    f"imports; import by name, use f\"{{__name__}}.<module>\" for a registry, or list the "
                    f"module in pipeline/deps.py DYNAMIC_OK with the reason")


def _imports_in(nodes, module: str, is_package: bool, root: Path) -> set[str]:
    out = set()
    for top in nodes:
        for node in ast.walk(top):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                out.update(_targets(node, module, is_package, root))
            elif isinstance(node, ast.Call):
                out.update(_dynamic_targets(node, module, is_package, root) or ())
    return out


def dynamic_imports(module: str, root: Path = ROOT) -> set[str]:
    """The project modules `module` loads through import_module / __import__ calls."""
    out = set()
    for node in ast.walk(_parse(module, root)):
        if isinstance(node, ast.Call):
            out.update(_dynamic_targets(node, module, _is_package(module, root), root) or ())
    return out


def _with_parents(name: str) -> list[str]:
    """A module and the packages above it (importing a.b.c runs a/__init__ and a/b/__init__)."""
    parts = name.split(".")
    return [".".join(parts[:k]) for k in range(1, len(parts) + 1)]


def _parse(name: str, root: Path) -> ast.Module:
    path = module_file(name, root)
    if path is None:
        raise DepsError(f"{name}: not a module of the project packages ({', '.join(PACKAGES)})")
    return ast.parse(path.read_text(), str(path))


def entry_imports(module: str, functions: tuple[str, ...], root: Path = ROOT) -> set[str]:
    """Project modules imported when `module` is imported and `functions` run: module-level code
    (class bodies included) plus the top-level functions reached from it, followed by name."""
    tree = _parse(module, root)
    is_pkg = _is_package(module, root)
    defs = {n.name: n for n in tree.body if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))}
    missing = [f for f in functions if f not in defs]
    if missing:
        raise DepsError(f"{module}: no function {', '.join(missing)} (update pipeline/deps.py STAGES)")
    top_level = [n for n in tree.body if not isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]
    # decorators and defaults of every def run at import time too
    for d in defs.values():
        top_level += d.decorator_list + d.args.defaults + [x for x in d.args.kw_defaults if x]
    reached, todo = set(), list(functions)
    todo += [n for t in top_level for n in _local_names(t, defs)]
    while todo:
        f = todo.pop()
        if f in reached:
            continue
        reached.add(f)
        todo += _local_names(defs[f], defs)
    return _imports_in(top_level + [defs[f] for f in reached], module, is_pkg, root)


def _local_names(node: ast.AST, defs: dict) -> list[str]:
    """Top-level functions a piece of code refers to by name, except the `func=` a sub-command
    registers (`set_defaults(func=run)`): registering a stage does not run it."""
    skip = {id(k.value) for n in ast.walk(node) if isinstance(n, ast.Call)
            for k in n.keywords if k.arg == "func"}
    out, todo = [], [node]
    while todo:
        n = todo.pop()
        if id(n) in skip:
            continue
        if isinstance(n, ast.Name) and n.id in defs:
            out.append(n.id)
        todo.extend(ast.iter_child_nodes(n))
    return out


def closure(start: set[str] | list[str], root: Path = ROOT) -> set[str]:
    """Every project module reachable from `start` through import statements anywhere in them."""
    seen: set[str] = set()
    todo = [p for s in start for p in _with_parents(s)]
    while todo:
        m = todo.pop()
        if m in seen or module_file(m, root) is None:
            continue
        seen.add(m)
        todo += [p for t in _imports_in([_parse(m, root)], m, _is_package(m, root), root)
                 for p in _with_parents(t)]
    return seen


def stage_modules(stage: str, root: Path = ROOT) -> set[str]:
    """Project modules the stage's command can import (see the module docstring)."""
    module, func = STAGES[stage].split(":")
    first = set(_with_parents(module)) | set(ENTRY)
    first |= entry_imports(module, (func, "register"), root)
    deep = closure(first - {module}, root)
    if module in deep:       # imported back through another module: then all of it counts
        return deep
    return deep | {module}


def stage_files(stage: str, root: Path = ROOT) -> list[str]:
    return sorted(str(module_file(m, root).relative_to(root)) for m in stage_modules(stage, root))


def deps_mk(root: Path = ROOT) -> str:
    lines = ["# Generated by pipeline/deps.py from each stage's imports; do not edit (make regenerates it).",
             "# $(wildcard) drops a file deleted since: Make never waits for a source that is gone."]
    for stage in STAGES:
        lines.append(f"SRC_{stage} := $(wildcard {' '.join(stage_files(stage, root))})")
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------------------------------ cases
def _load(case_file: str):
    from geometry.params import load_case
    if _MAKE_UNSAFE.search(case_file):
        raise DepsError(f"CASE={case_file!r}: Make cannot handle this path (spaces or any of $#:%;=\\*?[]); "
                        f"copy or link the case file to a plain path")
    case = load_case(case_file)
    if not _NAME_TOKEN.match(case.name) or case.name in (".", ".."):
        raise DepsError(f"{case_file}: name = {case.name!r} cannot name a build folder; allowed: letters, "
                        f"digits and . _ - (not '.' or '..')")
    return case


def case_mk(case_file: str) -> str:
    """Make lines that add the case's name to CASE_NAMES and map the name to its file."""
    case = _load(case_file)
    n = case.name
    return (f"# Generated by pipeline/deps.py from {case_file}; do not edit.\n"
            f"ifneq ($(CASE_FILE_{n}),)\n"
            f"ifneq ($(abspath $(CASE_FILE_{n})),$(abspath {case_file}))\n"
            f"$(error two case files are named '{n}': $(CASE_FILE_{n}) and {case_file}; the build folder "
            f"is the case's name, so the names must differ)\n"
            f"endif\n"
            f"endif\n"
            f"CASE_NAMES += $(if $(filter {n},$(CASE_NAMES)),,{n})\n"
            f"CASE_FILE_{n} := {case_file}\n")


def write_if_changed(path: Path, text: str) -> bool:
    """Write `text` unless the file holds it already (its mtime then stays: nothing to rebuild)."""
    from geometry.artifacts import write_text_atomic
    if path.is_file() and path.read_text() == text:
        return False
    write_text_atomic(path, text)
    return True


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m pipeline.deps", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="what", required=True)
    s = sub.add_parser("sources", help="SRC_<stage> lists from the imports")
    s.add_argument("--out", required=True)
    c = sub.add_parser("case", help="Make lines naming a case file's build folder")
    c.add_argument("case_file")
    c.add_argument("--out", required=True)
    f = sub.add_parser("fingerprint", help="the case's content fingerprint (file rewritten on change)")
    f.add_argument("case_file")
    f.add_argument("--name", required=True, help="the build folder the caller expects")
    f.add_argument("--out", required=True)
    args = p.parse_args(argv)
    from geometry.artifacts import InputError, write_text_atomic
    try:
        if args.what == "sources":      # always rewritten: Make remade it because a source changed
            write_text_atomic(Path(args.out), deps_mk())
        elif args.what == "case":
            write_text_atomic(Path(args.out), case_mk(args.case_file))
        else:
            from geometry.fingerprint import case_fingerprint
            case = _load(args.case_file)
            if case.name != args.name:
                raise DepsError(f"{args.case_file}: name = {case.name!r}, but Make expected {args.name!r} "
                                f"(the name changed while make ran): run make again")
            write_if_changed(Path(args.out), case_fingerprint(case) + "\n")
    except (DepsError, InputError, SyntaxError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""DESIGN.md's import rules, checked on the source (ast: every import, lazy ones inside functions too).

- no package but `pipeline/` imports `pipeline`;
- `geometry/` imports no solver package (fem, dynamics, pipeline, numba, scikit-fem);
- `fem/` never imports `dynamics/`;
- `dynamics/` takes from `fem/` only the stiffness schema module `fem/stiffness.py`;
- no import cycle between modules;
- no module over 600 lines.
Failures name the module, the line and the offending import. The checker is exercised on synthetic
sources and graphs first, so a rule that silently checks nothing fails too.
"""
from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("geometry", "fem", "dynamics", "pipeline")
MAX_LINES = 600
# third-party solver packages geometry must not use (numba kernels and scikit-fem belong downstream)
GEOMETRY_FORBIDDEN = ("fem", "dynamics", "pipeline", "numba", "skfem")


@dataclass(frozen=True)
class Import:
    module: str      # importing module, dotted
    target: str      # imported module, dotted (the most specific project module when it is one)
    line: int

    def __str__(self) -> str:
        return f"{self.module} (line {self.line}) imports {self.target}"


def module_name(path: Path, root: Path = ROOT) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def project_modules(root: Path = ROOT) -> dict[str, Path]:
    """Dotted name -> file for every module of the four packages (subpackages included)."""
    return {module_name(p, root): p for pkg in PACKAGES for p in sorted((root / pkg).rglob("*.py"))}


def imports_of(source: str, module: str, is_package: bool, known: set[str]) -> list[Import]:
    """Every import statement anywhere in the source (ast.walk reaches function bodies).
    `from a import b` targets a.b when that is a module of `known`, else a."""
    out = []
    base = module.split(".") if is_package else module.split(".")[:-1]
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out += [Import(module, a.name, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:                                   # relative: resolve against the package
                anchor = base[:len(base) - node.level + 1]
                src = ".".join(anchor + ([node.module] if node.module else []))
            else:
                src = node.module or ""
            for a in node.names:
                sub = f"{src}.{a.name}"
                out.append(Import(module, sub if sub in known else src, node.lineno))
    return out


def all_imports(root: Path = ROOT) -> list[Import]:
    mods = project_modules(root)
    known = set(mods)
    return [imp for name, path in mods.items()
            for imp in imports_of(path.read_text(), name, path.name == "__init__.py", known)]


def top(name: str) -> str:
    return name.split(".")[0]


def rule_violations(imports: list[Import]) -> dict[str, list[str]]:
    """Per rule, the offending imports (as text naming module, line and import)."""
    out: dict[str, list[str]] = {"pipeline": [], "geometry": [], "fem": [], "dynamics": []}
    for imp in imports:
        src, dst = top(imp.module), imp.target
        if src != "pipeline" and top(dst) == "pipeline":
            out["pipeline"].append(str(imp))
        if src == "geometry" and top(dst) in GEOMETRY_FORBIDDEN:
            out["geometry"].append(str(imp))
        if src == "fem" and top(dst) == "dynamics":
            out["fem"].append(str(imp))
        if src == "dynamics" and top(dst) == "fem" and dst != "fem.stiffness":
            out["dynamics"].append(str(imp))
    return out


def import_graph(imports: list[Import], known: set[str]) -> dict[str, dict[str, int]]:
    """module -> {imported project module: first line}; only edges between project modules."""
    g: dict[str, dict[str, int]] = {m: {} for m in known}
    for imp in imports:
        if imp.target in known and imp.target != imp.module:
            g[imp.module].setdefault(imp.target, imp.line)
    return g


def cycles(graph: dict[str, dict[str, int]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan, iterative), sorted."""
    index, low, on, stack, out = {}, {}, set(), [], []
    counter = 0
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on.add(start)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph.get(w, {})))))
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    if len(comp) > 1:
                        out.append(sorted(comp))
    return sorted(out)


def describe_cycle(comp: list[str], graph: dict[str, dict[str, int]]) -> str:
    edges = [f"{a} (line {graph[a][b]}) -> {b}" for a in comp for b in sorted(graph[a]) if b in comp]
    return "cycle among " + ", ".join(comp) + ": " + "; ".join(edges)


# ----------------------------------------------------------------------------- the checker itself
def test_the_checker_sees_lazy_and_relative_imports():
    src = ("import numpy as np\n"
           "from geometry import params\n"
           "def f():\n"
           "    from pipeline.records import load\n"
           "    from . import kernels\n"
           "    return load\n")
    known = {"geometry.params", "pipeline.records", "dynamics.kernels", "dynamics.x"}
    got = {(i.target, i.line) for i in imports_of(src, "dynamics.x", False, known)}
    assert got == {("numpy", 1), ("geometry.params", 2), ("pipeline.records", 4), ("dynamics.kernels", 5)}


def test_the_rules_flag_synthetic_offenders():
    bad = [Import("dynamics.x", "fem.hertz", 3), Import("dynamics.y", "fem.stiffness", 1),
           Import("geometry.a", "numba", 7), Import("geometry.b", "skfem.helpers", 2),
           Import("fem.z", "dynamics.model", 9), Import("fem.w", "pipeline.records", 4),
           Import("pipeline.cli", "pipeline.records", 1)]
    v = rule_violations(bad)
    assert v["dynamics"] == ["dynamics.x (line 3) imports fem.hertz"]
    assert v["geometry"] == ["geometry.a (line 7) imports numba", "geometry.b (line 2) imports skfem.helpers"]
    assert v["fem"] == ["fem.z (line 9) imports dynamics.model"]
    assert v["pipeline"] == ["fem.w (line 4) imports pipeline.records"]


def test_a_synthetic_cycle_is_found_and_named():
    # a -> b -> c -> a is one cycle (through a lazy import or not: edges are edges); d -> a is not
    g = {"a": {"b": 1}, "b": {"c": 5}, "c": {"a": 12}, "d": {"a": 2}, "e": {}}
    assert cycles(g) == [["a", "b", "c"]]
    assert describe_cycle(["a", "b", "c"], g) == \
        "cycle among a, b, c: a (line 1) -> b; b (line 5) -> c; c (line 12) -> a"
    assert cycles({"a": {"b": 1}, "b": {}}) == []
    assert cycles({"a": {"b": 1}, "b": {"a": 1}, "c": {"d": 1}, "d": {"c": 1}}) == [["a", "b"], ["c", "d"]]


def test_the_project_scan_finds_the_known_edges():
    # guards against a scan that silently reads nothing: the modules exist and a known edge is there
    imps = all_imports()
    mods = project_modules()
    assert {"geometry.params", "fem.pin_contact", "dynamics.model", "pipeline.cli"} <= set(mods)
    assert any(i.module == "geometry.clearance" and i.target == "geometry.params" for i in imps)


# ----------------------------------------------------------------------------- the project
IMPORTS = all_imports()


@pytest.mark.parametrize("rule, text", [
    ("pipeline", "no package but pipeline/ imports pipeline"),
    ("geometry", f"geometry/ imports no solver package ({', '.join(GEOMETRY_FORBIDDEN)})"),
    ("fem", "fem/ never imports dynamics/"),
    ("dynamics", "dynamics/ takes from fem/ only fem/stiffness.py"),
])
def test_import_rule(rule, text):
    bad = rule_violations(IMPORTS)[rule]
    assert not bad, f"{text}: " + "; ".join(bad)


def test_no_import_cycle_between_modules():
    g = import_graph(IMPORTS, set(project_modules()))
    found = cycles(g)
    assert not found, "\n".join(describe_cycle(c, g) for c in found)


def test_no_module_over_600_lines():
    long = {name: n for name, path in project_modules().items()
            if (n := len(path.read_text().splitlines())) > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines: {long}"

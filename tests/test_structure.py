"""Structure of the shipid package, read from the source with :mod:`ast` (nothing is imported).

Checked (issue 14, targets "no import cycle; no shipid import inside a function outside cli/; no module
importing another module's private name; no source file over 600 lines"; DESIGN "shared layers never
import a method"):

(a) no cycle among module-level imports of shipid modules;
(b) no ``import shipid...`` / ``from shipid... import`` (absolute or relative) inside a function, and no
    ``importlib.import_module("shipid...")`` of a literal name there either, except in ``shipid/cli/``, in a
    method's ``cli*.py`` modules and ``shipid/api.py`` (the command line and the Python API load a method
    where it is called, for start-up) and in a package's module-level ``__getattr__``
    (PEP 562 lazy attributes, as ``shipid.__getattr__``); the plug-in look-ups of ``shipid/registry.py``
    and ``shipid/demo/__init__.py`` (``importlib`` on names found at run time) are allowed;
(c) no ``from shipid.x import _name`` of a module-private name defined in another module;
(d) every source file has at most 600 lines;
(e) the shared layers (data, estimate, models, simulate, studies, report, analysis, result, outputs,
    progress, registry) never import ``shipid.methods`` statically (at module level or in a function);
(f) no docstring and no click help text (``help=``, ``short_help=``, ``epilog=``) names a work session, an
    issue number, a tuning seed or a date (:data:`HISTORY`): they say what the code does; history and
    measurements live in ``docs/validation/`` and the commit messages (a command such as ``--seed 9501`` and
    an ISO timestamp example are allowed);
(g) the package-level import graph points one way, down the layers of :data:`LAYERS` (``io``, ``numerics``
    <- ``models`` <- ``simulate``, ``estimate`` <- ``methods`` <- ``api``, ``report`` <- ``demo`` <- ``cli``;
    ``numerics`` holds what simulators and estimators share: the one RK4, linear algebra, compiled helpers):
    a module imports (at module level or in a function) only packages of a lower layer or its own; so the
    package graph has no cycle.
    A method's ``cli*.py`` modules are command modules and count as the ``cli`` layer, its ``report.py`` (the
    sections it registers) as the ``report`` layer; ``shipid.report.convention`` (the plain data structures a
    result's series are described in) sits below the methods that build them;
(h) every module is reached from a user path: the root package and its lazy names, ``shipid.api``, the command
    line (``shipid.cli`` and every command module), the registry's plug-in modules of each method package
    (``validate``, ``report``, ``demo``, ``cli*``), the demo, following static imports and the module names a
    string spells (campaign tasks ``"shipid.x.y:run_one"``, ``importlib`` look-ups).

``PENDING`` below can name module prefixes that a check skips while a restructuring is under way (an
entry silences only the named check); :data:`PENDING_LAYER_EDGES` and :data:`PENDING_UNREACHED` do the same
for (g) and (h). The lead empties them as the branches that fix those modules are merged.
``python tests/test_structure.py`` prints every violation, ignoring ``PENDING``.
"""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
PKG = SRC / "shipid"
MAX_LINES = 600

# check -> module-name prefixes still being fixed in other branches (see the module docstring).
# The lead empties these after merging; a prefix ends with "." to mean a whole package.
PENDING: dict[str, tuple[str, ...]] = {
    "cycles": (),
    "function_imports": (),
    "private_imports": (),
    "file_length": (),
    "shared_imports_methods": (),
    "history_in_docstrings": (),
}

#: Layer of each top-level package of shipid (lower imports nothing higher; equal layers do not import each
#: other). The root package ``shipid`` (lazy names only) is importable from anywhere.
LAYERS = {
    "errors": 0,
    "outputs": 1, "progress": 1, "registry": 1, "vessels": 1, "warning_lines": 1,
    "io": 2, "result": 2, "summary": 1.5, "report.convention": 2, "numerics": 2,
    "models": 3,
    "simulate": 4, "estimate": 4,
    "analysis": 5, "campaign": 5,
    "methods": 6,
    "api": 7, "report": 7, "export": 7,
    "demo": 7.5,
    "cli": 8,
    "__main__": 9,
}

#: Package edges ``"a -> b"`` that break :data:`LAYERS` today and are being removed on other branches.
PENDING_LAYER_EDGES: tuple[str, ...] = ()

#: Modules no user path reaches today, being removed or wired in on other branches (the lead empties this).
PENDING_UNREACHED: tuple[str, ...] = ()

#: Submodules of a method package that the registry, the report and the demo find by name.
PLUGIN_SUBMODULES = ("validate", "report", "demo")
_MODULE_STRING = re.compile(r"^(shipid(?:\.\w+)+)(?::\w+)?$")

#: What a docstring or help text must not say: a session, an issue number, a tuning seed, a date.
HISTORY = re.compile(r"\bsessions? \d|\bissues? \d|\bissue-\d|#\d\d|(?<!-)\bseeds? \d{3}|\bseed-\d{3}"
                     r"|\b20\d\d-\d\d-\d\d(?!T)", re.I)

#: Modules whose ``importlib`` calls are plug-in discovery (the method registry, the demo's steps).
PLUGIN_LOOKUPS = ("shipid.registry", "shipid.demo")

SHARED = ("io", "numerics", "estimate", "models", "simulate", "campaign", "report", "analysis", "result", "outputs",
          "progress", "registry")


def _pending(check: str, module: str) -> bool:
    return any(module == p or module.startswith(p) for p in PENDING.get(check, ()))


def _modules() -> dict[str, Path]:
    """Dotted module name -> file, for every ``.py`` file under ``src/shipid``."""
    out = {}
    for path in sorted(PKG.rglob("*.py")):
        parts = list(path.relative_to(SRC).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


MODULES = _modules()
TREES = {name: ast.parse(path.read_text(encoding="utf-8"), str(path)) for name, path in MODULES.items()}


def _is_package(module: str) -> bool:
    return MODULES[module].name == "__init__.py"


def _base(module: str, node: ast.ImportFrom) -> str:
    """Absolute module named by ``from X import ...`` (relative imports resolved against ``module``)."""
    if not node.level:
        return node.module or ""
    package = module if _is_package(module) else module.rpartition(".")[0]
    for _ in range(node.level - 1):
        package = package.rpartition(".")[0]
    return f"{package}.{node.module}" if node.module else package


def _targets(module: str, node: ast.AST) -> list[tuple[str, str | None]]:
    """(shipid module imported, name taken from it or None) for one import statement."""
    out: list[tuple[str, str | None]] = []
    if isinstance(node, ast.Import):
        for alias in node.names:
            if alias.name == "shipid" or alias.name.startswith("shipid."):
                out.append((alias.name, None))
    elif isinstance(node, ast.ImportFrom):
        base = _base(module, node)
        if base == "shipid" or base.startswith("shipid."):
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                # `from a.b import c` where a.b.c is a module is an edge to a.b.c
                out.append((sub, None) if sub in MODULES else (base, alias.name))
    return out


def _in_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _module_level_imports(module: str) -> list[tuple[ast.AST, str, str | None]]:
    """Imports executed when the module is imported (not in functions, not under TYPE_CHECKING)."""
    out = []

    def visit(body):
        for node in body:
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                out.extend((node, t, n) for t, n in _targets(module, node))
            elif isinstance(node, ast.If):
                if not _in_type_checking(node):
                    visit(node.body)
                visit(node.orelse)
            elif isinstance(node, (ast.Try,)):
                visit(node.body)
                for h in node.handlers:
                    visit(h.body)
                visit(node.orelse)
                visit(node.finalbody)
            elif isinstance(node, (ast.With, ast.ClassDef)):
                visit(node.body)

    visit(TREES[module].body)
    return out


def _functions(module: str):
    """Every function of ``module`` except a package's module-level ``__getattr__`` (PEP 562)."""
    tree = TREES[module]
    lazy = {id(n) for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == "__getattr__"} \
        if _is_package(module) else set()
    for fn in ast.walk(tree):
        if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)) and id(fn) not in lazy:
            yield fn


def _function_imports(module: str) -> list[tuple[ast.AST, str, str | None]]:
    """shipid imports inside functions: import statements, and ``import_module("shipid...")`` literals."""
    out, seen = [], set()
    for fn in _functions(module):
        for node in ast.walk(fn):
            if id(node) in seen:
                continue
            seen.add(id(node))
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                out.extend((node, t, n) for t, n in _targets(module, node))
            elif (isinstance(node, ast.Call) and module not in PLUGIN_LOOKUPS and node.args
                  and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str)
                  and (node.args[0].value == "shipid" or node.args[0].value.startswith("shipid."))
                  and ast.unparse(node.func).endswith("import_module")):
                out.append((node, node.args[0].value, None))
    return out


def _resolve(target: str) -> str | None:
    """The shipid module a dotted import target lands in (the longest existing prefix)."""
    while target and target not in MODULES:
        target = target.rpartition(".")[0]
    return target or None


def _graph() -> dict[str, set[str]]:
    graph: dict[str, set[str]] = {m: set() for m in MODULES}
    for module in MODULES:
        for _node, target, _name in _module_level_imports(module):
            dest = _resolve(target)
            if dest is None or dest == module:
                continue
            # a package's __init__ importing its own submodules is not a cycle by itself
            if _is_package(module) and dest.startswith(module + "."):
                continue
            graph[module].add(dest)
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    comps: list[list[str]] = []
    counter = [0]

    def strong(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                comps.append(sorted(comp))


    old = sys.getrecursionlimit()
    sys.setrecursionlimit(max(old, 10 * len(graph)))
    try:
        for v in sorted(graph):
            if v not in index:
                strong(v)
    finally:
        sys.setrecursionlimit(old)
    return comps


def _defined_private(module: str, name: str) -> bool:
    """True when ``name`` is private (leading underscore, not dunder) and ``module`` is a real module."""
    return name.startswith("_") and not name.startswith("__") and module in MODULES


def _lazy_allowed(module: str) -> bool:
    return module in ("shipid.cli", "shipid.api") or module.startswith("shipid.cli.") or \
        module.rpartition(".")[2].startswith("cli")


def test_no_import_cycles():
    comps = [c for c in _cycles(_graph()) if not all(_pending("cycles", m) for m in c)]
    assert not comps, "import cycles:\n" + "\n".join(" <-> ".join(c) for c in comps)


def test_no_shipid_import_inside_functions():
    bad = []
    for module in MODULES:
        if _lazy_allowed(module) or _pending("function_imports", module):
            continue
        for node, target, _name in _function_imports(module):
            bad.append(f"{MODULES[module].relative_to(SRC)}:{node.lineno} imports {target}")
    assert not bad, "shipid imports inside functions:\n" + "\n".join(sorted(set(bad)))


def test_no_private_name_imports():
    bad = []
    for module in MODULES:
        if _pending("private_imports", module):
            continue
        for node, target, name in _module_level_imports(module) + _function_imports(module):
            if name is not None and _defined_private(target, name) and target != module:
                bad.append(f"{MODULES[module].relative_to(SRC)}:{node.lineno} imports {target}.{name}")
    assert not bad, "private names imported across modules:\n" + "\n".join(sorted(set(bad)))


def test_files_at_most_600_lines():
    bad = []
    for module, path in MODULES.items():
        if _pending("file_length", module):
            continue
        n = len(path.read_text(encoding="utf-8").splitlines())
        if n > MAX_LINES:
            bad.append(f"{path.relative_to(SRC)}: {n} lines")
    assert not bad, f"files over {MAX_LINES} lines:\n" + "\n".join(bad)


def test_shared_layers_never_import_methods():
    bad = []
    for module in MODULES:
        parts = module.split(".")
        if len(parts) < 2 or parts[1] not in SHARED or _pending("shared_imports_methods", module):
            continue
        for node, target, _name in _module_level_imports(module) + _function_imports(module):
            if target == "shipid.methods" or target.startswith("shipid.methods."):
                bad.append(f"{MODULES[module].relative_to(SRC)}:{node.lineno} imports {target}")
    assert not bad, "shared layers importing a method:\n" + "\n".join(sorted(set(bad)))


def _layer_package(module: str) -> str:
    """The package whose layer ``module`` belongs to (a method's ``cli*`` modules: ``cli``)."""
    parts = module.split(".")
    if parts[1:2] == ["methods"] and parts[-1].startswith("cli"):
        return "cli"
    if parts[1:2] == ["methods"] and len(parts) == 4 and parts[-1] == "report":
        return "report"
    if module == "shipid.report.convention":
        return "report.convention"
    return parts[1] if len(parts) > 1 else "shipid"


def _layer_violations() -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for module in MODULES:
        a = _layer_package(module)
        for node, target, _name in _module_level_imports(module) + _function_imports(module):
            b = _layer_package(target)
            if b == "shipid" or a == b:
                continue
            if LAYERS[a] <= LAYERS[b]:
                out.setdefault(f"{a} -> {b}", []).append(f"{MODULES[module].relative_to(SRC)}:{node.lineno}")
    return out


def test_every_package_has_a_layer():
    missing = sorted({_layer_package(m) for m in MODULES} - set(LAYERS) - {"shipid"})
    assert not missing, f"packages without a layer in LAYERS: {missing}"


def test_package_imports_point_down_the_layers():
    bad = {edge: where for edge, where in _layer_violations().items() if edge not in PENDING_LAYER_EDGES}
    assert not bad, "imports against the layers (LAYERS):\n" + "\n".join(
        f"{edge}: {', '.join(sorted(set(w))[:6])}" for edge, w in sorted(bad.items()))


def _known_module(name: str) -> str | None:
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name or None


def _reached_from(module: str) -> set[str]:
    out = {_known_module(t) for _n, t, _m in _module_level_imports(module) + _function_imports(module)}
    for node in ast.walk(TREES[module]):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            m = _MODULE_STRING.match(node.value)
            if m:
                out.add(_known_module(m.group(1)))
    parts = module.split(".")
    out.update(".".join(parts[:i]) for i in range(1, len(parts)))
    return {m for m in out if m in MODULES}


def _user_roots() -> set[str]:
    roots = {"shipid", "shipid.__main__", "shipid.api", "shipid.registry", "shipid.demo", "shipid.demo.report_step"}
    for module in MODULES:
        parts = module.split(".")
        if parts[1:2] == ["cli"]:
            roots.add(module)
        if parts[1:2] == ["methods"] and (len(parts) == 3 or (len(parts) == 4 and (
                parts[3] in PLUGIN_SUBMODULES or parts[3].startswith("cli")))):
            roots.add(module)
    return roots


def unreached() -> list[str]:
    """Modules that no user path reaches (module docstring, (h))."""
    seen: set[str] = set()
    todo = list(_user_roots())
    while todo:
        m = todo.pop()
        if m not in seen and m in MODULES:
            seen.add(m)
            todo.extend(_reached_from(m) - seen)
    return sorted(set(MODULES) - seen)


def test_every_module_is_reached_from_a_user_path():
    bad = [m for m in unreached() if m not in PENDING_UNREACHED]
    assert not bad, "modules no user path reaches (delete them, or move them to a top-level studies/ script):\n" + \
        "\n".join(bad)


def _texts(module: str):
    """(line, text) of every docstring and click help text of ``module``."""
    for node in ast.walk(TREES[module]):
        if isinstance(node, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            doc = ast.get_docstring(node, clean=False)
            if doc:
                yield getattr(node, "lineno", 1), doc
        if isinstance(node, ast.Call):
            for kw in node.keywords:
                if kw.arg in ("help", "short_help", "epilog"):
                    for c in ast.walk(kw.value):
                        if isinstance(c, ast.Constant) and isinstance(c.value, str):
                            yield c.lineno, c.value


def _history(module: str) -> list[str]:
    return [f"{MODULES[module].relative_to(SRC)}:{line}: {m.group(0)!r}"
            for line, text in _texts(module) for m in HISTORY.finditer(text)]


def test_no_history_in_docstrings_or_help():
    bad = [h for module in MODULES if not _pending("history_in_docstrings", module) for h in _history(module)]
    assert not bad, "docstrings / help texts naming a session, issue, tuning seed or date:\n" + "\n".join(bad)


# --- the checker checks itself on small made-up packages -------------------------------------------------

def test_checker_resolves_relative_and_submodule_imports():
    node = ast.parse("from .files import read_trial").body[0]
    assert _base("shipid.io.nmea", node) == "shipid.io.files"
    node = ast.parse("from ..errors import InputError").body[0]
    assert _base("shipid.io.nmea", node) == "shipid.errors"
    node = ast.parse("from . import files").body[0]
    assert _targets("shipid.io", node) == [("shipid.io.files", None)]
    node = ast.parse("from shipid.io import Trial").body[0]
    assert _targets("shipid.io.files", node) == [("shipid.io", "Trial")]


def test_checker_sees_lazy_imports_and_spares_pep562():
    tree = ast.parse("import importlib\ndef f():\n    from shipid.io import files\n"
                     "    return importlib.import_module('shipid.report.html')\n"
                     "def __getattr__(name):\n    from shipid.report import html\n")
    MODULES["shipid._probe"] = PKG / "_probe" / "__init__.py"
    TREES["shipid._probe"] = tree
    try:
        found = sorted(t for _n, t, _m in _function_imports("shipid._probe"))
    finally:
        del MODULES["shipid._probe"], TREES["shipid._probe"]
    assert found == ["shipid.io.files", "shipid.report.html"]


def test_checker_finds_history():
    found = [m.group(0) for t in ("in session 3 of issue 6", "tuning seed 950", "on 2026-12-04", "see #12",
                                  "``--seed 9501``", "2026-11-22T02:30:00Z", "Linder et al. 2015")
             for m in HISTORY.finditer(t)]
    assert found == ["session 3", "issue 6", "seed 950", "2026-12-04", "#12"]


def test_checker_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


if __name__ == "__main__":  # pragma: no cover - a quick report of every violation, allowlist ignored
    PENDING.clear()
    PENDING_LAYER_EDGES, PENDING_UNREACHED = (), ()
    for fn in (test_no_import_cycles, test_no_shipid_import_inside_functions, test_no_private_name_imports,
               test_files_at_most_600_lines, test_shared_layers_never_import_methods,
               test_no_history_in_docstrings_or_help, test_package_imports_point_down_the_layers,
               test_every_module_is_reached_from_a_user_path):
        try:
            fn()
        except AssertionError as exc:
            print(exc, "\n")

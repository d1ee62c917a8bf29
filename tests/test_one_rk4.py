"""One RK4 in the package, read from the source with :mod:`ast` (nothing is imported).

Issue 14: "one dynamics signature ``f(t, x, u, θ)`` and one RK4 for simulators and filters; each model's
equations written once, with the compiled kernel tested against that one source". The RK4 is
:func:`shipid.numerics.integrate.rk4_propagate` (with :func:`~shipid.numerics.integrate.rk4_step` and
:func:`~shipid.numerics.integrate.rk4_step_jacobians` built on it).

An RK4 is recognised by its weighted sum of the four stages, ``k1 + 2 k2 + 2 k3 + k4`` (or
``k1 + 2 (k2 + k3) + k4``), whatever the names. Outside ``shipid.numerics.integrate`` only the
compiled (numba) twins of :data:`COMPILED` may contain one, each with the test file that checks it
against the one RK4 on the same model; a listed twin must exist, be decorated with numba's ``njit``
and be named in its test file, so the list cannot go stale.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "src" / "shipid"
HOME = "shipid.numerics.integrate"

#: compiled twin (module.function) -> the test that checks it against the one RK4 (rtol ~1e-12)
COMPILED = {
    "shipid.methods.ebm.kernels.rk4_into": "tests/methods/ebm/test_kernels.py",
    "shipid.methods.dp.loglik._mom_rk4": "tests/methods/dp/test_rk4_kernels.py",
    "shipid.methods.dp.loglik._surge_rk4": "tests/methods/dp/test_rk4_kernels.py",
    "shipid.methods.dp.aekf_kernels.rk4_aug": "tests/methods/dp/test_aekf_kernels.py",
    "shipid.methods.mmg.kernels._kin_rk4": "tests/methods/mmg/test_kernels.py",
    "shipid.models.mmg_kernels.rows_rk4_kernel": "tests/models/test_mmg_kernels.py",
}


def _terms(node: ast.AST) -> list[ast.AST]:
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add):
        return _terms(node.left) + _terms(node.right)
    return [node]


def _doubled(node: ast.AST) -> ast.AST | None:
    """``X`` when ``node`` is ``2 * X`` or ``X * 2`` (2 or 2.0), else None."""
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult):
        for a, b in ((node.left, node.right), (node.right, node.left)):
            if isinstance(a, ast.Constant) and not isinstance(a.value, bool) and a.value == 2:
                return b
    return None


def _is_rk4_sum(node: ast.AST) -> bool:
    t = _terms(node)
    if len(t) == 4:
        return _doubled(t[1]) is not None and _doubled(t[2]) is not None and \
            _doubled(t[0]) is None and _doubled(t[3]) is None
    if len(t) == 3:
        mid = _doubled(t[1])
        return mid is not None and len(_terms(mid)) == 2 and _doubled(t[0]) is None and _doubled(t[2]) is None
    return False


def rk4_definers(tree: ast.AST) -> dict[str, ast.FunctionDef]:
    """Innermost functions (dotted name within the module) holding an RK4 stage sum."""
    out: dict[str, ast.FunctionDef] = {}

    def visit(node, path, fn):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                name = path + [child.name]
                visit(child, name, child if not isinstance(child, ast.ClassDef) else fn)
                continue
            if isinstance(child, ast.BinOp) and fn is not None and _is_rk4_sum(child):
                out[".".join(path)] = fn
            visit(child, path, fn)

    visit(tree, [], None)
    return out


def _modules():
    for path in sorted(PKG.rglob("*.py")):
        parts = list(path.relative_to(PKG.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        yield ".".join(parts), ast.parse(path.read_text(encoding="utf-8"), str(path))


def _is_njit(fn: ast.FunctionDef) -> bool:
    for d in fn.decorator_list:
        target = d.func if isinstance(d, ast.Call) else d
        if ast.unparse(target).rpartition(".")[2] == "njit":
            return True
    return False


def test_one_rk4_in_the_package():
    found = {}
    for module, tree in _modules():
        for name, fn in rk4_definers(tree).items():
            found[f"{module}.{name}"] = fn
    stray = sorted(q for q in found if not q.startswith(HOME + ".") and q not in COMPILED)
    assert not stray, ("RK4 outside shipid.numerics.integrate (use rk4_propagate / rk4_step / "
                       "rk4_step_jacobians, or list a compiled twin with its equality test):\n" + "\n".join(stray))
    assert f"{HOME}.rk4_propagate" in found
    for q, test in COMPILED.items():
        assert q in found, f"{q} is listed in COMPILED but holds no RK4 (remove it from the list)"
        assert _is_njit(found[q]), f"{q} is listed as a compiled twin but is not numba-compiled"
        text = (ROOT / test).read_text(encoding="utf-8")
        short = q.rpartition(".")[2]
        assert short in text and "rk4_" in text, f"{test} does not test {short} against the one RK4"


def test_detector_on_made_up_code():
    src = ("def a(h, k1, k2, k3, k4):\n    return (h / 6.0) * (k1 + 2 * k2 + 2.0 * k3 + k4)\n"
           "def b(x, h, k):\n    def inner():\n        return x + h * (k[0] + 2 * (k[1] + k[2]) + k[3])\n    return inner\n"
           "def c(a, b):\n    return a + 2 * b + 2 * a + 2 * b\n"
           "def d(a, b):\n    return a + 2 * b\n")
    assert sorted(rk4_definers(ast.parse(src))) == ["a", "b.inner"]


if __name__ == "__main__":  # pragma: no cover
    test_one_rk4_in_the_package()
    test_detector_on_made_up_code()

"""The package's modules import each other without a cycle (every import counted, at module level
or inside a function, except those under ``if TYPE_CHECKING:``), so that the layers read top down;
and its subpackages are layers: a module imports only its own subpackage and the layers below
(docs/architecture.md)."""

from __future__ import annotations

import ast
from pathlib import Path

import spotkin

PACKAGE = Path(spotkin.__file__).parent

# The layers, bottom up: the part of the package a module is in (``spotkin.model.chain``: ``model``)
# and its layer. A module may import its own part and the parts of lower layers, never a part beside
# it in its layer nor a higher one. FACE is the package itself and the public modules directly in it,
# which only re-export: nothing below imports them.
FACE = "<face>"
LAYERS = (
    ("_core", "reference", "robots"),  # the compiled core, the plain-Python references, package data
    ("_support",),  # argument checks, statuses, transforms, threads and ISA, the version
    ("dynamics", "urdf"),  # mass properties and rigid-body dynamics; reading descriptions
    ("model",),  # legs, arms, chains, robots, Spot
    ("kinematics", "scale", "sdk"),  # tools over the models; Dask and spotkin batch; the Spot SDK
    ("motion",),  # gaits, their plans and controllers, over the models and the kinematics
    (FACE,),  # spotkin, spotkin.dask, .differential, .inertia, .models, .paul, .trajectory
    ("plot", "sim"),  # the pictures and the simulator (optional extras), over the public API
    ("cli",),  # the command line
    ("__main__",),
)
FACE_MODULES = ("dask", "differential", "inertia", "models", "paul", "trajectory")


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path | None]:
    """The package's Python modules, and its compiled ones (no imports to read: None)."""
    modules: dict[str, Path | None] = {_module_name(p): p for p in PACKAGE.rglob("*.py")}
    for stub in PACKAGE.rglob("*.pyi"):  # _core: the extension module its stub describes
        modules.setdefault(_module_name(stub), None)
    return modules


def _type_checking_lines(tree: ast.AST) -> set[int]:
    lines = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for child in node.body:
                lines.update(range(child.lineno, (child.end_lineno or child.lineno) + 1))
    return lines


def import_graph() -> dict[str, set[str]]:
    """module -> the package's modules it imports (a name imported from a package resolves to the
    submodule of that name when there is one, else to the package itself)."""
    modules = _modules()
    graph: dict[str, set[str]] = {name: set() for name in modules}
    for name, path in modules.items():
        if path is None:
            continue
        tree = ast.parse(path.read_text(), str(path))
        skip = _type_checking_lines(tree)
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(tree):
            if getattr(node, "lineno", None) in skip:
                continue
            targets = []
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")
                    base = base[: len(base) - (node.level - 1)]
                    source = ".".join(base + ([node.module] if node.module else []))
                else:
                    source = node.module or ""
                targets = [
                    f"{source}.{alias.name}" if f"{source}.{alias.name}" in modules else source
                    for alias in node.names
                ]
            for target in targets:
                while target and target not in modules:  # spotkin.x.y (an attribute) -> spotkin.x
                    target = target.rpartition(".")[0]
                if target and target != name:
                    graph[name].add(target)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def part_of(module: str) -> str:
    """The part of the package a module is in: its subpackage, or FACE."""
    parts = module.split(".")
    if len(parts) == 1 or parts[1] in FACE_MODULES:
        return FACE
    return parts[1]


def layer_of(module: str) -> int:
    part = part_of(module)
    for layer, parts in enumerate(LAYERS):
        if part in parts:
            return layer
    raise AssertionError(f"{module} is in no layer: add its part ({part}) to LAYERS in tests/test_imports.py")


def test_the_graph_reads_the_imports():
    graph = import_graph()
    assert "spotkin.model.chain" in graph["spotkin.model.robot"]  # from .chain import Chain
    assert "spotkin._core" in graph["spotkin.model.leg"]  # from .. import _core: the submodule
    assert graph["spotkin"] >= {"spotkin.model.robot", "spotkin.model.chain"}  # the package re-exports them


def test_cycles_are_found():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycle():
    found = cycles(import_graph())
    assert not found, "import cycles: " + "; ".join(" <-> ".join(c) for c in found)


def test_every_module_is_in_a_layer():
    for module in import_graph():
        layer_of(module)


def test_the_graph_sees_the_subpackages():
    graph = import_graph()
    assert {"spotkin.model.robot", "spotkin.urdf.parse", "spotkin.scale.dask_kernel"} <= set(graph)
    assert "spotkin.urdf.files" in graph["spotkin.urdf.parse"]  # from .files import read_file
    assert "spotkin.model.body" in graph["spotkin.kinematics.cartesian_paths"]  # from ..model.body import


def layer_violations(graph: dict[str, set[str]]) -> list[str]:
    """The imports of ``graph`` from one part into another that is not in a lower layer."""
    wrong = []
    for module, imported in sorted(graph.items()):
        for target in sorted(imported):
            if part_of(target) != part_of(module) and layer_of(target) >= layer_of(module):
                wrong.append(f"{module} ({part_of(module)}) imports {target} ({part_of(target)})")
    return wrong


def test_the_layer_rule_is_read():
    assert part_of("spotkin.dask") == part_of("spotkin") == FACE
    assert part_of("spotkin.scale.dask_calls") == "scale"
    assert not layer_violations({"spotkin.kinematics.paul": {"spotkin.model.chain", "spotkin._core"}})
    assert len(layer_violations({"spotkin.model.chain": {"spotkin.kinematics.paul"}})) == 1  # upward
    assert len(layer_violations({"spotkin.scale.dask_calls": {"spotkin.sdk.feet"}})) == 1  # sideways
    assert len(layer_violations({"spotkin.model.robot": {"spotkin.trajectory"}})) == 1  # into the face


def test_lower_layers_never_import_higher_ones():
    wrong = layer_violations(import_graph())
    assert not wrong, "imports against the layers:\n" + "\n".join(wrong)

"""The Python package's layers: no import cycles, no library module importing the command line, no private names
imported across modules, no module reaching into Flowsheet's core object, one unit-conversion module and one module
that interprets output names. Read from the sources (python/granuflow), not by importing them."""
import ast
import pathlib
import re

import pytest

PKG = pathlib.Path(__file__).resolve().parents[2] / "python" / "granuflow"


def modules() -> dict[str, pathlib.Path]:
    out = {}
    for p in sorted(PKG.rglob("*.py")):
        rel = p.relative_to(PKG.parent).with_suffix("")
        name = ".".join(rel.parts)
        out[name[: -len(".__init__")] if name.endswith(".__init__") else name] = p
    return out


def imports(mods: dict[str, pathlib.Path]) -> dict[str, set[tuple[str, str]]]:
    """Per module: (imported module, imported name or "") for every import of a granuflow module, including the
    ones inside functions (a lazy import still ties the layers together)."""
    graph = {}
    for name, path in mods.items():
        pkg = name if path.name == "__init__.py" else name.rpartition(".")[0]
        deps = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = pkg.split(".")[: len(pkg.split(".")) - node.level + 1]
                    target = ".".join(base + ([node.module] if node.module else []))
                elif (node.module or "").startswith("granuflow"):
                    target = node.module
                else:
                    continue
                for a in node.names:
                    if f"{target}.{a.name}" in mods:
                        deps.add((f"{target}.{a.name}", ""))
                    elif a.name not in ("_core", "_calibration") and not target.endswith(("._core", "._calibration")):
                        deps.add((target, a.name))
            elif isinstance(node, ast.Import):
                deps.update((a.name, "") for a in node.names if a.name in mods)
        graph[name] = {(m, n) for m, n in deps if m != name}
    return graph


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected groups of more than one module (Tarjan)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                out.append(sorted(group))

    for v in list(edges):
        if v not in index:
            visit(v)
    return out


def test_the_cycle_finder_finds_cycles():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycles():
    mods = modules()
    graph = imports(mods)
    edges = {m: {d for d, _ in deps if d in mods} for m, deps in graph.items()}
    assert cycles(edges) == []


def test_library_modules_do_not_import_the_command_line():
    graph = imports(modules())
    bad = {m: sorted(d for d, _ in deps if d == "granuflow.cli" or d.startswith("granuflow.cli."))
           for m, deps in graph.items() if not (m.startswith("granuflow.cli") or m == "granuflow.__main__")}
    assert {m: d for m, d in bad.items() if d} == {}


def test_no_private_names_imported_across_modules():
    graph = imports(modules())
    bad = {m: sorted(f"{d}.{n}" for d, n in deps if n.startswith("_") and n != "__version__")
           for m, deps in graph.items()}
    assert {m: d for m, d in bad.items() if d} == {}


def test_only_the_flowsheet_touches_its_core_object():
    bad = [f"{m}:{i + 1}" for m, p in modules().items() if m != "granuflow.flowsheet"
           for i, line in enumerate(p.read_text().splitlines()) if re.search(r"\._scene\b", line)]
    assert bad == []


def test_one_unit_conversion_module_and_one_output_name_module():
    conv, names = [], []
    for m, p in modules().items():
        text = p.read_text()
        if m != "granuflow.quantity" and re.search(r"_core\.to_si\(|\b273\.15\b|\*\s*1e6\b|/\s*1e6\b", text):
            conv.append(m)
        if m != "granuflow.outputs" and re.search(r"re\.compile\([^)]*(balance_|psd_|reg_)", text):
            names.append(m)
    assert conv == [], "unit conversions belong in granuflow/quantity.py"
    assert names == [], "output-name patterns belong in granuflow/outputs.py"


@pytest.mark.parametrize("layer, below", [
    ("granuflow.textfile", set()),
    ("granuflow.quantity", {"granuflow.outputs", "granuflow.progress", "granuflow.textfile"}),
    ("granuflow.outputs", set()),
    ("granuflow.result", {"granuflow.outputs", "granuflow.quantity", "granuflow.textfile"}),
])
def test_foundation_modules_depend_only_downwards(layer, below):
    deps = {d for d, _ in imports(modules())[layer]}
    assert deps <= below, f"{layer} imports {sorted(deps - below)}"

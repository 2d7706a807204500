"""The house's layers (docs/ARCHITECTURE.md, "Layers"): imports flow one way, with no cycle.

Every import counts, also those inside functions (they are how a command stays light, not a way round
the layers). The graph is read from the source, so these checks cost no imports.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("isu_validate", "capture", "style_transfer")

CLI = ("isu_validate.cli", "isu_validate.commands")
# modules that import nothing of the project: every layer may use them
LEAVES = ("isu_validate.errors", "isu_validate.atomic", "isu_validate.srgb", "isu_validate.exr",
          "isu_validate.image_files", "isu_validate.tomlfile", "isu_validate.paths", "isu_validate.progress",
          "isu_validate.config", "isu_validate.lazy", "isu_validate.devices")
# workflows: above the domain packages, below the command line
WORKFLOWS = ("isu_validate.bench", "isu_validate.search", "isu_validate.pipeline", "isu_validate.execution",
             "isu_validate.analysis", "isu_validate.recreate", "isu_validate.agree", "isu_validate.replay",
             "isu_validate.dataset", "isu_validate.yardstick", "isu_validate.transfer")


def _modules() -> dict[str, Path]:
    found = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            found[".".join(parts)] = path
    return found


MODULES = _modules()


def _resolve(name: str) -> str | None:
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name or None


def _imports(module: str) -> set[str]:
    path = MODULES[module]
    base = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
    out = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            prefix = (".".join(base[: len(base) - node.level + 1] + ([node.module] if node.module else []))
                      if node.level else node.module or "")
            names = [f"{prefix}.{a.name}" for a in node.names]
        else:
            continue
        out.update(r for r in map(_resolve, names) if r and r != module)
    return out


GRAPH = {module: _imports(module) for module in MODULES}


def _within(module: str, prefixes) -> bool:
    return any(module == p or module.startswith(p + ".") for p in prefixes)


def _edges(frm, to, but=()) -> list[str]:
    """Imports from modules within ``frm`` (and not within ``but``) of modules within ``to``."""
    return sorted(f"{a} -> {b}" for a, targets in GRAPH.items() if _within(a, frm) and not _within(a, but)
                  for b in targets if _within(b, to))


def test_the_graph_sees_the_whole_product():
    assert len(MODULES) > 200 and "isu_validate.cli" in MODULES and "capture.camera" in MODULES


def test_no_import_cycle():
    index, low, stack, on, cycles = {}, {}, [], set(), []

    def visit(v):  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in GRAPH[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in GRAPH:
        if v not in index:
            visit(v)
    assert cycles == []


def test_nothing_below_the_command_line_imports_it():
    assert _edges(PACKAGES, CLI, but=CLI) == []


def test_leaves_import_nothing_of_the_project_but_its_errors():
    assert [f"{m} -> {t}" for m in LEAVES for t in sorted(GRAPH[m]) if t != "isu_validate.errors"] == []


@pytest.mark.parametrize("domain", ["isu_validate.space", "isu_validate.render", "isu_validate.sut",
                                    "isu_validate.evaluate", "isu_validate.archive", "isu_validate.realism",
                                    "isu_validate.reference", "isu_validate.recognition", "isu_validate.realphotos",
                                    "capture",
                                    "style_transfer"])
def test_domain_packages_do_not_import_workflows(domain):
    assert _edges([domain], WORKFLOWS) == []


def test_capture_never_imports_the_renderer():
    assert _edges(["capture"], ["isu_validate.render"]) == []


def test_benchmarks_are_imported_only_by_the_bench_command():
    bench = ["isu_validate.bench"]
    assert {edge.split(" -> ")[0] for edge in _edges(PACKAGES, bench, but=bench)} <= {"isu_validate.commands.bench"}

"""The layout's rules, checked on the source: no import cycle, layers imported downwards only
(golden <- hdl <- sim <- boards; the command root sim/cli may import boards), no module
importing another module's private name, no module over 600 lines, every package folder in the
packaging, one configuration error and one engine list."""

from __future__ import annotations

import ast
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LAYERS = ("golden", "hdl", "sim", "boards")
MAX_LINES = 600


def _modules() -> dict[str, Path]:
    mods = {}
    for top in LAYERS:
        for path in sorted((ROOT / top).rglob("*.py")):
            rel = path.relative_to(ROOT).with_suffix("")
            parts = list(rel.parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            mods[".".join(["cuneate", *parts])] = path
    return mods


MODULES = _modules()


def _imports(name: str, path: Path):
    """``(target module, imported name or None, line)`` of every import in the file, module
    level and inside functions, relative imports resolved."""
    tree = ast.parse(path.read_text(), str(path))
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package
                for _ in range(node.level - 1):
                    base = base.rsplit(".", 1)[0]
                mod = base + (f".{node.module}" if node.module else "")
            else:
                mod = node.module or ""
            for alias in node.names:
                full = f"{mod}.{alias.name}"
                if full in MODULES:
                    yield full, None, node.lineno
                else:
                    yield mod, alias.name, node.lineno
        elif isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, None, node.lineno


def _graph() -> dict[str, set[str]]:
    g = {m: set() for m in MODULES}
    for m, path in MODULES.items():
        for target, _, _ in _imports(m, path):
            if target in MODULES and target != m:
                g[m].add(target)
    return g


def _cycles(g: dict[str, set[str]]) -> list[list[str]]:
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in g[v]:
            if w not in index:
                visit(w)
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
                out.append(sorted(comp))
    for v in g:
        if v not in index:
            visit(v)
    return out


def test_the_layout_is_what_the_checks_read():
    """The checks below read every module: make sure they do."""
    assert "cuneate.hdl.izhikevich.core" in MODULES and "cuneate.sim.scenes.runner" in MODULES
    assert len(MODULES) > 100


def test_no_import_cycle():
    assert _cycles(_graph()) == []


def _layer(module: str) -> str:
    return module.split(".")[1]


def test_layers_are_imported_downwards_only():
    bad = []
    for m, path in MODULES.items():
        here = LAYERS.index(_layer(m))
        for target, _, line in _imports(m, path):
            if not target.startswith("cuneate.") or target == "cuneate":
                continue
            there = _layer(target)
            if there not in LAYERS:
                continue
            allowed = LAYERS.index(there) <= here or (
                m.startswith("cuneate.sim.cli") and there == "boards")
            if not allowed:
                bad.append(f"{path.relative_to(ROOT)}:{line} imports {target}")
    assert bad == []


def test_no_module_imports_another_modules_private_name():
    bad = []
    for m, path in MODULES.items():
        for target, name, line in _imports(m, path):
            if not target.startswith("cuneate"):
                continue
            private = (name or "").startswith("_") or any(
                part.startswith("_") and part != "__init__" for part in target.split("."))
            if private:
                bad.append(f"{path.relative_to(ROOT)}:{line} imports {target}.{name}")
    assert bad == []


def test_no_module_is_over_600_lines():
    long = {str(p.relative_to(ROOT)): n for p in MODULES.values()
            if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert long == {}


def test_every_package_folder_is_packaged():
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(cfg["packages"])
    assert cfg["package-dir"] == {"cuneate": "."}
    folders = {"cuneate"}
    for top in LAYERS:
        for d in [ROOT / top, *(p for p in (ROOT / top).rglob("*") if p.is_dir())]:
            if d.name == "__pycache__":
                continue
            has_code = any(d.glob("*.py")) or any(d.glob("*.toml")) or any(d.glob("*.cpp"))
            if not has_code:
                continue
            assert (d / "__init__.py").exists(), f"{d.relative_to(ROOT)} has no __init__.py"
            folders.add(".".join(["cuneate", *d.relative_to(ROOT).parts]))
    assert folders - listed == set(), "package folders missing from pyproject.toml"
    assert listed - folders == set(), "pyproject.toml lists packages that do not exist"


def test_one_configuration_error():
    from cuneate.hdl import coincidence, izhikevich, lif, link, network
    from cuneate.hdl.lib.config import ConfigError
    for block in (izhikevich, lif, coincidence, network):
        assert block.ConfigError is ConfigError
    assert link.config.ConfigError is ConfigError
    defined = [p.relative_to(ROOT).as_posix() for p in MODULES.values()
               if any(isinstance(n, ast.ClassDef) and n.name == "ConfigError"
                      for n in ast.walk(ast.parse(p.read_text())))]
    assert defined == ["hdl/lib/config.py"]


@pytest.mark.parametrize("block", ["izhikevich", "lif", "coincidence"])
def test_one_engine_list(block):
    """A block's engines are the registry's (no block keeps a list of its own), and every
    engine a block supports is accepted where that block runs: its command line."""
    from cuneate.sim.engines.registry import ENGINES, block_engines
    assert set(block_engines(block)) <= set(ENGINES)
    from cuneate.sim.cli import build_parser
    sub = next(a for a in build_parser()._actions if a.dest == "command").choices["simulate"]
    parser = next(a for a in sub._actions if a.dest == "model").choices[block]
    choices = next(a for a in parser._actions if a.dest == "engine").choices
    assert tuple(choices) == block_engines(block)


def test_verilator_fast_is_a_scene_engine():
    """The fast Verilator harness runs wherever the Izhikevich block does, scenes included."""
    from cuneate.sim.scenes import parse_scene
    from cuneate.sim.scenes.scene import DEFAULT_SCENE_TOML
    s = parse_scene(DEFAULT_SCENE_TOML.replace('engines = ["golden", "fixed", "verilator"]',
                                               'engines = ["fixed", "verilator-fast"]'))
    assert s.engines == ["fixed", "verilator-fast"]
    from cuneate.sim.scenes import afferent
    assert "verilator-fast" in afferent.ENGINES


def test_public_api_and_version(capsys):
    import cuneate
    from cuneate.sim.cli import main
    assert cuneate.__version__ and cuneate.IzhikevichConfig.__name__ == "IzhikevichConfig"
    assert callable(cuneate.run_scene)
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0 and capsys.readouterr().out.strip() == \
        f"cuneate {cuneate.__version__}"

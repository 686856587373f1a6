"""
The package's layout follows the data flow: imports run down the chain, never up.

Layers, earliest first (a module may import from its own layer and earlier ones):

base (with the instruments: what is each instrument's own) → sun → stages
(channels → scene → optics → camera → reduction: what they share) → products
→ analysis → run (config, pipeline) → cli → the package itself.

The test parses every module's imports (module level and inside functions) with
`ast`, so a late import cannot hide an import against the flow.
"""
import ast
from pathlib import Path

import pytest

import gongsynth

PACKAGE = Path(gongsynth.__file__).parent

#: Module-name prefixes in flow order; the longest matching prefix decides a module's rank.
LAYERS = (
    ("gongsynth.version", "gongsynth._version", "gongsynth.optional", "gongsynth.validation",
     "gongsynth.seeding", "gongsynth.threads", "gongsynth.precompile", "gongsynth.files", "gongsynth.tomlfmt",
     "gongsynth.instruments", "gongsynth.geometry", "gongsynth.observing"),
    ("gongsynth.sun.rt.atomic_data", "gongsynth.sun.rt.eos", "gongsynth.sun.rt.opacity",
     "gongsynth.sun.rt.hydrostatic"),
    ("gongsynth.sun", "gongsynth.sun.atmosphere_files", "gongsynth.sun.atmosphere",
     "gongsynth.sun.surface_field"),
    ("gongsynth.sun.rt", "gongsynth.sun.rt.kernels", "gongsynth.sun.rt.rays", "gongsynth.sun.rt.truth",
     "gongsynth.sun.rt.synthesis"),
    ("gongsynth.sun.model_atmosphere",),
    ("gongsynth.stages", "gongsynth.stages.channels"),
    ("gongsynth.stages.scene",),
    ("gongsynth.stages.optics", "gongsynth.stages.psf", "gongsynth.stages.imagers",
     "gongsynth.stages.seeing", "gongsynth.stages.pixelization"),
    ("gongsynth.stages.camera",),
    # An instrument's reduction algorithm returns the shared stage's Observables.
    ("gongsynth.stages.reduction", "gongsynth.stages.averaging", "gongsynth.instruments.hmi.observables",
     "gongsynth.instruments.hmi.noise"),
    ("gongsynth.products",),
    ("gongsynth.analysis",),
    ("gongsynth.suns", "gongsynth.config", "gongsynth.chain", "gongsynth.resources", "gongsynth.pipeline",
     "gongsynth.run_cache", "gongsynth.calibration_sweep", "gongsynth.cross_calibration_sweep"),
    ("gongsynth.cli",),
)

#: Modules allowed to exceed MAX_LINES, and why.
LONG_MODULES = {
    # One job, the run's configuration: the dataclass, its TOML round trip and the checks that
    # refuse a run before any computing (issue 28).  To split next: the checks into their own module.
    "gongsynth.config": "the run configuration and its before-computing checks",
}

MAX_LINES = 600


def module_name(path):
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def rank(name):
    """Layer index of a module name, or None for the package itself / unknown names."""
    best, best_len = None, -1
    for index, prefixes in enumerate(LAYERS):
        for prefix in prefixes:
            if (name == prefix or name.startswith(prefix + ".")) and len(prefix) > best_len:
                best, best_len = index, len(prefix)
    return best


def is_module(dotted):
    path = PACKAGE.parent.joinpath(*dotted.split("."))
    return path.with_suffix(".py").is_file() or (path / "__init__.py").is_file()


def package_modules():
    return sorted(p for p in PACKAGE.rglob("*.py") if "_build" not in p.parts)


def imports_of(path):
    """(line, imported module, imported names) for every gongsynth import in ``path``."""
    name = module_name(path)
    is_package = path.name == "__init__.py"
    tree = ast.parse(path.read_text())
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(node.lineno, a.name, ()) for a in node.names if a.name.split(".")[0] == "gongsynth"]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".") if is_package else name.split(".")[:-1]
                base = base[: len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "gongsynth":
                continue
            submodules = [a.name for a in node.names if is_module(f"{target}.{a.name}")]
            # ``from gongsynth.stages import optics`` imports the module gongsynth.stages.optics.
            found += [(node.lineno, f"{target}.{s}", ()) for s in submodules]
            names = tuple(a.name for a in node.names if a.name not in submodules)
            if names or not submodules:
                found.append((node.lineno, target, names))
    return found


@pytest.mark.parametrize("path", package_modules(), ids=lambda p: module_name(p))
def test_imports_follow_the_data_flow(path):
    name = module_name(path)
    if name == "gongsynth":  # the package's front door may import anything
        return
    own = rank(name)
    assert own is not None, f"{name} is in no layer of the data flow: add it to LAYERS"
    against = []
    for line, target, names in imports_of(path):
        if target == "gongsynth":
            # ``from gongsynth import x`` inside the package reaches back up through the front door.
            against.append(f"line {line}: from gongsynth import {', '.join(names)}")
            continue
        other = rank(target)
        if other is None or other > own:
            against.append(f"line {line}: {target}")
    assert not against, f"{name} imports against the data flow: {against}"


@pytest.mark.parametrize("path", package_modules(), ids=lambda p: module_name(p))
def test_no_private_name_crosses_a_module(path):
    name = module_name(path)
    leaks = [f"line {line}: {target}.{n}" for line, target, names in imports_of(path)
             for n in names if n.startswith("_") and not n.startswith("__") and target != name]
    leaks += [f"line {line}: {target}" for line, target, _ in imports_of(path)
              if any(part.startswith("_") and not part.startswith("__") for part in target.split(".")[1:])
              and target.rsplit(".", 1)[0] != name.rsplit(".", 1)[0]]
    assert not leaks, f"{name} uses private names of other modules: {leaks}"


@pytest.mark.parametrize("path", package_modules(), ids=lambda p: module_name(p))
def test_every_module_declares_all(path):
    tree = ast.parse(path.read_text())
    names = {t.id for node in tree.body if isinstance(node, ast.Assign) for t in node.targets
             if isinstance(t, ast.Name)}
    if path.name == "_version.py":
        return
    assert "__all__" in names, f"{module_name(path)} has no __all__"


@pytest.mark.parametrize("path", package_modules(), ids=lambda p: module_name(p))
def test_modules_stay_small(path):
    lines = len(path.read_text().splitlines())
    name = module_name(path)
    if name in LONG_MODULES:
        return
    assert lines <= MAX_LINES, (f"{name} has {lines} lines (> {MAX_LINES}): split it by job, or add it to "
                                f"LONG_MODULES with the reason")


def test_the_checker_catches_an_import_against_the_flow(tmp_path, monkeypatch):
    """The rule is not vacuous: a stage importing the pipeline is caught."""
    fake = PACKAGE / "stages" / "optics.py"
    assert rank("gongsynth.pipeline") > rank(module_name(fake))
    assert rank("gongsynth.stages.camera.integrate") > rank("gongsynth.stages.optics")
    assert rank("gongsynth.sun.stokes") < rank("gongsynth.stages.filters")
    assert rank("gongsynth.analysis.compare") > rank("gongsynth.products.maps")


def test_public_dotted_paths_of_the_design():
    """DESIGN §2 names stay importable where users were told they are."""
    import importlib

    for dotted, attribute in [("gongsynth.filters", "channel_responses"),
                              ("gongsynth.filters", "channel_weights"),
                              ("gongsynth.reduction", "reduce"),
                              ("gongsynth.compare", "load_observation"),
                              ("gongsynth.compare", "degrade_to_gong"),
                              ("gongsynth.calibration", "calibration_curve"),
                              ("gongsynth.photosphere", "model_photosphere"),
                              ("gongsynth.photosphere", "synthesize"),
                              ("gongsynth", "simulate"), ("gongsynth", "GONGInstrument"),
                              ("gongsynth", "StokesCube"), ("gongsynth", "load_observation")]:
        module = importlib.import_module(dotted)
        assert hasattr(module, attribute), f"{dotted}.{attribute}"
    assert importlib.import_module("gongsynth.filters") is importlib.import_module("gongsynth.stages.filters")


def _outside_sources():
    """Python files outside the package that import it: gallery, benchmarks, docs extensions."""
    root = PACKAGE.parent
    folders = ("examples", "benchmarks", "docs/_ext", "scripts")
    return sorted(p for folder in folders for p in (root / folder).glob("*.py"))


@pytest.mark.skipif(not (PACKAGE.parent / "examples").is_dir(), reason="needs a source checkout")
@pytest.mark.parametrize("path", _outside_sources(), ids=lambda p: f"{p.parent.name}/{p.name}")
def test_gallery_and_benchmark_imports_resolve(path):
    # The gallery runs only when the docs are built: a name moved in the
    # package must not break an example unnoticed until then.
    import importlib

    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("gongsynth"):
            module = importlib.import_module(node.module)
            for alias in node.names:
                submodule = hasattr(module, "__path__") and importlib.util.find_spec(
                    f"{node.module}.{alias.name}") is not None
                where = f"{path.name}: {node.module}.{alias.name}"
                assert hasattr(module, alias.name) or submodule, f"{where} does not exist"
                assert not alias.name.startswith("_"), f"{where} is private"
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("gongsynth"):
                    importlib.import_module(alias.name)

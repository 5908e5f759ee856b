"""The Hydra adapter (config/hydra_adapter.py): what it relies on is still in the installed
Hydra, and the composition memos give the config Hydra gives without them."""

from __future__ import annotations

import shutil

import pytest
from hydra import initialize_config_dir
from hydra.core.global_hydra import GlobalHydra
from hydra.types import RunMode
from omegaconf import DictConfig, ListConfig, OmegaConf

from compliant_docking import CONF_DIR
from compliant_docking.config import hydra_adapter, register_schemas

#: group choices, value overrides, presets, nested and list values, an added key
OVERRIDE_SETS = (
    (),
    ("task.misalignment.seed=3",),
    ("controller=hqp", "robot=fr3", "controller.K0=[1,2,3,4,5,6]"),
    ("+experiment=tracking_gate",),
    ("+experiment=misalignment", "trajectory=se3topp"),
    ("render=video", "controller.k=100", "figures=true"),
)


def tree(node, path: str = "", out: dict | None = None) -> dict:
    """Every node's path → (class, object type, reference type, flags, optional): what the
    YAML text leaves out, and what decides whether a later assignment is accepted."""
    out = {} if out is None else out
    meta = node._metadata
    out[path] = (type(node).__name__, meta.object_type, meta.ref_type, dict(meta.flags or {}), meta.optional)
    if isinstance(node, (DictConfig, ListConfig)) and not node._is_missing() and not node._is_none():
        keys = node.keys() if isinstance(node, DictConfig) else range(len(node))
        for key in keys:
            tree(node._get_node(key), f"{path}.{key}", out)
    return out


def compose_all(sets) -> dict:
    """Each set composed as the command line does, in both of Hydra's run modes, with
    Hydra's own node: its YAML, its node tree, or the error it raised."""
    register_schemas()
    GlobalHydra.instance().clear()
    out = {}
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        hydra = GlobalHydra.instance().hydra
        for overrides in sets:
            for mode in (RunMode.MULTIRUN, RunMode.RUN):
                try:
                    cfg = hydra.compose_config("config", list(overrides), run_mode=mode)
                    out[overrides, mode] = (OmegaConf.to_yaml(cfg), tree(cfg))
                except Exception as exc:
                    out[overrides, mode] = f"{type(exc).__name__}: {exc}"
    return out


@pytest.fixture
def without_memos():
    """Hydra's own composition for the test; the memos back afterwards."""
    hydra_adapter.uninstall()
    yield
    hydra_adapter.install()


def test_memoized_compositions_equal_hydras_own(without_memos):
    plain = compose_all(OVERRIDE_SETS)
    hydra_adapter.install()
    first = compose_all(OVERRIDE_SETS)  # misses, then hits within the passes
    again = compose_all(OVERRIDE_SETS)  # all hits
    assert first == plain and again == plain
    hits, misses = hydra_adapter.stats["composed"]
    assert hits >= len(plain) and misses <= len(OVERRIDE_SETS)  # the memo served most
    hits, misses = hydra_adapter.stats["files"]
    assert hits > misses > 0  # every config file parsed once, then served from the memo


@pytest.mark.parametrize(
    "overrides",
    [
        ("controller.nope=1",),  # unknown key
        ("controller=nope",),  # unknown option
        ("controller.k=abc",),  # wrong type
        ("robot=fr3", "controller.K0=[1]"),  # a key of another controller
    ],
)
def test_a_wrong_override_is_refused_as_without_the_memos(without_memos, overrides):
    plain = compose_all([overrides])
    hydra_adapter.install()
    assert compose_all([overrides]) == compose_all([overrides]) == plain
    assert all(isinstance(v, str) for v in plain.values())  # refused, in both modes


def test_an_edited_config_file_is_read_again(tmp_path):
    conf = tmp_path / "conf"
    shutil.copytree(CONF_DIR, conf)
    register_schemas()
    hydra_adapter.install()

    def k() -> float:
        GlobalHydra.instance().clear()
        with initialize_config_dir(config_dir=str(conf), version_base="1.3"):
            return (
                GlobalHydra.instance().hydra.compose_config("config", [], run_mode=RunMode.RUN).controller.k
            )

    assert k() == 50.0 and k() == 50.0
    path = conf / "controller" / "impedance.yaml"
    path.write_text(path.read_text().replace("k: 50.0", "k: 77.0"))
    assert k() == 77.0


def test_a_file_edited_to_the_same_size_and_time_is_parsed_again(tmp_path):
    """The file memo keys on the text, not on a stamp an edit may leave unchanged."""
    import os

    from hydra._internal.sources_registry import SourcesRegistry

    hydra_adapter.install()
    compose_all([()])  # a composition wraps the class of Hydra's file sources
    source = SourcesRegistry.instance().resolve("file")("test", f"file://{tmp_path}")
    path = tmp_path / "gain.yaml"
    path.write_text("k: 50.0\n")
    stamp = os.stat(path).st_mtime_ns
    first = source.load_config("gain")
    first.config.k = 1.0  # a caller that changes what it got changes no later copy
    hits = hydra_adapter.stats["files"][0]
    assert source.load_config("gain").config.k == 50.0
    assert hydra_adapter.stats["files"][0] == hits + 1  # served by the memo
    path.write_text("k: 77.0\n")
    os.utime(path, ns=(stamp, stamp))
    assert source.load_config("gain").config.k == 77.0


def test_schemas_are_stored_once_and_again_once_removed():
    from hydra.core.config_store import ConfigStore

    cs = ConfigStore.instance()
    register_schemas()
    stored = cs.repo["schema"]["controller"]["hqp.yaml"]
    register_schemas()
    assert cs.repo["schema"]["controller"]["hqp.yaml"] is stored  # not converted again
    hydra_adapter.unstore(cs, "schema/controller", "hqp")
    register_schemas()
    assert cs.repo["schema"]["controller"]["hqp.yaml"].node == stored.node


# --------------------------------------------------------------------------- what it relies on
def test_the_installed_hydra_offers_what_the_adapter_relies_on():
    """Fails first when a Hydra release changes a non-public object the adapter uses."""
    assert hydra_adapter.problems() == [], "\n".join(hydra_adapter.problems())


def test_a_changed_hydra_is_named(monkeypatch):
    from hydra._internal.core_plugins.basic_sweeper import BasicSweeper

    monkeypatch.setattr(BasicSweeper, "split_arguments", staticmethod(lambda overrides: [[overrides]]))
    monkeypatch.setattr(BasicSweeper, "validate_batch_is_legal", lambda self, batch: None)
    found = hydra_adapter.problems()
    assert len(found) == 2 and all("hydra-core" in p and "hydra_adapter.py" in p for p in found)
    assert "split_arguments('overrides',)" in found[0] and "splitting a sweep" in found[0]
    assert "no longer composes through its config loader's load_sweep_config" in found[1]


class _Loader:
    """A config loader's ``load_sweep_config``, counting its compositions."""

    def __init__(self) -> None:
        self.composed: list[tuple[str, ...]] = []

    def load_sweep_config(self, master_config, sweep_overrides):
        self.composed.append(tuple(sweep_overrides))
        return {"composed": tuple(sweep_overrides)}


def test_a_sweeps_checked_compositions_are_composed_once_in_all():
    """The guard offers what it composed; Hydra's check gets those (each once), and the
    launcher takes what the check got; an overrides list nobody offered is composed."""
    import pickle

    loader, master = _Loader(), object()
    shared = hydra_adapter.share_compositions(loader)
    assert hydra_adapter.share_compositions(loader) is shared  # one per loader
    shared.offer({("a=1",): "guard's a=1"})
    shared.keep_for(master)
    assert loader.load_sweep_config(master, ["a=1"]) == "guard's a=1"  # Hydra's check
    assert loader.load_sweep_config(master, ["a=2"]) == {"composed": ("a=2",)}
    assert shared.take(master, ["a=1"]) == "guard's a=1"  # the launcher
    assert shared.take(master, ["a=2"]) == {"composed": ("a=2",)}
    assert loader.composed == [("a=2",)]  # each composed once
    assert shared.take(master, ["a=1"]) == {"composed": ("a=1",)}  # taken already: composed
    sent = pickle.loads(pickle.dumps(loader))  # Hydra sends its context to the jobs
    assert sent.load_sweep_config.offered == {} and sent.load_sweep_config.loader is sent

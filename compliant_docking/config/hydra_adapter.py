"""The one module that relies on Hydra's non-public objects; everything else in the
package uses Hydra's public API (``hydra.main``, the compose API, callbacks, launcher and
sweeper plugins, the ConfigStore, ``HydraConfig``).

What it relies on, and why there is no public way (:func:`problems` checks each of them
against the installed Hydra; tests/config/test_hydra_adapter.py fails first, naming
what changed — Hydra is pinned below 1.4 in pyproject.toml for them):

1. **The composition memos** (:func:`install`): four functions of ``hydra._internal``
   wrapped, ``config_loader_impl.create_defaults_list``,
   ``ConfigLoaderImpl._compose_config_from_defaults_list``,
   ``CachingConfigRepository.__init__`` and ``FileConfigSource.load_config`` (wrapped at
   the first composition: see :func:`_memoize_file_sources`). Hydra offers no hook into
   its composition.
2. **The compositions a sweep's check made, reused** (:func:`share_compositions`): the
   basic sweeper composes every job once in the launching process to check it
   (``validate_batch_is_legal``, through its config loader's ``load_sweep_config``); the
   guard composed them already, and the pool launcher sends them to the jobs. One object,
   set on the one loader instance of the command, serves both.
3. **The basic sweeper's split of a sweep into jobs** (:func:`split_sweep`):
   ``hydra._internal.core_plugins.basic_sweeper.BasicSweeper.split_arguments``, so the
   guard checks (and the tuning sweeper draws) exactly the jobs Hydra will launch.
4. **An entry removed from the ConfigStore** (:func:`unstore`): its ``repo`` dict, which
   the store offers no method to delete from; a plugin's presets that our config files
   of the same names replace (sweep/launchers.py).

**The memos of item 1.** A sweep composes each job's config twice — in the launching process, where Hydra's
sweeper checks every job before any starts, and in the worker that runs it — and a
single run composes twice too (Hydra first composes to read ``hydra.mode``). Each
composition parses the YAML files, builds the defaults tree and merges some 30 nodes
into the typed schemas: about 0.15 s of CPU, a quarter of a default job's simulation
loop. Most of it is the same from job to job: the jobs of a sweep differ in a few values
(a seed, a gain) and often not at all in their config-group choices. So two memos, each
keeping what Hydra computed and handing out a deep copy, so no caller shares a node:

- the **defaults list** (which config files make up the config), keyed by the
  overrides that choose config groups: Hydra computes the same list whatever the value
  overrides (``key=value``), which it applies afterwards. A list found without leaving
  a group unchosen (``???``) also serves the lenient request Hydra makes for
  ``hydra.mode`` and for a sweep's master config;
- the **merged config before the value overrides**, keyed by that defaults list.

A third memo keeps every **config file** as parsed, keyed by its path and text: Hydra
parses each file again at every composition (~5 ms a file, ~35 a composition: a quarter
of a composition that misses the memos above). A hit is unpickled from the parsed file
(plain YAML: no typed node that pickling could change), ~20 times cheaper; an edited
file has another text, so it is parsed again.

The keys of the first two memos hold a stamp of each config directory (newest
modification time, number of files), so an edited YAML file is read again. The typed
schemas (the ConfigStore) are code and are taken as fixed within a process
(:func:`clear` forgets everything). All that follows — the value overrides, Hydra's own
``hydra`` node (overrides, choices, output directory) — runs as before, for every job.
Also, Hydra deep-copies its config repository for every composition, which copies the
whole ConfigStore (~9 ms); a shallow copy does the same job (:func:`_shallow_repository`).

The composed configs equal Hydra's own, nodes, types and flags alike, in both run
modes, and a wrong override is refused with the same error
(tests/config/test_hydra_adapter.py). Through Hydra's compose API as ``load_config``
calls it (benchmarks/composition.py), a composition that hits both memos takes ~30 ms
instead of ~470 ms, and one of config groups not chosen before ~350 ms.
"""

from __future__ import annotations

import copy
import dataclasses
import os
import pickle
from typing import Any

#: entries kept per memo; past that the memo is emptied (a sweep has a few group choices)
MAX_ENTRIES = 256

_defaults: dict[tuple, Any] = {}
_composed: dict[tuple, Any] = {}
_files: dict[tuple, Any] = {}
#: (owner, attribute name, Hydra's original) of every patch in place
_originals: list[tuple[Any, str, Any]] = []
#: hits and misses of each memo since the last :func:`clear` (for tests and benchmarks)
stats = {"defaults": [0, 0], "composed": [0, 0], "files": [0, 0]}


def clear() -> None:
    """Forget everything memoized (and the counts)."""
    for memo in (_defaults, _composed, _files):
        memo.clear()
    for counts in stats.values():
        counts[0] = counts[1] = 0


def _remember(memo: dict, name: str, key: tuple, make) -> Any:
    """The value for ``key`` (made by ``make()`` on a miss) — the kept original; callers copy."""
    hit = memo.get(key)
    if hit is None:
        stats[name][1] += 1
        hit = make()
        if len(memo) >= MAX_ENTRIES:
            memo.clear()
        memo[key] = hit
    else:
        stats[name][0] += 1
    return hit


def _sources_key(repo) -> tuple:
    """The config sources and, for directories of files, a stamp of their contents (the
    newest modification time and the number of files): an edited, added or removed
    YAML file makes a new key, so its next composition reads it again."""
    return tuple(
        (kind, s.provider, s.path, _stamp(s.path) if kind == "FileConfigSource" else None)
        for s in repo.get_sources()
        for kind in [type(s).__name__]
    )  # package resources (Hydra's own) and the ConfigStore do not change


def _stamp(path: str) -> tuple[int, int]:
    newest, count = 0, 0
    for folder, _dirs, files in os.walk(path):
        for name in files:
            try:
                newest = max(newest, os.stat(os.path.join(folder, name)).st_mtime_ns)
                count += 1
            except OSError:
                pass
    return newest, count


def installed() -> bool:
    return bool(_originals)


def uninstall() -> None:
    """Put Hydra's own methods back and forget the memos (for tests)."""
    while _originals:
        owner, name, original = _originals.pop()
        setattr(owner, name, original)
    clear()


def _patch(owner, name: str, make) -> None:
    original = getattr(owner, name)
    _originals.append((owner, name, original))
    setattr(owner, name, make(original))


def install() -> None:
    """Wrap Hydra's config loading with the memos (idempotent). The command line calls it
    on import (so the sweep's workers, which import it to run their jobs, have it too),
    and so does :func:`compliant_docking.config.load_config`."""
    if _originals:
        return
    try:
        from hydra._internal import config_loader_impl
        from hydra._internal.config_loader_impl import ConfigLoaderImpl
        from hydra._internal.config_repository import CachingConfigRepository

        _patch(config_loader_impl, "create_defaults_list", _defaults_list)
        _patch(ConfigLoaderImpl, "_compose_config_from_defaults_list", _compose)
        _patch(CachingConfigRepository, "__init__", _shallow_repository)
    except (ImportError, AttributeError) as exc:
        uninstall()
        raise RuntimeError(_changed(f"{exc}")) from None


def _changed(what: str) -> str:
    import hydra

    return (
        f"hydra-core {hydra.__version__} changed what compliant_docking/config/hydra_adapter.py "
        f"relies on ({what}); install hydra-core < 1.4 (pyproject.toml) or update the adapter"
    )


def _shallow_repository(original):
    def __init__(self, delegate) -> None:
        # Hydra's own body deep-copies the delegate "to avoid mutating it with
        # initialize_sources()", which copies the whole ConfigStore its schema source
        # holds (~9 ms a composition). initialize_sources() rebinds the copy's list of
        # sources to new ones, so a shallow copy leaves the original untouched just as well.
        self.delegate = copy.copy(delegate)
        self.cache = {}
        _memoize_file_sources(delegate)

    return __init__


def _memoize_file_sources(repo) -> None:
    """Wrap ``load_config`` of the class of ``repo``'s file sources with the file memo, once
    per class: the class Hydra instantiates, which its plugin scan loaded anew (``import``
    gives another class). At a composition's start, so an import of the command line (in
    every sweep worker) scans no plugins."""
    for source in repo.get_sources():
        kind = type(source)
        if source.scheme() == "file" and not any(o is kind and n == "load_config" for o, n, _ in _originals):
            _patch(kind, "load_config", _parsed_file)


def _parsed_file(original):
    def load_config(self, config_path):
        # the file Hydra's own body opens; an unreadable one gets Hydra's own error
        path = os.path.realpath(os.path.join(self.path, self._normalize_file_name(config_path)))
        try:
            with open(path, "rb") as file:
                text = file.read()
        except OSError:
            return original(self, config_path)

        def parse() -> tuple[Any, bytes]:  # the result without its config, and the config pickled
            found = original(self, config_path)
            blob = pickle.dumps(found.config)
            return dataclasses.replace(found, config=None, header=dict(found.header)), blob

        kept, config = _remember(_files, "files", (self.provider, self.path, config_path, text), parse)
        return dataclasses.replace(kept, config=pickle.loads(config), header=dict(kept.header))

    return load_config


def _defaults_list(original):
    from hydra._internal.defaults_list import DefaultsList

    def create_defaults_list(repo, config_name, overrides_list, prepend_hydra, skip_missing):
        groups, values = [], []
        for override in overrides_list:
            if override.is_sweep_override():  # Hydra's defaults list ignores them too
                continue
            value = override.value()
            is_value = isinstance(value, dict) or not repo.group_exists(override.key_or_group)
            (values if is_value else groups).append(override)
        if any(o.input_line is None for o in groups):
            return original(repo, config_name, overrides_list, prepend_hydra, skip_missing)
        key = (config_name, prepend_hydra, _sources_key(repo), tuple(o.input_line for o in groups))
        kept = _remember(
            _defaults,
            "defaults",
            key + (skip_missing,),
            lambda: (
                _lenient(original, repo, config_name, groups, prepend_hydra)
                if skip_missing
                else (True, original(repo, config_name, groups, prepend_hydra, False))
            ),
        )
        if skip_missing and kept[0]:  # found strictly: the same list, filed for both
            _defaults.setdefault(key + (False,), kept)
        kept = kept[1]
        overrides = copy.copy(kept.overrides)
        overrides.config_overrides = values
        return DefaultsList(
            defaults=list(kept.defaults),
            defaults_tree=kept.defaults_tree,
            config_overrides=values,
            overrides=overrides,
        )

    return create_defaults_list


def _lenient(original, repo, config_name, groups, prepend_hydra) -> tuple[bool, Any]:
    """(strict, list) for skip_missing=True — what Hydra composes for ``hydra.mode`` and a
    sweep's master config: a list found strictly (no config group left ``???``) is the
    same list, and then also serves the jobs' own compositions (skip_missing=False)."""
    try:
        return True, original(repo, config_name, groups, prepend_hydra, False)
    except Exception:  # a group left missing: only the lenient list exists
        return False, original(repo, config_name, groups, prepend_hydra, True)


def _compose(original):
    def compose(self, defaults, repo):
        key = (
            _sources_key(repo),
            tuple(
                (d.config_path, d.parent, d.package, d.is_self, d.primary, d.override_key) for d in defaults
            ),
        )
        return copy.deepcopy(_remember(_composed, "composed", key, lambda: original(self, defaults, repo)))

    return compose


# --------------------------------------------------------------------------- a sweep's jobs
def split_sweep(overrides: list) -> list[list[str]]:
    """The jobs of a sweep (each job's overrides, in launch order) as Hydra's basic sweeper
    splits the parsed ``overrides`` (``hydra.core.override_parser`` objects): the product
    of every discrete sweep, the last value of a key winning. Raises Hydra's error for
    what the basic sweeper refuses (an interval sweep)."""
    from hydra._internal.core_plugins.basic_sweeper import BasicSweeper

    return [list(job) for batch in BasicSweeper.split_arguments(overrides, None) for job in batch]


def share_compositions(loader: Any) -> Compositions:
    """The :class:`Compositions` of the command's config ``loader`` (set on it the first
    time: an instance attribute named like the loader's ``load_sweep_config``)."""
    found = vars(loader).get("load_sweep_config")
    if isinstance(found, Compositions):
        return found
    shared = Compositions(loader)
    loader.load_sweep_config = shared
    return shared


class Compositions:
    """The job configs a sweep composed once, handed to whoever composes them next.

    - :meth:`offer`: the guard composed and checked every job before the sweep directory
      existed; Hydra's basic sweeper then composes every job again to check it
      (``validate_batch_is_legal``), and gets the guard's config instead (each once).
    - :meth:`keep_for` / :meth:`take`: the pool launcher keeps what the sweeper's check
      got for its master config and sends those configs to the jobs, so a job's config is
      composed once in all. A config nobody offered is composed as Hydra composes it.

    Pickled with the loader (Hydra sends its context to every job) it holds nothing.
    """

    def __init__(self, loader: Any) -> None:
        self.loader = loader
        self.offered: dict[tuple[str, ...], Any] = {}
        self.kept: dict[tuple[str, ...], Any] = {}
        self.master: Any = None

    def __getstate__(self) -> dict:
        return {"loader": self.loader, "offered": {}, "kept": {}, "master": None}

    def offer(self, configs: dict[tuple[str, ...], Any]) -> None:
        """Configs composed for these overrides (of the sweep's master config), each served once."""
        self.offered.update(configs)

    def keep_for(self, master_config: Any) -> None:
        """Keep every config composed for ``master_config`` from now on, for :meth:`take`."""
        self.master, self.kept = master_config, {}

    def compose(self, master_config: Any, sweep_overrides: list[str]) -> Any:
        """Hydra's own ``load_sweep_config`` of the loader."""
        return type(self.loader).load_sweep_config(self.loader, master_config, list(sweep_overrides))

    def __call__(self, master_config: Any, sweep_overrides: list[str]) -> Any:
        key = tuple(sweep_overrides)
        found = self.offered.pop(key, None)
        if found is None:
            found = self.compose(master_config, sweep_overrides)
        if self.master is not None and master_config is self.master:
            self.kept[key] = found
        return found

    def take(self, master_config: Any, sweep_overrides: list[str]) -> Any:
        """The config kept for these overrides (each once), else composed now."""
        found = self.kept.pop(tuple(sweep_overrides), None)
        return found if found is not None else self.compose(master_config, sweep_overrides)


def unstore(cs: Any, group: str, name: str) -> None:
    """Remove the entry ``name`` of ``group`` (``a/b``) from the ConfigStore ``cs``, if there."""
    node = cs.repo
    for part in group.split("/"):
        node = node.get(part, {})
    node.pop(f"{name}.yaml", None)


# --------------------------------------------------------------------------- the check
def problems() -> list[str]:
    """What the installed Hydra no longer offers as this module relies on it (one sentence
    each, naming the object); [] when everything is there (tests/config/test_hydra_adapter.py)."""
    import inspect

    found: list[str] = []

    def signature(owner_path: str, name: str, params: tuple[str, ...], why: str) -> Any:
        import importlib

        module_path, _, owner_name = owner_path.partition(":")
        try:
            owner = importlib.import_module(module_path)
            owner = getattr(owner, owner_name) if owner_name else owner
            fn = getattr(owner, name)
            # the wrapped one if the memos are installed: Hydra's own is in _originals
            fn = next((o for (w, n, o) in _originals if w is owner and n == name), fn)
            got = tuple(inspect.signature(fn).parameters)
        except (ImportError, AttributeError, ValueError, TypeError) as exc:
            found.append(_changed(f"{owner_path}.{name}: {exc}; used for {why}"))
            return None
        if got != params:
            found.append(_changed(f"{owner_path}.{name}{got} is not {name}{params}; used for {why}"))
        return fn

    memo = "the composition memos"
    loader = "hydra._internal.config_loader_impl"
    signature(
        loader,
        "create_defaults_list",
        ("repo", "config_name", "overrides_list", "prepend_hydra", "skip_missing"),
        memo,
    )
    signature(
        f"{loader}:ConfigLoaderImpl", "_compose_config_from_defaults_list", ("self", "defaults", "repo"), memo
    )
    signature(
        "hydra._internal.config_repository:CachingConfigRepository", "__init__", ("self", "delegate"), memo
    )
    signature(
        "hydra._internal.core_plugins.file_config_source:FileConfigSource",
        "load_config",
        ("self", "config_path"),
        memo,
    )
    signature("hydra._internal.config_repository:ConfigRepository", "get_sources", ("self",), memo)
    signature(
        f"{loader}:ConfigLoaderImpl",
        "load_sweep_config",
        ("self", "master_config", "sweep_overrides"),
        "reusing a sweep's compositions",
    )
    signature(
        "hydra._internal.core_plugins.basic_sweeper:BasicSweeper",
        "split_arguments",
        ("overrides", "max_batch_size"),
        "splitting a sweep into its jobs",
    )
    check = signature(
        "hydra._internal.core_plugins.basic_sweeper:BasicSweeper",
        "validate_batch_is_legal",
        ("self", "batch"),
        "reusing a sweep's compositions",
    )
    if check is not None and "config_loader.load_sweep_config(" not in inspect.getsource(check):
        found.append(
            _changed(
                "BasicSweeper.validate_batch_is_legal no longer composes through its config loader's "
                "load_sweep_config; used for reusing a sweep's compositions"
            )
        )
    try:
        from dataclasses import fields

        from hydra._internal.defaults_list import DefaultsList

        names = tuple(f.name for f in fields(DefaultsList))
        if names != ("defaults", "defaults_tree", "config_overrides", "overrides"):
            found.append(_changed(f"DefaultsList has the fields {names}; used for the composition memos"))
    except (ImportError, TypeError) as exc:
        found.append(
            _changed(f"hydra._internal.defaults_list.DefaultsList: {exc}; used for the composition memos")
        )
    from hydra.core.config_store import ConfigStore

    repo = getattr(ConfigStore.instance(), "repo", None)
    if not isinstance(repo, dict) or not isinstance(repo.get("hydra"), dict):
        found.append(_changed("ConfigStore.repo is not a dict of groups; used for removing a stored entry"))
    return found

"""The scenarios of a study's groups, loaded once per process and checked with each run's planner.

A study's tasks carry their scenario's text and overrides (plain data, for
any worker); :func:`load_cached` loads each pair once per process, keyed by
their digest, and :func:`check_run_settings` checks a scenario as a study's
run plans it (with the study's algorithm and K, not the file's).
"""

from __future__ import annotations

import collections
import hashlib
from pathlib import Path

from drake_social.scenario import Scenario, load_scenario_text, validate_planner_choice

__all__ = ["check_run_settings", "load_cached"]


def load_cached(source: str, text: str, overrides: tuple[str, ...], overrides_name: str = "overrides") -> Scenario:
    """The scenario of ``text`` with ``overrides``, loaded once per pair and
    process while it is among the last :data:`_LOADED_MOST` loaded (keyed by
    their digest and the file's folder, whatever the groups are called, and
    by the SHA-256 of the bytes of its ``people_file``: a recording changed on
    disk is loaded and checked again); errors name ``source``, the scenario
    file, whose folder a relative ``people_file`` is resolved against."""
    key = _load_key(str(Path(source).parent.absolute()), text, overrides)
    entry = _loaded.get(key)
    if entry is not None and entry[1] != _file_digest(entry[0].people_file):
        entry = None
    if entry is None:
        scenario = load_scenario_text(text, source, list(overrides), overrides_name=overrides_name,
                                      base_dir=Path(source).parent)
        # The digest read after the load (which read and checked the file); a
        # file changed in between is caught at the next call.
        entry = (scenario, _file_digest(scenario.people_file))
        _loaded[key] = entry
        if len(_loaded) > _LOADED_MOST:
            _loaded.popitem(last=False)
    _loaded.move_to_end(key)
    return entry[0]


#: The most scenarios :func:`load_cached` keeps (the least recently used go first).
_LOADED_MOST = 64
#: (folder, text, overrides) digest -> (scenario, its people file's digest).
_loaded: "collections.OrderedDict[bytes, tuple[Scenario, bytes | None]]" = collections.OrderedDict()


def _load_key(folder: str, text: str, overrides: tuple[str, ...]) -> bytes:
    digest = hashlib.sha256()
    for part in (folder, text, *overrides):
        data = part.encode("utf-8", "surrogatepass")
        digest.update(len(data).to_bytes(8, "little") + data)
    return digest.digest()


def _file_digest(path: str | None) -> bytes | None:
    """SHA-256 of the bytes of the file at ``path`` (a loaded scenario's
    absolute ``people_file``); b"" without a file, None when it cannot be
    read (then the scenario is loaded again, which names the problem)."""
    if path is None:
        return b""
    try:
        with open(path, "rb") as f:
            return hashlib.file_digest(f, "sha256").digest()
    except OSError:
        return None


def check_run_settings(scenario: Scenario, algorithm: str, iterations: int, source: str) -> None:
    """Checks ``scenario`` as a study's run plans it, with the study's
    ``algorithm`` and ``iterations`` (:func:`~drake_social.scenario.validate_planner_choice`).

    Raises:
        ScenarioError: ``<source> with the study's algorithm <algorithm>: <field>: ...``.
    """
    validate_planner_choice(scenario, algorithm, iterations, f"{source} with the study's algorithm {algorithm}")

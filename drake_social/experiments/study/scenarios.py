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
    their digest and the file's folder, whatever the groups are called);
    errors name ``source``, the scenario file, whose folder a relative
    ``people_file`` is resolved against."""
    key = _load_key(str(Path(source).parent.absolute()), text, overrides)
    scenario = _loaded.get(key)
    if scenario is None:
        scenario = load_scenario_text(text, source, list(overrides), overrides_name=overrides_name,
                                      base_dir=Path(source).parent)
        _loaded[key] = scenario
        if len(_loaded) > _LOADED_MOST:
            _loaded.popitem(last=False)
    _loaded.move_to_end(key)
    return scenario


#: The most scenarios :func:`load_cached` keeps (the least recently used go first).
_LOADED_MOST = 64
_loaded: "collections.OrderedDict[bytes, Scenario]" = collections.OrderedDict()


def _load_key(folder: str, text: str, overrides: tuple[str, ...]) -> bytes:
    digest = hashlib.sha256()
    for part in (folder, text, *overrides):
        data = part.encode("utf-8", "surrogatepass")
        digest.update(len(data).to_bytes(8, "little") + data)
    return digest.digest()



def check_run_settings(scenario: Scenario, algorithm: str, iterations: int, source: str) -> None:
    """Checks ``scenario`` as a study's run plans it, with the study's
    ``algorithm`` and ``iterations`` (:func:`~drake_social.scenario.validate_planner_choice`).

    Raises:
        ScenarioError: ``<source> with the study's algorithm <algorithm>: <field>: ...``.
    """
    validate_planner_choice(scenario, algorithm, iterations, f"{source} with the study's algorithm {algorithm}")

"""The scenario files shipped with drake-social, found from the package.

Commands whose defaults name shipped scenarios (``bench``'s ``--scenarios``,
the office of ``bench --map`` and of ``bench --replan-runs``) find them in
the ``scenarios/`` folder beside the package, not in the working folder, so
they run from any folder of a checkout or an editable install. A package
installed without that folder (a built wheel) has none: the commands then
name the file that is missing and the option that replaces it.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["SHIPPED_SCENARIOS", "shipped_scenario"]

#: The ``scenarios/`` folder beside the ``drake_social`` package.
SHIPPED_SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"


def shipped_scenario(name: str) -> Path:
    """The shipped scenario file ``name`` (e.g. ``"office_bar.yaml"``): an
    absolute path, whatever the working folder."""
    return SHIPPED_SCENARIOS / name

"""The error of invalid user input, shared by every reader of the user's files.

:class:`ScenarioError` is raised for a scenario file, an override (``--set``),
a sweep file or a path CSV that is missing, malformed or out of range; the
command line prints its message and exits with status 2. It lives in a module
without imports so that the lowest layers (:mod:`drake_social.io.textfile`)
can raise it; :mod:`drake_social.scenario` re-exports it.
"""

__all__ = ["ScenarioError"]


class ScenarioError(ValueError):
    """A scenario file or override is invalid; the message names file and field."""

"""Evaluation: the measures of a plan or a run, per body part and over time.

What ``plan`` and ``simulate`` record, and what the studies and the bench
measure, in one place below the commands and the runners:

* :mod:`.records`: a planning run's record (:func:`~.records.run_record`)
  and a path's measures (:func:`~.records.path_costs`), named as
  :data:`drake_social.io.records.RUN_FIELDS` names them;
* :mod:`.metrics`: per-part distances, Hall's zones and AGF of a planned
  path (:func:`~.metrics.path_metrics`) or an executed trajectory
  (:func:`~.metrics.executed_metrics`);
* :mod:`.nav_metrics`: the social-navigation metrics over time against where
  the people were (:func:`~.nav_metrics.run_metrics`, the ``nav_*`` fields:
  :func:`~.nav_metrics.execution_metrics`);
* :mod:`.proxemics` and :mod:`.time_series`: the zones and track measures,
  and the reductions of a logged time series, that both use.

These modules read results (waypoints, logs, a
:class:`~drake_social.people.PeopleLog`); they run no planner or simulation.
"""

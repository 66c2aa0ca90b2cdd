"""Experiments: the runners. ``bench/`` times and compares the planners and
checkers; ``study/`` runs studies (sweeps, the paper's) and the crowd study
is ``crowd*.py``. Their measures are :mod:`drake_social.evaluation`'s."""

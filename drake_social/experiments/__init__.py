"""Experiments: the runners. ``bench/`` times and compares the planners and
checkers; ``study/`` is the one study framework (sweeps, the paper's study
and the crowd study are its kinds). Their measures are
:mod:`drake_social.evaluation`'s."""

"""``drake-social bench``: planners, checkers, scaling and execution, measured."""

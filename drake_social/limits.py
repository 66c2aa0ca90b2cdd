"""Limits shared by the scenario check and the compiled kernels.

A module of its own so that the kernels can compile its constants in and
:mod:`drake_social._kernel_cache` can drop their cached code when one
changes (it hashes this file with the kernel sources). No imports.
"""

#: The most trapezoid steps of ``social.resolution`` one motion's social cost
#: may take (its samples are held in memory): 100 km at the default 0.1 m.
#: ``validate_scenario`` refuses a resolution that a motion in the room could
#: need more steps of.
MAX_MOTION_STEPS = 1_000_000

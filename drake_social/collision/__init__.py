"""Validity: the checker protocol, the numpy reference, the exact planar checker and its kernel, Drake's checker."""

"""drake-social: socially-aware object transportation by a planar mobile manipulator."""

__version__ = "0.1.0"

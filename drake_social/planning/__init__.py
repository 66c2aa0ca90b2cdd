"""Sampling-based planning (pure numpy): state space, validity protocol, RRT* family."""

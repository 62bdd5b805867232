"""Demonstrations: the pendulum on a cart, co-simulated in ecospy against one monolithic model."""

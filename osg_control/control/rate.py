"""The core arm's control rate, in a module of its own so light layers (a domain's data,
the data-set exports) can name it without importing MuJoCo."""

CONTROL_HZ = 20.0
"""The rate of the arm's control loop [Hz]: one IK solve and servo target per 50 ms."""

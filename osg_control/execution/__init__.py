"""Execution layer: the executor that classifies, plans, runs options and replans."""

MAX_REPLANS = 1000
"""The most replans an executor takes (``Executor.max_replans``, ``--replans``,
``--max-replans``): each replan re-runs a plan, so more would never end."""

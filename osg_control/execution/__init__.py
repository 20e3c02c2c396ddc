"""Execution layer: the executor that classifies, plans, runs options and replans."""

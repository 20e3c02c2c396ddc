"""Evaluation layer: the paper's tables and the reproduction report."""

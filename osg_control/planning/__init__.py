"""Symbolic planning over the skill graph: grounding, A*/UCS search, Fast Downward, results.

Entry points: ``plan_for_goal`` (the kitchen, from skill specs or a skill graph) and
``plan_files`` (any STRIPS + typing + action-costs domain/problem pair), both in ``api``.
"""

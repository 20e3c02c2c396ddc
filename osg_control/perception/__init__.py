"""Perception: what a robot measures, the only input of everything that decides.

A ``Percept`` holds the policy state (10-D), the perceived joints and the perceived world
(the domain's world fields, from simulated sensors with the noise of a named
``PerceptionSpec``), and the facts the domain's detectors read from it. The simulator's
truth is read only by the sensors here, to score an episode and by scripted collection.
"""

"""Gymnasium-Robotics FrankaKitchen-v1 (the D4RL kitchen) as an osg-control domain.

Needs the ``franka`` extra (``pip install osg-control[franka]``); every module here imports
``gymnasium_robotics`` only inside functions, so importing the package is cheap.
"""

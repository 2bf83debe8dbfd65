"""Measured-like runs from code the diagnosis never runs (numpy and scipy only).

The diagnosis fits the project's model (``hems_ros.physics``) to data. Runs made with that
same model can only show that the fit agrees with itself, so the truths of the diagnosis
suite come from here: another SMA model family (Brinson's, ``brinson``), integrated with
scipy's ``solve_ivp`` in a rig of its own (``rig``). Nothing in this package imports the
project's physics, the diagnosis or its candidate effects (tests/foundation/test_layers.py).
"""

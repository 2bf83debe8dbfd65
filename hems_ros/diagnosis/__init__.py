"""Model against measurement: find where they disagree, name the missing effect, add it.

Plain Python (no rclpy). The layers, bottom up: measured data (``runs``, ``units``,
``csvload``, ``bagload``), replay on the physics batch (``replay``,
``dataset``, ``features``, ``phases``), the candidate library (``candidates``), fitting and
selection (``batching``, ``fit``, ``search``), the workflow (``workflow``, ``localise``) and
the report folder (``report``); ``suite`` is the hidden-effect suite.
"""

"""Model against measurement: find where they disagree, name the missing effect, add it.

Plain Python (no rclpy). The layers, bottom up: measured data (``runs``, ``units``,
``csvload``, ``bagload``), replay on the physics batch (``replay``,
``dataset``, ``features``, ``phases``), the candidate library (``candidates``), fitting and
selection (``batching``, ``fit``, ``search``), the workflow (``workflow``, ``localise``,
``intervals``); ``suite`` is the hidden-effect suite, ``blind`` the suite on truths from
:mod:`hems_ros.truth`, and ``cluster`` runs the suites and archives as tasks on Dask (the one
module that imports it). The report pages and figures are written by :mod:`hems_ros.reports`.
"""

"""Closed-loop experiments of the dissertation in simulation (dissertation chapters 5 and 6).

:mod:`.lockstep` couples one controller and one actuation unit in process (plant 1 kHz,
control 100 Hz); :mod:`.chapters` runs the chapter 5 and 6 protocols; :mod:`.findings`
checks the dissertation's claims and measures the evidence behind the ones not reproduced;
:mod:`.tuning` fits BPID gains on the model. The tables, figures and docs/experiments.md are
written by :mod:`hems_ros.reports.experiments` and :mod:`hems_ros.reports.findings`.
"""

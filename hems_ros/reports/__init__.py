"""Every report the project writes, rendered in one place above the analyses: Markdown pages
and PNG figures from the data that the physics, experiments and diagnosis modules return.

- :mod:`hems_ros.reports.validation`: ``hems validate`` (docs/validation.md);
- :mod:`hems_ros.reports.experiments`: ``hems experiment`` (docs/experiments.md, results/), with the
  chapter 5 and 6 claims checked in :mod:`hems_ros.reports.findings`;
- :mod:`hems_ros.reports.diagnosis`: one ``hems diagnose`` run (report.md, summary.json, figures);
- :mod:`hems_ros.reports.diagnosis_suite`: ``hems diagnose-suite`` (docs/diagnosis-suite.md).
"""

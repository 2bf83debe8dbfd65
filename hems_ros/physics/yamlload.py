"""YAML as people write numbers in it.

PyYAML follows YAML 1.1, whose float pattern needs a dot: ``5e-10`` and ``1E3`` load as
strings. The loader here also resolves the YAML 1.2 forms (exponent without a dot, with or
without a sign), so a parameter file written by hand loads as it reads.
"""

from __future__ import annotations

import re

import yaml


class NumberLoader(yaml.SafeLoader):
    """SafeLoader that reads ``5e-10``, ``1E3`` and ``-2e+4`` as floats."""


NumberLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"""^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"""),
    list("-+0123456789"),
)


def load_yaml(text: str):
    """Parse ``text`` like ``yaml.safe_load``, with YAML 1.2 exponent floats."""
    return yaml.load(text, Loader=NumberLoader)  # noqa: S506 - NumberLoader is a SafeLoader

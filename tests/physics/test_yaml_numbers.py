"""A physics file written by hand loads its numbers in every usual form (YAML 1.1, which
PyYAML follows, reads an exponent without a dot as a string)."""

from __future__ import annotations

from pathlib import Path

import pytest

from hems_ros.physics.params import load_params
from hems_ros.physics.yamlload import load_yaml

TABLE41 = Path(__file__).resolve().parents[2] / "config" / "physics" / "table41.yaml"


def test_exponent_forms_load_as_floats():
    data = load_yaml("a: 5e-10\nb: 1E3\nc: -2e+4\nd: 6.89e6\ne: 12\nf: 1e3x\ng: .nan\n")
    assert (
        data["a"] == 5e-10 and data["b"] == 1000.0 and data["c"] == -20000.0 and data["d"] == 6.89e6
    )
    assert isinstance(data["b"], float) and data["e"] == 12 and data["f"] == "1e3x"


def test_a_physics_file_with_exponents_loads(tmp_path):
    text = TABLE41.read_text()
    text = text.replace(
        "drho_dt_austenite_ohm_m_per_c: 5.0e-10", "drho_dt_austenite_ohm_m_per_c: 5e-10"
    )
    text = text.replace("cm_pa_per_c: 6890000.0", "cm_pa_per_c: 6.89E6").replace(
        "length_m: 0.9", "length_m: 9e-1"
    )
    text = text.replace("density_kg_m3: 6450.0", "density_kg_m3: 645E1")
    path = tmp_path / "hand.yaml"
    path.write_text(text)
    params, reference = load_params(path), load_params(TABLE41)
    assert params.electrical.drho_dt_austenite_ohm_m_per_c == pytest.approx(5e-10)
    assert params.kinetics.cm_pa_per_c == 6.89e6 and params.wire.length_m == 0.9
    assert params.thermal.density_kg_m3 == 6450.0
    assert params.to_dict() == {
        **reference.to_dict(),
        "name": params.name,
        "description": params.description,
    }

"""The blind suite's bookkeeping: the tuning and evaluation halves never share a row, what
counts as right for each kind of truth, the detection limit, and the committed page against
a row diagnosed again here."""

from __future__ import annotations

import math
import os
import pickle
import re
import subprocess
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from hems_ros.diagnosis import blind, candidates, cluster, search, speedup
from hems_ros.diagnosis.fit import Fit
from hems_ros.diagnosis.relation import Named
from hems_ros.physics.params import UnitParams
from hems_ros.reports import blind as page
from hems_ros.reports import blind_tuning as tuning
from hems_ros.truth import cases

REPO = Path(__file__).resolve().parents[2]
PAGE = REPO / "docs" / "diagnosis.md"


def test_the_halves_split_the_rows_by_seed_and_share_none():
    tuning = blind.grid(half="tuning")
    evaluation = blind.grid(half="evaluation")
    assert {r.half for r in tuning} == {"tuning"} and {r.half for r in evaluation} == {"evaluation"}
    assert not {r.key for r in tuning} & {r.key for r in evaluation}
    everything = blind.grid()
    assert len({r.key for r in everything}) == len(everything) == len(tuning) + len(evaluation)
    # a truth only of the families it is written for (the supply's loop: the independent form)
    assert not [r for r in everything if r.family == "brinson" and r.effect == "supply_droop"]
    # every effect at every size and noise level in both halves
    assert {(r.effect, r.size, r.noise) for r in tuning} == {
        (r.effect, r.size, r.noise) for r in evaluation
    }


def test_what_counts_as_right():
    friction = cases.BY_NAME["dahl_friction"]
    assert blind.right(friction, "named", ["tendon_friction"])
    assert blind.right(friction, "partial", ["capstan_friction", "supply_sag"])
    assert not blind.right(friction, "recalibrated", [])
    assert not blind.right(friction, "named", ["encoder_gain"])
    assert blind.right(cases.BY_NAME["none"], "none", [])
    assert blind.right(cases.BY_NAME["none"], "recalibrated", [])
    assert not blind.right(cases.BY_NAME["none"], "partial", ["sheath_heat_sink"])
    drift = cases.BY_NAME["encoder_drift"]
    assert blind.right(drift, "unexplained", []) and blind.right(drift, "partial", ["ambient"])
    assert not blind.right(drift, "named", ["force_sensor_drift"])


def _record(size: float, right: bool, noise: str = "mid") -> dict:
    return {
        "family": "brinson",
        "effect": "dahl_friction",
        "kind": "effect",
        "size": size,
        "noise": noise,
        "right": right,
        "ranked_first": right,
        "verdict": "named" if right else "unexplained",
        "named": ["tendon_friction"] if right else [],
    }


def test_the_detection_limit_is_the_smallest_size_from_which_every_run_is_right():
    records = [
        _record(4.0, True),
        _record(4.0, True),
        _record(2.0, True),
        _record(1.0, False),
        _record(0.5, True),
        _record(4.0, False, "high"),
    ]
    limits = blind.detection_limits(records)
    # 0.5 N was right, but 1 N was not: the limit is where it holds from there up
    assert limits[("brinson", "dahl_friction", "mid")] == 2.0
    assert limits[("brinson", "dahl_friction", "high")] is None
    assert ("brinson", "dahl_friction", "low") not in limits
    text = page.render(records, [30.0, 40.0], "f.png")
    assert "| another model family | dahl_friction (" in text
    assert "| - | 2 N | not named up to 4 N |" in text
    assert "| another model family: an effect, named | 67% (4 of 6) | 70% |" in text
    assert "How much faster two workers run than one is measured by" in text
    measured = speedup.Speedup(8, speedup.Timing(90.0, 88.0), speedup.Timing(50.0, 96.8))
    text = page.render(records, [30.0, 40.0], "f.png", measured=measured)
    assert "8 of these tasks (taken at even steps through the grid) ran 1.80x as fast" in text
    assert "(50 s against 90 s from the call" in text
    assert "the tasks took 1.10x their time on one worker" in text


def test_the_speed_up_tasks_are_spread_through_the_grid():
    tasks = [cluster.Task(f"t{i}", print) for i in range(20)]
    assert [t.key for t in speedup.spread(tasks, 4)] == ["t0", "t5", "t10", "t15"]
    assert len(speedup.spread(tasks[:3], 8)) == 3


@pytest.mark.skipif(not PAGE.is_file(), reason="docs/diagnosis.md not generated")
def test_the_committed_page_shows_what_a_row_diagnosed_here_gives():
    row = blind.Row(*blind.QUICK[0])
    record = blind.run_row(row)
    line = next(
        line
        for line in PAGE.read_text().splitlines()
        if re.match(
            rf"\| {page.TIERS[row.family]} \| {row.effect} \| {row.size:g} \S+ \| {row.noise} \|",
            line,
        )
    )
    assert f"{record['verdict']} (" in line
    assert all(f"{name} (" in line for name in record["named"])
    # what the load relation's candidates offered at its first selection: the friction it
    # named far above the gain the search asks for
    (relation,) = record["openings"]["relation"]
    assert {"tendon_friction", "load_damping"} <= set(relation["offers"])
    assert relation["chosen"] in ("tendon_friction", "capstan_friction")
    gain, share = relation["offers"][relation["chosen"]]
    assert gain > 10 * search.RELATION_MIN_GAIN and 0.0 < share <= 1.0


def _fit(name: str, train: float, heldout: float) -> Fit:
    return Fit((candidates.BY_NAME[name],), np.zeros(1), UnitParams(), train, heldout, 100, [])


def test_the_replays_first_offers_are_counted_from_the_relations_effects_on_the_replay():
    """The load relation's costs are in its own noise units: the replay's first step offers
    against the relation's effects costed on the replayed outputs, as the search judged it."""
    start = replace(_fit("tendon_friction", 9.0, 9.0), structure=(), values=np.zeros(0))
    on_relation = _fit("tendon_friction", 1.1, 1.2)  # the relation's own costs
    on_replay = replace(on_relation, train=4.0, heldout=5.0)
    step = _fit("convection", 2.0, 2.0)
    named = Named(start, (on_relation,), (on_relation,), 0.05, None)
    found = search.Search(start, on_replay, [search.Step([step], step, [])], step, [], "named")
    found.load_relation = named
    [offers] = blind.openings(found)["replay"]
    assert offers["chosen"] == "convection"
    assert offers["offers"]["convection"] == pytest.approx([3.0, (2.0 - 1.0) / math.sqrt(8.0)])


def _opened(kind, effect, offers, chosen=None, right=True, family="brinson", replay=()) -> dict:
    """A record whose load relation offered ``offers`` and named ``chosen``."""
    openings = {"relation": [{"offers": offers, "chosen": chosen}]}
    if replay:
        openings["replay"] = [{"offers": o, "chosen": c} for o, c in replay]
    return {
        "family": family,
        "kind": kind,
        "effect": effect,
        "right": right,
        "openings": openings,
    }


def test_the_tuning_page_sets_each_threshold_between_what_null_and_hidden_truths_offered():
    records = [
        # nothing hidden: the best effect's offer counts, a recalibration's does not
        _opened("null", "none", {"load_damping": [0.04, 0.0], "ambient": [5.0, 0.5]}),
        _opened("null", "none", {"capstan_friction": [0.07, 0.0]}),
        # a hidden friction: what the candidate that named it offered there
        _opened(
            "effect",
            "dahl_friction",
            {
                "tendon_friction": [3.0, 0.9],
                "capstan_friction": [4.0, 0.9],
                "load_damping": [9.0, 0.9],
            },
            chosen="tendon_friction",
        ),
        _opened(
            "effect", "stiffening_spring", {"spring_stiffening": [0.5, 0.4]}, "spring_stiffening"
        ),
        # a hidden effect missed is not what the threshold let through
        _opened("effect", "stiffening_spring", {"spring_stiffening": [0.01, 0.0]}, right=False),
        _opened("outside", "encoder_drift", {"load_damping": [0.3, 0.1]}),
        # no force measured: no relation
        {"family": "brinson", "kind": "null", "effect": "none", "right": True, "openings": {}},
        # the replay's steps: the most any effect offered at any step, with nothing hidden;
        # read on the independent form only
        _opened(
            "null",
            "none",
            {},
            family="dissertation",
            replay=(
                ({"ambient": [5.0, 0.5], "load_damping": [0.2, 0.05]}, "ambient"),
                ({"load_damping": [0.35, 0.08], "supply_sag": [0.1, 0.02]}, None),
            ),
        ),
        _opened("null", "none", {}, replay=(({"load_damping": [9.0, 0.9]}, None),)),
    ]
    gain = tuning.THRESHOLDS[0]
    assert (gain.stage, gain.index) == ("relation", 0)
    assert tuning.spread(records, gain) == {
        "null": [0.04, 0.07],
        "effect": [3.0, 0.5],
        "outside": [0.3],
    }
    replay = {t.name: t for t in tuning.THRESHOLDS if t.stage == "replay"}
    assert tuning.spread(records, replay["MIN_GAIN"])["null"] == [0.35]
    assert tuning.spread(records, replay["MATERIAL"]) == {
        "null": [0.08],
        "effect": [],
        "outside": [],
    }
    text = tuning.render(records, "t.png")
    assert "| `RELATION_MIN_GAIN` | 0.1 | held-out gain on the load relation" in text
    assert (
        "| 0.07 (2 truths) | 0.5 (2 truths) | tells them apart: any value in [0.07, 0.5] |" in text
    )
    # a threshold the offers straddle says how many fall on the wrong side
    assert tuning._reading({"null": [0.04, 0.2], "effect": [0.05, 3.0]}, 0.1) == (
        "1 of 2 with nothing hidden at or above it, 1 of 2 hidden effects below it"
    )
    assert tuning._reading({"null": [0.04, 0.2], "effect": [0.5, 3.0]}, 0.1) == (
        "1 of 2 with nothing hidden at or above it, 0 of 2 hidden effects below it; any value "
        "in [0.2, 0.5] would tell them apart"
    )


@pytest.mark.skipif(not PAGE.is_file(), reason="docs/diagnosis.md not generated")
def test_the_committed_page_holds_its_floors_where_it_meets_them():
    """Every headline floor of the evaluation half, the null rows on their thirty runs each
    (the first six of the independent form named a capstan friction twice)."""
    shares = {
        m.group(1): (int(m.group(2)), int(m.group(3)))
        for m in re.finditer(r"^\| ([^|]+) \| \d+% \((\d+) of (\d+)\) \|", PAGE.read_text(), re.M)
    }
    held = (
        ("independent form: an effect, ranked first, low and mid noise", 0.8),
        ("independent form: nothing hidden: no effect named", 0.9),
        ("independent form: outside the library: unexplained or partial", 0.9),
        ("another model family: an effect, named", 0.7),
        ("another model family: nothing hidden: no effect named", 0.9),
        ("another model family: outside the library: unexplained or partial", 0.9),
    )
    for label, floor in held:
        right, runs = shares[label]
        assert runs >= 6 and right >= floor * runs, (label, right, runs)


def test_diagnose_blind_half_tuning_writes_the_tuning_page_from_stored_results(tmp_path):
    """The verb resumes every row from its output folder (nothing is diagnosed again) and
    writes the thresholds' page instead of the evaluation page."""
    cases_folder = tmp_path / "out" / "cases"
    cases_folder.mkdir(parents=True)
    offers = ({"tendon_friction": [4.0, 0.8]}, {"load_damping": [0.02, 0.0]})
    for row, relation in zip(blind.grid(quick=True), offers):
        effect = cases.BY_NAME[row.effect]
        record = row.identity | {
            "verdict": "named" if effect.kind == "effect" else "none",
            "named": list(effect.expected[:1]),
            "first": None,
            "openings": {"relation": [{"offers": relation, "chosen": next(iter(relation))}]},
            "right": True,
        }
        with (cases_folder / f"{row.key}{cluster.SUFFIX}").open("wb") as f:
            pickle.dump(cluster.Done(record, 1.0, "here"), f)
    docs = tmp_path / "docs" / "diagnosis-tuning.md"
    done = subprocess.run(
        [
            str(REPO / ".venv" / "bin" / "hems"),
            "diagnose-blind",
            "--quick",
            "--half",
            "tuning",
            "--out",
            str(tmp_path / "out"),
            "--docs",
            str(docs),
            "--scheduler",
            "serial",
        ],
        env=dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST"),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert "resuming: 2 of 2" in done.stderr + done.stdout
    text = docs.read_text()
    assert "| 0.02 (1 truths) | 4 (1 truths) | tells them apart: any value in [0.02, 4] |" in text
    assert (docs.parent / "figures" / "diagnosis_tuning.png").stat().st_size > 10_000
    assert (tmp_path / "out" / "tuning.md").is_file()
    assert not (tmp_path / "out" / "blind.md").exists()


TUNING_PAGE = REPO / "docs" / "diagnosis-tuning.md"


@pytest.mark.skipif(not TUNING_PAGE.is_file(), reason="docs/diagnosis-tuning.md not generated")
def test_every_threshold_lies_where_the_committed_tuning_page_tells_the_halves_apart():
    """The search's thresholds are set on the tuning half: each sits between what its truths
    with nothing hidden offered and what every hidden effect named offered."""
    rows = [line for line in TUNING_PAGE.read_text().splitlines() if line.startswith("| `")]
    assert len(rows) == len(tuning.THRESHOLDS)
    for threshold, row in zip(tuning.THRESHOLDS, rows):
        assert row.startswith(f"| `{threshold.name}` | {threshold.value:g} |"), row
        found = re.search(r"tells them apart: any value in \[([\d.e+-]+), ([\d.e+-]+)\]", row)
        assert found, row
        low, high = map(float, found.groups())
        assert low < threshold.value <= high
        assert getattr(search, threshold.name) == threshold.value

"""The records the planner's compiled steps read by field name (:mod:`viapath.planning.viapath.records`): each value
the planner packs lands in the field of its name, and no compiled step reads its settings by number."""

from __future__ import annotations

import inspect
import re
from pathlib import Path

import numpy as np
import pytest

from viapath.planning.viapath import records


def _distinct(fields, start):
    """A distinct value for each field, of its kind (float fields get a fraction)."""
    return {name: (start + k + 0.25 if code == "d" else start + k) for k, (name, code) in enumerate(fields)}


def test_choice_row_puts_each_value_in_its_field():
    episode_values = _distinct(records.CHOICE_EPISODE_FIELDS, 1)
    cycle_values = _distinct(records.CHOICE_CYCLE_FIELDS, 100)
    parameters = list(inspect.signature(records.ChoiceRow.write).parameters)[1:]
    assert parameters == [name for name, _ in records.CHOICE_CYCLE_FIELDS]
    row = records.ChoiceRow(records.choice_episode(**episode_values)).write(*cycle_values.values())
    assert row.shape == (1,) and row.dtype == records.CHOICE
    for name, value in (episode_values | cycle_values).items():
        assert getattr(row[0], name) == value, name  # attribute access, as the compiled steps read it
        assert type(row[name][0].item()) is type(value), name


def test_the_episode_is_packed_once_and_each_cycle_writes_its_fields_in_place():
    episode_values = _distinct(records.CHOICE_EPISODE_FIELDS, 1)
    episode = records.choice_episode(**episode_values)
    cycle = list(_distinct(records.CHOICE_CYCLE_FIELDS, 200).values())
    kept, other = records.ChoiceRow(episode), records.ChoiceRow(episode)
    first = kept.write(*cycle)
    assert first[0].try_step_one == 206 and first[0].only_root == 215
    second = kept.write(*cycle[:6], 0, *cycle[7:14], 7, *cycle[15:])
    assert second is first and second.flags.writeable
    assert second[0].try_step_one == 0 and second[0].only_side == 7 and second[0].only_root == 215
    assert all(getattr(second[0], name) == value for name, value in episode_values.items())
    assert not np.shares_memory(kept.row, other.row) and other.row[0].try_step_one == 0


def test_the_escape_and_the_roll_out_put_each_value_in_its_field():
    values = _distinct(records.ESCAPE_FIELDS, 3)
    assert list(inspect.signature(records.escape_settings).parameters) == list(values)
    row = records.escape_settings(*values.values())
    assert row.dtype == records.ESCAPE and [getattr(row[0], name) for name in values] == list(values.values())
    episode = records.choice_episode(zero_others=True, rollout_dt_s=0.1, rollout_steps=20)
    rollout = records.rollout_settings(episode, 0.05)
    given = {"rollout_dt_s": 0.1, "rollout_steps": 20, "corridor_tolerance_m": 0.05}
    assert {name: rollout[name][0] for name in records.CHOICE.names} == {
        name: given.get(name, 0) for name in records.CHOICE.names
    }


def test_a_record_refuses_missing_and_unknown_fields():
    values = _distinct(records.CHOICE_EPISODE_FIELDS, 1)
    del values["k2_per_s"]
    with pytest.raises(TypeError, match=r"settings: missing fields \['k2_per_s'\], unknown fields \['k2'\]"):
        records.choice_episode(**values, k2=1.0)
    with pytest.raises(TypeError, match=r"missing fields \[\], unknown fields \['horizon_s'\]"):
        records.choice_episode(zero_others=True, horizon_s=4.0)  # a cycle's field


def test_no_compiled_step_reads_its_settings_by_number():
    """The planner's compiled modules read the records by field name: no ``settings[...]``, no slot constants."""
    folder = Path(records.__file__).parent
    offending = []
    for path in sorted(folder.glob("*.py")):
        text = path.read_text()
        if "from viapath.jit import compiled" not in text:
            continue
        for number, line in enumerate(text.splitlines(), 1):
            if re.search(r"\bsettings\[|\b[FC]_[A-Z]+\b|\b_E_[A-Z]+\b|\bslots\b", line):
                offending.append(f"{path.name}:{number}: {line.strip()}")
    assert offending == []

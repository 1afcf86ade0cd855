"""The FMU state codec (altfusion.fmi.state) on core values the system tests do not reach."""

import json

import pytest

from altfusion.estimators.base import Status
from altfusion.fmi.state import StateError, StateHeader, assemble, dump, load

HEADER = StateHeader("Model", "guid", "0.1.0+x")


def test_enum_members_and_flag_combinations_round_trip():
    state = [Status.INITIALIZED, Status.INITIALIZED | Status.SAMPLE_HELD, Status(0)]
    restored = load(dump(HEADER, state), HEADER)
    assert restored == state
    assert all(type(value) is Status for value in restored)


def test_an_enum_tree_with_a_non_scalar_value_is_refused():
    body = {"$t": "enum", "class": f"{Status.__module__}:Status", "v": [1]}
    data = assemble(HEADER, json.dumps(body).encode())
    with pytest.raises(StateError, match="enum"):
        load(data, HEADER)

"""The FMU state codec (altfusion.fmi.state) on core values the system tests do not reach."""

import json
import re

import pytest

from altfusion.estimators.health import Status
from altfusion.fmi.state import StateError, StateHeader, assemble, check_like, dump, load

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


def baseline_state() -> dict:
    """A BaselineKF core in the adapter's state dict, as ``fmi2GetFMUstate`` copies it."""
    from altfusion.estimators.baseline import BaselineKF

    core = BaselineKF()
    return {"core": core, "params": {}, "step_size": 0.01, "start_time": 0.0, "failure": None}


@pytest.mark.parametrize("edit, named", [
    (lambda s: setattr(s["core"], "h_est", "x"), "state['core'].h_est is a str"),
    (lambda s: setattr(s["core"], "P", s["core"].P[:1]),
     "state['core'].P is not a square matrix"),
    (lambda s: setattr(s["core"], "P", [row[:1] for row in s["core"].P]),
     "state['core'].P is not a square matrix"),
    (lambda s: setattr(s["core"], "x", [complex(v) for v in s["core"].x]),
     "state['core'].x[0] is a complex"),
    (lambda s: setattr(s["core"], "started", 1.0), "state['core'].started is a float"),
    (lambda s: delattr(s["core"], "bias"), "lacks ['bias']"),
    (lambda s: s.update(step_size="0.01"), "state['step_size'] is a str"),
])
def test_a_decoded_state_of_another_shape_is_refused_field_by_field(edit, named):
    """Bytes with a correct checksum can still hold a wrongly typed field: check_like names
    it against the current state (which the restore would replace)."""
    current = baseline_state()
    stored = load(dump(HEADER, current), HEADER)
    check_like(stored, current)                          # a state of its own kind passes
    edit(stored)
    with pytest.raises(StateError, match=re.escape(named)):
        check_like(stored, current)


def test_unset_optional_fields_and_number_types_match():
    current = baseline_state()
    stored = load(dump(HEADER, current), HEADER)
    stored["failure"] = "a message"                      # None in the current state
    stored["core"].n_rejected = 3.0                      # a number for a number
    check_like(stored, current)


def test_a_covariance_of_another_size_with_its_parameters_is_a_state_of_its_kind():
    """YangFusionKF's state count follows its parameters (the GNSS offset state only with
    ``gps_bias_psd`` > 0), which a state brings along: a state of an instance with that
    state is restored into one without it (6 x 6 over 5 x 5); a ragged covariance is not."""
    from altfusion.estimators.yang import YangFusionKF, YangParams

    def state(params) -> dict:
        return {"core": YangFusionKF(params), "params": {}, "step_size": 0.01,
                "start_time": 0.0, "failure": None}

    with_offset = load(dump(HEADER, state(YangParams(gps_bias_psd=1e-4))), HEADER)
    current = state(YangParams(gps_bias_psd=0.0))
    assert (len(with_offset["core"].P), len(current["core"].P)) == (6, 5)
    check_like(with_offset, current)
    with_offset["core"].P = tuple(row[:5] for row in with_offset["core"].P)
    with pytest.raises(StateError, match=re.escape("state['core'].P is not a square matrix")):
        check_like(with_offset, current)

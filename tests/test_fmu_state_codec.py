"""The FMU state codec (altfusion.fmi.state) on core values the system tests do not reach."""

import json
import re

import pytest

from altfusion.estimators.health import Status
from altfusion.fmi.state import (
    StateError,
    StateHeader,
    assemble,
    check_like,
    dump,
    load,
    read_header,
)

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
    (lambda s: setattr(s["core"], "x", s["core"].x[:2]),
     "state['core'].x has 2 states where its covariance state['core'].P is 3 x 3"),
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
    with_offset["core"].P = [row[:5] for row in with_offset["core"].P]
    with pytest.raises(StateError, match=re.escape("state['core'].P is not a square matrix")):
        check_like(with_offset, current)


def test_every_estimators_state_of_one_time_is_a_state_of_its_kind_at_another():
    """fmi2GetFMUstate at one time, fmi2SetFMUstate at another (a host re-running from the
    start, or from a later point): the fault flight's seven estimators, their states at
    0 s (before any sample), 0.05 s (the first samples), 3 s and 12 s, each checked against
    each other time's. YangFusionKF's state vector and covariance were tuples before its
    first step and after a prediction, lists after an update: a state of t = 0 was refused
    at 3 s ("x is a tuple where this instance has a list")."""
    import copy
    import itertools

    from test_estimator_checksums import CoreFlight, _estimators, derived_seed, scenario

    spec, _ = scenario("nominal")
    seeds = {c.name: derived_seed(0, 7, c.name) for c in spec.components}
    estimators = _estimators(spec)
    assert len(estimators) == 7
    states = {}
    for time in (0.0, 0.05, 3.0, 12.0):
        flight = CoreFlight(spec, seeds)
        if time:
            flight.run(time, {})
        states[time] = {name: {"core": copy.deepcopy(flight.objects[name])}
                        for name in estimators}
    for (saved, restored), name in itertools.product(itertools.permutations(states, 2),
                                                     estimators):
        check_like(load(dump(HEADER, states[saved][name]), HEADER), states[restored][name])


def test_the_compiled_machinery_round_trips_as_itself():
    """An aid source with its bias window, stuck checks and noise check (native classes of
    mypyc where the build compiled them, Python classes otherwise): rebuilt blank, without
    ``__init__``, as the same classes with every field as saved; a field of another type in
    the bytes is refused (by the native class when compiled, by check_like either way)."""
    import altfusion.estimators.aid_source as aid_source
    from altfusion.compiled import is_compiled
    from altfusion.estimators.noise_check import ShownNoise
    from altfusion.estimators.stuck import StuckReadings

    source = aid_source.AidSource("baro")
    source.shown = ShownNoise(source)
    for now, y in enumerate((0.5, -0.25, 1.5)):
        source.window.add(float(now), y, 0.04, 10.0)
        source.shown.gated(y, 0.04, 0.01)
    source.refused()
    stuck = StuckReadings(("baro", "gps"), 5)
    stuck.checks["gps"].stuck(12.0, 1.0)
    state = {"source": source, "stuck": stuck}
    restored = load(dump(HEADER, state), HEADER)
    check_like(restored, state)
    copy = restored["source"]
    assert type(copy) is aid_source.AidSource and copy is not source
    assert hasattr(aid_source.AidSource, "__mypyc_attrs__") == is_compiled(aid_source)
    assert copy.shown.source is copy                    # the sharing survives
    for name in ("test_ratio", "rejected", "bits", "innovation", "last_gated"):
        assert getattr(copy, name) == getattr(source, name), name
    assert list(copy.window.samples) == list(source.window.samples)
    assert (copy.window.sum_y, copy.window.sum_S) == (source.window.sum_y, source.window.sum_S)
    assert (copy.shown.ratio, copy.shown.pairs) == (source.shown.ratio, source.shown.pairs)
    assert restored["stuck"].checks["gps"].last == 12.0

    tree = json.loads(read_header(dump(HEADER, state))[1])
    tree["v"][0][1]["v"]["rejected"] = "one"             # source.rejected: an int
    with pytest.raises(StateError, match="rejected"):
        check_like(load(assemble(HEADER, json.dumps(tree).encode()), HEADER), state)

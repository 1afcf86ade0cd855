"""Serialized FMU states are data, never code: fmi2DeSerializeFMUstate of bytes that are not a
state of this very FMU (a crafted pickle, another FMU's state, another GUID or core version,
a corrupted or truncated state, a well-formed state naming a class outside the core) is
refused (fmi2Error) with a message naming the reason, runs nothing, and leaves the instance
able to step and to restore a good state bit-exactly."""

import json
import pickle
import re

import pytest
from test_estimator_robustness import TUNING, Harness

from altfusion.cosim.instances import CosimError
from altfusion.fmi import state as fmu_state

CONTINUATION = 30
"""Steps compared after a restore (0.2 s each: at least one GPS sample every 5 steps)."""


class WritesAFile:
    """A pickle payload that, unpickled, creates the file it names."""

    def __init__(self, path):
        self.path = str(path)

    def __reduce__(self):
        return exec, (f"open({self.path!r}, 'w').write('ran')",)


def with_header(data: bytes, **changes: str) -> bytes:
    """``data`` with header fields replaced (the body and its checksum kept)."""
    header, body = fmu_state.read_header(data)
    fields = {**vars(header), **changes}
    return fmu_state.assemble(fmu_state.StateHeader(**fields), body)


def with_body(data: bytes, tree) -> bytes:
    """``data``'s header over a new, correctly checksummed body."""
    header, _ = fmu_state.read_header(data)
    return fmu_state.assemble(header, json.dumps(tree).encode())


def tick_clock(data: bytes) -> str:
    """The name the state ``data`` gives the core's TickClock class (its module lies in the
    FMU's private copy of the core, ``altfusion_<digest>.timegrid``)."""
    _, body = fmu_state.read_header(data)
    names = re.findall(r'"class":\s*"([\w.]+\.timegrid:TickClock)"', body.decode())
    assert names, "the state holds no TickClock"
    return names[0]


def yang_state(fmus) -> bytes:
    other = Harness(fmus["YangFusionKF"], TUNING["YangFusionKF"], seed=4)
    try:
        for _ in range(10):
            other.step()
        return other.instance.fmu.serializeFMUstate(other.instance.get_state())
    finally:
        other.free()


BAD_STATES = {
    "crafted pickle": (lambda good, fmus, path: pickle.dumps(WritesAFile(path)),
                       "not an altfusion FMU state"),
    "another FMU's state": (lambda good, fmus, path: yang_state(fmus),
                            "foreign state: written by model 'YangFusionKF', "
                            "this FMU is 'BaselineKF'"),
    "another GUID": (lambda good, fmus, path: with_header(good, guid="0" * 36),
                     "foreign state: written by guid '0000"),
    "another core version": (lambda good, fmus, path: with_header(good, core_version="0.0.0"),
                             "foreign state: written by core_version '0.0.0'"),
    "truncated": (lambda good, fmus, path: good[:-7], "checksum mismatch"),
    "truncated header": (lambda good, fmus, path: good[:20], "truncated state"),
    "corrupted": (lambda good, fmus, path: good[:-40] + bytes([good[-40] ^ 1]) + good[-39:],
                  "checksum mismatch"),
    "non-core class": (lambda good, fmus, path: with_body(good, {
        "$t": "object", "class": "subprocess:Popen", "v": {}}),
        "class 'subprocess:Popen' is not a core class"),
    "dunder attribute": (lambda good, fmus, path: with_body(good, {
        "$t": "object", "class": tick_clock(good), "v": {"__class__": "x"}}),
        r"attribute '__class__' of 'altfusion_\w+\.timegrid:TickClock' refused"),
    "object array": (lambda good, fmus, path: with_body(good, {
        "$t": "ndarray", "dtype": "|O", "shape": [1], "data": "AAAAAAAAAAA="}),
        "array of dtype object refused"),
}


def saved_state_and_continuation(harness: Harness):
    """After 20 steps of ``harness``: its serialized state, and a function that steps
    CONTINUATION more from there (the harness's own inputs rewound to the same point)."""
    for _ in range(20):
        harness.step()
    good = harness.instance.fmu.serializeFMUstate(harness.instance.get_state())
    rng_state, n, counts = harness.rng.bit_generator.state, harness.n, dict(harness.counts)

    def continuation():
        harness.rng.bit_generator.state = rng_state
        harness.n, harness.counts = n, dict(counts)
        return [harness.step() for _ in range(CONTINUATION)]
    return good, continuation


@pytest.mark.parametrize("kind", BAD_STATES)
def test_a_bad_state_is_refused_runs_nothing_and_leaves_the_instance_usable(fmus, tmp_path,
                                                                            kind):
    make, reason = BAD_STATES[kind]
    marker = tmp_path / "payload_ran"
    harness = Harness(fmus["BaselineKF"], TUNING["BaselineKF"], seed=4)
    try:
        good, continuation = saved_state_and_continuation(harness)

        first = continuation()
        instance = harness.instance
        # The native shim returns fmi2Error (state freed) with the reason logged as fmi2Error.
        with pytest.raises(CosimError,
                           match=f"fmi2DeSerializeFMUstate refused the state: .*{reason}"):
            instance._call("deSerializeFMUstate", instance.fmu.deSerializeFMUstate,
                           make(good, fmus, marker))
        assert not marker.exists()
        harness.step()                                 # still steps after the refusal
        harness.instance.set_state(harness.instance.fmu.deSerializeFMUstate(good))
        assert continuation() == first
    finally:
        harness.free()


def test_the_state_header_names_the_fmu_its_guid_and_core_version(fmus):
    harness = Harness(fmus["BaselineKF"], TUNING["BaselineKF"])
    try:
        data = harness.instance.fmu.serializeFMUstate(harness.instance.get_state())
    finally:
        harness.free()
    header, _ = fmu_state.read_header(data)
    assert data.startswith(fmu_state.MAGIC)
    assert header == fmu_state.StateHeader(model="BaselineKF", guid=harness.info.guid,
                                           core_version=harness.info.core_version)


def with_field(data: bytes, name: str, value) -> bytes:
    """``data`` with every object attribute ``name`` set to ``value``, correctly checksummed."""
    header, body = fmu_state.read_header(data)
    tree = json.loads(body)

    def edit(node):
        if isinstance(node, dict):
            if node.get("$t") == "object" and name in node["v"]:
                node["v"][name] = value
            for child in node.values():
                edit(child)
        elif isinstance(node, list):
            for child in node:
                edit(child)
    edit(tree)
    return fmu_state.assemble(header, json.dumps(tree).encode())


@pytest.mark.parametrize("name, value, reason", [
    ("h_est", "x", r"\.h_est is a str \('x'\) where this instance has a float"),
    ("P", {"$t": "ndarray", "dtype": "<f8", "shape": [1], "data": "AAAAAAAAAAA="},
     r"\.P is an array of float64 \[1\] where this instance has a list \(\[\["),
    ("x", {"$t": "list", "v": [0.0, 0.0]},
     r"\.x has 2 states where its covariance .*\.P is 3 x 3"),
])
def test_a_state_with_a_wrongly_typed_field_is_refused_at_set_state(fmus, name, value, reason):
    """A correct checksum does not make a state this instance's: fmi2SetFMUstate checks it
    field by field against the current state before replacing it (fmi2Error naming the
    field); the instance keeps its state and steps on as if nothing happened."""
    harness = Harness(fmus["BaselineKF"], TUNING["BaselineKF"], seed=4)
    try:
        good, continuation = saved_state_and_continuation(harness)

        instance = harness.instance
        bad = instance.fmu.deSerializeFMUstate(with_field(good, name, value))
        with pytest.raises(CosimError, match=f"setFMUstate refused the state: .*{reason}"):
            instance.set_state(bad)
        instance.set_state(instance.fmu.deSerializeFMUstate(good))
        first = continuation()
        instance.set_state(instance.fmu.deSerializeFMUstate(good))
        assert continuation() == first
    finally:
        harness.free()

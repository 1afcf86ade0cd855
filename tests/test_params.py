"""Parameter declarations and their checks (altfusion.params)."""

from dataclasses import dataclass

import pytest

from altfusion.errors import ParameterError
from altfusion.params import (
    check_params,
    coerce,
    param,
    param_infos,
    parse_boolean,
    parse_integer,
)
from altfusion.physics.atmosphere import Atmosphere, AtmosphereParams
from altfusion.physics.vertical_dynamics import VerticalDynamics, VerticalDynamicsParams


@dataclass(frozen=True)
class Example:
    mass: float = param(1.0, "kg", "a mass", positive=True)
    sigma: float = param(0.0, "m", "a deviation", min=0.0)
    count: int = param(3, None, "a count", min=1, max=5)
    flag: bool = param(False, None, "a switch")
    name: str = param("a", None, "a name")


def test_infos_carry_unit_description_and_bounds():
    infos = {i.name: i for i in param_infos(Example)}
    assert infos["mass"].unit == "kg" and infos["mass"].positive
    assert infos["count"].type is int and infos["count"].max == 5


@pytest.mark.parametrize(("field", "value", "message"), [
    ("mass", 0.0, "'mass' = 0.0: must be > 0"),
    ("sigma", -1.0, "'sigma' = -1.0: must be >= 0.0"),
    ("sigma", float("nan"), "'sigma' = nan: must be finite"),
    ("sigma", float("inf"), "'sigma' = inf: must be finite"),
    ("count", 6, "'count' = 6: must be <= 5"),
    ("count", 2.5, "'count' = 2.5: must be an integer"),
    ("name", 3, "'name' = 3: must be a string"),
])
def test_bad_values_are_rejected_naming_the_parameter(field, value, message):
    with pytest.raises(ParameterError) as error:
        check_params(Example(**{field: value}))
    assert message in str(error.value)


def test_components_reject_bad_parameters_at_construction():
    with pytest.raises(ParameterError, match="'mass' = -1.0"):
        VerticalDynamics(VerticalDynamicsParams(mass=-1.0))
    with pytest.raises(ParameterError, match="'h0' = -5.0: is below ground_h"):
        VerticalDynamics(VerticalDynamicsParams(h0=-5.0))
    with pytest.raises(ParameterError, match="'lapse_rate_period' = 0.015"):
        Atmosphere(AtmosphereParams(lapse_rate_period=0.015))


def test_coerce_converts_host_values_to_the_declared_type():
    assert coerce(Example, "count", 4.0) == 4 and isinstance(coerce(Example, "count", 4.0), int)
    assert coerce(Example, "mass", "2.5") == 2.5
    with pytest.raises(KeyError):
        coerce(Example, "nope", 1)


@pytest.mark.parametrize(("text", "value"), [
    ("true", True), ("TRUE", True), (" Yes ", True), ("1", True),
    ("false", False), ("False", False), ("no", False), ("0", False),
])
def test_a_boolean_text_is_one_of_its_words(text, value):
    assert parse_boolean(text) is value


@pytest.mark.parametrize("text", ["maybe", "", "2", "on", "truth"])
def test_any_other_boolean_text_is_refused_not_taken_as_false(text):
    with pytest.raises(ValueError, match="expected true or false"):
        parse_boolean(text)


@pytest.mark.parametrize(("text", "value"), [("3", 3), ("-2", -2), ("3.0", 3), ("1e3", 1000),
                                             ("12345678901234567890", 12345678901234567890)])
def test_an_integer_text_may_be_written_as_a_whole_number(text, value):
    assert parse_integer(text) == value and isinstance(parse_integer(text), int)


@pytest.mark.parametrize("text", ["2.5", "1e-3", "inf", "nan", "abc"])
def test_a_fraction_or_no_number_is_refused_as_an_integer_not_cut_off(text):
    with pytest.raises(ValueError):
        parse_integer(text)


@pytest.mark.parametrize(("field", "value", "message"), [
    ("count", 2.5, "'count' = 2.5: must be an integer"),
    ("flag", "maybe", "'flag' = 'maybe': must be a Boolean"),
])
def test_coerce_leaves_a_value_of_another_type_for_the_check_to_refuse(field, value, message):
    coerced = coerce(Example, field, value)
    assert coerced == value
    with pytest.raises(ParameterError) as error:
        check_params(Example(**{field: coerced}))
    assert message in str(error.value)


def test_coerce_reads_boolean_words():
    assert coerce(Example, "flag", "Yes") is True and coerce(Example, "flag", "0") is False

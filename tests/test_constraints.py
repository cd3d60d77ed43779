"""Declared constraints of a function's own arguments: ``check_argument``."""
import numpy as np
import pytest

from discrepancy.constraints import Integral, Interval, Options, Real, check_argument
from discrepancy.errors import ParameterError


def test_a_value_meeting_any_constraint_passes():
    check_argument("steps", np.int64(3), Interval(Integral, 1))
    check_argument("max_terms", None, None, Interval(Integral, 1))
    check_argument("u_hold", "zoh", Options(("linear", "zoh")))
    check_argument("compile", False, bool)


@pytest.mark.parametrize("value, allowed, message", [
    (0, [Interval(Integral, 1, 1000)], "substeps must be an integer >= 1 and <= 1000; got 0"),
    (True, [Interval(Integral, 1)], "substeps must be an integer >= 1; got True"),
    (2.5, [None, Interval(Integral, 2)], "substeps must be None or an integer >= 2; got 2.5"),
    (np.nan, [Interval(Real, 0, 1, closed="neither")],
     "substeps must be a finite number > 0 and < 1; got nan"),
    ("cubic", [Options(("linear", "zoh"))], "substeps must be one of 'linear', 'zoh'; got 'cubic'"),
])
def test_a_rejected_value_names_the_argument_what_was_expected_and_what_was_given(
        value, allowed, message):
    with pytest.raises(ParameterError) as caught:
        check_argument("substeps", value, *allowed)
    assert str(caught.value) == message

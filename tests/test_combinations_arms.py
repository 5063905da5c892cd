"""The combinations of :mod:`test_combinations` for the rheologies with Maxwell arms (standard
linear solid, Prony series): the same checks, in a file of their own so that the two test
workers share the work."""

import pytest

from test_combinations import check_combination, combinations

COMBINATIONS = combinations(("standard_linear_solid", "prony"))


@pytest.mark.parametrize("rheology,until,zone,machine,history,option", COMBINATIONS,
                         ids=["-".join(str(p) for p in c) for c in COMBINATIONS])
def test_every_setting_is_honoured_or_refused(rheology, until, zone, machine, history, option):
    check_combination(rheology, until, zone, machine, history, option)

"""Tests for armlab.runner.memory: a run's arrays without NumPy's huge-page advice, restored after."""

from __future__ import annotations

import pytest

from armlab.runner.memory import _setter, small_pages

pytestmark = pytest.mark.skipif(_setter() is None, reason="this NumPy has no huge-page switch")


@pytest.mark.parametrize("before", [True, False])
def test_the_advice_is_off_inside_and_as_before_after(before):
    setter = _setter()
    original = setter(before)
    try:
        with small_pages():
            assert setter(False) is False  # returns the value set inside the block
        assert setter(before) is before  # restored on leaving
        with pytest.raises(RuntimeError), small_pages():
            raise RuntimeError("a run that fails")
        assert setter(before) is before  # restored on an error too
    finally:
        setter(original)


def test_a_run_function_decorated_with_it_runs_without_the_advice():
    setter = _setter()

    @small_pages()
    def inside() -> bool:
        return setter(False)  # what was set while the function ran

    original = setter(True)
    try:
        assert inside() is False
        assert setter(True) is True
    finally:
        setter(original)

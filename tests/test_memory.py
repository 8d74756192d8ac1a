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


def test_frozen_views_and_their_bases_are_made_writeable_again_in_either_order():
    # a saved channel can be a view of another saved array (Scene.sensors_of): thawing must not
    # depend on the order they were frozen in
    import numpy as np

    from armlab.runner.run import _freeze, _thaw

    for order in ("view first", "base first"):
        base = np.zeros((4, 6))
        view = base[:, 2:4]
        frozen = _freeze([view, base] if order == "view first" else [base, view])
        assert not base.flags.writeable and not view.flags.writeable
        _thaw(frozen)
        assert base.flags.writeable and view.flags.writeable, order

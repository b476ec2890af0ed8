"""The progress bar of a run counts the path D(t), and says how much time was lost."""

from __future__ import annotations

from dualarm_qp.experiments.run import _progress


def test_the_bar_counts_the_path_and_shows_the_time_lost() -> None:
    bar, update = _progress("beam", True)
    assert bar is not None
    try:
        update(0.0, 0.0)
        update(0.5, 0.25)
        text = str(bar)
        assert text.startswith("beam:  50% of the path |"), text
        assert text.endswith(", time lost to slowing 0.25 s"), text
        update(1.0, 0.651)  # a slowed run: more samples than nominal, still 100%
        text = str(bar)
        assert text.startswith("beam: 100% of the path |"), text
        assert text.endswith("time lost to slowing 0.65 s"), text
    finally:
        bar.close()


def test_no_bar_when_not_shown() -> None:
    bar, update = _progress("beam", False)
    assert bar is None
    update(0.5, 0.0)  # the callback still runs (it checks for swallowed interrupts)

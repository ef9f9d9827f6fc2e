"""A fragment that grows and grows with its hypotheses still apart is given up on, and the
map records the ambiguity (ExplorerParams.fragment_max). fig15 seed 5 at drift paper, with
``cut_past`` and ``past_candidates`` on, grew one fragment over the whole run: at each
arrival some move split the hypotheses by the old nodes they predicted, nodes that look
alike, so the robot saw the same whichever was right, and fig15's ambiguity was never
reported."""

from __future__ import annotations

from dataclasses import replace

import pytest

from tslam.core.explorer import ExplorerParams
from tslam.programs.sim_cmd import explore, report


@pytest.mark.parametrize("bound", [30, 0])
def test_fig15_records_its_ambiguity_once_the_fragment_has_grown_too_far(bound):
    # Without ``test_paths`` and with hypotheses ageing out after two silent arrivals, as
    # when the bound was made: with them, the robot goes back to test the hypotheses, the
    # fragment grows to 8 nodes only, and the ambiguity is recorded before any bound is
    # reached (the test below).
    # Nor with ``merge_compatible``: a proven placement held up only by rivals that said
    # nothing against it merges at 714 s, and the ambiguity is recorded before the bound.
    params = replace(
        ExplorerParams(),
        fragment_max=bound,
        test_paths=False,
        silent_life=2,
        merge_compatible=False,
    )
    run = explore("fig15", 5, "paper", duration_s=1300.0, progress=False, params=params)
    rep = report(run, "fig15", 5, "paper")
    assert rep["false_merges"] == 0
    notes = [n.text for n in run.explorer.notes if "no move has told" in n.text]
    if bound:
        assert notes and rep["ambiguous_nodes"] > 0, rep
        # The fragment was given up at the bound, not before it.
        sizes = [int(t.split(": ")[1].split()[0]) for t in notes]
        assert min(sizes) >= bound
    else:
        assert not notes and rep["ambiguous_nodes"] == 0, rep


def test_fig15_testing_its_hypotheses_records_the_ambiguity_before_the_bound():
    run = explore("fig15", 5, "paper", duration_s=1300.0, progress=False)
    rep = report(run, "fig15", 5, "paper")
    assert rep["false_merges"] == 0 and rep["ambiguous_nodes"] > 0, rep
    assert not [n for n in run.explorer.notes if "no move has told" in n.text]
    assert any("is ambiguous with" in n.text for n in run.explorer.notes)

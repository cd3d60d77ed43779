"""The cart leaderboard end to end (quick mode).

One campaign per module, so that the test workers run the campaigns side by side."""
import numpy as np
import pytest

from campaigns import CONTROLLERS, quick_run


@pytest.fixture(scope="module")
def grid(tmp_path_factory):
    return quick_run("cart-leaderboard", tmp_path_factory)


@pytest.mark.slow
def test_leaderboard_maps_agree_with_its_cells(grid):
    out, res = grid
    assert (out / "success_maps.png").stat().st_size > 1000
    cells = res["grid"]["cells"]
    assert len(cells) == res["grid"]["n_cells"] == 2
    for c in CONTROLLERS:
        assert res["grid"]["success_counts"][c] == sum(r[c]["success"] for r in cells)
        flat = np.concatenate([np.ravel(m) for m in res["success_maps"][c].values()])
        assert flat.sum() == res["grid"]["success_counts"][c]
    assert all(not r["flawed + TVLQR"]["success"] for r in cells)
    assert all(r["hybrid + MPC + re-identification"]["success"] for r in cells)


def test_the_deferred_first_log_is_fitted_once_before_the_first_new_log():
    """The same updates in the same order as fitting the flawed log up front; none when no
    attempt fails."""
    from discrepancy_paper.experiments.cart_leaderboard import FirstLogDeferred

    class Recorder:
        def __init__(self):
            self.calls = []

        def update(self, x, t, *, u):
            self.calls.append((x, t, u))
            return len(self.calls)

    unused = Recorder()
    FirstLogDeferred(unused, ("y0", 0.02, "u0"))
    assert unused.calls == []
    recorder = Recorder()
    deferred = FirstLogDeferred(recorder, ("y0", 0.02, "u0"))
    assert deferred.update("y1", 0.02, u="u1") == 2
    assert deferred.update("y2", 0.02, u="u2") == 3
    assert recorder.calls == [("y0", 0.02, "u0"), ("y1", 0.02, "u1"), ("y2", 0.02, "u2")]

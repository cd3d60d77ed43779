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

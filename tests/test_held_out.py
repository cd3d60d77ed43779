"""Forecast windows kept beside the statistics: which samples, which fold, whatever the
arrival (whole, in chunks, merged), against indices computed by hand."""
import numpy as np

from discrepancy.fitting.held_out import HeldOutWindows


def feed(held, pieces, first_row=0):
    held.begin(first_row)
    for t, x in pieces:
        held.add(t, x, None)
    held.end()
    return held


def data(m):
    t = np.arange(m) * 0.1
    return t, np.column_stack([np.arange(m), -np.arange(m)]).astype(float)


def test_windows_start_at_segment_starts_with_their_halo_and_fold():
    t, x = data(100)
    held = feed(HeldOutWindows(segment=16, n_folds=5, pre=3, max_lead=20), [(t, x)])
    origins = [16, 32, 48, 64, 80, 96]          # 0 lacks the 3 samples before it
    assert [int(w.x[w.origin, 0]) for w in held.windows] == origins
    for w, o in zip(held.windows, origins, strict=True):
        expected = np.arange(o - 3, min(100, o + 21))
        np.testing.assert_array_equal(w.x[:w.filled, 0], expected)
        assert w.fold == (o // 16) % 5
    assert held.windows[-1].lead == 3             # samples 97..99 after the last origin
    np.testing.assert_array_equal(held.low, [0, -99])
    np.testing.assert_array_equal(held.high, [99, 0])


def test_chunks_of_any_size_give_the_same_windows():
    t, x = data(300)
    whole = feed(HeldOutWindows(segment=32, n_folds=5, pre=5, max_lead=40), [(t, x)])
    for size in (1, 7, 33, 64):
        pieces = [(t[i:i + size], x[i:i + size]) for i in range(0, 300, size)]
        chunked = feed(HeldOutWindows(segment=32, n_folds=5, pre=5, max_lead=40), pieces)
        assert len(chunked.windows) == len(whole.windows)
        for a, b in zip(whole.windows, chunked.windows, strict=True):
            assert (a.fold, a.origin, a.filled) == (b.fold, b.origin, b.filled)
            np.testing.assert_array_equal(a.x[:a.filled], b.x[:b.filled])


def test_windows_kept_through_thinning_hold_their_samples_whatever_the_chunks():
    """Windows thinned away are never filled; the kept ones hold exactly their samples
    (halo before the origin, lead after it), whether the data arrive whole or in pieces."""
    t, x = data(2000)
    for size in (2000, 1, 45, 500):
        pieces = [(t[i:i + size], x[i:i + size]) for i in range(0, 2000, size)]
        held = feed(HeldOutWindows(segment=32, n_folds=5, pre=6, max_lead=50, max_windows=3),
                    pieces)
        origins = list(range(32, 2000, 32))            # 0 lacks the 6 samples before it
        expected = []
        for o in origins:
            expected.append(o)
            if len(expected) > 6:
                expected = expected[::2]
        assert [int(w.x[w.origin, 0]) for w in held.windows] == expected, size
        for w in held.windows:
            o = int(w.x[w.origin, 0])
            np.testing.assert_array_equal(w.x[:w.filled, 0], np.arange(o - 6, min(2000, o + 51)))


def test_rows_continue_across_trajectories_and_thinning_keeps_every_other():
    t, x = data(70)
    held = HeldOutWindows(segment=10, n_folds=5, pre=0, max_lead=5, max_windows=3)
    feed(held, [(t, x)], first_row=0)       # origins at rows 0, 10, ..., 60
    feed(held, [(t, x + 1000)], first_row=70)   # rows 70..139: origins at samples 0, 10...
    # 14 origins registered; at the 7th the list (7 > 6) was halved to 4, and so on
    kept = [int(w.x[w.origin, 0]) for w in held.windows]
    order = list(range(0, 70, 10)) + [1000 + s for s in range(0, 70, 10)]
    expected = []
    for o in order:
        expected.append(o)
        if len(expected) > 6:
            expected = expected[::2]
    assert kept == expected
    folds = {int(w.x[w.origin, 0]): w.fold for w in held.windows}
    for value, fold in folds.items():
        row = value if value < 1000 else 70 + value - 1000
        assert fold == (row // 10) % 5


def test_merging_adds_windows_in_order_and_widens_the_range():
    t, x = data(50)
    a = feed(HeldOutWindows(segment=10, n_folds=5, pre=0, max_lead=5), [(t, x)])
    b = feed(HeldOutWindows(segment=10, n_folds=5, pre=0, max_lead=5), [(t, 3 * x)])
    a.merge(b)
    assert [int(w.x[w.origin, 0]) for w in a.windows] == [0, 10, 20, 30, 40, 0, 30, 60, 90,
                                                          120]
    np.testing.assert_array_equal(a.high, [147, 0])

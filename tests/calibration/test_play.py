"""The play operators of the causal compensation, against their definition.

Reference: the play (backlash) operator p_t = max(w_t − r, min(w_t + r, p_{t−1})) (Brokate & Sprekels 1996,
ch. 2) and a noisy ramp whose one reversal is known by construction.
"""

from __future__ import annotations

import numpy as np

from fsrlab.calibration.play import causal_features


def test_play_operators_follow_their_closed_form():
    # Reference: the play operator's definition. Loading from rest to w: p = w - r; after a
    # reversal p holds until w has fallen by 2r, then p = w + r.
    w = np.concatenate([np.linspace(0, 0.5, 51), np.linspace(0.5, 0.2, 31)[1:]])
    r = 0.05
    p, _, d = causal_features(w, (r,), ())
    up = w[:51]
    np.testing.assert_allclose(p[:51, 0], np.maximum(up - r, 0), atol=1e-15)
    down = w[51:]
    np.testing.assert_allclose(p[51:, 0], np.minimum(0.45, down + r), atol=1e-15)


def test_reversal_detection_survives_noise():
    # A slow ramp up then down with noise of ±0.4 % FS (smaller than the 1 % direction threshold):
    # the direction must change once (one reversal), never flicker.
    rng = np.random.default_rng(0)
    w = np.concatenate([np.linspace(0, 0.8, 800), np.linspace(0.8, 0.1, 700)]) + rng.uniform(-0.004, 0.004, 1500)
    _, _, d = causal_features(w, (), ())
    moving = d[d != 0]
    assert np.count_nonzero(np.diff(moving)) == 1

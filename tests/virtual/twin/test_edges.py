"""Edge streaming of the digital twin (fsrlab.virtual.twin.edges): chunks joined = one run of the transient.

Reference: fsrlab.circuits.transient.simulate run once over the whole time series (the source's
grid, zero-order hold, and the C_off switch as one more sample), the exact event-driven transient.
Property: however the stream is cut into chunks (any look-ahead, a switch of C_off anywhere), the
edges it emits are those of the one run, in order, none lost or repeated. Cuts at rising edges and
falling edges restart from the exact state (bit-identical edges); a cut at a chunk's end with the
output high carries the voltage over an RC segment split in two (exp(-a)·exp(-b) vs exp(-(a+b)):
rounding, 1e-12 s allowed).
"""

from __future__ import annotations

import numpy as np
import pytest

from fsrlab.virtual.sources import PhysicsSource, StressProfile
from fsrlab.virtual.twin.edges import EdgeStream

TOL_S = 1e-12


def one_shot(stream: EdgeStream, t_end: float):
    """Rising and falling edges of one transient run over [0, t_end) with the stream's range series."""
    times = stream.sample_times(0.0, t_end)
    r, c = stream.parts(times)
    res = stream.circuit.simulate(r, c, time_s=times)
    return res.rising_s, res.falling_s


def joined(chunks):
    t = np.concatenate([c.t_s for c in chunks])
    level = np.concatenate([c.level for c in chunks])
    return t[level == 1], t[level == 0]


def check_same(rising, falling, ref_rising, ref_falling, t_end):
    ref_r, ref_f = ref_rising[ref_rising < t_end], ref_falling[ref_falling < t_end]
    r, f = rising[rising < t_end], falling[falling < t_end]
    assert r.size == ref_r.size and f.size == ref_f.size, (r.size, ref_r.size, f.size, ref_f.size)
    assert r.size > 10
    np.testing.assert_allclose(r, ref_r, rtol=0, atol=TOL_S)
    np.testing.assert_allclose(f, ref_f, rtol=0, atol=TOL_S)


@pytest.mark.parametrize("kind,peak,seed", [("triangle", 50e3, 1), ("sine", 20e3, 2), ("steps", 60e3, 3),
                                            ("hold", 10e3, 4)])
def test_chunks_joined_equal_one_run(kind, peak, seed):
    source = PhysicsSource(StressProfile(kind, peak_pa=peak, period_s=0.5))
    stream = EdgeStream(source)
    rng = np.random.default_rng(seed)
    chunks, t = [], 0.0
    while t < 0.6:
        t += float(rng.uniform(1e-4, 0.03))  # look-aheads from shorter than a period to many grid steps
        chunks.append(stream.advance(t))
    for a, b in zip(chunks, chunks[1:], strict=False):
        assert b.first_index == a.first_index + a.t_s.size  # indices continue: nothing lost or repeated
        assert b.done_s >= a.done_s
    rising, falling = joined(chunks)
    assert np.all(np.diff(np.concatenate([c.t_s for c in chunks])) > 0)
    ref_r, ref_f = one_shot(stream, stream.done_s)
    check_same(rising, falling, ref_r, ref_f, stream.done_s)


@pytest.mark.parametrize("t_switch,range_", [(0.1234567, 1), (0.0501, 1)])
def test_switch_recomputes_from_the_change(t_switch, range_):
    """A switch after the stream ran ahead: the consumer's edges before it plus the recomputed ones
    equal one run with the capacitance stepping at the switch."""
    source = PhysicsSource(StressProfile("triangle", peak_pa=50e3, period_s=0.5))
    stream = EdgeStream(source)
    first = stream.advance(t_switch + 0.04)  # look-ahead past the switch
    consumed = int(np.sum(first.t_s < t_switch))  # what the firmware had seen at the switch
    again = stream.switch(t_switch, range_, consumed, t_switch + 0.05)
    assert again.first_index == consumed
    more = stream.advance(0.3)
    rising, falling = joined([type(first)(first.t_s[:consumed], first.level[:consumed], 0, t_switch), again, more])
    ref_r, ref_f = one_shot(stream, stream.done_s)
    check_same(rising, falling, ref_r, ref_f, stream.done_s)
    # and C_off does act: the periods after the switch are longer than without it (independent check:
    # the steady period grows with the capacitance, eqs. 21 and 33)
    plain = one_shot(EdgeStream(source), stream.done_s)[0]
    after = rising[rising > t_switch + 0.01]
    before = plain[plain > t_switch + 0.01]
    assert np.mean(np.diff(after[:50])) > 1.2 * np.mean(np.diff(before[:50]))


def test_memory_bounded_with_forget():
    source = PhysicsSource(StressProfile("sine", peak_pa=30e3, period_s=1.0))
    stream = EdgeStream(source)
    t = 0.0
    for _ in range(400):
        t += 0.025
        stream.advance(t)
        stream.forget_before(t - 0.05)
    assert len(stream._cuts) <= 5  # the state since the consumer's position only

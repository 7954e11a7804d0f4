"""The meter's hardware constants: the Uno's clock and timer tick, its ADC, the capture limit.

The circuits' models (the decoding of tick sums, the design's frequency band), the meter model and the
serial protocol all use these numbers; they live here, below every layer, so that the circuits do not
depend on the acquisition code. ``docs/protocol.md`` gives them with the frames that carry them.
"""

__all__ = ["F_CPU", "TICK_S", "ADC_BITS", "ADC_COUNTS", "ADC_VREF_V", "ADC_V_PER_COUNT", "CAPTURE_MAX_HZ"]

F_CPU = 16_000_000
"""ATmega328P clock of the Arduino Uno. [Hz]"""
TICK_S = 62.5e-9
"""One Timer1 tick at prescaler 1 (1/F_CPU); all tick counts on the wire use it. [s]"""
ADC_BITS = 10
"""Resolution of the Uno's ADC (the ``adc`` field of an ``M`` frame). [bit]"""
ADC_COUNTS = 2**ADC_BITS
"""Number of ADC codes, 0..1023."""
ADC_VREF_V = 5.0
"""ADC reference: the Uno's default AVcc reference. [V]"""
ADC_V_PER_COUNT = ADC_VREF_V / ADC_COUNTS
"""One ADC step, ``Vref/1024`` (code = floor(V·1024/Vref)). [V]"""
CAPTURE_MAX_HZ = 50e3
"""Highest signal frequency the firmware captures every edge of, at 5 to 95 % duty cycle. [Hz]

The supported range, 10 Hz to 50 kHz, is checked in simavr by ``tests/firmware/test_firmware_sim.py``;
the upward search of ``benchmarks/bench_firmware.py`` (simavr, 4 % steps) measured the last clean
frequency at 52.5 kHz at 5 and 95 % duty cycle and 54.6 kHz at 50 % (``docs/performance.md``,
``firmware/README.md``, "Limits"). Above it windows report ``missed > 0``. Not yet measured on an Uno."""

"""Protocol version 3 on the host: the channel mask, the v3 measurement frame, the scan commands.

References: docs/protocol.md (version 3: ``SCAN`` mask 1..255 with bit k = channel k, ``DWELL`` 1..60000 ms,
``SETTLE`` 0..100; the ``M`` frame's ``channel`` 0..7 and ``scan`` 0..65535 appended once a SCAN was
accepted); the firmware's answers to the same commands are checked in simavr
(tests/firmware/test_firmware_scan.py, tests/acquisition/test_conformance.py).
"""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fsrlab.acquisition import protocol as P
from fsrlab.acquisition.messages import Measurement
from fsrlab.acquisition.stream import Scan
from fsrlab.errors import ParameterError


@given(st.sets(st.integers(0, 7), min_size=1))
def test_mask_round_trip(channels):
    # property: mask_channels(channel_mask(c)) = sorted(c), and the mask is the sum of 2^k
    mask = P.channel_mask(channels)
    assert mask == sum(1 << k for k in channels)
    assert P.mask_channels(mask) == tuple(sorted(channels))


@pytest.mark.parametrize("text, channels", [("0-7", tuple(range(8))), ("0,2,5", (0, 2, 5)), ("1-3,6", (1, 2, 3, 6)),
                                            ("4", (4,)), (" 3 , 1 ", (1, 3))])
def test_parse_channels(text, channels):
    assert P.parse_channels(text) == channels


@pytest.mark.parametrize("text", ["", "8", "0-8", "3-1", "a", "1,1", "0-", "-3", "1.5"])
def test_bad_channels_name_the_parameter(text):
    with pytest.raises(ParameterError) as err:
        P.parse_channels(text)
    assert err.value.parameter == "text"


@pytest.mark.parametrize("mask", [0, 256, -1, True, 1.0])
def test_bad_mask(mask):
    with pytest.raises(ParameterError):
        P.mask_channels(mask)


@pytest.mark.parametrize("name, value", [("SCAN", 0), ("SCAN", 256), ("DWELL", 0), ("DWELL", 60001),
                                         ("SETTLE", 101), ("SETTLE", None), ("DWELL", 2.5), ("SCAN", "3"),
                                         ("SETTLE", float("nan"))])
def test_bad_scan_commands_are_refused_before_sending(name, value):
    # Reference: the ranges docs/protocol.md gives (SCAN 1..255, DWELL 1..60000 ms, SETTLE 0..100).
    with pytest.raises(ParameterError, match=name) as err:
        P.encode_command(name, value)
    assert err.value.parameter == "value"


@pytest.mark.parametrize("line, token", [(b"SCAN 0\n", "SCAN"), (b"DWELL 0\n", "DWELL"), (b"SETTLE 101\n", "SETTLE"),
                                         (b"SCAN\n", "SCAN")])
def test_parse_command_gives_the_firmwares_error(line, token):
    with pytest.raises(P.CommandError) as err:
        P.parse_command(line)
    assert (err.value.code, err.value.token) == (P.ERR_BAD_VALUE, token)


def test_v3_frame_carries_channel_and_scan():
    fields = (1234, 3, 26, 83200, 20800, 0, 409, 0, 0, 0, 0, 5, 65535)
    frame = P.FrameParser().feed(P.encode_frame("M", 7, fields))[0]
    m = Measurement.from_frame(frame)
    assert (m.channel, m.scan, m.window_ms, m.periods) == (5, 65535, 3, 26)
    assert m.frequency_hz == pytest.approx(26 * 16e6 / 83200)  # the decoding formula, docs/protocol.md
    v2 = Measurement.from_frame(P.FrameParser().feed(P.encode_frame("M", 8, fields[:11]))[0])
    assert (v2.channel, v2.scan) == (0, None)


@pytest.mark.parametrize("channel, scan", [(8, 0), (0, 65536)])
def test_v3_frame_values_out_of_range_are_malformed(channel, scan):
    fields = ("1", "3", "26", "83200", "20800", "0", "409", "0", "0", "0", "0", str(channel), str(scan))
    payload = ",".join(("M", "1") + fields).encode()
    parser = P.FrameParser()
    assert parser.feed(b"$" + payload + b"*%04X\r\n" % P.crc16(payload)) == []
    assert parser.malformed == 1


def test_scan_settings_are_checked():
    assert Scan((3, 1)).channels == (1, 3) and Scan((3, 1)).mask == 0b1010
    for kwargs, parameter in (({"dwell_ms": 0}, "dwell_ms"), ({"settle": 101}, "settle"),
                              ({"dwell_ms": 2.5}, "dwell_ms")):
        with pytest.raises(ParameterError) as err:
            Scan((0, 1), **kwargs)
        assert err.value.parameter == parameter
    with pytest.raises(ParameterError) as err:
        Scan(())
    assert err.value.parameter == "channels"

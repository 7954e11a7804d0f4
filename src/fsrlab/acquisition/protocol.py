"""Serial protocol (version 3; versions 1 and 2 still read) between the fsrlab meter (Arduino firmware) and the
host: pure framing, no I/O.

The device sends one ASCII frame per line, ``$<TYPE>,<SEQ>[,<field>...]*<CRC>\\r\\n``, where CRC is
CRC-16/CCITT-FALSE over the bytes strictly between ``$`` and ``*``; the host sends short command
lines (``WINDOW 100\\n``). ``docs/protocol.md`` is the normative description; this module is its
one implementation on the host (the firmware in ``firmware/`` and the virtual device match it).

The frames' meaning in physical units (:class:`~fsrlab.acquisition.messages.Measurement` and the
other messages) is :mod:`fsrlab.acquisition.messages`. Everything here works on bytes and returns values: the transport
(:mod:`fsrlab.acquisition.serial_link`)
only moves bytes, as in pyserial's ``serial.threaded`` framing classes.

References
----------
.. [1] Matute, A., Paredes-Madrid, L., Gutierrez, E., Vargas, C. A. P. (2018). A Novel and
   Inexpensive Approach for Force Sensing Based on FSR Piezocapacitance Aimed at Hysteresis
   Error Reduction. Journal of Sensors, 2018, 6561901. doi:10.1155/2018/6561901
"""

from __future__ import annotations

import binascii
import math
import numbers
from dataclasses import dataclass, field

from fsrlab.errors import FsrlabError, ParameterError
from fsrlab.hardware import ADC_BITS, ADC_COUNTS, ADC_V_PER_COUNT, ADC_VREF_V, CAPTURE_MAX_HZ, F_CPU, TICK_S

__all__ = [
    "PROTOCOL_VERSION", "SUPPORTED_PROTOCOLS", "M_FIELDS_V1", "M_FIELDS_V2", "M_FIELDS_V3", "CHANNELS",
    "SCAN_MASK_MAX", "DWELL_MS_MIN", "DWELL_MS_MAX", "DWELL_MS_DEFAULT", "SETTLE_MAX", "SETTLE_DEFAULT",
    "channel_mask", "mask_channels", "parse_channels", "HX711_MIN", "HX711_MAX", "F_CPU", "TICK_S", "ADC_BITS",
    "ADC_COUNTS", "ADC_VREF_V", "ADC_V_PER_COUNT", "DEFAULT_BAUD", "MAX_LINE", "MAX_COMMAND", "SEQ_MODULO",
    "UINT32_MODULO", "CAPTURE_MAX_HZ",
    "WINDOW_MS_MIN", "WINDOW_MS_MAX", "WINDOW_MS_DEFAULT", "DEVICE_NAME", "FRAME_TYPES", "COMMANDS",
    "ERR_UNKNOWN_COMMAND", "ERR_BAD_VALUE", "ERR_LINE_TOO_LONG",
    "ProtocolError", "CommandError", "Frame",
    "ParserStats", "FrameParser", "crc16", "encode_frame", "encode_command", "parse_command", "check_fields",
    "max_frame_rate", "min_frame_length", "max_frame_length",
]

PROTOCOL_VERSION = 3
"""Version of this protocol, sent in the ``ID`` frame of a current device (and the virtual device)."""
SUPPORTED_PROTOCOLS = (1, 2, 3)
"""Versions the host reads: version 1 (no reference fields) and 2 (no channel) devices keep working."""
M_FIELDS_V1 = 8
"""Fields after ``SEQ`` of a version-1 ``M`` frame (``t_ms`` .. ``range``)."""
M_FIELDS_V2 = 11
"""Fields after ``SEQ`` of a version-2 ``M`` frame: version 1's plus ``ref_ok``, ``ref_n``, ``ref_mean``."""
M_FIELDS_V3 = 13
"""Fields after ``SEQ`` of a version-3 ``M`` frame: version 2's plus ``channel``, ``scan``."""
CHANNELS = 8
"""Channels of the meter's multiplexer (a CD74HC4051: 0..7)."""
SCAN_MASK_MAX = 2**CHANNELS - 1
"""Largest channel mask of ``SCAN`` (bit k = channel k; at least one bit set)."""
DWELL_MS_MIN, DWELL_MS_MAX, DWELL_MS_DEFAULT = 1, 60000, 3
"""Allowed and boot values of the counting time per channel in a scan of more than one channel. [ms]"""
SETTLE_MAX, SETTLE_DEFAULT = 100, 2
"""Largest and boot value of ``SETTLE``: periods discarded after the first edge that follows a switch."""
HX711_MIN, HX711_MAX = -(2**23), 2**23 - 1
"""Range of the HX711's 24-bit two's-complement output (``ref_mean`` of an ``M`` frame). [count]"""
DEFAULT_BAUD = 115200
"""Default line rate, 8N1. [bit/s]"""
MAX_LINE = 112
"""Longest device frame, from ``$`` to ``\\n`` inclusive (version 1 allowed 96). [byte]"""
MAX_COMMAND = 32
"""Longest host command line, ``\\n`` included. [byte]"""
SEQ_MODULO = 65536
"""Sequence numbers run 0..65535 and wrap."""
UINT32_MODULO = 2**32
"""Integers on the wire are unsigned 32-bit: ``t_ms`` wraps modulo 2³², tick sums stay below it."""
WINDOW_MS_MIN, WINDOW_MS_MAX, WINDOW_MS_DEFAULT = 10, 60000, 100
"""Allowed and boot values of the measurement window. [ms]"""
DEVICE_NAME = "fsrlab-meter"
"""Device name in the ``ID`` frame."""

ERR_UNKNOWN_COMMAND, ERR_BAD_VALUE, ERR_LINE_TOO_LONG = 1, 2, 3
"""Codes of ``$ERR`` frames."""

_U32 = UINT32_MODULO - 1
# Per type: number of fields after TYPE and SEQ (min, max).
FRAME_TYPES: dict[str, tuple[int, int]] = {"M": (M_FIELDS_V1, M_FIELDS_V3), "ID": (4, 4), "ACK": (1, 2), "ERR": (2, 2)}
"""Frame types and how many fields follow ``SEQ`` (minimum, maximum; an ``M`` frame has exactly
:data:`M_FIELDS_V1`, :data:`M_FIELDS_V2` or :data:`M_FIELDS_V3`)."""
# Commands and the allowed range of their value (None: takes no value).
COMMANDS: dict[str, tuple[int, int] | None] = {
    "ID": None, "START": None, "STOP": None,
    "WINDOW": (WINDOW_MS_MIN, WINDOW_MS_MAX), "RANGE": (0, 1),
    "SCAN": (1, SCAN_MASK_MAX), "DWELL": (DWELL_MS_MIN, DWELL_MS_MAX), "SETTLE": (0, SETTLE_MAX),
}
"""Host commands and the inclusive range of their value (``None``: no value); ``SCAN``, ``DWELL`` and
``SETTLE`` are version 3's."""

_HEX = frozenset(b"0123456789ABCDEF")
_DOLLAR, _NL, _CR, _STAR = 0x24, 0x0A, 0x0D, 0x2A


class ProtocolError(FsrlabError, ValueError):
    """A frame or value that the protocol does not allow.

    Parameters
    ----------
    reason, parameter
        As for :class:`~fsrlab.errors.FsrlabError`: the message and the parameter at fault.
    """


class CommandError(ProtocolError):
    """A host command the device rejects.

    Parameters
    ----------
    message : str
        What is wrong.
    code : int
        ``$ERR`` code: 1 unknown command, 2 bad value, 3 line too long.
    token : str
        ``$ERR`` token: the command word (``LINE`` for code 3).
    """

    def __init__(self, message: str, code: int, token: str) -> None:
        super().__init__(message)
        self.code = code
        self.token = token


def crc16(payload: bytes) -> int:
    """CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, not reflected, no final xor).

    Parameters
    ----------
    payload : bytes
        The bytes strictly between ``$`` and ``*`` (bytes, bytearray or memoryview).

    Returns
    -------
    int
        The checksum, 0..65535 (``crc16(b"123456789") == 0x29B1``, the catalogue check value).
    """
    if not isinstance(payload, bytes | bytearray | memoryview):
        raise ParameterError(f"must be bytes, got {type(payload).__name__}", parameter="payload")
    return binascii.crc_hqx(payload, 0xFFFF)


@dataclass(frozen=True, slots=True)
class Frame:
    """One intact device frame.

    Attributes
    ----------
    kind : str
        ``M``, ``ID``, ``ACK`` or ``ERR``.
    seq : int
        Sequence number 0..65535.
    fields : tuple of str
        The fields after ``SEQ``, as sent.
    gap : int
        Frames missing from the sequence just before this one (lost or corrupted); not part of equality.
    reset : bool
        True when this frame shows that the device restarted (a boot ``ID`` with sequence 0 out of
        turn, or a backward jump of the sequence).
    """

    kind: str
    seq: int
    fields: tuple[str, ...] = ()
    gap: int = field(default=0, compare=False)
    reset: bool = field(default=False, compare=False)

    def encode(self) -> bytes:
        """The frame's bytes on the wire (``$...*CRC\\r\\n``)."""
        return encode_frame(self.kind, self.seq, self.fields)


def encode_frame(kind: str, seq: int, fields=()) -> bytes:
    """Build a device frame, checksum and line end included.

    Parameters
    ----------
    kind : str
        Frame type, one of :data:`FRAME_TYPES`.
    seq : int
        Sequence number, 0..65535.
    fields : sequence of int or str
        Fields after ``SEQ``: integers (written in decimal; negative only where the protocol has a
        signed field, ``ref_mean``) or printable ASCII tokens without ``,``, ``*``, ``$``, CR or LF.

    Returns
    -------
    bytes
        ``$<kind>,<seq>[,<field>...]*<CRC>\\r\\n``, at most :data:`MAX_LINE` bytes.

    Raises
    ------
    ParameterError
        When ``kind``, ``seq`` or a field is not allowed, or the frame would be too long.
    """
    _check_frame_args(kind, fields)
    if isinstance(seq, bool) or not isinstance(seq, int) or not 0 <= seq < SEQ_MODULO:
        raise ParameterError(f"must be an integer in 0..65535, got {seq!r}", parameter="seq")
    lo, hi = FRAME_TYPES[kind]
    if not lo <= len(fields) <= hi:
        raise ParameterError(f"a {kind} frame has {lo}..{hi} fields after SEQ, got {len(fields)}", parameter="fields")
    signed = kind == "M" and len(fields) >= M_FIELDS_V2  # ref_mean (field 11) has a sign
    parts = [kind, str(seq)]
    for k, value in enumerate(fields):
        if isinstance(value, bool):
            value = int(value)
        if isinstance(value, int):
            if value < 0 and not (signed and k == M_FIELDS_V2 - 1):
                raise ParameterError(f"must be non-negative integers or tokens, got {value}", parameter="fields")
            parts.append(str(value))
        else:
            token = str(value)
            if not token or not token.isascii() or not token.isprintable() or any(c in token for c in ",*$"):
                raise ParameterError(f"token {token!r} must be non-empty printable ASCII without ',', '*', '$'",
                                     parameter="fields")
            parts.append(token)
    payload = ",".join(parts).encode("ascii")
    line = b"$" + payload + b"*%04X\r\n" % crc16(payload)
    if len(line) > MAX_LINE:
        raise ParameterError(f"frame is {len(line)} bytes, the maximum line length is {MAX_LINE}", parameter="fields")
    return line


def min_frame_length() -> int:
    """Length of the shortest valid measurement frame (all numbers one digit, window 10 ms). [byte]"""
    return len(encode_frame("M", 0, (0, WINDOW_MS_MIN, 0, 0, 0, 0, 0, 0)))


def max_frame_length() -> int:
    """Length of the longest valid frame: a version-3 ``M`` frame with every number at its widest. [byte]"""
    return len(encode_frame("M", SEQ_MODULO - 1, (_U32, WINDOW_MS_MAX, _U32, _U32, _U32, _U32, 1023, 1, 1, 65535,
                                                  HX711_MIN, CHANNELS - 1, SEQ_MODULO - 1)))


def max_frame_rate(baud: float, frame_bytes: int | None = None, bits_per_byte: int = 10) -> float:
    """Highest number of frames per second a serial line can carry.

    Parameters
    ----------
    baud : float
        Line rate. [bit/s]
    frame_bytes : int, optional
        Frame length; the shortest valid measurement frame by default. [byte]
    bits_per_byte : int
        Bits per byte on the wire: 10 for 8N1 (start + 8 data + stop).

    Returns
    -------
    float
        Frames per second. [1/s]
    """
    for name, value in (("baud", baud), ("bits_per_byte", bits_per_byte)):
        if isinstance(value, bool) or not isinstance(value, numbers.Real) or not 0 < value < math.inf:
            raise ParameterError(f"must be a number > 0, got {value!r}", parameter=name)
    if frame_bytes is not None and (isinstance(frame_bytes, bool) or not isinstance(frame_bytes, numbers.Integral)
                                    or frame_bytes <= 0):
        raise ParameterError(f"must be a whole number of bytes > 0, got {frame_bytes!r}", parameter="frame_bytes")
    n = min_frame_length() if frame_bytes is None else int(frame_bytes)
    return baud / bits_per_byte / n


def _uint(text: str, hi: int = _U32) -> int:
    # Plain decimal only: no sign, no spaces, no underscores (int() would accept those).
    if not text or len(text) > 10 or not text.isdigit() or not text.isascii():
        raise ProtocolError(f"not a decimal integer: {text!r}")
    value = int(text)
    if value > hi:
        raise ProtocolError(f"{value} exceeds {hi}")
    return value


def _int24(text: str) -> int:
    # Signed decimal: an optional '-' then plain digits, within the HX711's 24-bit range.
    digits = text[1:] if text.startswith("-") else text
    if not digits or len(digits) > 8 or not digits.isdigit() or not digits.isascii() or text == "-0":
        raise ProtocolError(f"not a signed decimal integer: {text!r}")
    value = int(text)
    if not HX711_MIN <= value <= HX711_MAX:
        raise ProtocolError(f"{value} is outside the 24-bit range")
    return value


def _check_frame_args(kind, fields) -> None:
    """A known frame type and a tuple (or list) of fields, or a ParameterError naming the one at fault."""
    if not isinstance(kind, str) or kind not in FRAME_TYPES:
        raise ParameterError(f"must be one of {sorted(FRAME_TYPES)}, got {kind!r}", parameter="kind")
    if not isinstance(fields, tuple | list):
        raise ParameterError(f"must be a tuple of fields, got {type(fields).__name__}", parameter="fields")


def check_fields(kind: str, fields: tuple[str, ...]) -> None:
    """Raise ProtocolError when the fields of a known frame type are not valid protocol (v1, v2 or v3).

    Parameters
    ----------
    kind : str
        A frame type of :data:`FRAME_TYPES`.
    fields : tuple of str
        The fields after ``SEQ``.
    """
    _check_frame_args(kind, fields)
    lo, hi = FRAME_TYPES[kind]
    if not lo <= len(fields) <= hi:
        raise ProtocolError(f"{kind} frame with {len(fields)} fields")
    if kind == "M":
        if len(fields) not in (M_FIELDS_V1, M_FIELDS_V2, M_FIELDS_V3):
            raise ProtocolError(f"M frame with {len(fields)} fields")
        t_ms, window, periods, sum_p, sum_h, missed, adc, rng = (_uint(f) for f in fields[:M_FIELDS_V1])
        if adc > 1023 or rng > 1 or window == 0 or sum_h > sum_p or (periods > 0 and sum_p == 0):
            raise ProtocolError("M frame values out of range")
        if len(fields) >= M_FIELDS_V2:
            ref_ok, ref_n, ref_mean = _uint(fields[8]), _uint(fields[9], 65535), _int24(fields[10])
            if ref_ok > 1 or (ref_ok == 0 and ref_n > 0) or (ref_n == 0 and ref_mean != 0):
                raise ProtocolError("M frame reference values out of range")
        if len(fields) == M_FIELDS_V3:
            _uint(fields[11], CHANNELS - 1)
            _uint(fields[12], SEQ_MODULO - 1)
    elif kind == "ID":
        _uint(fields[2])
        _uint(fields[3])
        if not fields[0] or not fields[1]:
            raise ProtocolError("empty token")
    elif kind == "ACK":
        if not fields[0]:
            raise ProtocolError("empty token")
        if len(fields) == 2:
            _uint(fields[1])
    else:  # ERR
        _uint(fields[0])
        if not fields[1]:
            raise ProtocolError("empty token")


@dataclass(frozen=True, slots=True)
class ParserStats:
    """Counters of a :class:`FrameParser` (a snapshot).

    Attributes
    ----------
    frames : int
        Intact frames returned.
    bad_checksum : int
        Well-formed lines whose CRC did not match.
    malformed : int
        Lines that began with ``$`` but were cut short, too long, or not valid protocol.
    garbage_bytes : int
        Bytes outside any line that began with ``$`` (noise, a baud mismatch, a partial first line).
    lost : int
        Frames missing from the sequence numbers (never arrived, or arrived corrupted).
    resets : int
        Device restarts seen (boot ``ID`` frame out of turn, or the sequence jumped backwards).
    bytes_in : int
        All bytes fed.
    """

    frames: int
    bad_checksum: int
    malformed: int
    garbage_bytes: int
    lost: int
    resets: int
    bytes_in: int

    @property
    def bad_frames(self) -> int:
        """Lines rejected as corrupt (``bad_checksum + malformed``)."""
        return self.bad_checksum + self.malformed


class FrameParser:
    """Incremental parser of device frames that survives any byte stream.

    Feed it bytes as they arrive, in chunks of any size; it returns the intact frames and counts
    everything else. It never raises on input: garbage, partial frames, a device reset in the
    middle of a line and a wrong baud rate all end up in the counters.

    Notes
    -----
    A candidate line starts at ``$`` and ends at the next ``\\n``. It is abandoned (counted as
    ``malformed``) when another ``$`` arrives first (the device restarted mid-line, or the line
    end was corrupted) or when it grows beyond :data:`MAX_LINE` bytes. Because of this rule, a
    frame whose own bytes are intact is always recovered, whatever precedes it. Bytes outside
    candidates are ``garbage_bytes``. A line is ``bad_checksum`` when it is well formed
    (``$payload*XXXX\\r\\n``) but its CRC does not match, and ``malformed`` when it is not well
    formed, or has a valid CRC but is not a valid protocol frame (version 1 or 2).

    Sequence numbers: each intact frame should carry the previous one's ``seq + 1`` (mod 65536).
    A forward gap of ``d < 32768`` adds ``d`` to ``lost``. The boot ``ID`` frame (``seq == 0``)
    when another number was expected, or a backward jump (gap ≥ 32768, this includes a repeated
    number), counts as a device reset and adds nothing to ``lost`` (frames between the last one
    seen and the restart cannot be known).
    """

    __slots__ = ("_buf", "frames", "bad_checksum", "malformed", "garbage_bytes", "lost", "resets",
                 "bytes_in", "frame_bytes", "bad_bytes", "_expected")

    def __init__(self) -> None:
        self._buf = b""
        self.frames = 0
        self.bad_checksum = 0
        self.malformed = 0
        self.garbage_bytes = 0
        self.lost = 0
        self.resets = 0
        self.bytes_in = 0
        self.frame_bytes = 0  # bytes of intact frames
        self.bad_bytes = 0  # bytes of rejected candidate lines
        self._expected: int | None = None

    @property
    def bad_frames(self) -> int:
        """Lines rejected as corrupt (``bad_checksum + malformed``)."""
        return self.bad_checksum + self.malformed

    @property
    def pending(self) -> int:
        """Bytes held back: the start of a line whose end has not arrived yet. [byte]"""
        return len(self._buf)

    def stats(self) -> ParserStats:
        """A snapshot of the counters."""
        return ParserStats(self.frames, self.bad_checksum, self.malformed, self.garbage_bytes,
                           self.lost, self.resets, self.bytes_in)

    def feed(self, data: bytes) -> list[Frame]:
        """Parse more bytes.

        Parameters
        ----------
        data : bytes
            The next bytes from the link, any length (bytes, bytearray or memoryview).

        Returns
        -------
        list of Frame
            The frames completed by these bytes, in order.
        """
        self.bytes_in += len(data)
        buf = self._buf + bytes(data) if self._buf else bytes(data)
        n = len(buf)
        out: list[Frame] = []
        i = 0
        find = buf.find
        while i < n:
            if buf[i] != _DOLLAR:
                j = find(b"$", i)
                if j < 0:
                    self.garbage_bytes += n - i
                    i = n
                    break
                self.garbage_bytes += j - i
                i = j
            limit = i + MAX_LINE
            nl = find(b"\n", i + 1, limit)
            dl = find(b"$", i + 1, nl if nl >= 0 else limit)
            if dl >= 0:  # a new line started before this one ended
                self.malformed += 1
                self.bad_bytes += dl - i
                i = dl
                continue
            if nl < 0:
                if n >= limit:  # too long without an end: abandon it (no '$' inside, so skip all)
                    self.malformed += 1
                    self.bad_bytes += MAX_LINE
                    i = limit
                    continue
                break  # wait for the rest
            frame = self._line(buf, i, nl + 1)
            if frame is not None:
                out.append(frame)
            i = nl + 1
        self._buf = buf[i:] if i < n else b""
        return out

    def finish(self) -> None:
        """End of stream: count a pending, unterminated line as ``malformed``."""
        if self._buf:
            self.malformed += 1
            self.bad_bytes += len(self._buf)
            self._buf = b""

    def _line(self, buf: bytes, start: int, end: int) -> Frame | None:
        size = end - start
        # Well formed: $ payload * H H H H \r \n
        star = end - 7
        if size < 9 or buf[end - 2] != _CR or buf[star] != _STAR:
            return self._bad(size)
        crc_text = buf[star + 1:end - 2]
        if not _HEX.issuperset(crc_text):
            return self._bad(size)
        payload = buf[start + 1:star]
        if binascii.crc_hqx(payload, 0xFFFF) != int(crc_text, 16):
            self.bad_checksum += 1
            self.bad_bytes += size
            return None
        try:
            text = payload.decode("ascii")
            if not text.isprintable() or "*" in text:
                raise ProtocolError("non-printable")
            parts = text.split(",")
            kind = parts[0]
            if kind not in FRAME_TYPES or len(parts) < 2:
                raise ProtocolError("unknown type")
            seq = _uint(parts[1], SEQ_MODULO - 1)
            fields = tuple(parts[2:])
            check_fields(kind, fields)
        except (ProtocolError, UnicodeDecodeError):
            return self._bad(size)
        self.frames += 1
        self.frame_bytes += size
        gap, reset = 0, False
        expected = self._expected
        if expected is not None and seq != expected:
            d = (seq - expected) % SEQ_MODULO
            if (seq == 0 and kind == "ID") or d >= SEQ_MODULO // 2:
                reset = True
                self.resets += 1
            else:
                gap = d
                self.lost += d
        self._expected = (seq + 1) % SEQ_MODULO
        return Frame(kind, seq, fields, gap, reset)

    def _bad(self, size: int) -> None:
        self.malformed += 1
        self.bad_bytes += size
        return None


def encode_command(name: str, value: int | None = None) -> bytes:
    """Build a host command line.

    Parameters
    ----------
    name : str
        ``ID``, ``START``, ``STOP``, ``WINDOW``, ``RANGE``, ``SCAN``, ``DWELL`` or ``SETTLE``.
    value : int, optional
        Window length for ``WINDOW`` (10..60000) [ms]; switch state for ``RANGE`` (0 or 1); channel
        mask for ``SCAN`` (1..255, bit k = channel k); counting time per channel for ``DWELL``
        (1..60000) [ms]; periods discarded after a switch's first edge for ``SETTLE`` (0..100).

    Returns
    -------
    bytes
        E.g. ``encode_command("WINDOW", 100) == b"WINDOW 100\\n"``.

    Raises
    ------
    ParameterError
        When the command is unknown or the value is missing, superfluous or out of range.
    """
    key = str(name).upper()
    if key not in COMMANDS:
        raise ParameterError(f"must be one of {', '.join(COMMANDS)}, got {name!r}", parameter="name")
    allowed = COMMANDS[key]
    if allowed is None:
        if value is not None:
            raise ParameterError(f"{key} takes no value, got {value!r}", parameter="value")
        return key.encode("ascii") + b"\n"
    if not isinstance(value, numbers.Real) or isinstance(value, bool) or not allowed[0] <= value <= allowed[1] \
            or value != int(value):
        raise ParameterError(f"{key} needs an integer in {allowed[0]}..{allowed[1]}, got {value!r}", parameter="value")
    return f"{key} {int(value)}\n".encode("ascii")


def parse_command(line: bytes) -> tuple[str, int | None]:
    """Interpret a host command line the way the firmware does.

    Parameters
    ----------
    line : bytes
        One line, with or without its ``\\n``; ``\\r`` bytes are ignored, as are leading and
        trailing spaces. Command words are case-sensitive (upper case).

    Returns
    -------
    (str, int or None)
        The command and its value.

    Raises
    ------
    CommandError
        With ``code`` 1 (unknown command), 2 (bad or missing value) or 3 (line longer than
        :data:`MAX_COMMAND` bytes) and the ``token`` the device reports in ``$ERR``.
    """
    if not isinstance(line, bytes | bytearray | memoryview):
        raise ParameterError(f"must be bytes, got {type(line).__name__}", parameter="line")
    raw = bytes(line)
    if raw.endswith(b"\n"):
        raw = raw[:-1]
    raw = raw.replace(b"\r", b"")
    if len(raw) + 1 > MAX_COMMAND:
        raise CommandError("command line too long", ERR_LINE_TOO_LONG, "LINE")
    words = raw.decode("ascii", "replace").split()
    word = words[0] if words else ""
    token = _token(word)
    if word not in COMMANDS:
        raise CommandError(f"unknown command {word!r}", ERR_UNKNOWN_COMMAND, token)
    allowed = COMMANDS[word]
    if allowed is None:
        if len(words) != 1:
            raise CommandError(f"{word} takes no value", ERR_BAD_VALUE, token)
        return word, None
    if len(words) != 2 or not words[1].isdigit() or not words[1].isascii() or len(words[1]) > 5:
        raise CommandError(f"{word} needs an integer value", ERR_BAD_VALUE, token)
    value = int(words[1])
    if not allowed[0] <= value <= allowed[1]:
        raise CommandError(f"{word} value out of range", ERR_BAD_VALUE, token)
    return word, value


def _token(word: str) -> str:
    """The command word as reported in ``$ERR``: printable ASCII without ``,*$``, ≤ 12 chars, ``?`` if empty."""
    safe = "".join(c for c in word if c.isascii() and c.isprintable() and c not in ",*$ ")[:12]
    return safe or "?"


def channel_mask(channels) -> int:
    """The ``SCAN`` mask of a set of multiplexer channels.

    Parameters
    ----------
    channels : iterable of int
        Distinct channels, each 0..7 (at least one).

    Returns
    -------
    int
        Bit k set for channel k, 1..255.

    Raises
    ------
    ParameterError
        An empty set, a repeated channel or one outside 0..7 (``parameter="channels"``).
    """
    if isinstance(channels, str | bytes) or not hasattr(channels, "__iter__"):
        raise ParameterError(f"must be a sequence of channel numbers 0..{CHANNELS - 1}, got {channels!r}",
                             parameter="channels")
    chans = list(channels)
    if not chans:
        raise ParameterError("at least one channel is needed", parameter="channels")
    mask = 0
    for ch in chans:
        if isinstance(ch, bool) or not hasattr(ch, "__index__"):
            raise ParameterError(f"{ch!r} is not a channel number 0..{CHANNELS - 1}", parameter="channels")
        ch = int(ch)
        if not 0 <= ch < CHANNELS:
            raise ParameterError(f"{ch} is outside 0..{CHANNELS - 1} (the multiplexer has {CHANNELS})",
                                 parameter="channels")
        if mask & (1 << ch):
            raise ParameterError(f"channel {ch} is given twice", parameter="channels")
        mask |= 1 << ch
    return mask


def mask_channels(mask: int) -> tuple[int, ...]:
    """The channels of a ``SCAN`` mask, in scan order (ascending).

    Parameters
    ----------
    mask : int
        1..255.

    Returns
    -------
    tuple of int
    """
    if isinstance(mask, bool) or not isinstance(mask, int) or not 1 <= mask <= SCAN_MASK_MAX:
        raise ParameterError(f"a channel mask is an integer 1..{SCAN_MASK_MAX}, got {mask!r}", parameter="mask")
    return tuple(k for k in range(CHANNELS) if mask >> k & 1)


def parse_channels(text: str) -> tuple[int, ...]:
    """Channels written as on a command line: ``0-7``, ``0,2,5``, ``1-3,6`` or ``4``.

    Parameters
    ----------
    text : str
        Channel numbers 0..7 and ranges ``a-b`` (a ≤ b), separated by commas.

    Returns
    -------
    tuple of int
        The channels, ascending.

    Raises
    ------
    ParameterError
        Anything else, a repeated channel or one outside 0..7 (``parameter="text"``).
    """
    if not isinstance(text, str):
        raise ParameterError(f"must be a text such as 0-7 or 0,2,5, got {text!r}", parameter="text")
    try:
        return _parse_channels(text)
    except ParameterError as err:
        raise ParameterError(err.reason, parameter="text") from None


def _parse_channels(text: str) -> tuple[int, ...]:
    chans: list[int] = []
    for part in text.replace(" ", "").split(","):
        lo, sep, hi = part.partition("-")
        if not lo.isdigit() or (sep and not hi.isdigit()) or not lo.isascii() or not hi.isascii():
            raise ParameterError(f"{text!r} is not a list of channels 0..{CHANNELS - 1} such as 0-7 or 0,2,5",
                                 parameter="channels")
        a, b = int(lo), int(hi) if sep else int(lo)
        if b < a:
            raise ParameterError(f"the range {part} runs backwards", parameter="channels")
        chans.extend(range(a, b + 1))
    return mask_channels(channel_mask(chans))

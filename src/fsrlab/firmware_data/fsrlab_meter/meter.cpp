// fsrlab meter: the background (everything but the edge handlers): serial protocol v3
// (docs/protocol.md), commands, measurement windows, the ADC on A0, the C_off switch on D4, the
// reference load cell's HX711 on D2 (DOUT) and D3 (SCK), and the channel scan of a CD74HC4051
// multiplexer on the timing node (select lines S0..S2 on D5..D7, inhibit on D9; docs/multiplexing.md).
// Matute et al. 2018, J. Sensors 6561901, doi:10.1155/2018/6561901, section 5.
//
// The edges are served by the interrupt handlers of capture.S / capture.cpp (see capture.h). This
// code is ordinary C that they interrupt anywhere; it keeps only two duties short: the receiver is
// polled at least every few hundred cycles of its own time (the USART holds two bytes, 174 us at
// 115200 baud), so long work calls rx_poll() between digits and bytes and service() between
// fields; and interrupts
// are never disabled longer than capture_snapshot_now() (~100 cycles, only without fast edges).
#include <avr/io.h>
#include <avr/interrupt.h>
#include <avr/pgmspace.h>
#include <util/crc16.h>
#include "capture.h"
#include "meter.h"

#define UBRR_115200 16     // with U2X0: 16e6 / (8 * 17) = 117647 baud (Arduino's choice)
#define WINDOW_MIN 10u
#define WINDOW_MAX 60000u
#define WINDOW_DEFAULT 100u
#define SCAN_MAX 255u      // channel mask: bit k = channel k of the multiplexer
#define DWELL_MIN 1u       // counting time per channel in a scan [ms]
#define DWELL_MAX 60000u
#define DWELL_DEFAULT 3u
#define SETTLE_MAX 100u    // periods discarded after the first edge that follows a switch
#define SETTLE_DEFAULT 2u
#define MUX_SHIFT 5        // S0..S2 on PD5..PD7 (D5..D7): written together, in one write of PORTD
#define MUX_BITS (7u << MUX_SHIFT)
#define CMD_MAX 32u        // longest command line, '\n' included [bytes]
#define SNAP_WAIT_MS 2u    // the handler answers a snapshot request at the next rising edge; after
                           // this long without one the background takes it itself

// ---------------------------------------------------------------------------------------------
// Time: Timer2 free-running at clk/128 (8 us per count, wraps every 2.048 ms), polled, with its
// overflow flag: polls up to 4 ms apart lose nothing. A gap of 2 ms or more between two polls means
// the edge handlers leave the background (almost) no time: it raises F_STARVE (the handlers then
// step aside for 128 us at a time and report the edges that go by as missed) until its polls come
// less than 1 ms apart again. (service() runs every few hundred cycles of background work.)
#define T2_PER_MS 125u
static uint8_t t2_last;
static uint32_t now8;    // [8 us] since boot
static uint32_t now_ms;  // now8 / 125
static uint32_t ref_last8;  // completion of the last HX711 conversion [8 us]
static uint8_t ref_seen;    // ... within the last second (REF_OK_8)
#define REF_OK_8 (1000ul * T2_PER_MS)  // ref_ok: a conversion completed within 1000 ms [8 us]

static void clock_poll(void) {
  uint8_t t = TCNT2;
  uint8_t ov = TIFR2 & _BV(TOV2);
  uint8_t t_after = TCNT2;
  if (t_after < t) {  // wrapped between the two reads: the flag shows that wrap
    t = t_after;
    ov = TIFR2 & _BV(TOV2);
  }
  uint16_t d = (uint8_t)(t - t2_last);
  if (ov) {
    TIFR2 = _BV(TOV2);
    if (t >= t2_last) d += 256u;  // a whole wrap more than the counts show
  }
  t2_last = t;
  if (d >= 2u * T2_PER_MS) capture_starving();
  else if (d < T2_PER_MS && (GPIOR0 & _BV(F_STARVE))) capture_fed();
  now8 += d;
  static uint16_t frac;
  frac += d;
  while (frac >= T2_PER_MS) {
    frac -= T2_PER_MS;
    now_ms++;
    // once a millisecond (not every turn: the background's time is scarce at 50 kHz): forget a
    // conversion older than a second before now8 - ref_last8 could wrap (9.5 h)
    if (ref_seen && now8 - ref_last8 >= REF_OK_8) ref_seen = 0;
  }
}

// ---------------------------------------------------------------------------------------------
// Transmit ring, polled.
static uint8_t txbuf[256];
static uint8_t tx_head, tx_tail;

static void tx_poll(void) {
  if (tx_head != tx_tail && (UCSR0A & _BV(UDRE0))) UDR0 = txbuf[tx_tail++];
}

// Receiver: one command line (CR dropped), handled by the main loop when its LF came.
static char line[CMD_MAX];
static uint8_t line_len, line_over, line_ready;

static void rx_byte(void) {
  uint8_t c = UDR0;
  if (c == '\r') return;
  if (c == '\n') {
    line_ready = 1;
    return;
  }
  if (line_len >= CMD_MAX - 1u) line_over = 1;
  else line[line_len++] = (char)c;
}

// Cheap enough to call between any two steps of long work (a line waits: the host waits for its
// answer, so nothing more comes).
static inline void rx_poll(void) {
  if (!line_ready && (UCSR0A & _BV(RXC0))) rx_byte();
}

// The duties that must not wait long: called from the main loop and from inside long work.
static void service(void) {
  clock_poll();
  rx_poll();
  tx_poll();
}

// ---------------------------------------------------------------------------------------------
// Frames: "$" payload "*" CRC16 CR LF, written straight into the transmit ring with the CRC
// computed on the way (no second pass over a frame buffer: at 50 kHz the background has ~12 % of
// the CPU, and a 10 ms window leaves it ~19000 cycles for everything, frame included). The ring
// has room for a whole frame (MAX_FRAME) before one begins; bytes already written may go out while
// the rest is formatted.
#define MAX_FRAME 112u  // protocol line limit (the longest frame, a v3 M frame, is 108 bytes)
static uint16_t seq_next;
static uint16_t crc;
static const uint32_t pow10_tab[10] = {1ul, 10ul, 100ul, 1000ul, 10000ul, 100000ul,
                                       1000000ul, 10000000ul, 100000000ul, 1000000000ul};

static inline void put_raw(char c) { txbuf[tx_head++] = (uint8_t)c; }

static void put_c(char c) {
  put_raw(c);
  crc = _crc_xmodem_update(crc, (uint8_t)c);
}

static void put_P(const char *s) {
  char c;
  while ((c = (char)pgm_read_byte(s++))) put_c(c);
}

static void put_u32(uint32_t v) {
  if (v < 10u) {  // most fields of a frame (missed, range, ref_ok, ...): no scan of the powers
    put_c((char)('0' + (uint8_t)v));
    rx_poll();
    return;
  }
  int8_t i = 9;
  while (i > 0 && v < pow10_tab[i]) i--;
  for (; i >= 0; i--) {
    uint32_t p = pow10_tab[i];
    char d = '0';
    while (v >= p) {
      v -= p;
      d++;
    }
    put_c(d);
    rx_poll();
  }
  service();
}

static void field_u32(uint32_t v) {
  put_c(',');
  put_u32(v);
}

static void field_i32(int32_t v) {
  put_c(',');
  if (v < 0) {
    put_c('-');
    v = -v;  // (never -2^31: the value is a mean of 24-bit samples)
  }
  put_u32((uint32_t)v);
}

static void field_P(const char *s) {
  put_c(',');
  put_P(s);
}

static void frame_begin(const char *type) {
  while ((uint8_t)(tx_tail - tx_head - 1u) < MAX_FRAME) service();  // room (255 usable)
  put_raw('$');
  crc = 0xFFFF;
  put_P(type);
  field_u32(seq_next);
}

static void frame_end(void) {
  put_raw('*');
  for (int8_t s = 12; s >= 0; s -= 4) {
    uint8_t n = (uint8_t)((crc >> s) & 0xF);
    put_raw((char)(n < 10 ? '0' + n : 'A' + n - 10));
  }
  put_raw('\r');
  put_raw('\n');
  seq_next++;
}

static const char s_M[] PROGMEM = "M";
static const char s_ID[] PROGMEM = "ID";
static const char s_ACK[] PROGMEM = "ACK";
static const char s_ERR[] PROGMEM = "ERR";
static const char s_dev[] PROGMEM = "fsrlab-meter";
static const char s_ver[] PROGMEM = METER_FW_VERSION;

static void send_id(void) {
  frame_begin(s_ID);
  field_P(s_dev);
  field_P(s_ver);
  field_u32(METER_PROTOCOL_VERSION);
  field_u32(F_CPU);
  frame_end();
}

// ---------------------------------------------------------------------------------------------
// Measurement windows. A window's end is a due time in Timer2 counts: the snapshot is asked for
// 0.8 ms early and the handler takes it at the first rising edge at or after the due time, so a
// window's boundaries are exact to one period plus 8 us, however busy the background is.
#define EARLY 100u              // [8 us] ask this long before the due time (< 128)
static uint8_t running, range_sel;
static uint16_t window_ms = WINDOW_DEFAULT;
static uint32_t win_end_ms;     // end of the window in progress [ms]
static uint32_t win_end8;       // ... [8 us]
static CaptureSums base;        // the sums at the window's start
enum { SNAP_NONE, SNAP_BASE, SNAP_FRAME, SNAP_FIRST };
static uint8_t snap_want;
static uint32_t snap_due8;      // due time of the pending snapshot [8 us]
static uint32_t fr_t;           // the pending frame: end time, window, range, channel, scan
static uint16_t fr_window;
static uint8_t fr_range, fr_channel;
static uint16_t fr_scan;
// The scan (a mask of more than one channel): for each channel in turn, select it, wait for the
// first rising edge after the switch (SNAP_FIRST) and SETTLE complete periods more (SC_SETTLE),
// take the base at the next rising edge (SNAP_BASE), count for DWELL ms (SC_COUNT), send the
// reading. A mask of one channel is the single-channel meter: contiguous windows of WINDOW ms.
static uint8_t scan_mask = 1, channel;
static uint8_t scan_set;        // a SCAN was accepted since boot: M frames carry channel and scan (v3);
                                // until then they are version 2's (the background's time at 50 kHz is
                                // scarce: a single-channel meter sends no byte more than before)
static uint16_t scan_no, dwell_ms = DWELL_DEFAULT;
static uint8_t settle_n = SETTLE_DEFAULT;
enum { SC_FIRST, SC_SETTLE, SC_BASE, SC_COUNT };
static uint8_t scan_phase = SC_COUNT;
static uint32_t settle_p1;      // periods at the first edge after the switch
static uint32_t settle_t8;      // when the channel was selected [8 us]
static uint32_t adc_sum;
static uint16_t adc_n;

static void snap_request(uint8_t why, uint32_t due8) {
  snap_want = why;
  snap_due8 = due8;
  capture_request((uint8_t)(t2_last + (due8 - now8)));  // TCNT2 at due8 (t2_last was read at now8)
}

static void window_restart(void) {
  clock_poll();  // now, not when the command's line was complete (parsing it takes a while)
  win_end_ms = now_ms + window_ms;
  win_end8 = now8 + (uint32_t)window_ms * T2_PER_MS;
  snap_request(SNAP_BASE, now8);
}

static uint8_t scanning(void) { return (uint8_t)(scan_mask & (scan_mask - 1u)) != 0; }  // > 1 channel

static void mux_select(uint8_t ch) {
  channel = ch;
  // one write: the three select lines change together (only the background writes PORTD)
  PORTD = (uint8_t)((PORTD & (uint8_t)~MUX_BITS) | (uint8_t)(ch << MUX_SHIFT));
}

static uint8_t first_channel(void) {
  uint8_t ch = 0;
  while (!(scan_mask & (1u << ch))) ch++;
  return ch;
}

// Complete periods so far (the handler writes them: read with interrupts off, ~10 cycles).
static uint32_t periods_now(void) {
  uint8_t sreg = SREG;
  cli();
  uint32_t p = capture_state.acc.periods;
  SREG = sreg;
  return p;
}

// The channel just selected: its first rising edge ends the period that spans the switch.
static void settle_begin(void) {
  clock_poll();
  settle_t8 = now8;
  scan_phase = SC_FIRST;
  snap_request(SNAP_FIRST, now8);
}

// Select the next channel of the mask (the scan number counts the returns to the first one).
static void scan_next(void) {
  uint8_t ch = channel;
  do {
    ch = (uint8_t)((ch + 1u) & 7u);
  } while (!(scan_mask & (1u << ch)));
  if (ch <= channel) scan_no++;
  mux_select(ch);
  settle_begin();
}

// START, or a new mask while started: from the first channel of the mask.
static void measure_restart(void) {
  mux_select(first_channel());
  if (scanning()) settle_begin();
  else {
    scan_phase = SC_COUNT;
    window_restart();
  }
}

// SETTLE periods after the first edge (or, for an open or very slow channel, one dwell after the
// switch): the base is taken at the next rising edge.
static void settle_poll(void) {
  if (!running || scan_phase != SC_SETTLE || snap_want != SNAP_NONE) return;
  if ((uint32_t)(periods_now() - settle_p1) + 1u < settle_n &&
      now8 - settle_t8 < (uint32_t)dwell_ms * T2_PER_MS)
    return;
  scan_phase = SC_BASE;
  snap_request(SNAP_BASE, now8);
}

// A scan's base has been taken: the reading counts from it for DWELL ms.
static void count_begin(void) {
  clock_poll();
  win_end_ms = now_ms + dwell_ms;
  win_end8 = now8 + (uint32_t)dwell_ms * T2_PER_MS;
  scan_phase = SC_COUNT;
}

static void adc_poll(void) {
  if (ADCSRA & _BV(ADSC)) return;
  adc_sum += ADC;
  adc_n++;
  ADCSRA |= _BV(ADSC);
}

static void window_poll(void) {
  if (!running || snap_want != SNAP_NONE || scan_phase != SC_COUNT ||
      (int32_t)(now8 + EARLY - win_end8) < 0)
    return;
  fr_t = win_end_ms;
  fr_range = range_sel;
  fr_channel = channel;
  fr_scan = scan_no;
  snap_request(SNAP_FRAME, win_end8);
  if (scanning()) {
    fr_window = dwell_ms;
    scan_phase = SC_BASE;  // (the next reading begins after the switch: no window until then)
  } else {
    fr_window = window_ms;
    scan_no++;
    win_end_ms += window_ms;
    win_end8 += (uint32_t)window_ms * T2_PER_MS;
  }
}

// ---------------------------------------------------------------------------------------------
// Reference load cell: HX711 (gain 128, channel A), DOUT on D2 = PD2 (input, pull-up: a missing
// board reads high = never ready), SCK on D3 = PD3 (output, idle low). A conversion is ready when
// DOUT is low; 24 SCK pulses shift it out MSB first (two's complement), a 25th selects gain 128 and
// channel A for the next one and sets DOUT high again.
//
// The HX711 powers down when SCK stays high for more than 60 us (datasheet: SCK high 0.2..50 us).
// An edge handler's visit can last up to 128 us (its poll after a break in the signal), so a pulse
// with interrupts enabled could meet one and be stretched past that. Each pulse is therefore made
// with interrupts disabled for 9 cycles (cli ... sei and the read of DOUT that sei lets through):
// SCK is high for exactly 5 cycles (sbi to cbi, 0.31 us), whatever the edges do; an edge's
// interrupt waits at most ~5 cycles longer than behind a 4-cycle instruction (firmware/README.md:
// measured in simavr at 50 kHz, 5 and 95 % duty, with an HX711 at 80 samples/s). Between pulses
// interrupts are enabled and SCK may stay low as long as it needs.
#define HX_DOUT PD2
#define HX_SCK PD3

// One SCK pulse; returns PIND after it (DOUT holds the bit from the rising edge to the next one).
static inline uint8_t hx_pulse(void) {
  uint8_t pin;
  asm volatile(
      "cli\n\t"
      "sbi %[port], %[sck]\n\t"
      "nop\n\t"
      "nop\n\t"
      "nop\n\t"
      "cbi %[port], %[sck]\n\t"
      "sei\n\t"
      "in %[pin], %[pinr]\n\t"  // runs before a pending interrupt: the disabled span ends here
      : [pin] "=r"(pin)
      : [port] "I"(_SFR_IO_ADDR(PORTD)), [sck] "I"(HX_SCK), [pinr] "I"(_SFR_IO_ADDR(PIND))
      : "memory");
  return pin;
}

// Clocks out a ready conversion (25 pulses). The receiver is polled between
// pulses and the clock every 8 (the read takes ~700 background cycles).
static int32_t hx_read(void) {
  uint32_t v = 0;
  for (uint8_t i = 1; i <= 24; i++) {
    uint8_t pin = hx_pulse();
    v <<= 1;
    if (pin & _BV(HX_DOUT)) v |= 1;
    if (i & 7) rx_poll();
    else service();
  }
  hx_pulse();  // the 25th: gain 128, channel A
  if (v & 0x800000ul) v |= 0xFF000000ul;
  return (int32_t)v;
}

// The conversions of the window in progress (cur) and of the next one (next: completed at or after
// the due time of the window's end while its snapshot is pending). A conversion belongs to the
// window in which it completed, on the background's clock (8 us), read right after its 25th pulse.
struct RefAcc {
  int64_t sum;
  uint16_t n;
};
static RefAcc ref_cur, ref_next;

// Reads the conversion that DOUT announces and adds it to its window.
static void __attribute__((noinline)) ref_take(void) {
  int32_t v = hx_read();
  clock_poll();
  ref_last8 = now8;
  ref_seen = 1;
  uint8_t later;
  if (snap_want != SNAP_NONE) later = (int32_t)(now8 - snap_due8) >= 0;
  else later = running && (int32_t)(now8 - win_end8) >= 0;
  RefAcc &a = later ? ref_next : ref_cur;
  if (a.n < 0xFFFFu) {
    a.sum += v;
    a.n++;
  }
}

// Called from every turn of the main loop: returns after one test of DOUT unless it is low.
static inline void ref_poll(void) {
  if (PIND & _BV(HX_DOUT)) return;
  ref_take();
}

// floor(sum / n + 1/2) = floor((2 sum + n) / 2n) by shift-and-subtract, with the clock and the
// receiver served every 8 steps: libgcc's 64-bit division would hold the background for ~2000
// cycles, which at 50 kHz (12 % of the CPU left to it) is more than the 2 ms after which the
// background counts itself starved and the edge handlers step aside. |2 sum + n| < 2^41.
static int32_t ref_mean(int64_t sum, uint16_t n) {
  if (n == 1) return (int32_t)sum;  // (windows shorter than the HX711's period: no division)
  int64_t num = 2 * sum + n;
  uint8_t neg = num < 0;
  uint64_t u = neg ? (uint64_t)(-num) : (uint64_t)num;
  uint32_t d = 2ul * n;
  if (neg) u += d - 1u;  // floor of a negative quotient: minus the ceiling of its magnitude
  uint32_t hi = (uint32_t)(u >> 32), lo = (uint32_t)u;
  hi <<= 22;  // its 10 significant bits first
  uint32_t r = 0, q = 0;
  for (uint8_t b = 0; b < 42; b++) {
    uint32_t w = b < 10 ? hi : lo;
    r = (r << 1) | (w >> 31);
    if (b < 10) hi <<= 1;
    else lo <<= 1;
    q <<= 1;
    if (r >= d) {
      r -= d;
      q |= 1;
    }
    if ((b & 7) == 7) service();
  }
  return neg ? -(int32_t)q : (int32_t)q;
}

static void snap_poll(void) {
  if (snap_want == SNAP_NONE) return;
  if (!capture_ready() && (int32_t)(now8 - snap_due8) >= (int32_t)(SNAP_WAIT_MS * T2_PER_MS))
    capture_snapshot_now();
  if (!capture_ready()) return;
  // a copy: in a scan the next request (after the switch) comes before the frame is written
  CaptureSums n = *(const CaptureSums *)&capture_state.snap;
  CaptureSums b = base;
  uint8_t why = snap_want;
  uint16_t adc = adc_n ? (uint16_t)((adc_sum + adc_n / 2u) / adc_n) : 0;
  adc_sum = 0;
  adc_n = 0;
  // the reference: ref_ok at the window's end (snap_due8); no count without it (docs/protocol.md)
  uint8_t ok = ref_seen && (int32_t)(snap_due8 - ref_last8) < (int32_t)REF_OK_8;
  RefAcc ref = ref_cur;
  base = n;
  ref_cur = ref_next;  // (a base discards the conversions before it)
  ref_next.sum = 0;
  ref_next.n = 0;
  snap_want = SNAP_NONE;
  if (running && why == SNAP_FIRST) {
    settle_p1 = n.periods;
    if (settle_n) scan_phase = SC_SETTLE;
    else count_begin();  // the first edge itself is the base
  } else if (running && why == SNAP_BASE && scan_phase == SC_BASE) {
    count_begin();
  }
  if (why != SNAP_FRAME) return;
  // the pending frame's own values: window_poll may ask for the next window's end while this one waits
  // for room in the transmit ring
  uint32_t t = fr_t;
  uint16_t win = fr_window, sc = fr_scan;
  uint8_t rg = fr_range, ch = fr_channel;
  if (running && scanning()) scan_next();  // the next channel settles while this frame goes out
  uint32_t high = n.sum_high - b.sum_high;
  frame_begin(s_M);
  field_u32(t);
  field_u32(win);
  field_u32(n.periods - b.periods);
  field_u32(n.sum_low - b.sum_low + high);
  field_u32(high);
  field_u32(n.missed - b.missed);
  field_u32(adc);
  field_u32(rg);
  uint16_t rn = ok ? ref.n : 0;
  field_u32(ok);
  field_u32(rn);
  field_i32(rn ? ref_mean(ref.sum, rn) : 0);
  if (scan_set) {
    field_u32(ch);
    field_u32(sc);
  }
  frame_end();
}

// ---------------------------------------------------------------------------------------------
// Commands (matches fsrlab.acquisition.protocol.parse_command; docs/protocol.md).
enum { C_ID, C_START, C_STOP, C_WINDOW, C_RANGE, C_SCAN, C_DWELL, C_SETTLE, C_COUNT };
static const char cmd_names[C_COUNT][7] PROGMEM = {"ID", "START", "STOP", "WINDOW", "RANGE",
                                                   "SCAN", "DWELL", "SETTLE"};
static const uint16_t cmd_max[C_COUNT] = {0, 0, 0, WINDOW_MAX, 1, SCAN_MAX, DWELL_MAX,
                                          SETTLE_MAX};  // 0: takes no value
static const uint16_t cmd_min[C_COUNT] = {0, 0, 0, WINDOW_MIN, 0, 1, DWELL_MIN, 0};

static uint8_t is_space(uint8_t c) {
  return c == ' ' || (c >= '\t' && c <= '\f' && c != '\n') || (c >= 0x1c && c <= 0x1f);
}

static void answer_err(uint8_t code, const char *tok, uint8_t tok_len) {
  frame_begin(s_ERR);
  field_u32(code);
  put_c(',');
  uint8_t n = 0;
  for (uint8_t i = 0; i < tok_len && n < 12; i++) {
    char c = tok[i];
    if (c > 0x20 && c < 0x7f && c != ',' && c != '*' && c != '$') {
      put_c(c);
      n++;
    }
  }
  if (!n) put_c('?');
  frame_end();
}

static void handle_line(void) {
  if (line_over) {
    answer_err(3, "LINE", 4);
    return;
  }
  // words: [ws[k], we[k]) for the first three
  uint8_t ws[3], we[3], nw = 0, i = 0;
  while (i < line_len) {
    while (i < line_len && is_space((uint8_t)line[i])) i++;
    if (i >= line_len) break;
    uint8_t s = i;
    while (i < line_len && !is_space((uint8_t)line[i])) i++;
    if (nw < 3) {
      ws[nw] = s;
      we[nw] = i;
    }
    if (nw < 3) nw++;
  }
  const char *w0 = nw ? line + ws[0] : line;
  uint8_t w0len = nw ? (uint8_t)(we[0] - ws[0]) : 0;
  int8_t cmd = -1;
  for (uint8_t k = 0; k < C_COUNT; k++) {
    uint8_t j = 0;
    while (j < w0len && j < 6 && pgm_read_byte(&cmd_names[k][j]) == (uint8_t)w0[j]) j++;
    if (j == w0len && w0len && pgm_read_byte(&cmd_names[k][j]) == 0) cmd = (int8_t)k;
  }
  if (cmd < 0) {
    answer_err(1, w0, w0len);
    return;
  }
  uint16_t value = 0;
  if (cmd_max[cmd] == 0) {
    if (nw != 1) {
      answer_err(2, w0, w0len);
      return;
    }
  } else {
    uint8_t ok = nw == 2 && we[1] - ws[1] <= 5;
    uint32_t v = 0;
    for (uint8_t j = ws[1]; ok && j < we[1]; j++) {
      uint8_t c = (uint8_t)line[j];
      if (c < '0' || c > '9') ok = 0;
      else v = v * 10u + (uint8_t)(c - '0');
    }
    if (!ok || v < cmd_min[cmd] || v > cmd_max[cmd]) {
      answer_err(2, w0, w0len);
      return;
    }
    value = (uint16_t)v;
  }
  switch (cmd) {
    case C_ID:
      send_id();
      break;
    case C_START:
      if (!running) {
        running = 1;
        scan_no = 0;
        measure_restart();
      }
      break;
    case C_STOP:
      running = 0;  // (a snapshot still pending becomes the next base: harmless)
      break;
    case C_WINDOW:
      window_ms = value;
      if (running && !scanning()) window_restart();
      break;
    case C_SCAN:
      scan_mask = (uint8_t)value;
      scan_set = 1;
      if (running) measure_restart();
      else mux_select(first_channel());
      break;
    case C_DWELL:  // (the reading in progress keeps its own; the next one counts this long)
      dwell_ms = value;
      break;
    case C_SETTLE:
      settle_n = (uint8_t)value;
      break;
    case C_RANGE:
      range_sel = (uint8_t)value;
      if (value) PORTD |= _BV(PD4);
      else PORTD &= (uint8_t)~_BV(PD4);
      break;
  }
  frame_begin(s_ACK);
  field_P(cmd_names[cmd]);
  if (cmd_max[cmd]) field_u32(value);
  frame_end();
}

// ---------------------------------------------------------------------------------------------
static void hw_init(void) {
  // Timer2: normal mode, clk/128: the background's clock (8 us per count), no interrupt
  TIMSK2 = 0;
  TCCR2A = 0;
  TCCR2B = _BV(CS22) | _BV(CS20);
  TIFR2 = _BV(TOV2) | _BV(OCF2A) | _BV(OCF2B);  // Arduino's init() ran it: a stale overflow flag
                                                // would add a wrap (2 ms) to the first clock poll
  // C_off range switch on D4 = PD4, low at boot (range 0)
  DDRD |= _BV(PD4);
  PORTD &= (uint8_t)~_BV(PD4);
  // multiplexer: S0..S2 on D5..D7 low (channel 0), inhibit on D9 = PB1 low (the switch enabled)
  PORTD &= (uint8_t)~MUX_BITS;
  DDRD |= MUX_BITS;
  PORTB &= (uint8_t)~_BV(PB1);
  DDRB |= _BV(PB1);
  // HX711: DOUT on D2 input with pull-up, SCK on D3 output low (a long high powers it down)
  DDRD &= (uint8_t)~_BV(PD2);
  PORTD |= _BV(PD2);
  PORTD &= (uint8_t)~_BV(PD3);
  DDRD |= _BV(PD3);
  // ADC: AVcc reference, channel A0, clk/128 (one conversion per 104 us), polled
  ADMUX = _BV(REFS0);
  ADCSRB = 0;
  DIDR0 = _BV(ADC0D);
  ADCSRA = _BV(ADEN) | _BV(ADPS2) | _BV(ADPS1) | _BV(ADPS0) | _BV(ADSC);
  // USART0 115200 8N1, polled
  UCSR0A |= _BV(U2X0);  // read-modify-write keeps UDRE0 (simavr 1.6 would clear it on a plain write)
  UBRR0 = UBRR_115200;
  UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
  UCSR0B = _BV(RXEN0) | _BV(TXEN0);
}

#ifdef METER_PROFILE
// Profiling build (make PROFILE=1): main-loop turns, read from RAM by the simavr harness (--peek);
// with the turns counted without a signal, they give the CPU share left to the background.
volatile uint32_t prof_loops __attribute__((used));
#endif

void meter_run(void) {
  cli();
  hw_init();
  capture_init();
  t2_last = TCNT2;
  send_id();  // boot identification, SEQ 0
  sei();
  for (;;) {
#ifdef METER_PROFILE
    prof_loops++;
#endif
    service();
    if (line_ready) {
      handle_line();
      line_len = 0;
      line_over = 0;
      line_ready = 0;
    }
    adc_poll();
    ref_poll();
    window_poll();
    settle_poll();
    snap_poll();
  }
}

// fsrlab meter core: polled Timer1 input capture with a cycle-budgeted background scheduler.
//
// Why polling and not a capture interrupt: at 50 kHz and 5 % (or 95 %) duty cycle one phase lasts
// 1 us = 16 CPU cycles. After an edge is captured, the edge select ICES1 must be flipped before the
// next edge arrives, or that edge is lost. An interrupt needs 4 cycles to respond, 3 for the vector
// jump, up to 4 more to finish the current instruction, plus pushes, before it can flip ICES1 -- and
// any other interrupt (millis, UART) delays it by tens of cycles. A polling loop with interrupts
// disabled flips ICES1 at most 11 cycles after the edge (see capture()).
//
// Everything else (1 ms tick, ADC, UART receive/transmit, command parsing, frame formatting) runs
// as small background "tasks" between edges. Each task has a bound on its length in cycles, and
// after every edge the scheduler predicts, from the last measured high and low times, when the
// next edge will come; it starts a task only when the task ends before that edge (with a 1/8
// margin). When the next phase is long, being late is harmless and one task always runs.
//
// Missed edges are detected, not assumed away: after flipping ICES1 the pin level must still be
// the one the captured edge produced, unless the flag shows that the next edge was captured. If not,
// an edge went by unseen: it is counted in `missed` and the period it belongs to is not used.
// Periods longer than 65535 ticks (f < 244 Hz) are extended with the 1 ms tick count (no Timer1
// overflow flag is used, so nothing depends on how TIFR1 writes clear other flags).
#include <avr/io.h>
#include <avr/pgmspace.h>
#include <util/crc16.h>
#include <stdint.h>
#include "meter.h"

// ---------------------------------------------------------------------------------------------
// Constants
#define TCCR_RISE (_BV(CS10) | _BV(ICES1))  // Timer1 normal mode, prescaler 1, capture rising edges
#define TCCR_FALL (_BV(CS10))               // ... capture falling edges
#define TICKS_PER_MS 16000u
#define UBRR_115200 16                      // with U2X0: 16e6 / (8 * 17) = 117647 baud (Arduino's choice)
#define WINDOW_MIN 10u
#define WINDOW_MAX 60000u
#define WINDOW_DEFAULT 100u
#define CMD_MAX 32u                         // longest command line, '\n' included [bytes]
#define MAX_GAP_MS 2000u                    // a phase longer than this is not a period of the signal

// Task cost bounds [cycles], including the scheduler's own overhead around one task; the
// benchmark and the simavr tests check that nothing is missed inside the supported range with them.
#define COST_SMALL 80u     // tx byte, rx byte, one formatter character or digit step, tick
#define COST_LARGE 400u    // command execution, window snapshot
#define SERVICE 24u        // from an edge to ICES1 flipped, worst case, plus the flag check
#define SAFE_NEXT (COST_SMALL + SERVICE + 16u)  // a next phase this long tolerates one late task
#define SPIN_TIMEOUT 2300u // capture wait loop iterations (6 cycles each, ~0.86 ms) before giving up
#define STARVE_EDGES 48u   // edges in a row without any task before tasks are forced

// ---------------------------------------------------------------------------------------------
// Measurement state (single thread: no interrupt is enabled anywhere)
struct Acc {
  uint32_t periods, sum_p, sum_h, missed, adc_sum;
  uint16_t adc_cnt;
};
static Acc acc;                // live window accumulators
static uint8_t armed_rise;     // 1: the capture unit waits for a rising edge
static uint8_t have;           // bit0: last rise valid, bit1: high time of that rise known, bit2: last fall valid
static uint16_t last_rise, last_fall, ms_rise, ms_fall;
static uint32_t high_pending;  // high time of the period that started at last_rise [ticks]
static uint16_t hi_len, lo_len;  // last measured high and low times, saturated to 16 bits [ticks]
static uint8_t pred;           // bit0: hi_len known, bit1: lo_len known
static uint16_t ms16;          // free-running ms count (phase extension, gap detection)
static uint16_t ms_last_edge;
static uint32_t now_ms;        // device time since boot [ms]

// Settings
static uint8_t running;
static uint16_t window_ms = WINDOW_DEFAULT;
static uint16_t win_left;
static uint8_t range_sel;
static uint32_t t_last_end;

// ---------------------------------------------------------------------------------------------
// Transmit ring
static uint8_t txbuf[128];
static uint8_t tx_head, tx_tail;
static inline uint8_t tx_free(void) { return (uint8_t)(127u - (uint8_t)((tx_head - tx_tail) & 127u)); }

// Frame formatter
enum { K_NONE = 0, K_ID, K_M, K_ACK, K_ERR };
enum { C_ID = 0, C_START, C_STOP, C_WINDOW, C_RANGE, C_COUNT };
static const char cmd_names[C_COUNT][7] PROGMEM = {"ID", "START", "STOP", "WINDOW", "RANGE"};
static const uint8_t cmd_len[C_COUNT] = {2, 5, 4, 6, 5};

struct Resp {
  uint8_t kind, cmd, has_val, code;
  uint16_t val;
  char tok[13];
};
#define RESPQ 4
static Resp respq[RESPQ];
static uint8_t rq_head, rq_tail;

struct Snap {
  uint32_t t_ms, window, periods, sum_p, sum_h, missed, adc_sum, adc_cnt, range;
  uint32_t adc_q, adc_r;  // bit-serial division state
  uint8_t div_bits;
};
static Snap snap;
static uint8_t snap_state;  // 0 none, 1 dividing, 2 ready to format
static uint8_t snap_due;

static uint8_t f_state, f_kind, f_item, f_started, f_digit, f_pidx;
static uint16_t f_crc, f_seq, seq_next;
static uint32_t f_val;
static const char *f_str;
static uint8_t f_str_pgm;
static Resp f_resp;

static const uint32_t pow10_tab[10] = {1ul, 10ul, 100ul, 1000ul, 10000ul, 100000ul,
                                       1000000ul, 10000000ul, 100000000ul, 1000000000ul};
static const char s_dev[] PROGMEM = "fsrlab-meter";
static const char s_ver[] PROGMEM = METER_FW_VERSION;
static const char s_M[] PROGMEM = "M";
static const char s_ACK[] PROGMEM = "ACK";
static const char s_ERR[] PROGMEM = "ERR";
static const char s_LINE[] PROGMEM = "LINE";

// Command receiver (incremental parser, one byte per task)
static uint8_t rx_len, rx_words, rx_inword, rx_overflow;
static uint8_t rx_w0len, rx_cand, rx_toklen;
static uint8_t rx_digits_ok, rx_ndig;
static uint32_t rx_val;
static char rx_tok[13];
static uint8_t cmd_ready;
static struct {
  uint8_t overflow, words, cand, w0len, digits_ok, ndig;
  uint32_t val;
  char tok[13];
} cmd;

// ---------------------------------------------------------------------------------------------
static inline void push_tx(uint8_t c) {
  txbuf[tx_head] = c;
  tx_head = (uint8_t)((tx_head + 1u) & 127u);
}

static inline void emit_crc(uint8_t c) {
  f_crc = _crc_xmodem_update(f_crc, c);
  push_tx(c);
}

static void queue_resp(uint8_t kind, uint8_t c, uint8_t code, uint8_t has_val, uint16_t val, const char *tok) {
  uint8_t next = (uint8_t)((rq_head + 1u) % RESPQ);
  if (next == rq_tail) return;  // queue full: the host sends faster than 115200 baud can answer
  Resp *r = &respq[rq_head];
  r->kind = kind;
  r->cmd = c;
  r->code = code;
  r->has_val = has_val;
  r->val = val;
  uint8_t i = 0;
  if (tok)
    for (; i < 12 && tok[i]; i++) r->tok[i] = tok[i];
  r->tok[i] = 0;
  rq_head = next;
}

// Item `idx` of the frame being formatted: 0 end, 1 number (f_val), 2 string (f_str)
static uint8_t frame_item(uint8_t idx) {
  f_str_pgm = 1;
  if (idx == 1) { f_val = f_seq; return 1; }
  switch (f_kind) {
    case K_ID:
      switch (idx) {
        case 0: f_str = cmd_names[C_ID]; return 2;
        case 2: f_str = s_dev; return 2;
        case 3: f_str = s_ver; return 2;
        case 4: f_val = METER_PROTOCOL_VERSION; return 1;
        case 5: f_val = F_CPU; return 1;
      }
      return 0;
    case K_M:
      switch (idx) {
        case 0: f_str = s_M; return 2;
        case 2: f_val = snap.t_ms; return 1;
        case 3: f_val = snap.window; return 1;
        case 4: f_val = snap.periods; return 1;
        case 5: f_val = snap.sum_p; return 1;
        case 6: f_val = snap.sum_h; return 1;
        case 7: f_val = snap.missed; return 1;
        case 8: f_val = snap.adc_q; return 1;
        case 9: f_val = snap.range; return 1;
      }
      return 0;
    case K_ACK:
      switch (idx) {
        case 0: f_str = s_ACK; return 2;
        case 2: f_str = cmd_names[f_resp.cmd]; return 2;
        case 3: if (f_resp.has_val) { f_val = f_resp.val; return 1; } return 0;
      }
      return 0;
    case K_ERR:
      switch (idx) {
        case 0: f_str = s_ERR; return 2;
        case 2: f_val = f_resp.code; return 1;
        case 3:
          if (f_resp.code == 3) { f_str = s_LINE; return 2; }
          f_str = f_resp.tok; f_str_pgm = 0; return 2;
      }
      return 0;
  }
  return 0;
}

enum { FS_IDLE = 0, FS_ITEM, FS_STR, FS_NUM, FS_STAR, FS_H0, FS_H1, FS_H2, FS_H3, FS_CR, FS_LF };

static inline uint8_t hexdigit(uint8_t v) { v &= 15u; return (uint8_t)(v < 10 ? '0' + v : 'A' - 10 + v); }

// One formatter step: at most one character or one decimal subtraction. Needs tx_free() >= 1.
static void fmt_step(void) {
  switch (f_state) {
    case FS_ITEM: {
      uint8_t t = frame_item(f_item);
      if (t == 0) { f_state = FS_STAR; return; }
      if (f_item) emit_crc(',');
      f_item++;
      if (t == 1) { f_pidx = 9; f_digit = 0; f_started = 0; f_state = FS_NUM; }
      else f_state = FS_STR;
      return;
    }
    case FS_STR: {
      uint8_t c = f_str_pgm ? pgm_read_byte(f_str) : (uint8_t)*f_str;
      if (!c) { f_state = FS_ITEM; return; }
      f_str++;
      emit_crc(c);
      return;
    }
    case FS_NUM: {
      uint32_t p = pow10_tab[f_pidx];
      if (f_val >= p) { f_val -= p; f_digit++; return; }
      if (f_digit || f_started || f_pidx == 0) { emit_crc((uint8_t)('0' + f_digit)); f_started = 1; }
      f_digit = 0;
      if (f_pidx == 0) f_state = FS_ITEM; else f_pidx--;
      return;
    }
    case FS_STAR: push_tx('*'); f_state = FS_H0; return;
    case FS_H0: push_tx(hexdigit((uint8_t)(f_crc >> 12))); f_state = FS_H1; return;
    case FS_H1: push_tx(hexdigit((uint8_t)(f_crc >> 8))); f_state = FS_H2; return;
    case FS_H2: push_tx(hexdigit((uint8_t)(f_crc >> 4))); f_state = FS_H3; return;
    case FS_H3: push_tx(hexdigit((uint8_t)f_crc)); f_state = FS_CR; return;
    case FS_CR: push_tx('\r'); f_state = FS_LF; return;
    case FS_LF:
      push_tx('\n');
      f_state = FS_IDLE;
      if (f_kind == K_M) snap_state = 0;
      return;
  }
}

// Start the next frame (responses before measurements). Cost: small copy, counted as large.
static uint8_t fmt_start(void) {
  if (rq_tail != rq_head) {
    f_resp = respq[rq_tail];
    rq_tail = (uint8_t)((rq_tail + 1u) % RESPQ);
    f_kind = f_resp.kind;
  } else if (snap_state == 2) {
    f_kind = K_M;
  } else {
    return 0;
  }
  f_seq = seq_next++;
  f_crc = 0xFFFF;
  f_item = 0;
  push_tx('$');
  f_state = FS_ITEM;
  return 1;
}

// ---------------------------------------------------------------------------------------------
// Command receiver: one byte per call.
static inline uint8_t is_space(uint8_t c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f' || (c >= 0x1c && c <= 0x1f); }

static void rx_reset(void) {
  rx_len = 0; rx_words = 0; rx_inword = 0; rx_overflow = 0;
  rx_w0len = 0; rx_cand = 0; rx_toklen = 0; rx_digits_ok = 1; rx_ndig = 0; rx_val = 0;
  rx_tok[0] = 0;
}

static void rx_byte(uint8_t c) {
  if (c == '\r') return;
  if (c == '\n') {
    if (!cmd_ready) {
      cmd.overflow = rx_overflow; cmd.words = rx_words; cmd.cand = rx_cand; cmd.w0len = rx_w0len;
      cmd.digits_ok = rx_digits_ok; cmd.ndig = rx_ndig; cmd.val = rx_val;
      for (uint8_t i = 0; i < 13; i++) cmd.tok[i] = rx_tok[i];
      cmd_ready = 1;
    }
    rx_reset();
    return;
  }
  if (++rx_len >= CMD_MAX) { rx_overflow = 1; return; }
  if (is_space(c)) { rx_inword = 0; return; }
  if (!rx_inword) { rx_inword = 1; rx_words++; }
  if (rx_words == 1) {
    uint8_t i = rx_w0len++;
    if (i == 0) {
      rx_cand = c == 'I' ? 1u << C_ID : c == 'S' ? (1u << C_START) | (1u << C_STOP)
              : c == 'W' ? 1u << C_WINDOW : c == 'R' ? 1u << C_RANGE : 0;
    } else if (rx_cand) {
      for (uint8_t k = 0; k < C_COUNT; k++)
        if ((rx_cand & (1u << k)) && (i >= cmd_len[k] || pgm_read_byte(&cmd_names[k][i]) != c)) rx_cand &= (uint8_t)~(1u << k);
    }
    if (rx_toklen < 12 && c > 0x20 && c < 0x7f && c != ',' && c != '*' && c != '$') {
      rx_tok[rx_toklen++] = (char)c;
      rx_tok[rx_toklen] = 0;
    }
  } else if (rx_words == 2) {
    if (c < '0' || c > '9' || rx_ndig >= 5) rx_digits_ok = 0;
    else { rx_val = rx_val * 10u + (uint8_t)(c - '0'); rx_ndig++; }
  }
}

static void apply_range(uint8_t r) {
  range_sel = r;
  if (r) PORTD |= _BV(PD4); else PORTD &= (uint8_t)~_BV(PD4);
}

static void reset_acc(void) {
  acc.periods = 0; acc.sum_p = 0; acc.sum_h = 0; acc.missed = 0; acc.adc_sum = 0; acc.adc_cnt = 0;
}

static void cmd_exec(void) {
  cmd_ready = 0;
  if (cmd.overflow) { queue_resp(K_ERR, 0, 3, 0, 0, 0); return; }
  const char *tok = cmd.tok[0] ? cmd.tok : "?";
  int8_t c = -1;
  for (uint8_t k = 0; k < C_COUNT; k++)
    if ((cmd.cand & (1u << k)) && cmd_len[k] == cmd.w0len) c = (int8_t)k;
  if (c < 0) { queue_resp(K_ERR, 0, 1, 0, 0, tok); return; }
  if (c == C_WINDOW || c == C_RANGE) {
    uint32_t v = cmd.val;
    uint8_t ok = cmd.words == 2 && cmd.digits_ok && cmd.ndig > 0;
    if (ok) ok = c == C_WINDOW ? (v >= WINDOW_MIN && v <= WINDOW_MAX) : v <= 1;
    if (!ok) { queue_resp(K_ERR, 0, 2, 0, 0, tok); return; }
    if (c == C_WINDOW) {
      window_ms = (uint16_t)v;
      win_left = window_ms;  // the current window restarts with the new length
      t_last_end = now_ms;
      reset_acc();
    } else {
      apply_range((uint8_t)v);
    }
    queue_resp(K_ACK, (uint8_t)c, 0, 1, (uint16_t)v, 0);
    return;
  }
  if (cmd.words != 1) { queue_resp(K_ERR, 0, 2, 0, 0, tok); return; }
  if (c == C_ID) {
    queue_resp(K_ID, 0, 0, 0, 0, 0);
  } else if (c == C_START) {
    if (!running) {
      running = 1;
      win_left = window_ms;
      t_last_end = now_ms;
      reset_acc();
    }
  } else {
    running = 0;
    snap_due = 0;
  }
  queue_resp(K_ACK, (uint8_t)c, 0, 0, 0, 0);
}

// ---------------------------------------------------------------------------------------------
static void tick(void) {
  TIFR2 = _BV(OCF2A);
  ms16++;
  now_ms++;
  if (!(ADCSRA & _BV(ADSC))) {  // conversion started one tick ago is done (104 us at clk/128)
    acc.adc_sum += ADC;
    acc.adc_cnt++;
    ADCSRA |= _BV(ADSC);
  }
  if ((uint16_t)(ms16 - ms_last_edge) > MAX_GAP_MS) { have = 0; pred = 0; ms_last_edge = ms16 - MAX_GAP_MS; }
  if (running && --win_left == 0) { snap_due = 1; win_left = window_ms; }
}

static void take_snapshot(void) {
  snap_due = 0;
  snap.t_ms = now_ms;
  snap.window = now_ms - t_last_end;
  t_last_end = now_ms;
  snap.periods = acc.periods;
  snap.sum_p = acc.sum_p;
  snap.sum_h = acc.sum_h;
  snap.missed = acc.missed;
  snap.adc_sum = acc.adc_sum + (acc.adc_cnt >> 1);  // rounded mean
  snap.adc_cnt = acc.adc_cnt;
  snap.range = range_sel;
  snap.adc_q = 0;
  snap.adc_r = 0;
  snap.div_bits = 32;
  snap_state = snap.adc_cnt ? 1 : 2;
  reset_acc();
}

static void div_step(void) {  // two bits of adc_sum / adc_cnt (restoring division)
  for (uint8_t i = 0; i < 2; i++) {
    snap.adc_r = (snap.adc_r << 1) | (snap.adc_sum >> 31);
    snap.adc_sum <<= 1;
    snap.adc_q <<= 1;
    if (snap.adc_r >= snap.adc_cnt) { snap.adc_r -= snap.adc_cnt; snap.adc_q |= 1; }
  }
  snap.div_bits -= 2;
  if (!snap.div_bits) {
    if (snap.adc_q > 1023) snap.adc_q = 1023;
    snap_state = 2;
  }
}

// One background task whose cost fits `budget` cycles. Returns 1 if something was done.
static uint8_t task(uint16_t budget) {
  if (budget < COST_SMALL) return 0;
  if (TIFR2 & _BV(OCF2A)) { tick(); return 1; }
  if (UCSR0A & _BV(RXC0)) { rx_byte(UDR0); return 1; }
  if (tx_head != tx_tail && (UCSR0A & _BV(UDRE0))) {
    UDR0 = txbuf[tx_tail];
    tx_tail = (uint8_t)((tx_tail + 1u) & 127u);
    return 1;
  }
  if (f_state != FS_IDLE) {
    if (tx_free() == 0) return 0;
    fmt_step();
    return 1;
  }
  if (snap_state == 1) { div_step(); return 1; }
  if (budget < COST_LARGE) return 0;
  if (cmd_ready) { cmd_exec(); return 1; }
  if (snap_due && snap_state == 0) { take_snapshot(); return 1; }
  if (tx_free() >= 96) return fmt_start();
  return 0;
}

static uint8_t work_pending(void) {
  return (TIFR2 & _BV(OCF2A)) || (UCSR0A & _BV(RXC0)) || tx_head != tx_tail || f_state != FS_IDLE ||
         snap_state || cmd_ready || snap_due || rq_tail != rq_head;
}

// ---------------------------------------------------------------------------------------------
// Wait for the armed edge (at most SPIN_TIMEOUT loop turns), then at once arm the other edge, read
// ICR1, clear ICF1 and sample PINB and TIFR1. Worst case from the flag to ICES1 flipped: 6 cycles
// between two flag reads + sbic (1) + rjmp (2) + sts (2) = 11 cycles.
struct Cap {
  uint16_t ts;
  uint8_t pin, fl, ok;
};
static inline __attribute__((always_inline)) Cap capture(uint8_t next_tccr) {
  Cap c;
  uint16_t n = SPIN_TIMEOUT;
  uint8_t icf = _BV(ICF1);
  asm volatile(
      "1: sbic %[tifr], %[icf1]\n\t"
      "rjmp 2f\n\t"
      "sbiw %[n], 1\n\t"
      "brne 1b\n\t"
      "clr %[ok]\n\t"
      "rjmp 3f\n\t"
      "2: sts %[tccr1b], %[nx]\n\t"
      "lds %A[ts], %[icr1l]\n\t"
      "lds %B[ts], %[icr1h]\n\t"
      "out %[tifr], %[icf]\n\t"
      "in %[pin], %[pinb]\n\t"
      "in %[fl], %[tifr]\n\t"
      "ldi %[ok], 1\n\t"
      "3:\n\t"
      : [ts] "=&r"(c.ts), [pin] "=&r"(c.pin), [fl] "=&r"(c.fl), [ok] "=&d"(c.ok), [n] "+w"(n)
      : [nx] "r"(next_tccr), [icf] "r"(icf), [tifr] "I"(_SFR_IO_ADDR(TIFR1)), [icf1] "I"(ICF1),
        [tccr1b] "n"(_SFR_MEM_ADDR(TCCR1B)), [icr1l] "n"(_SFR_MEM_ADDR(ICR1L)),
        [icr1h] "n"(_SFR_MEM_ADDR(ICR1H)), [pinb] "I"(_SFR_IO_ADDR(PINB))
      : "memory");
  return c;
}

// Length of a phase of 16-bit length d16 whose ends were serviced m ms apart [ticks].
static inline uint32_t extend(uint16_t d16, uint16_t m) {
  if (m < 2) return d16;  // less than 3 ms: shorter than 65536 ticks
  int32_t k = ((int32_t)TICKS_PER_MS * (int32_t)m - (int32_t)d16 + 32768) >> 16;
  if (k < 0) k = 0;
  return ((uint32_t)k << 16) + d16;
}

static inline uint16_t sat16(uint32_t v) { return v > 0xFFFFu ? 0xFFFFu : (uint16_t)v; }

static void resync(void) {
  uint8_t level = PINB & _BV(PB0);
  armed_rise = level ? 0 : 1;
  TCCR1B = level ? TCCR_FALL : TCCR_RISE;
  TIFR1 = _BV(ICF1);
}

static void hw_init(void) {
  // Timer0 (Arduino millis) and every interrupt off: the meter is fully polled.
  TIMSK0 = 0; TIMSK1 = 0; TIMSK2 = 0;
  TCCR0A = 0; TCCR0B = 0;
  // Timer1: normal mode, prescaler 1, input capture on ICP1 = PB0 = D8, no noise canceller.
  TCCR1A = 0;
  TCCR1C = 0;
  DDRB &= (uint8_t)~_BV(PB0);
  PORTB &= (uint8_t)~_BV(PB0);
  // Timer2: CTC, clk/64, OCR2A = 249 -> OCF2A every 16000 cycles = 1 ms (polled).
  TCCR2A = _BV(WGM21);
  TCCR2B = _BV(CS22);
  OCR2A = 249;
  TCNT2 = 0;
  TIFR2 = 0xFF;
  // C_off range switch on D4 = PD4, low at boot (range 0).
  DDRD |= _BV(PD4);
  PORTD &= (uint8_t)~_BV(PD4);
  // ADC: AVcc reference, channel A0, clk/128 (125 kHz), one conversion started per ms.
  ADMUX = _BV(REFS0);
  ADCSRB = 0;
  DIDR0 = _BV(ADC0D);
  ADCSRA = _BV(ADEN) | _BV(ADPS2) | _BV(ADPS1) | _BV(ADPS0) | _BV(ADSC);
  // USART0 115200 8N1, polled.
  UCSR0A |= _BV(U2X0);  // read-modify-write: simavr 1.6 would clear UDRE0 on a plain write
  UBRR0 = UBRR_115200;
  UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
  UCSR0B = _BV(RXEN0) | _BV(TXEN0);
  TCCR1B = TCCR_RISE;
  armed_rise = 1;
  resync();
}

void meter_run(void) {
  asm volatile("cli");
  hw_init();
  rx_reset();
  queue_resp(K_ID, 0, 0, 0, 0, 0);  // boot identification, SEQ 0

  uint16_t t_edge = 0;
  uint16_t limit = 0xFFFF;  // 0xFFFF: no prediction, tasks may run until an edge is pending
  uint8_t late_ok = 1;      // one task may run even past the limit (the next phase is long)
  uint8_t starve = 0;

  for (;;) {
    // ---- background tasks while the next edge is far enough away
    for (;;) {
      if (TIFR1 & _BV(ICF1)) break;
      uint16_t budget;
      if (limit == 0xFFFF) {
        budget = 0xFFFF;
      } else {
        uint16_t el = TCNT1 - t_edge;
        budget = el < limit ? (uint16_t)(limit - el) : 0;
        if (budget < COST_SMALL && late_ok) budget = COST_SMALL;
      }
      if (budget < COST_SMALL) break;
      starve = 0;
      if (task(budget)) late_ok = 0;
      else if (limit != 0xFFFF && budget != 0xFFFF && !late_ok) break;  // nothing fits: wait for the edge
    }

    // ---- wait for the edge and capture it
    uint8_t was_rise = armed_rise;
    Cap c = capture(was_rise ? TCCR_FALL : TCCR_RISE);
    if (!c.ok) {  // no edge for ~0.9 ms although one was predicted: the signal changed or stopped
      limit = 0xFFFF;
      pred = 0;
      continue;
    }
    armed_rise = (uint8_t)!was_rise;
    uint16_t ts = c.ts;
    uint8_t level = c.pin & _BV(PB0);
    if (!(c.fl & _BV(ICF1)) && (was_rise ? !level : level)) {
      // the next edge passed before ICES1 was flipped: it is lost, and with it this period
      acc.missed++;
      have = 0;
      armed_rise = was_rise;
      TCCR1B = was_rise ? TCCR_RISE : TCCR_FALL;
      TIFR1 = _BV(ICF1);
      limit = 0xFFFF;
      continue;
    }
    uint16_t ms = ms16;
    ms_last_edge = ms;
    uint16_t l_cur, l_next;
    if (was_rise) {
      if (have & 4) {
        uint16_t m = ms - ms_fall;
        if (m > MAX_GAP_MS) have = 0;
        else { lo_len = sat16(extend(ts - last_fall, m)); pred |= 2; }
      }
      if ((have & 3) == 3) {
        uint16_t m = ms - ms_rise;
        if (m <= MAX_GAP_MS) {
          acc.sum_p += extend(ts - last_rise, m);
          acc.sum_h += high_pending;
          acc.periods++;
        }
      }
      last_rise = ts;
      ms_rise = ms;
      have = (uint8_t)((have & 4) | 1);
      l_cur = hi_len;
      l_next = lo_len;
    } else {
      if (have & 1) {
        uint16_t m = ms - ms_rise;
        if (m > MAX_GAP_MS) have = 0;
        else {
          high_pending = extend(ts - last_rise, m);
          hi_len = sat16(high_pending);
          have |= 2;
          pred |= 1;
        }
      }
      last_fall = ts;
      ms_fall = ms;
      have |= 4;
      l_cur = lo_len;
      l_next = hi_len;
    }
    t_edge = ts;
    if (pred != 3) {
      limit = 0xFFFF;
      late_ok = 1;
    } else {
      uint16_t l = (uint16_t)(l_cur - (l_cur >> 3));
      limit = l > SERVICE ? (uint16_t)(l - SERVICE) : 0;  // tasks must end before this (since t_edge)
      if (limit == 0xFFFF) limit = 0xFFFE;
      late_ok = l_next >= SAFE_NEXT;
    }

    // ---- starvation: edges too fast for any task; run some blind and count what went by
    if (++starve >= STARVE_EDGES && work_pending()) {
      starve = 0;
      uint16_t t0 = TCNT1;
      uint8_t p0 = PINB & _BV(PB0);
      for (uint8_t i = 0; i < 16; i++) task(0xFFFF);
      uint16_t blind = TCNT1 - t0;
      if ((TIFR1 & _BV(ICF1)) || (PINB & _BV(PB0)) != p0) {
        uint16_t per = hi_len + lo_len;
        uint32_t est = (pred == 3 && per) ? (2u * (uint32_t)blind) / per : 1u;
        acc.missed += est ? est : 1u;
        have = 0;
        resync();
        limit = 0xFFFF;
      }
    }
  }
}

// fsrlab meter core: polled Timer1 input capture with a cycle-budgeted background scheduler.
//
// Why polling and not a capture interrupt: at 50 kHz and 5 % (or 95 %) duty cycle one phase lasts
// 1 us = 16 CPU cycles. After an edge is captured, the edge select ICES1 must be flipped before the
// next edge arrives, or that edge is lost. An interrupt needs up to 4 cycles to finish the current
// instruction, 4 to respond and 3 for the vector jump, then pushes before it can flip ICES1, and
// any other interrupt (millis, UART) delays it by tens of cycles. The polling loop in capture()
// flips ICES1 at most 11 cycles after the capture flag rises. Interrupts stay disabled.
//
// Hot path (per edge): capture(), check that no edge went by unseen, add the edge to the window
// sums, update the last high and low times used for prediction.
// Everything else is a background task with a bounded length: 1 ms tick (time, ADC, window end),
// UART receive/transmit, command execution and frame formatting (one character or one decimal
// digit step per task). After each edge the
// scheduler knows the length of the phase that just began (last measurement); if the phase after
// it is short, a task may start only if it ends, with a 1/8 margin, before the next edge, so the
// capture loop is spinning when that edge arrives. If the phase after it is long, a late service
// of the next edge is harmless and tasks run freely.
//
// Missed edges are detected, not assumed away: after flipping ICES1 the pin must still be at the
// level the captured edge produced unless the flag shows that the next edge was captured too; if
// not, an edge went by unseen, it is counted in `missed`, and the periods around it are dropped.
// Forced (starved) tasks are counted the same way. A window with missed > 0 is
// not a clean measurement. Periods longer than 65535 ticks (f < 244 Hz) are extended with the 1 ms
// tick count; no Timer1 overflow flag is used, so nothing depends on how TIFR1 writes clear flags.
#include <avr/io.h>
#include <avr/interrupt.h>
#include <avr/pgmspace.h>
#include <util/crc16.h>
#include <stdint.h>
#include "meter.h"

// ---------------------------------------------------------------------------------------------
// Constants
#define TCCR_RISE (_BV(CS10) | _BV(ICES1))  // Timer1 normal mode, prescaler 1, capture rising edges
#define TCCR_FALL (_BV(CS10))               // ... capture falling edges
#define TICKS_PER_MS 16000L
#define UBRR_115200 16                      // with U2X0: 16e6 / (8 * 17) = 117647 baud (Arduino's choice)
#define WINDOW_MIN 10u
#define WINDOW_MAX 60000u
#define WINDOW_DEFAULT 100u
#define CMD_MAX 32u                         // longest command line, '\n' included [bytes]
#define MAX_PHASE_MS 250u                   // a longer high or low time is a gap, not a period

// Upper bounds of task lengths [cycles] including dispatch, measured with `make PROFILE=1` in
// simavr (benchmarks/bench_firmware.py prints them); the scheduler starts a task only when its
// bound fits before the next edge that must be serviced on time.
#define COST_TICK 110u
#define COST_RX 120u
#define COST_TX 70u
#define COST_FMT 120u
#define COST_DIV 110u
#define COST_EXEC 120u
#define COST_SNAP 120u
#define COST_START 110u
#define HOT 110u            // capture + bookkeeping of one edge, worst case [cycles]
#define SERVICE 20u         // flag check to ICES1 flipped, worst case, with loop exit [cycles]
#define MARGIN 24u
#define BURST 4000u         // longest forced run of tasks [cycles]

#ifdef METER_PROFILE
// Profiling build (make PROFILE=1): longest duration of each task and of the hot path, read
// from RAM by the simavr harness (--peek). Adds a few cycles around every task.
extern "C" {
uint16_t prof_task[16];
uint16_t prof_hot;      // from the capture returning to the end of the edge bookkeeping
uint16_t prof_late;     // from the capture timestamp to the capture returning
uint16_t prof_cnt[4];   // pin-check misses, starvation bursts, timeouts, late (> 11 cycles) services
}
#endif

// ---------------------------------------------------------------------------------------------
// Window accumulators. The sum of periods is kept as a chain: between two breaks (a missed edge,
// a window end) the periods are contiguous, so their sum is last_rise - chain_start (extended by
// the number of 16-bit wraps in between), and each rising edge only counts one period.
struct Acc {
  uint32_t periods, sum_p, sum_h, missed, adc_sum;
  uint16_t adc_cnt;
};
static Acc acc;
static uint8_t chain;           // 1: last_rise starts or continues a contiguous chain
static uint8_t have_high;       // 1: the high time of the period begun at last_rise is in sum_h
static uint16_t chain_start, last_rise, wraps;
static uint8_t ms_rise;         // low byte of the ms count at last_rise
static uint32_t high_pending;   // high time added to sum_h for the still open period [ticks]
static uint16_t idle_ms;        // ms since the last edge
// Time
static uint16_t ms16;           // ms since boot, low 16 bits
static uint16_t ms_hi;          // ... high 16 bits
// Settings
static uint8_t running;
static uint16_t window_ms = WINDOW_DEFAULT;
static uint16_t win_left;
static uint8_t range_sel;
static uint32_t t_last_end;
static uint8_t snap_stage;      // window end in progress: 1 fold, 2 copy rest
// Starvation: edges so fast that no task fits. Detected by the 1 ms tick (no task but the tick
// ran for 2 ms although work waits) or by the main loop (the tick itself waited 0.5 ms); the
// main loop then runs tasks blind for up to BURST cycles and counts the edges that went by.
static uint8_t progress, stall, force;

// Transmit ring
static uint8_t txbuf[128];
static uint8_t tx_head, tx_tail;
static inline uint8_t tx_used(void) { return (uint8_t)((tx_head - tx_tail) & 127u); }

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
#define RESPQ 4u
static Resp respq[RESPQ];
static uint8_t rq_head, rq_tail;

struct Snap {
  uint32_t t_ms, window, periods, sum_p, sum_h, missed, adc_sum, adc_cnt, range;
  uint32_t adc_q, adc_r;  // bit-serial division state
  uint8_t div_bits;
};
static Snap snap;
static uint8_t snap_state;  // 0 free, 1 dividing, 2 ready to format, 3 being formatted

static uint8_t f_state, f_kind, f_item, f_started, f_digit, f_pidx;
static uint16_t f_crc, f_seq, seq_next;
static uint32_t f_val;
static const char *f_str;
static uint8_t f_str_pgm;
static uint8_t f_resp;  // index into respq of the response being formatted

static const uint32_t pow10_tab[10] = {1ul, 10ul, 100ul, 1000ul, 10000ul, 100000ul,
                                       1000000ul, 10000000ul, 100000000ul, 1000000000ul};
static const char s_dev[] PROGMEM = "fsrlab-meter";
static const char s_ver[] PROGMEM = METER_FW_VERSION;
static const char s_M[] PROGMEM = "M";
static const char s_ACK[] PROGMEM = "ACK";
static const char s_ERR[] PROGMEM = "ERR";
static const char s_LINE[] PROGMEM = "LINE";
static const char s_Q[] = "?";

// Command receiver (incremental parser, one byte per task). While a received line waits for
// execution (cmd_ready), further bytes stay in the USART.
static struct {
  uint8_t len, words, inword, overflow, w0len, cand, toklen, digits_ok, ndig;
  uint32_t val;
  char tok[13];
} rx;
static uint8_t cmd_ready;

// ---------------------------------------------------------------------------------------------
static inline void push_tx(uint8_t c) {
  txbuf[tx_head] = c;
  tx_head = (uint8_t)((tx_head + 1u) & 127u);
}

static inline void emit_crc(uint8_t c) {
  f_crc = _crc_xmodem_update(f_crc, c);
  push_tx(c);
}

static uint8_t queue_resp(uint8_t kind, uint8_t c, uint8_t code, uint8_t has_val, uint16_t val) {
  uint8_t next = (uint8_t)((rq_head + 1u) & (RESPQ - 1u));
  if (next == rq_tail) return 0xFF;  // full: the host sends faster than 115200 baud can answer
  Resp *r = &respq[rq_head];
  r->kind = kind;
  r->cmd = c;
  r->code = code;
  r->has_val = has_val;
  r->val = val;
  r->tok[0] = 0;
  uint8_t i = rq_head;
  rq_head = next;
  return i;
}

// Item `idx` of the frame being formatted: 0 end, 1 number (f_val), 2 string (f_str)
static uint8_t frame_item(uint8_t idx) {
  f_str_pgm = 1;
  if (idx == 1) { f_val = f_seq; return 1; }
  const Resp *r = &respq[f_resp];
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
        case 2: f_str = cmd_names[r->cmd]; return 2;
        case 3: if (r->has_val) { f_val = r->val; return 1; } return 0;
      }
      return 0;
    case K_ERR:
      switch (idx) {
        case 0: f_str = s_ERR; return 2;
        case 2: f_val = r->code; return 1;
        case 3:
          if (r->code == 3) { f_str = s_LINE; return 2; }
          f_str = r->tok; f_str_pgm = 0; return 2;
      }
      return 0;
  }
  return 0;
}

enum { FS_IDLE = 0, FS_ITEM, FS_STR, FS_NUM, FS_STAR, FS_H0, FS_H1, FS_H2, FS_H3, FS_CR, FS_LF };

static inline uint8_t hexdigit(uint8_t v) { v &= 15u; return (uint8_t)(v < 10 ? '0' + v : 'A' - 10 + v); }

// One formatter step: at most one character or one decimal subtraction. Needs one free byte.
static void __attribute__((noinline)) fmt_step(void) {
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
      else rq_tail = (uint8_t)((rq_tail + 1u) & (RESPQ - 1u));
      return;
  }
}

// Start the next frame (responses before measurements).
static void __attribute__((noinline)) fmt_start(void) {
  if (rq_tail != rq_head) {
    f_resp = rq_tail;
    f_kind = respq[rq_tail].kind;
  } else {
    f_kind = K_M;
    snap_state = 3;
  }
  f_seq = seq_next++;
  f_crc = 0xFFFF;
  f_item = 0;
  push_tx('$');
  f_state = FS_ITEM;
}

// ---------------------------------------------------------------------------------------------
// Command receiver: one byte per call. Matches protocol.parse_command of the host package.
static inline uint8_t is_space(uint8_t c) { return c == ' ' || (c >= '\t' && c <= '\f' && c != '\n') || (c >= 0x1c && c <= 0x1f); }

static void rx_reset(void) {
  rx.len = 0; rx.words = 0; rx.inword = 0; rx.overflow = 0;
  rx.w0len = 0; rx.cand = 0; rx.toklen = 0; rx.digits_ok = 1; rx.ndig = 0; rx.val = 0;
  rx.tok[0] = 0;
}

static void __attribute__((noinline)) rx_byte(uint8_t c) {
  if (c == '\r') return;
  if (c == '\n') { cmd_ready = 1; return; }
  if (++rx.len >= CMD_MAX) { rx.overflow = 1; rx.len = CMD_MAX; return; }
  if (is_space(c)) { rx.inword = 0; return; }
  if (!rx.inword) { rx.inword = 1; if (rx.words < 3) rx.words++; }
  if (rx.words == 1) {
    uint8_t i = rx.w0len++;
    if (i == 0) {
      rx.cand = c == 'I' ? 1u << C_ID : c == 'S' ? (1u << C_START) | (1u << C_STOP)
              : c == 'W' ? 1u << C_WINDOW : c == 'R' ? 1u << C_RANGE : 0;
    } else if (rx.cand) {
      uint8_t cand = rx.cand, bit = 1;
      for (uint8_t k = 0; k < C_COUNT; k++, bit <<= 1)
        if ((cand & bit) && (i >= cmd_len[k] || pgm_read_byte(&cmd_names[k][i]) != c)) cand &= (uint8_t)~bit;
      rx.cand = cand;
    }
    if (rx.toklen < 12 && c > 0x20 && c < 0x7f && c != ',' && c != '*' && c != '$') {
      rx.tok[rx.toklen++] = (char)c;
      rx.tok[rx.toklen] = 0;
    }
  } else if (rx.words == 2) {
    if (c < '0' || c > '9' || rx.ndig >= 5) rx.digits_ok = 0;
    else { rx.val = rx.val * 10u + (uint8_t)(c - '0'); rx.ndig++; }
  }
}

static inline uint32_t now_ms(void) { return ((uint32_t)ms_hi << 16) | ms16; }

// Command execution in two tasks: decide (cmd_ready 1 -> 2), then act and answer (2 -> 0).
static uint8_t ex_cmd, ex_code;  // ex_code: 0 accept, else the ERR code
static void __attribute__((noinline)) cmd_decide(void) {
  cmd_ready = 2;
  ex_code = 0;
  if (rx.overflow) { ex_code = 3; return; }
  int8_t c = -1;
  uint8_t bit = 1;
  for (uint8_t k = 0; k < C_COUNT; k++, bit <<= 1)
    if ((rx.cand & bit) && cmd_len[k] == rx.w0len) c = (int8_t)k;
  if (c < 0) { ex_code = 1; return; }
  ex_cmd = (uint8_t)c;
  if (c == C_WINDOW || c == C_RANGE) {
    uint32_t v = rx.val;
    uint8_t ok = rx.words == 2 && rx.digits_ok && rx.ndig > 0;
    if (ok) ok = c == C_WINDOW ? (v >= WINDOW_MIN && v <= WINDOW_MAX) : v <= 1;
    if (!ok) ex_code = 2;
  } else if (rx.words != 1) {
    ex_code = 2;
  }
}

static void __attribute__((noinline)) cmd_act(void) {
  uint8_t c = ex_cmd;
  if (ex_code) {
    uint8_t i = queue_resp(K_ERR, 0, ex_code, 0, 0);
    if (i != 0xFF && ex_code != 3) {
      const char *t = rx.tok[0] ? rx.tok : s_Q;
      char *d = respq[i].tok;
      while ((*d++ = *t++)) {}
    }
  } else if (c == C_WINDOW) {
    window_ms = (uint16_t)rx.val;
    win_left = window_ms;  // the current window restarts with the new length
    t_last_end = now_ms();
    acc.missed = 0;
    snap_stage = 3;        // discard what the old window accumulated (see take_snapshot)
    queue_resp(K_ACK, c, 0, 1, window_ms);
  } else if (c == C_RANGE) {
    range_sel = (uint8_t)rx.val;
    if (range_sel) PORTD |= _BV(PD4); else PORTD &= (uint8_t)~_BV(PD4);
    queue_resp(K_ACK, c, 0, 1, range_sel);
  } else {
    if (c == C_ID) {
      queue_resp(K_ID, 0, 0, 0, 0);
    } else if (c == C_START) {
      if (!running) {
        running = 1;
        win_left = window_ms;
        t_last_end = now_ms();
        snap_stage = 3;
      }
    } else {
      running = 0;
    }
    queue_resp(K_ACK, c, 0, 0, 0);
  }
  rx_reset();
  cmd_ready = 0;
}

static void chain_break(void);

// ---------------------------------------------------------------------------------------------
static uint8_t work_waiting(void);

static void __attribute__((noinline)) tick(void) {
  TIFR2 = _BV(OCF2A);
  if (!progress && work_waiting()) {
    if (++stall >= 2) force = 1;
  } else {
    stall = 0;
  }
  progress = 0;
  if (++ms16 == 0) ms_hi++;
  if (!(ADCSRA & _BV(ADSC))) {  // the conversion started one tick ago is done (104 us at clk/128)
    acc.adc_sum += ADC;
    acc.adc_cnt++;
    ADCSRA |= _BV(ADSC);
  }
  if (++idle_ms > MAX_PHASE_MS) { idle_ms = MAX_PHASE_MS; chain_break(); }
  if (running && --win_left == 0) { snap_stage = 1; win_left = window_ms; }
}

// Close the period chain into sum_p (window end or a break).
static void __attribute__((noinline)) fold_chain(void) {
  if (chain) {
    acc.sum_p += ((uint32_t)wraps << 16) + (uint16_t)(last_rise - chain_start) -
                 (last_rise < chain_start ? 0x10000ul : 0ul);
    chain_start = last_rise;
    wraps = 0;
  }
}

static void chain_break(void) {
  fold_chain();
  if (have_high) acc.sum_h -= high_pending;  // its period will not be counted
  chain = 0;
  have_high = 0;
}

// Window end in two tasks. Stage 1 closes the sums of the ended window (the open period's high
// time moves on to the next window), stage 2 copies time, missed and ADC. Stage 3 (START,
// WINDOW) discards instead of reporting.
static void __attribute__((noinline)) take_snapshot(void) {
  if (snap_stage == 1 || snap_stage == 3) {
    fold_chain();
    uint32_t hp = have_high ? high_pending : 0;
    snap.periods = acc.periods;
    snap.sum_p = acc.sum_p;
    snap.sum_h = acc.sum_h - hp;
    acc.periods = 0;
    acc.sum_p = 0;
    acc.sum_h = hp;
    if (snap_stage == 3) { acc.missed = 0; acc.adc_sum = 0; acc.adc_cnt = 0; snap_stage = 0; return; }
    snap_stage = 2;
    return;
  }
  uint32_t t = now_ms();
  snap.t_ms = t;
  snap.window = t - t_last_end;
  t_last_end = t;
  snap.missed = acc.missed;
  snap.adc_sum = acc.adc_sum + (acc.adc_cnt >> 1);  // rounded mean
  snap.adc_cnt = acc.adc_cnt;
  snap.range = range_sel;
  snap.adc_q = 0;
  snap.adc_r = 0;
  snap.div_bits = 32;
  acc.missed = 0;
  acc.adc_sum = 0;
  acc.adc_cnt = 0;
  snap_state = snap.adc_cnt ? 1 : 2;
  snap_stage = 0;
}

static void __attribute__((noinline)) div_step(void) {  // one bit of adc_sum / adc_cnt
  snap.adc_r = (snap.adc_r << 1) | (snap.adc_sum >> 31);
  snap.adc_sum <<= 1;
  snap.adc_q <<= 1;
  if (snap.adc_r >= snap.adc_cnt) { snap.adc_r -= snap.adc_cnt; snap.adc_q |= 1; }
  if (!--snap.div_bits) {
    if (snap.adc_q > 1023) snap.adc_q = 1023;
    snap_state = 2;
  }
}

// Number of whole 65536-tick turns in a phase of 16-bit length d16 whose ends were seen m >= 2 ms
// apart: the one k with |k 65536 + d16 - 16000 m| < 32768 (the ms count is off by < 1 ms).
static uint16_t __attribute__((noinline)) turns(uint16_t d16, uint8_t m) {
  int32_t k = ((int32_t)TICKS_PER_MS * (int32_t)m - (int32_t)d16 + 32768L) >> 16;
  return k < 0 ? 0 : (uint16_t)k;
}

// ---------------------------------------------------------------------------------------------
// Background dispatcher: runs the first pending task whose cost bound fits `budget` cycles.
// Returns its number, 0 if none ran.
static inline __attribute__((always_inline)) uint8_t task(uint16_t budget) {
  if (TIFR2 & _BV(OCF2A)) { if (budget >= COST_TICK) { tick(); return 1; } return 0; }
  progress = 1;
  if (!cmd_ready && (UCSR0A & _BV(RXC0))) { if (budget >= COST_RX) { rx_byte(UDR0); return 2; } return 0; }
  if (tx_head != tx_tail && (UCSR0A & _BV(UDRE0))) {
    if (budget < COST_TX) return 0;
    UDR0 = txbuf[tx_tail];
    tx_tail = (uint8_t)((tx_tail + 1u) & 127u);
    return 3;
  }
  if (snap_stage && snap_state == 0) { if (budget >= COST_SNAP) { take_snapshot(); return 4; } return 0; }
  if (f_state != FS_IDLE) {
    if (budget < COST_FMT || tx_used() >= 127u) return 0;
    fmt_step();
    return 5;
  }
  if (snap_state == 1) { if (budget >= COST_DIV) { div_step(); return 6; } return 0; }
  if (cmd_ready == 1) { if (budget >= COST_EXEC) { cmd_decide(); return 7; } return 0; }
  if (cmd_ready == 2) { if (budget >= COST_EXEC) { cmd_act(); return 8; } return 0; }
  if ((rq_tail != rq_head || snap_state == 2) && tx_used() < 32u) {
    if (budget >= COST_START) { fmt_start(); return 9; }
  }
  return 0;
}

static uint8_t work_waiting(void) {
  return tx_head != tx_tail || f_state != FS_IDLE || snap_stage || snap_state == 1 || cmd_ready ||
         (UCSR0A & _BV(RXC0)) || ((rq_tail != rq_head || snap_state == 2));
}

static inline __attribute__((always_inline)) uint8_t run_task(uint16_t budget) {
#ifdef METER_PROFILE
  uint16_t t0 = TCNT1;
  uint8_t id = task(budget);
  uint16_t d = TCNT1 - t0;
  if (d > prof_task[id]) prof_task[id] = d;
  return id;
#else
  return task(budget);
#endif
}

// ---------------------------------------------------------------------------------------------
// meter_spin(next_tccr): wait for the armed edge with interrupts enabled for one purpose only, a
// Timer0 compare match as timeout; then read ICR1, write the other edge into TCCR1B, clear ICF1
// (this order is the datasheet's: a change of ICES1 may set ICF1), disable interrupts and sample
// PINB and TIFR1. The wait loop is `sbis; rjmp` (3 cycles), so from the capture flag to ICES1
// flipped takes at most 3 + 2 (sbis skip) + 4 (lds, lds) + 2 (sts) = 11 cycles, and ICF1 is
// cleared one cycle later. An edge in that last cycle is lost and seen as missed by the caller.
// Returns ICR1 << 16 | TIFR1 << 8 | PINB; TIFR1 byte 0xFF (impossible) on timeout.
// Registers: r18..r21, r30, r31 and r0 are call-clobbered in the avr-gcc ABI.
extern "C" uint32_t meter_spin(uint8_t next_tccr);
asm(R"ASM(
  .section .text.meter_spin,"ax",@progbits
  .global meter_spin
  .global meter_spin_timeout
meter_spin:
  ldi r21, 0x20          ; 1 << ICF1
  sei
1:
  sbis 0x16, 5           ; TIFR1.ICF1
  rjmp 1b
  lds r18, 0x86          ; ICR1L (latches ICR1H)
  lds r19, 0x87          ; ICR1H
  sts 0x81, r24          ; TCCR1B: arm the other edge
  out 0x16, r21          ; clear ICF1
  cli
  in r22, 0x03           ; PINB
  in r23, 0x16           ; TIFR1
  movw r24, r18
  ret
meter_spin_timeout:      ; the Timer0 compare interrupt returns here instead of into the loop
  cli
  ldi r23, 0xFF
  clr r22
  clr r24
  clr r25
  ret
)ASM");

// Timer0 compare A: the spin timed out. Replace the interrupted address (inside meter_spin's
// loop, or in its last instructions if an edge came at the same moment: the caller resyncs) by
// meter_spin_timeout. The return address on the stack is big-endian, high byte on top.
ISR(TIMER0_COMPA_vect, ISR_NAKED) {
  asm volatile(
      "pop r0\n\t"
      "pop r0\n\t"
      "ldi r30, lo8(gs(meter_spin_timeout))\n\t"
      "ldi r31, hi8(gs(meter_spin_timeout))\n\t"
      "push r30\n\t"
      "push r31\n\t"
      "reti\n\t");
}

struct Cap {
  uint16_t ts;
  uint8_t pin, fl, ok;
};
static inline __attribute__((always_inline)) Cap capture(uint8_t next_tccr) {
  OCR0A = (uint8_t)(TCNT0 + 14u);  // timeout: 14 x 64 us = 0.9 ms
  TIFR0 = _BV(OCF0A);
  uint32_t r = meter_spin(next_tccr);
  Cap c;
  c.pin = (uint8_t)r;
  c.fl = (uint8_t)(r >> 8);
  c.ts = (uint16_t)(r >> 16);
  c.ok = c.fl != 0xFF;
  return c;
}

static void hw_init(void) {
  // Timer0 (Arduino millis) and every interrupt off: the meter is fully polled.
  TIMSK1 = 0; TIMSK2 = 0;
  // Timer0: normal mode, clk/1024 (64 us); its compare A interrupt is the capture wait timeout,
  // the only interrupt ever enabled (only while meter_spin waits).
  TCCR0A = 0;
  TCCR0B = _BV(CS02) | _BV(CS00);
  TIMSK0 = _BV(OCIE0A);
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
  UCSR0A |= _BV(U2X0);  // read-modify-write keeps UDRE0 (simavr 1.6 would clear it on a plain write)
  UBRR0 = UBRR_115200;
  UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
  UCSR0B = _BV(RXEN0) | _BV(TXEN0);
}

// Latest time after the edge at ts by which a task must end [ticks since ts], from the current
// phase (l_cur, just begun) and the next one (l_next), each with a 1/8 margin for jitter:
// either the task ends before the next edge, or it ends late enough that the next edge, served
// late, still has its successor armed in time and the backlog (one HOT) is gone before the edge
// after that. 0xFFFF: no limit (phases long or unknown).
static uint16_t task_limit(uint16_t l_cur, uint16_t l_next) {
  if (l_cur >= 0x3000u || l_next >= 0x3000u) return 0xFFFF;
  uint16_t a = (uint16_t)(l_cur - (l_cur >> 3));
  a = a > MARGIN ? (uint16_t)(a - MARGIN) : 0;
  uint16_t s2 = (uint16_t)(l_cur + l_next);
  s2 = (uint16_t)(s2 - (s2 >> 3));
  uint16_t s3 = (uint16_t)(s2 + l_cur - (l_cur >> 3));
  uint16_t b1 = s2 > SERVICE + MARGIN ? (uint16_t)(s2 - SERVICE - MARGIN) : 0;
  uint16_t b2 = s3 > HOT + 2 * SERVICE + MARGIN ? (uint16_t)(s3 - HOT - 2 * SERVICE - MARGIN) : 0;
  uint16_t b = b1 < b2 ? b1 : b2;
  return a > b ? a : b;
}

void meter_run(void) {
  asm volatile("cli");
  hw_init();
  rx_reset();
  queue_resp(K_ID, 0, 0, 0, 0);  // boot identification, SEQ 0

  uint8_t armed;            // 1: the capture unit waits for a rising edge
  uint16_t ts = 0;          // last captured edge [ticks]
  uint8_t ms_prev = 0;      // ms count (low byte) at that edge
  uint16_t l_hi = 0, l_lo = 0;  // last measured high and low times [ticks], 0xFFFF if >= 1 ms
  uint8_t pk = 0;           // bit0: l_hi valid, bit1: l_lo valid, bit2: ts is the previous edge
  uint16_t lim = 0xFFFF;    // tasks must end before TCNT1 - ts reaches lim

  {  // arm for the edge opposite to the present level
    uint8_t level = PINB & _BV(PB0);
    armed = level ? 0 : 1;
    TCCR1B = level ? TCCR_FALL : TCCR_RISE;
    TIFR1 = _BV(ICF1);
  }

  for (;;) {
    // ---- starvation: edges too fast for the tasks; run some blind and count what went by
    // (TCNT2 counts 4 us steps since OCF2A rose: a tick waiting for 0.5 ms forces the tasks)
    if ((TIFR2 & _BV(OCF2A)) && TCNT2 >= 125u) force = 1;
    if (force) {
      force = 0;
#ifdef METER_PROFILE
      prof_cnt[1]++;
#endif
      uint16_t t0 = TCNT1;
      uint8_t p0 = PINB & _BV(PB0);
      do {  // up to 1/4 ms: the USART needs wall time, 87 us per byte
        if (!task(0xFFFF) && !work_waiting()) break;
      } while ((uint16_t)(TCNT1 - t0) < BURST);
      uint16_t blind = TCNT1 - t0;
      if ((TIFR1 & _BV(ICF1)) || (PINB & _BV(PB0)) != p0) {
        uint16_t per = (pk & 3) == 3 ? (uint16_t)(l_hi + l_lo) : 0;
        uint16_t est = per ? (uint16_t)((2u * (uint32_t)blind) / per) : 1u;
        acc.missed += est ? est : 1u;
        chain_break();
        uint8_t lv = PINB & _BV(PB0);
        armed = lv ? 0 : 1;
        TCCR1B = lv ? TCCR_FALL : TCCR_RISE;
        TIFR1 = _BV(ICF1);
        pk &= 3;
        lim = 0xFFFF;
      }
    }

    // ---- background tasks while the next edges allow
    for (;;) {
      if (TIFR1 & _BV(ICF1)) break;
      uint16_t budget = 0xFFFF;
      if (lim != 0xFFFF) {
        uint16_t el = TCNT1 - ts;
        budget = el < lim ? (uint16_t)(lim - el) : 0;
      }
      if (run_task(budget)) continue;
      if (lim != 0xFFFF) break;  // nothing fits: wait for the edge in the capture loop
    }

    // ---- capture
    uint8_t was_rise = armed;
    Cap c = capture(was_rise ? TCCR_FALL : TCCR_RISE);
#ifdef METER_PROFILE
    uint16_t t_ret = TCNT1;
    if (c.ok) {
      uint16_t d = t_ret - c.ts;
      if (d > prof_late) prof_late = d;
    } else {
      prof_cnt[2]++;
    }
#endif
    if (!c.ok) {  // no edge for ~0.9 ms although one was predicted soon
      lim = 0xFFFF;
      pk = 0;
      continue;
    }
    uint8_t level = c.pin & _BV(PB0);
    uint8_t ms = (uint8_t)ms16;
    idle_ms = 0;
    if (!(c.fl & _BV(ICF1)) && (was_rise ? !level : level)) {
      // the next edge passed before ICES1 was flipped: it is lost; stay armed for this polarity
#ifdef METER_PROFILE
      prof_cnt[0]++;
#endif
      TCCR1B = was_rise ? TCCR_RISE : TCCR_FALL;
      TIFR1 = _BV(ICF1);
      acc.missed++;
      chain_break();
      pk &= 3;
      lim = 0xFFFF;
      continue;
    }
    armed = (uint8_t)!was_rise;
    uint16_t d16 = c.ts - ts;
    uint8_t m = (uint8_t)(ms - ms_prev);
    uint16_t l_cur, l_next;
    uint16_t phase = m >= 2 ? 0xFFFF : d16;
    if (was_rise) {
      // period bookkeeping: a rising edge closes the period begun at last_rise
      if (chain) {
        uint8_t mr = (uint8_t)(ms - ms_rise);
        if (c.ts < last_rise) wraps++;
        if (mr >= 2) wraps += turns((uint16_t)(c.ts - last_rise), mr);
        if (have_high) acc.periods++;
        else { chain_break(); chain = 1; chain_start = c.ts; wraps = 0; }
      } else {
        chain = 1;
        chain_start = c.ts;
        wraps = 0;
      }
      last_rise = c.ts;
      ms_rise = ms;
      have_high = 0;
      if (pk & 4) { l_lo = phase; pk |= 2; }
      l_cur = l_hi;
      l_next = l_lo;
    } else {
      if (chain && !have_high) {
        uint16_t h16 = (uint16_t)(c.ts - last_rise);
        uint8_t mr = (uint8_t)(ms - ms_rise);
        uint32_t h = h16;
        if (mr >= 2) h += (uint32_t)turns(h16, mr) << 16;
        acc.sum_h += h;
        high_pending = h;
        have_high = 1;
      }
      if (pk & 4) { l_hi = phase; pk |= 1; }
      l_cur = l_lo;
      l_next = l_hi;
    }
    pk |= 4;
    ts = c.ts;
    ms_prev = ms;
    lim = (pk & 3) == 3 ? task_limit(l_cur, l_next) : 0xFFFF;
#ifdef METER_PROFILE
    {
      uint16_t d = TCNT1 - t_ret;
      if (d > prof_hot) prof_hot = d;
    }
#endif

  }
}

// fsrlab meter core: polled Timer1 input capture with a cycle-budgeted background scheduler.
// Matute et al. 2018, J. Sensors 6561901, doi:10.1155/2018/6561901, section 5.
//
// Why polling and not a capture interrupt: at 50 kHz and 5 % (or 95 %) duty cycle one phase lasts
// 1 us = 16 CPU cycles. After an edge is captured, the edge select ICES1 must be flipped before the
// next edge arrives, or that edge is lost. An interrupt needs up to 4 cycles to finish the current
// instruction, 4 to respond and 3 for the vector jump, then pushes before it can flip ICES1, and
// any other interrupt (millis, UART) delays it by tens of cycles. The wait loop in meter_edge
// (assembly) flips ICES1 at most 11 cycles after the capture flag rises. Interrupts stay disabled
// except Timer0's compare interrupt, the wait's timeout, while waiting.
//
// Hot path (per edge, meter_edge): capture, check that no edge went by unseen, count the period
// (rising edge) or add the high time (falling edge), keep the last high and low times.
// Everything else is a background task of bounded length: 1 ms tick (time, ADC, window end),
// USART receive/transmit, command decision and action, frame formatting (one character or one
// decimal digit step per task), window end (three stages), ADC mean, prediction limits. After each
// edge the scheduler knows the phase that began and the next one (last measurement) and starts a
// task only if its bound ends before the limit from task_limit(): either before the next edge, or
// late enough for that edge but with its successor still armed in time.
//
// Missed edges are detected, not assumed away: after flipping ICES1 the pin must still be at the
// level the captured edge produced unless the flag shows that the next edge was captured too; if
// not, an edge went by unseen, it is counted in `missed`, and the periods around it are dropped.
// Late captures that could hide a pair and blind (starved) task runs are counted the same way. A
// window with missed > 0 is not a clean measurement. Periods longer than 65535 ticks
// (f < 244 Hz) are extended with the 1 ms tick count; no Timer1 overflow flag is used, so nothing
// depends on how TIFR1 writes clear other flags (simavr 1.6 clears them all).
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
#define COST_TICK 180u
#define COST_RX 240u
#define COST_TX 55u
#define COST_FMT 235u
#define COST_DIV 185u
#define COST_EXEC 250u
#define COST_SNAP 310u
#define COST_START 170u
#define COST_PRED 225u
#define COST_MAX 310u       // the largest of the above
#define HOT 210u            // capture + bookkeeping + main loop for one edge, worst case [cycles]
#define SERVICE 20u         // flag check to ICES1 flipped, worst case, with loop exit [cycles]
#define MARGIN 24u
#define BURST 4000u         // longest forced run of tasks [cycles]

#ifdef METER_PROFILE
// Profiling build (make PROFILE=1): longest duration of each task and of the hot path, read
// from RAM by the simavr harness (--peek). Adds about 20 cycles around every task.
extern "C" {
uint16_t prof_task[16];  // by task number, see task()
uint16_t prof_hot;      // from an edge's timestamp to meter_edge returning (fast path)
uint16_t prof_cnt[4];   // pin-check misses, forced task runs, wait timeouts, rejected late captures
uint16_t prof_fmt[12];  // formatter step by state
uint16_t prof_snap[6];  // window-end task by stage
uint16_t prof_why[8];   // forced runs: 0 tick waited, 1 no progress; what was pending (2..7)
// Cycles from one meter_edge return to the next when the next edge was already waiting and no
// task ran in between: main-loop overhead + capture + bookkeeping of one edge. [0] a falling
// edge, [1] a rising edge. Minimum over the run (the common path).
uint16_t prof_edge_cyc[2] = {0xFFFF, 0xFFFF};   // pin-check misses, starvation bursts, timeouts, late (> 11 cycles) services
}
#endif

// ---------------------------------------------------------------------------------------------
// Window accumulators. The sum of periods is kept as a chain: between two breaks (a missed edge,
// a window end) the periods are contiguous, so their sum is last_rise - chain_start (extended by
// the number of 16-bit wraps in between), and each rising edge only counts one period.
struct Acc {
  uint32_t periods, sum_p, sum_h, missed, adc_sum;  // offsets 0, 4, 8, 12, 16 (used by meter_edge)
  uint16_t adc_cnt;
};
// Hot-path state, shared with the assembly fast path meter_edge (offsets are fixed there).
struct Hot {
  uint16_t ts_prev;    //  0 last captured edge [ticks]
  uint16_t l_hi;       //  2 last high time [ticks], 0xFFFF if >= 1 ms
  uint16_t l_lo;       //  4 last low time
  uint16_t lim;        //  6 tasks must end before TCNT1 - ts_prev reaches lim (0xFFFF: no limit)
  uint16_t lim_r;      //  8 ... after a rising edge (computed by the pred task)
  uint16_t lim_f;      // 10 ... after a falling edge
  uint16_t last_rise;  // 12 rising edge that began the open period
  uint16_t unused14;   // 14
  uint16_t unused16;   // 16
  uint16_t hp16;       // 18 high time of the open period, low 16 bits (already in the sums)
  uint8_t flags;       // 20 HF_* below
  uint8_t ms_prev;     // 21 ms count (low byte) at ts_prev
  uint8_t ms_rise;     // 22 ms count (low byte) at last_rise
  uint8_t pad;         // 23
  uint16_t wraps;      // 24 16-bit timestamp wraps between chain_start and last_rise
  uint16_t hp_hi;      // 26 high time of the open period, high 16 bits
  uint16_t cap_ts;     // 28 capture handed to the C slow path
  uint8_t cap_ms;      // 30
  uint8_t pad31;       // 31
  uint32_t periods_part;  // 32 periods not yet added to acc.periods
  uint32_t sumh_part;     // 36 high times not yet added to acc.sum_h
};
enum {
  HF_ARMED_RISE = 1, HF_PREV = 2, HF_PK_HI = 4, HF_PK_LO = 8, HF_CHAIN = 16, HF_HIGH = 32,
  HF_LIMS = 64, HF_TASKED = 128,
};
extern "C" {
// Symbols used by the assembly below: kept visible under -flto (the Arduino IDE's default).
#define ASM_VISIBLE __attribute__((used, externally_visible))
Acc meter_acc;
ASM_VISIBLE Hot meter_hs;
ASM_VISIBLE uint16_t meter_idle_ms;  // ms since the last edge
// After lost edges the old prediction may be wrong (the signal got faster): no task runs until
// two consecutive phases are measured again (or the capture wait times out).
ASM_VISIBLE uint8_t meter_probe;
uint8_t meter_edge(void);
}
#define acc meter_acc
#define hs meter_hs
#define idle_ms meter_idle_ms
static_assert(__builtin_offsetof(Hot, flags) == 20 && __builtin_offsetof(Hot, wraps) == 24 &&
              __builtin_offsetof(Hot, cap_ms) == 30 && __builtin_offsetof(Hot, periods_part) == 32 &&
              __builtin_offsetof(Hot, sumh_part) == 36, "meter_edge offsets");
static uint16_t chain_start;
static uint8_t pred_due;       // the prediction limits should be recomputed
// Time
extern "C" uint16_t meter_ms16;  // ms since boot, low 16 bits (read by meter_edge)
ASM_VISIBLE uint16_t meter_ms16;
#define ms16 meter_ms16
static uint16_t ms_hi;          // ... high 16 bits
// Settings
static uint8_t running;
static uint16_t window_ms = WINDOW_DEFAULT;
static uint16_t win_left;
static uint8_t range_sel;
static uint32_t t_last_end;
static uint8_t snap_stage;      // window end in progress (see take_snapshot)
static uint32_t snap_hp;
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

enum { FS_IDLE = 0, FS_ITEM, FS_COMMA, FS_STR, FS_NUM, FS_TAIL };

static inline uint8_t hexdigit(uint8_t v) { v &= 15u; return (uint8_t)(v < 10 ? '0' + v : 'A' - 10 + v); }

// Formatter steps, one small function per state so that each costs only what it does: at most
// one character or one decimal subtraction per step. Each needs one free byte in txbuf.
static uint8_t f_next_num;  // kind of the item fetched by FS_ITEM (1 number, 2 string)
static uint32_t f_pow;      // power of ten of the digit being found
static uint8_t f_tail[7], f_tail_i;

static void __attribute__((noinline)) fmt_item(void) {
  uint8_t t = frame_item(f_item);
  if (t == 0) {  // '*', CRC in 4 hex digits, CR, LF
    uint16_t c = f_crc;
    f_tail[0] = '*';
    f_tail[1] = hexdigit((uint8_t)(c >> 12));
    f_tail[2] = hexdigit((uint8_t)(c >> 8));
    f_tail[3] = hexdigit((uint8_t)(c >> 4));
    f_tail[4] = hexdigit((uint8_t)c);
    f_tail[5] = '\r';
    f_tail[6] = '\n';
    f_tail_i = 0;
    f_state = FS_TAIL;
    return;
  }
  f_next_num = t;
  f_state = f_item++ ? FS_COMMA : FS_STR;  // item 0 (the type) is a string without a comma
}

static void __attribute__((noinline)) fmt_comma(void) {
  emit_crc(',');
  if (f_next_num == 1) {
    f_pidx = 9;
    f_pow = 1000000000ul;
    f_digit = 0;
    f_started = 0;
    f_state = FS_NUM;
  } else {
    f_state = FS_STR;
  }
}

static void __attribute__((noinline)) fmt_str(void) {
  uint8_t c = f_str_pgm ? pgm_read_byte(f_str) : (uint8_t)*f_str;
  if (!c) { f_state = FS_ITEM; return; }
  f_str++;
  emit_crc(c);
}

static void __attribute__((noinline)) fmt_num(void) {
  if (f_val >= f_pow) { f_val -= f_pow; f_digit++; return; }
  uint8_t i = f_pidx;
  if (f_digit || f_started || i == 0) { emit_crc((uint8_t)('0' + f_digit)); f_started = 1; }
  f_digit = 0;
  if (i == 0) { f_state = FS_ITEM; return; }
  f_pidx = --i;
  f_pow = pow10_tab[i];
}

static void __attribute__((noinline)) fmt_tail(void) {
  uint8_t i = f_tail_i;
  push_tx(f_tail[i]);
  if (++i < 7) { f_tail_i = i; return; }
  f_state = FS_IDLE;
  if (f_kind == K_M) snap_state = 0;
  else rq_tail = (uint8_t)((rq_tail + 1u) & (RESPQ - 1u));
}

static inline __attribute__((always_inline)) void fmt_step(void) {
  switch (f_state) {
    case FS_ITEM: fmt_item(); break;
    case FS_COMMA: fmt_comma(); break;
    case FS_STR: fmt_str(); break;
    case FS_NUM: fmt_num(); break;
    default: fmt_tail(); break;
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
static uint8_t stall_waiting(void);

static void __attribute__((noinline)) tick(void) {
  TIFR2 = _BV(OCF2A);
  if (!progress && stall_waiting()) {
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
  pred_due = 1;
  if (running && --win_left == 0) {
    win_left = window_ms;
    if (!snap_stage) snap_stage = 1;  // else the previous end is still being taken: one longer window
  }
}

// Move the 16-bit partial sums of the hot path into the window sums.
static void flush_partials(void) {
  acc.periods += hs.periods_part;
  acc.sum_h += hs.sumh_part;
  hs.periods_part = 0;
  hs.sumh_part = 0;
}

static inline uint32_t high_pending(void) { return ((uint32_t)hs.hp_hi << 16) | hs.hp16; }

// Close the period chain into sum_p (window end or a break).
static void __attribute__((noinline)) fold_chain(void) {
  if (hs.flags & HF_CHAIN) {
    uint16_t lr = hs.last_rise;
    acc.sum_p += ((uint32_t)hs.wraps << 16) + (uint16_t)(lr - chain_start) - (lr < chain_start ? 0x10000ul : 0ul);
    chain_start = lr;
    hs.wraps = 0;
  }
}

static void take_snapshot(void);

static void chain_break(void) {
  // between stage 1 and stage 4 of a window end acc must hold exactly the ended window
  if (snap_stage == 4 || snap_stage == 5) take_snapshot();
  flush_partials();
  fold_chain();
  if (hs.flags & HF_HIGH) acc.sum_h -= high_pending();  // its period will not be counted
  hs.flags &= (uint8_t)~(HF_CHAIN | HF_HIGH);
}

// Window end in three tasks. Stage 1 moves the hot path's partial sums into acc and closes the
// period chain; from then on the hot path only touches its partial sums, so acc holds exactly the
// ended window until stage 4 copies it (the open period's high time moves on to the next window)
// and stage 2 copies time, missed and ADC. After START or WINDOW (stage 3) the sums are
// discarded instead (stage 5).
static void __attribute__((noinline)) snap_fold(void) {  // stage 1 (report) or 3 (discard)
  flush_partials();
  fold_chain();
  snap_hp = (hs.flags & HF_HIGH) ? high_pending() : 0;  // in acc.sum_h, its period is still open
  snap_stage = snap_stage == 1 ? 4 : 5;
}

static void __attribute__((noinline)) snap_copy(void) {  // stage 4 (report) or 5 (discard)
  uint32_t hp = snap_hp;
  if (snap_stage == 4) {
    snap.periods = acc.periods;
    snap.sum_p = acc.sum_p;
    snap.sum_h = acc.sum_h - hp;
    snap_stage = 2;
  } else {
    acc.missed = 0;
    acc.adc_sum = 0;
    acc.adc_cnt = 0;
    snap_stage = 0;
  }
  acc.periods = 0;
  acc.sum_p = 0;
  acc.sum_h = hp;
}

static void __attribute__((noinline)) snap_meta(void) {  // stage 2
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

static void take_snapshot(void) {
  uint8_t st = snap_stage;
  if (st == 1 || st == 3) snap_fold();
  else if (st == 4 || st == 5) snap_copy();
  else snap_meta();
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

static uint16_t task_limit(uint16_t l_cur, uint16_t l_next);

// Recompute the task limits after a rising and after a falling edge from the last high and low
// times (the hot path only copies them); one of the two per run.
static uint8_t pred_which;
static void __attribute__((noinline)) pred_step(void) {
  uint8_t f = hs.flags;
  if ((f & (HF_PK_HI | HF_PK_LO)) != (HF_PK_HI | HF_PK_LO)) { pred_due = 0; return; }
  uint16_t hi = hs.l_hi, lo = hs.l_lo;
  if (pred_which) {
    hs.lim_f = task_limit(lo, hi);
    hs.flags |= HF_LIMS;
    pred_due = 0;
  } else {
    hs.lim_r = task_limit(hi, lo);
  }
  pred_which ^= 1;
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
    return 0;
  }
  // last: the limits change slowly, stale ones for a while are harmless
  if ((pred_due || !(hs.flags & HF_LIMS)) && (hs.flags & (HF_PK_HI | HF_PK_LO)) == (HF_PK_HI | HF_PK_LO)) {
    if (budget >= COST_PRED) { pred_step(); return 10; }
  }
  return 0;
}

// Work that a task must do (the transmitter drains by itself, one byte per 87 us).
static uint8_t stall_waiting(void) {
  return f_state != FS_IDLE || snap_stage || snap_state == 1 || cmd_ready ||
         (UCSR0A & _BV(RXC0)) || ((rq_tail != rq_head || snap_state == 2) && tx_used() < 32u);
}

static uint8_t work_waiting(void) {
  return tx_head != tx_tail || f_state != FS_IDLE || snap_stage || snap_state == 1 || cmd_ready ||
         (UCSR0A & _BV(RXC0)) || ((rq_tail != rq_head || snap_state == 2));
}

static inline __attribute__((always_inline)) uint8_t run_task(uint16_t budget) {
#ifdef METER_PROFILE
  uint8_t fs = f_state, ss = snap_stage;
  uint16_t t0 = TCNT1;
  uint8_t id = task(budget);
  uint16_t d = TCNT1 - t0;
  if (d > prof_task[id]) prof_task[id] = d;
  if (id == 5 && d > prof_fmt[fs]) prof_fmt[fs] = d;
  if (id == 4 && ss < 6 && d > prof_snap[ss]) prof_snap[ss] = d;
#else
  uint8_t id = task(budget);
#endif
  if (id == 2 || (id >= 4 && id < 10)) progress = 1;  // not tick, transmit, prediction
  return id;
}

// ---------------------------------------------------------------------------------------------
// meter_edge(): wait for the armed edge and do the common bookkeeping, in assembly because every
// cycle counts at 50 kHz. Interrupts are enabled only while waiting, for one purpose: a Timer0
// compare match as timeout (TIMER0_COMPA_vect below makes the wait return 1).
// Capture: the wait loop is `sbis; rjmp` (3 cycles); on the flag, read ICR1, write the other edge
// into TCCR1B, clear ICF1 (the datasheet's order: a change of ICES1 may set ICF1). From the flag
// to ICES1 flipped: at most 3 + 2 (sbis skip) + 4 (lds, lds) + 2 (sts) = 11 cycles; ICF1 is
// cleared one cycle later (an edge in that cycle is lost and caught by the pin check below).
// Then: pin check (the pin must still show the captured edge unless the next edge was captured
// too), latency check (only if a task ran: a capture served later than one full period may hide
// an edge pair), and for the common case (a chain of periods, phases < 2 ms) the period count,
// high time, wrap count, the last high/low times and the task limit for the next phase.
// Returns 0 done, 1 timeout, 2 missed edge (pin check), 3 slow path (C finishes, capture in
// cap_ts/cap_ms), 4 rejected (late capture). Uses only call-clobbered registers.
asm(R"ASM(
  .section .text.meter_edge,"ax",@progbits
  .global meter_edge
  .global meter_edge_timeout
meter_edge:
  in r18, 0x26            ; timeout: OCR0A = TCNT0 + 14 (14 x 64 us = 0.9 ms)
  subi r18, 0xF2
  out 0x27, r18
  ldi r18, 0x02
  out 0x15, r18           ; TIFR0 = 1 << OCF0A
  ldi r30, lo8(meter_hs)
  ldi r31, hi8(meter_hs)
  ldd r20, Z+20           ; flags
  ldi r24, 0x41           ; TCCR1B for a rising edge
  sbrc r20, 0             ; armed for rising: the next one is falling
  ldi r24, 0x01
  ldi r21, 0x20           ; 1 << ICF1
  sei
1:
  sbis 0x16, 5            ; TIFR1.ICF1
  rjmp 1b
  lds r18, 0x86           ; ICR1L (latches ICR1H)
  lds r19, 0x87           ; ICR1H
  sts 0x81, r24           ; TCCR1B: arm the other edge
  out 0x16, r21           ; clear ICF1
  cli
  in r22, 0x03            ; PINB
  in r23, 0x16            ; TIFR1
  sbrc r23, 5             ; next edge already captured: nothing was lost
  rjmp 2f
  eor r22, r20            ; PB0 must equal "captured a rising edge" = armed bit
  sbrc r22, 0
  rjmp edge_miss
2:
  ldi r21, 1
  eor r20, r21            ; armed toggles; bit 0 now set <=> a falling edge was captured
  std Z+20, r20
  sts meter_idle_ms, r1
  sts meter_idle_ms+1, r1
  sbrs r20, 7             ; HF_TASKED: a task ran since the last capture
  rjmp 3f
  andi r20, 0x7F
  lds r26, 0x84           ; TCNT1L
  lds r27, 0x85
  sub r26, r18
  sbc r27, r19            ; latency
  brpl .+2        ; >= 0x8000: a timestamp from the future (torn read in simulation)
  rjmp edge_reject
  mov r21, r20
  andi r21, 0x0C
  cpi r21, 0x0C
  brne 3f
  ldd r24, Z+2
  ldd r25, Z+3
  ldd r22, Z+4
  ldd r23, Z+5
  add r24, r22
  adc r25, r23            ; l_hi + l_lo
  brcs 3f
  cp r26, r24
  cpc r27, r25
  brlo .+2
  rjmp edge_reject
3:
  lds r26, meter_ms16     ; ms count, low byte
  ldd r27, Z+21           ; ms_prev
  mov r21, r26
  sub r21, r27
  cpi r21, 2
  brlo .+2          ; >= 1 ms since the last edge: C extends the phase
  rjmp edge_slow
  sbrc r20, 0
  rjmp edge_fall
  ; ---- rising edge: closes the period begun at last_rise
  sbrs r20, 4             ; HF_CHAIN
  rjmp edge_slow
  sbrs r20, 5             ; HF_HIGH
  rjmp edge_slow
  ldd r21, Z+22           ; ms_rise
  mov r22, r26
  sub r22, r21
  cpi r22, 2
  brlo .+2
  rjmp edge_slow
  ldd r22, Z+26
  ldd r23, Z+27
  or r22, r23
  breq .+2          ; high time >= 65536 ticks
  rjmp edge_slow
  ldd r24, Z+12
  ldd r25, Z+13
  movw r22, r18
  sub r22, r24
  sbc r23, r25            ; period = ts - last_rise, carry = the timestamp wrapped
  clr r21
  adc r21, r1
  ldd r24, Z+18
  ldd r25, Z+19           ; high time
  cp r24, r22
  cpc r25, r23
  brlo .+2          ; high >= period: C rejects the period
  rjmp edge_slow
  tst r21
  breq 4f
  ldd r24, Z+24
  ldd r25, Z+25
  adiw r24, 1
  std Z+24, r24
  std Z+25, r25
4:
  ldd r24, Z+32
  ldd r25, Z+33
  adiw r24, 1             ; periods_part++ (low half; carry below)
  std Z+32, r24
  std Z+33, r25
  brne 5f
  ldd r24, Z+34
  ldd r25, Z+35
  adiw r24, 1
  std Z+34, r24
  std Z+35, r25
5:
  std Z+12, r18           ; last_rise = ts
  std Z+13, r19
  std Z+22, r26           ; ms_rise
  andi r20, 0xDF          ; HF_HIGH = 0
  ldd r24, Z+0
  ldd r25, Z+1
  movw r22, r18
  sub r22, r24
  sbc r23, r25            ; low time just ended
  sbrs r20, 1             ; HF_PREV
  rjmp 6f
  std Z+4, r22
  std Z+5, r23
  ori r20, 0x08           ; HF_PK_LO
6:
  ldd r24, Z+8            ; lim_r
  ldd r25, Z+9
  rjmp edge_done
edge_fall:
  sbrs r20, 4             ; no chain: nothing to add
  rjmp 7f
  sbrc r20, 5             ; high time already known (cannot happen without a miss)
  rjmp 7f
  ldd r21, Z+22
  mov r22, r26
  sub r22, r21
  cpi r22, 2
  brlo .+2
  rjmp edge_slow
  ldd r24, Z+12
  ldd r25, Z+13
  movw r22, r18
  sub r22, r24
  sbc r23, r25            ; high time
  std Z+18, r22
  std Z+19, r23
  std Z+26, r1
  std Z+27, r1
  ldd r24, Z+36
  ldd r25, Z+37
  add r24, r22
  adc r25, r23            ; sumh_part += high (low half; carry below)
  std Z+36, r24
  std Z+37, r25
  brcc 8f
  ldd r24, Z+38
  ldd r25, Z+39
  adiw r24, 1
  std Z+38, r24
  std Z+39, r25
8:
  ori r20, 0x20           ; HF_HIGH
7:
  ldd r24, Z+0
  ldd r25, Z+1
  movw r22, r18
  sub r22, r24
  sbc r23, r25            ; high time just ended (for the prediction)
  sbrs r20, 1
  rjmp 9f
  std Z+2, r22
  std Z+3, r23
  ori r20, 0x04           ; HF_PK_HI
9:
  ldd r24, Z+10           ; lim_f
  ldd r25, Z+11
edge_done:
  mov r21, r20
  andi r21, 0x4C          ; limits valid and both phases known?
  cpi r21, 0x4C
  breq 10f
  ldi r24, 0xFF           ; no prediction: tasks may run freely ...
  ldi r25, 0xFF
  lds r21, meter_probe    ; ... unless edges were just lost: then none until the phases are known
  tst r21
  breq 10f
  clr r24
  clr r25
10:
  std Z+6, r24
  std Z+7, r25
  ori r20, 0x02           ; HF_PREV
  std Z+20, r20
  std Z+0, r18            ; ts_prev
  std Z+1, r19
  std Z+21, r26           ; ms_prev
  clr r24
  ret
edge_slow:
  std Z+20, r20
  std Z+28, r18
  std Z+29, r19
  std Z+30, r26
  ldi r24, 3
  ret
edge_reject:
  std Z+20, r20
  ldi r24, 4
  ret
edge_miss:
  ldi r24, 2
  ret
meter_edge_timeout:       ; the Timer0 compare interrupt returns here instead of into the wait
  cli
  ldi r24, 1
  ret
)ASM");

// Timer0 compare A: the wait timed out. Replace the interrupted address (inside meter_edge's
// loop, or in its next instructions if an edge came at the same moment: the caller resyncs) by
// meter_edge_timeout. The return address on the stack is big-endian, high byte on top.
ISR(TIMER0_COMPA_vect, ISR_NAKED) {
  asm volatile(
      "pop r0\n\t"
      "pop r0\n\t"
      "ldi r30, lo8(gs(meter_edge_timeout))\n\t"
      "ldi r31, hi8(gs(meter_edge_timeout))\n\t"
      "push r30\n\t"
      "push r31\n\t"
      "reti\n\t");
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

// Edges were lost: forget the phases, run no task until they are measured again.
static void lose_prediction(void) {
  hs.flags &= (uint8_t)~(HF_PK_HI | HF_PK_LO | HF_LIMS);
  meter_probe = 1;
}

// Arm for the edge opposite to the present level (after a break).
static void resync(void) {
  uint8_t lv = PINB & _BV(PB0);
  TCCR1B = lv ? TCCR_FALL : TCCR_RISE;
  TIFR1 = _BV(ICF1);
  hs.flags = (uint8_t)((hs.flags & ~(HF_ARMED_RISE | HF_PREV)) | (lv ? 0 : HF_ARMED_RISE));
  hs.lim = meter_probe ? 0 : 0xFFFF;
}

// The rare cases of meter_edge (codes 1..4), and the slow path of the bookkeeping.
static void __attribute__((noinline)) edge_rare(uint8_t code) {
  // the slow path writes acc: finish a window end that is half taken (see take_snapshot)
  if (snap_stage == 4 || snap_stage == 5) take_snapshot();
  if (code == 1) {  // no edge for ~0.9 ms although one was predicted soon
#ifdef METER_PROFILE
    prof_cnt[2]++;
#endif
    hs.flags &= (uint8_t)~(HF_PK_HI | HF_PK_LO | HF_LIMS);
    meter_probe = 0;
    chain_break();
    resync();
    return;
  }
  if (code == 2 || code == 4) {  // an edge went by unseen, or a capture may hide a pair
#ifdef METER_PROFILE
    prof_cnt[code == 2 ? 0 : 3]++;
#endif
    acc.missed++;
    chain_break();
    lose_prediction();
    resync();
    return;
  }
  // code 3: phases >= 1 ms, a chain starting, or a period to reject
  uint16_t ts = hs.cap_ts;
  uint8_t ms = hs.cap_ms;
  uint8_t f = hs.flags;
  uint8_t rise = !(f & HF_ARMED_RISE);
  uint16_t d16 = (uint16_t)(ts - hs.ts_prev);
  uint16_t phase = (uint8_t)(ms - hs.ms_prev) >= 2 ? 0xFFFF : d16;
  if (rise) {
    if (f & HF_CHAIN) {
      uint16_t p16 = (uint16_t)(ts - hs.last_rise);
      uint8_t mr = (uint8_t)(ms - hs.ms_rise);
      uint32_t hp = high_pending();
      if (!(f & HF_HIGH) || (mr < 2 && hp >= p16)) {
        // no high time, or not shorter than the period: this period is rejected
        if (f & HF_HIGH) acc.missed++;
        chain_break();
        chain_start = ts;
        hs.wraps = 0;
      } else {
        if (ts < hs.last_rise) hs.wraps++;
        if (mr >= 2) hs.wraps += turns(p16, mr);
        acc.periods++;
      }
    } else {
      chain_start = ts;
      hs.wraps = 0;
    }
    hs.flags |= HF_CHAIN;
    hs.flags &= (uint8_t)~HF_HIGH;
    hs.last_rise = ts;
    hs.ms_rise = ms;
    if (f & HF_PREV) { hs.l_lo = phase; hs.flags |= HF_PK_LO; }
  } else {
    if ((f & HF_CHAIN) && !(f & HF_HIGH)) {
      uint16_t h16 = (uint16_t)(ts - hs.last_rise);
      uint8_t mr = (uint8_t)(ms - hs.ms_rise);
      uint16_t turns_hi = mr >= 2 ? turns(h16, mr) : 0;
      acc.sum_h += ((uint32_t)turns_hi << 16) + h16;
      hs.hp16 = h16;
      hs.hp_hi = turns_hi;
      hs.flags |= HF_HIGH;
    }
    if (f & HF_PREV) { hs.l_hi = phase; hs.flags |= HF_PK_HI; }
  }
  hs.flags |= HF_PREV;
  hs.ts_prev = ts;
  hs.ms_prev = ms;
  f = hs.flags;
  hs.lim = (f & (HF_LIMS | HF_PK_HI | HF_PK_LO)) == (HF_LIMS | HF_PK_HI | HF_PK_LO)
               ? (rise ? hs.lim_r : hs.lim_f) : (meter_probe ? 0 : 0xFFFF);
}

void meter_run(void) {
  asm volatile("cli");
  hw_init();
  rx_reset();
  queue_resp(K_ID, 0, 0, 0, 0);  // boot identification, SEQ 0
  hs.flags = 0;
  resync();

  for (;;) {
    // ---- starvation: edges too fast for the tasks; run some blind and count what went by
    // (TCNT2 counts 4 us steps since OCF2A rose: a tick waiting for 0.5 ms forces the tasks)
    if ((TIFR2 & _BV(OCF2A)) && TCNT2 >= 125u) force = 2;
    if (force) {
#ifdef METER_PROFILE
      prof_cnt[1]++;
      prof_why[force == 2 ? 0 : 1]++;
      if (snap_stage) prof_why[2]++;
      if (f_state) prof_why[3]++;
      if (snap_state == 1) prof_why[4]++;
      if (pred_due) prof_why[5]++;
      if (cmd_ready) prof_why[6]++;
      if (rq_tail != rq_head || snap_state == 2) prof_why[7]++;
#endif
      force = 0;
      uint16_t t0 = TCNT1;
      uint8_t p0 = PINB & _BV(PB0);
      do {  // up to 1/4 ms: the USART needs wall time, 87 us per byte
        if (!task(0xFFFF) && !work_waiting()) break;
      } while ((uint16_t)(TCNT1 - t0) < BURST);
      uint16_t blind = TCNT1 - t0;
      if ((TIFR1 & _BV(ICF1)) || (PINB & _BV(PB0)) != p0) {
        uint8_t f = hs.flags;
        uint16_t per = (f & (HF_PK_HI | HF_PK_LO)) == (HF_PK_HI | HF_PK_LO) ? (uint16_t)(hs.l_hi + hs.l_lo) : 0;
        uint16_t est = per ? (uint16_t)((2u * (uint32_t)blind) / per) : 1u;
        acc.missed += est ? est : 1u;
        chain_break();
        lose_prediction();
        resync();
      }
    }

    // ---- background tasks while the next edges allow
    uint16_t lim = hs.lim;
    for (;;) {
      if (TIFR1 & _BV(ICF1)) break;
      uint16_t budget = 0xFFFF;
      if (lim != 0xFFFF) {
        uint16_t el = TCNT1 - hs.ts_prev;
        budget = el < lim ? (uint16_t)(lim - el) : 0;
      }
      if (budget < COST_TX) break;  // not even the shortest task fits
      if (run_task(budget)) { hs.flags |= HF_TASKED; continue; }
      // near the next edge (nothing fits): wait for it in the capture loop; far from it, keep
      // polling here so that the 1 ms tick is never held up by a long wait
      if (budget < COST_MAX) break;
    }

    // ---- capture and bookkeeping
#ifdef METER_PROFILE
    uint8_t tasked = hs.flags & HF_TASKED;
    uint8_t code = meter_edge();
    uint16_t t_ret = TCNT1;
    if (code == 0) {
      uint16_t d = t_ret - hs.ts_prev;
      if (d > prof_hot) prof_hot = d;
      static uint16_t prev_ret;
      static uint8_t prev_pending;
      if (prev_pending && !tasked) {
        uint8_t rise = !(hs.flags & HF_ARMED_RISE);
        uint16_t e = t_ret - prev_ret;
        if (e < prof_edge_cyc[rise]) prof_edge_cyc[rise] = e;
      }
      prev_ret = t_ret;
      prev_pending = TIFR1 & _BV(ICF1);
    }
#else
    uint8_t code = meter_edge();
#endif
    if (code) edge_rare(code);
    if (meter_probe && (hs.flags & (HF_PK_HI | HF_PK_LO)) == (HF_PK_HI | HF_PK_LO)) {
      // phases measured again: limits now (two prediction steps), then tasks may run
      pred_step();
      pred_step();
      meter_probe = 0;
      hs.lim = (hs.flags & HF_ARMED_RISE) ? hs.lim_f : hs.lim_r;
    }
  }
}

// fsrlab meter core: polled Timer1 input capture with a cycle-budgeted background scheduler.
// Matute et al. 2018, J. Sensors 6561901, doi:10.1155/2018/6561901, section 5.
//
// Why polling and not a capture interrupt: at 50 kHz and 5 % (or 95 %) duty cycle one phase lasts
// 1 us = 16 CPU cycles. After an edge is captured, the edge select ICES1 must be flipped before the
// next edge arrives, or that edge is lost. An interrupt needs up to 4 cycles to finish the current
// instruction, 4 to respond and 3 for the vector jump, then pushes before it can flip ICES1, and
// any other interrupt (millis, UART) delays it by tens of cycles. The wait loop in meter_loop
// (assembly) flips ICES1 at most 11 cycles after the capture flag rises. Interrupts stay disabled
// except Timer0's compare interrupt, the wait's timeout, while waiting.
//
// Measuring loop (meter_loop, assembly): the hot state (last edge, last rising edge, period
// count, high-time sum, last high time, task limit, flags) lives in call-saved registers; per
// edge it captures, checks that no edge went by unseen, counts the period (rising edge) or adds
// the high time (falling edge), keeps the phase just ended for the prediction, and loads the task
// limit for the phase that began (about 65 cycles for a rising, 50 for a falling edge, loop
// included). Between edges it calls the C dispatcher meter_task(budget), which runs one short
// task itself (1 ms tick, ADC sample or checks, USART receive byte / transmit byte) or selects the
// next step of the longer work as a job (meter_job): command receiver (word, candidate, token
// steps), command decision, effect and answer, window end (several small stages), ADC mean (one
// bit per step), frame start and frame formatting (one character, one decimal subtraction or one
// digit per step). The loop calls a selected job directly (icall) in a later slot that fits the
// job's own bound (job_cost), so that no slot has to hold the dispatcher's chain of checks and
// the longest step at once; a formatter step selects the next one itself unless other work waits
// (fmt_job), and a step selected with budget to spare runs at once. The prediction of the task
// limits and the window end's hand-over of the register sums are small assembly routines in the
// loop itself. The budget is the task limit minus the time since the last edge minus the call
// overhead; the limit (task_limit) lets a task end either before the next edge, or late enough
// for that edge but with its successor still armed in time. No call in a slot below COST_MIN
// (the longest selection, with the loop's checks): a small slot would only keep the edges late.
// The loop returns to C only for the rare cases: a missed edge, a phase >= 1 ms (extended with the
// 1 ms tick count), a rejected period, a timeout, starvation.
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
// The selected steps (jobs) have their own bounds (job_cost below).
#define COST_TICK 115      // profiled 108
#define COST_TICK2 92      // adc_take or adc_check, profiled 85
#define COST_RX 98         // profiled 90
#define COST_TX 64         // profiled 60
#define COST_FLUSH 130     // ml_flush in meter_loop (window end stage 1/3), with its dispatch
#define COST_PRED 125      // ml_pred_r or ml_pred_f (assembly, static count ~115) with its call
#define COST_MAX 130        // the largest of the above (COST_FLUSH)
#define COST_MIN 140        // no dispatcher call in a smaller slot: the selection (profiled 104) and
                            // the loop's checks of pending assembly jobs (up to ~30) must fit; 118
                            // was measured too small (an edge missed every few windows)
#define CALL_OVH 45         // meter_loop's part of a task call: 27 cycles from reading TCNT1 to the
                            // dispatcher, 19 after the task beyond SERVICE (static count)
#define HOT 90             // capture + bookkeeping + main loop for one edge, worst case [cycles]
#define SERVICE 14         // flag check to ICES1 flipped, worst case, with loop exit [cycles]
#define MARGIN 8
#define JOB_OVH 4           // a job's bound over its profiled length (prof_job counts ~11 cycles of
                            // profiling and call; meter_loop's job path costs ~1 more than CALL_OVH covers)
#define JOB_B(body) ((body) + JOB_OVH)
#define RUN_NOW 60          // meter_task: a selected step runs at once if the budget holds COST_MIN + RUN_NOW + its bound
#define LONG_PHASE 0x200    // lim_f of a low time of >= 32 us ends before the rising edge (multiple of 256)
#define PRED_SHIFT 5        // the prediction keeps 1/32 of the predicted phases as margin (ml_div16 too)
#define BURST 4000u         // longest forced run of tasks [cycles]

#ifdef METER_PROFILE
// Profiling build (make PROFILE=1): longest duration of each task and of the hot path, read
// from RAM by the simavr harness (--peek). Adds about 20 cycles around every task.
extern "C" {
uint16_t prof_task[16];  // by task number, see task()
uint16_t prof_cnt[4];   // pin-check misses, forced task runs, wait timeouts, rejected late captures
uint16_t prof_fmt[16];  // formatter step by state
uint16_t prof_snap[16];  // window-end task by stage
uint16_t prof_why[8];   // forced runs: 0 tick waited, 1 no progress; what was pending (2..7)
__attribute__((used, externally_visible)) uint16_t prof_job[32];
  // selected steps run by meter_loop, by job id
// Cycles from one meter_loop top to the next when the edge was already waiting and no
// task ran in between: main-loop overhead + capture + bookkeeping of one edge. [0] a falling
// edge, [1] a rising edge. Minimum over the run (the common path).
__attribute__((used, externally_visible)) uint16_t prof_edge_cyc[2] = {0xFFFF, 0xFFFF};
__attribute__((used, externally_visible)) uint16_t prof_prev;
__attribute__((used, externally_visible)) uint8_t prof_ok;  // the edge was waiting at the last loop top
}
#endif

// ---------------------------------------------------------------------------------------------
// Window accumulators. The sum of periods is kept as a chain: between two breaks (a missed edge,
// a window end) the periods are contiguous, so their sum is last_rise - chain_start (extended by
// the number of 16-bit wraps in between), and each rising edge only counts one period.
struct Acc {
  uint32_t periods, sum_p, sum_h, missed, adc_sum;  // offsets 0, 4, 8, 12, 16 (used by meter_loop)
  uint16_t adc_cnt;
};
// Hot-path state, shared with meter_loop (assembly; offsets are fixed there). While meter_loop
// runs, ts_prev, lim, last_rise, hp16, flags, ms_rise, periods_part (low half) and sumh_part live
// in its registers; it writes them back here when it returns to C.
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
ASM_VISIBLE Acc meter_acc;
ASM_VISIBLE Hot meter_hs;
ASM_VISIBLE uint16_t meter_idle_ms;  // ms since the last edge
// After lost edges the old prediction may be wrong (the signal got faster): no task runs until
// two consecutive phases are measured again (or the capture wait times out).
ASM_VISIBLE uint8_t meter_probe;
uint8_t meter_loop(void);
ASM_VISIBLE uint8_t meter_force;
ASM_VISIBLE uint8_t meter_snap_stage;
ASM_VISIBLE uint16_t meter_chain_start;
ASM_VISIBLE uint8_t meter_pred_due;
ASM_VISIBLE uint8_t meter_asm_job;  // for meter_loop: 1 lim_r due, 4 lim_f due, 2 window end's hand-over
// Chain state handed over by meter_loop with the sums at a window end (stage 10/12)
ASM_VISIBLE uint16_t meter_fold_lr, meter_fold_hp, meter_fold_wraps;
ASM_VISIBLE uint8_t meter_fold_flags;
ASM_VISIBLE uint8_t meter_rearm;  // meter_loop arms for the edge opposite to the pin level
ASM_VISIBLE uint8_t meter_fold_ok = 1;  // the sums are in RAM (meter_loop not running, or it flushed)
// Selected background step (see task()): meter_loop calls it directly (icall) in a slot of at
// least meter_job_cost cycles; 0 none. Cleared when meter_loop returns to C.
typedef void (*job_fn)(void);
ASM_VISIBLE job_fn meter_job;
ASM_VISIBLE uint8_t meter_job_cost;
ASM_VISIBLE uint8_t meter_job_id;  // which step (job_cost[], prof_job[])
}
#define acc meter_acc
#define hs meter_hs
#define idle_ms meter_idle_ms
static_assert(__builtin_offsetof(Hot, flags) == 20 && __builtin_offsetof(Hot, wraps) == 24 &&
              __builtin_offsetof(Hot, cap_ms) == 30 && __builtin_offsetof(Hot, periods_part) == 32 &&
              __builtin_offsetof(Hot, sumh_part) == 36, "meter_loop offsets");
#define chain_start meter_chain_start  // first rising edge of the period chain
#define fold_lr meter_fold_lr
#define fold_hp meter_fold_hp
#define fold_wraps meter_fold_wraps
#define fold_flags meter_fold_flags
#define pred_due meter_pred_due  // the prediction limits should be recomputed
// Time
extern "C" uint16_t meter_ms16;  // ms since boot, low 16 bits (read by meter_loop)
ASM_VISIBLE uint16_t meter_ms16;
#define ms16 meter_ms16
static uint16_t ms_hi;          // ... high 16 bits
// Settings
static uint8_t running;
static uint16_t window_ms = WINDOW_DEFAULT;
static uint16_t win_left;
static uint8_t range_sel;
static uint32_t t_last_end;
#define snap_stage meter_snap_stage  // window end in progress (see take_snapshot)
static uint32_t snap_hp;
static uint32_t snap_t;          // time of the window's end [ms]
// Starvation: edges so fast that no task fits. Detected by the 1 ms tick (no task but the tick
// ran for 2 ms although work waits) or by the main loop (the tick itself waited 0.5 ms); the
// main loop then runs tasks blind for up to BURST cycles and counts the edges that went by.
static uint8_t stall;
extern "C" uint8_t meter_progress;  // a task made progress since the last check
ASM_VISIBLE uint8_t meter_progress;
#define progress meter_progress
#define force meter_force

// Transmit ring
static uint8_t txbuf[128];
static uint8_t tx_head, tx_tail;
static inline __attribute__((always_inline)) uint8_t tx_used(void) { return (uint8_t)((tx_head - tx_tail) & 127u); }

// Frame formatter
enum { K_NONE = 0, K_ID, K_M, K_ACK, K_ERR };
enum { C_ID = 0, C_START, C_STOP, C_WINDOW, C_RANGE, C_COUNT };
static const char cmd_names[C_COUNT][8] PROGMEM = {"ID", "START", "STOP", "WINDOW", "RANGE"};
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
  uint32_t t_ms, window, periods, sum_p, sum_h, missed, adc_sum, range;
  uint16_t adc_cnt, adc_q, adc_r, adc_lo;  // bit-serial division state (adc_cnt <= 60000)
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
  uint16_t val;  // saturates at 0xFFFF (every value > 60000 is rejected anyway)
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

enum { FS_IDLE = 0, FS_ITEM, FS_COMMA, FS_STR, FS_NUM, FS_TAIL, FS_CRC, FS_DIGIT, FS_POW, FS_NUMINIT };

static inline uint8_t hexdigit(uint8_t v) { v &= 15u; return (uint8_t)(v < 10 ? '0' + v : 'A' - 10 + v); }

// Formatter steps, one small function per state so that each costs only what it does: at most
// one character or one decimal subtraction per step. Each needs one free byte in txbuf.
static uint8_t f_next_num;  // kind of the item fetched by FS_ITEM (1 number, 2 string)
static uint32_t f_pow;      // power of ten of the digit being found
static uint8_t f_tail[7], f_tail_i;

static void __attribute__((noinline)) fmt_item(void) {
  uint8_t t = frame_item(f_item);
  if (t == 0) {
    f_state = FS_CRC;
    return;
  }
  f_next_num = t;
  f_state = f_item++ ? FS_COMMA : FS_STR;  // item 0 (the type) is a string without a comma
}

static void __attribute__((noinline)) fmt_crc(void) {  // '*', CRC in 4 hex digits, CR, LF
  {
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
  }
}

static void __attribute__((noinline)) fmt_comma(void) {
  emit_crc(',');
  f_state = FS_NUMINIT;
}

static void __attribute__((noinline)) fmt_numinit(void) {
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
  if (!f_digit && !f_started && i) {  // a leading zero: the next power at once (one step, not three)
    f_pidx = --i;
    f_pow = pow10_tab[i];
    return;
  }
  f_state = FS_DIGIT;
}

static void __attribute__((noinline)) fmt_digit(void) {
  f_state = FS_POW;
  if (f_digit || f_started || f_pidx == 0) { emit_crc((uint8_t)('0' + f_digit)); f_started = 1; }
  f_digit = 0;
}

static void __attribute__((noinline)) fmt_pow(void) {
  f_state = FS_NUM;
  uint8_t i = f_pidx;
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
    case FS_DIGIT: fmt_digit(); break;
    case FS_POW: fmt_pow(); break;
    case FS_NUMINIT: fmt_numinit(); break;
    case FS_CRC: fmt_crc(); break;
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

// Receive in two steps per byte: rx_byte classifies it, rx_word (rx_c pending) handles the
// character of the first (command) or second (value) word.
static uint8_t rx_c, rx_step, rx_i, rx_rest, rx_keep;
static void __attribute__((noinline)) rx_byte(uint8_t c) {
  if (c == '\r') return;
  if (c == '\n') { cmd_ready = 1; return; }
  if (++rx.len >= CMD_MAX) { rx.overflow = 1; rx.len = CMD_MAX; return; }
  if (is_space(c)) { rx.inword = 0; return; }
  if (!rx.inword) { rx.inword = 1; if (rx.words < 3) rx.words++; }
  if (rx.words < 3) { rx_c = c; rx_step = 1; }
}

static void __attribute__((noinline)) rx_word(void) {
  uint8_t c = rx_c;
  rx_step = 0;
  if (rx.words == 1) {
    uint8_t i = rx.w0len++;
    if (i == 0) {
      rx.cand = c == 'I' ? 1u << C_ID : c == 'S' ? (1u << C_START) | (1u << C_STOP)
              : c == 'W' ? 1u << C_WINDOW : c == 'R' ? 1u << C_RANGE : 0;
    } else if (rx.cand) {
      rx_i = i;
      rx_rest = rx.cand;
      rx_keep = 0;
      rx_step = 3;  // the candidates next, one per step (rx_filt)
      return;
    }
    rx_step = 2;  // the token character next (rx_tok)
  } else if (rx.words == 2) {
    if (c < '0' || c > '9' || rx.ndig >= 5) rx.digits_ok = 0;
    else {
      uint16_t v = rx.val;
      v = v >= 6553u ? 0xFFFFu : (uint16_t)((v << 3) + (v << 1) + (uint8_t)(c - '0'));
      rx.val = v;
      rx.ndig++;
    }
  }
}

// rx_step 3: does candidate command k (the lowest left in rx_rest) have c at position rx_i?
static const uint8_t bit_k[17] = {0, 0, 1, 0, 2, 0, 0, 0, 3, 0, 0, 0, 0, 0, 0, 0, 4};
static void __attribute__((noinline)) rx_filt(void) {
  uint8_t rest = rx_rest, bit = (uint8_t)(rest & (uint8_t)-rest), k = bit_k[bit], i = rx_i;
  if (i < cmd_len[k] && pgm_read_byte(&cmd_names[k][i]) == rx_c) rx_keep |= bit;
  rest &= (uint8_t)~bit;
  rx_rest = rest;
  if (!rest) {
    rx.cand = rx_keep;
    rx_step = 2;  // the token character next (rx_tok)
  }
}

static void __attribute__((noinline)) rx_tok(void) {  // rx_step 2: the command word's token
  uint8_t c = rx_c;
  rx_step = 0;
  {
    if (rx.toklen < 12 && c > 0x20 && c < 0x7f && c != ',' && c != '*' && c != '$') {
      rx.tok[rx.toklen++] = (char)c;
      rx.tok[rx.toklen] = 0;
    }
  }
}

static inline uint32_t now_ms(void) { return ((uint32_t)ms_hi << 16) | ms16; }

// Command execution in two tasks: decide (cmd_ready 1 -> 2), then act and answer (2 -> 0).
static uint8_t ex_cmd, ex_code, ex_resp;  // ex_code: 0 accept, else the ERR code
static void __attribute__((noinline)) cmd_decide(void) {
  cmd_ready = 2;
  ex_code = 0;
  if (rx.overflow) { ex_code = 3; return; }
  int8_t c = -1;
  uint8_t cand = rx.cand, n = rx.w0len;
  if ((cand & (1u << C_ID)) && n == 2) c = C_ID;
  else if ((cand & (1u << C_START)) && n == 5) c = C_START;
  else if ((cand & (1u << C_STOP)) && n == 4) c = C_STOP;
  else if ((cand & (1u << C_WINDOW)) && n == 6) c = C_WINDOW;
  else if ((cand & (1u << C_RANGE)) && n == 5) c = C_RANGE;
  if (c < 0) { ex_code = 1; return; }
  ex_cmd = (uint8_t)c;
  if (c == C_WINDOW || c == C_RANGE) {
    uint16_t v = rx.val;
    uint8_t ok = rx.words == 2 && rx.digits_ok && rx.ndig > 0;
    if (ok) ok = c == C_WINDOW ? (v >= WINDOW_MIN && v <= WINDOW_MAX) : v <= 1;
    if (!ok) ex_code = 2;
  } else if (rx.words != 1) {
    ex_code = 2;
  }
}

// cmd_ready 2: the command's effect; 5: its answer (queued in a step of its own).
static uint8_t ex_kind, ex_hasval;
static uint16_t ex_val;
static void __attribute__((noinline)) cmd_act(void) {
  uint8_t c = ex_cmd;
  cmd_ready = 5;
  ex_kind = K_ACK;
  ex_hasval = 0;
  if (ex_code) {
    ex_kind = K_ERR;
  } else if (c == C_WINDOW) {
    window_ms = rx.val;
    win_left = window_ms;  // the current window restarts with the new length
    t_last_end = now_ms();
    snap_stage = 3;        // discard what the old window accumulated (see take_snapshot)
    meter_asm_job |= 2;
    ex_hasval = 1;
    ex_val = window_ms;
  } else if (c == C_RANGE) {
    range_sel = (uint8_t)rx.val;
    if (range_sel) PORTD |= _BV(PD4); else PORTD &= (uint8_t)~_BV(PD4);
    ex_hasval = 1;
    ex_val = range_sel;
  } else if (c == C_ID) {
    cmd_ready = 6;  // the ID frame first, then the ACK
  } else if (c == C_START) {
    if (!running) {
      running = 1;
      win_left = window_ms;
      t_last_end = now_ms();
      snap_stage = 3;
      meter_asm_job |= 2;
    }
  } else {
    running = 0;
  }
}

static void __attribute__((noinline)) cmd_answer(void) {  // cmd_ready 5 (or 6 for ID)
  if (cmd_ready == 6) {
    queue_resp(K_ID, 0, 0, 0, 0);
    cmd_ready = 5;
    return;
  }
  if (ex_kind == K_ERR) {
    uint8_t i = queue_resp(K_ERR, 0, ex_code, 0, 0);
    if (i != 0xFF && ex_code != 3) {
      ex_resp = i;
      cmd_ready = 3;  // the token is copied in the next step, before the answer is formatted
      return;
    }
  } else {
    queue_resp(K_ACK, ex_cmd, 0, ex_hasval, ex_val);
  }
  cmd_ready = 4;
}

static void __attribute__((noinline)) cmd_tok(void) {  // cmd_ready 3: the ERR token
  const char *t = rx.tok[0] ? rx.tok : s_Q;
  char *d = respq[ex_resp].tok;
  while ((*d++ = *t++)) {}
  cmd_ready = 4;
}

static void __attribute__((noinline)) cmd_done(void) {  // cmd_ready 4
  rx_reset();
  cmd_ready = 0;
}

static void chain_break(void);

// ---------------------------------------------------------------------------------------------
static uint8_t stall_waiting(void);

static uint8_t adc_due;
static void __attribute__((noinline)) adc_take(void) {  // once per ms, after the tick (adc_due 1)
  adc_due = 2;  // the checks next (adc_check)
  if (!(ADCSRA & _BV(ADSC))) {  // the conversion started one tick ago is done (104 us at clk/128)
    acc.adc_sum += ADC;
    acc.adc_cnt++;
    ADCSRA |= _BV(ADSC);
  }
}

static void __attribute__((noinline)) adc_check(void) {  // adc_due 2
  adc_due = 0;
  // starvation: work waited a whole ms without any progress, twice
  if (!progress && stall_waiting()) {
    if (++stall >= 2) force = 1;
  } else {
    stall = 0;
  }
  progress = 0;
  // no edge for MAX_PHASE_MS: a gap, not a period (the hot state is in meter_loop's registers:
  // C breaks the chain, see meter_run)
  if ((uint8_t)((uint8_t)ms16 - hs.ms_prev) == (uint8_t)(MAX_PHASE_MS + 1u)) force = 3;
}

static void __attribute__((noinline)) tick(void) {
  TIFR2 = _BV(OCF2A);
  if (++ms16 == 0) ms_hi++;
  adc_due = 1;  // the tick's second half: ADC, starvation and gap checks (adc_take)
  meter_asm_job |= 5;  // task limits from the latest phases
  if (running && --win_left == 0) {
    win_left = window_ms;
    if (!snap_stage) {  // else the previous end is still being taken: one longer window
      snap_stage = 1;
      snap_t = now_ms();  // the window's end (its sums are taken a few periods later)
      meter_asm_job |= 2;
    }
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
static void snap_settle(void);

static void chain_break(void) {
  // between stage 1 and stage 4 of a window end acc must hold exactly the ended window
  snap_settle();
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
  meter_asm_job &= (uint8_t)~2u;  // done here (meter_loop not running): no hand-over
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
    acc.periods = 0;
    acc.sum_p = 0;
    snap_stage = 8;
    return;
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

static void __attribute__((noinline)) snap_copy_h(void) {  // stage 8
  uint32_t hp = snap_hp;
  snap.sum_h = acc.sum_h - hp;
  acc.sum_h = hp;
  snap_stage = 2;
}

static void __attribute__((noinline)) snap_meta(void) {  // stage 2
  uint32_t t = snap_t;
  snap.t_ms = t;
  snap.window = t - t_last_end;
  t_last_end = t;
  snap_stage = 7;
}

static void __attribute__((noinline)) snap_adc(void) {  // stage 7
  uint16_t n = acc.adc_cnt;
  snap.adc_sum = acc.adc_sum + (n >> 1);  // rounded mean
  snap.adc_cnt = n;
  acc.adc_sum = 0;
  acc.adc_cnt = 0;
  snap_stage = 6;
}

static void __attribute__((noinline)) snap_meta2(void) {  // stage 6
  snap.missed = acc.missed;
  acc.missed = 0;
  snap.range = range_sel;
  // the mean is < 2048, so the remainder starts as the sum's bits above the 11 quotient bits
  snap.adc_q = 0;
  snap.div_bits = 11;
  snap_state = snap.adc_cnt ? 4 : 2;  // 4: div_init next
  snap_stage = 0;
}

// The division's start: the remainder is the sum's bits above the 11 quotient bits (byte moves,
// no shift loops), the low 11 bits are brought down one per div_step.
static void __attribute__((noinline)) div_init(void) {
  uint32_t s = snap.adc_sum;  // < 2^26
  uint8_t b0 = (uint8_t)s, b1 = (uint8_t)(s >> 8), b2 = (uint8_t)(s >> 16), b3 = (uint8_t)(s >> 24);
  // r = s >> 11 and lo = (s << 5) & 0xFFFF (bit 10 of s at bit 15), in 8-bit operations
  uint8_t rl = (uint8_t)((uint8_t)(b1 >> 3) | (uint8_t)(b2 << 5));
  uint8_t rh = (uint8_t)((uint8_t)(b2 >> 3) | (uint8_t)(b3 << 5));
  snap.adc_r = (uint16_t)(((uint16_t)rh << 8) | rl);
  uint8_t ll = (uint8_t)(b0 << 5);
  uint8_t lh = (uint8_t)((uint8_t)(b1 << 5) | (uint8_t)(b0 >> 3));
  snap.adc_lo = (uint16_t)(((uint16_t)lh << 8) | ll);
  snap_state = 1;
}

// Stage 10 (report) or 12 (discard): meter_loop moved the sums into acc and handed over the
// chain state at that moment (fold_*); close the chain there.
static void __attribute__((noinline)) snap_fold_loop(void) {
  if (fold_flags & HF_CHAIN) {
    uint16_t lr = fold_lr;
    acc.sum_p += ((uint32_t)fold_wraps << 16) + (uint16_t)(lr - chain_start) - (lr < chain_start ? 0x10000ul : 0ul);
    chain_start = lr;
  }
  snap_stage = (uint8_t)(snap_stage + 4);  // 10 -> 14, 12 -> 16
}

static void __attribute__((noinline)) snap_fold_hp(void) {  // stage 14 or 16
  snap_hp = (fold_flags & HF_HIGH) ? (((uint32_t)hs.hp_hi << 16) | fold_hp) : 0;
  snap_stage = snap_stage == 14 ? 4 : 5;
}

static void take_snapshot(void) {
  uint8_t st = snap_stage;
  if (st == 1 || st == 3) snap_fold();
  else if (st >= 14) snap_fold_hp();
  else if (st >= 10) snap_fold_loop();
  else if (st == 4 || st == 5) snap_copy();
  else if (st == 8) snap_copy_h();
  else if (st == 7) snap_adc();
  else if (st == 6) snap_meta2();
  else snap_meta();
}

// Before C writes acc (slow path, breaks): finish a window end whose sums are being taken.
static void snap_settle(void) {
  while (snap_stage >= 4 && snap_stage != 2) take_snapshot();
}

static void __attribute__((noinline)) div_step(void) {  // one bit of adc_sum / adc_cnt
  uint16_t r = snap.adc_r;
  uint8_t top = (uint8_t)(r >> 15);
  uint16_t lo = snap.adc_lo;
  r = (uint16_t)((r << 1) | (uint8_t)(lo >> 15));
  snap.adc_lo = (uint16_t)(lo << 1);
  snap.adc_q <<= 1;
  if (top || r >= snap.adc_cnt) { r = (uint16_t)(r - snap.adc_cnt); snap.adc_q |= 1; }
  snap.adc_r = r;
  if (!--snap.div_bits) {
    if (snap.adc_q > 1023) snap.adc_q = 1023;
    snap_state = 2;
  }
}

static uint16_t task_limit(uint16_t l_cur, uint16_t l_next, uint8_t through);

// Recompute the task limits after a rising and after a falling edge from the last high and low
// times (the hot path only copies them); one of the two per run.
static uint8_t pred_which;
static void __attribute__((noinline)) pred_step(void) {
  uint16_t hi = hs.l_hi, lo = hs.l_lo;  // 0xFFFF: unknown (task_limit gives no limit)
  if (pred_which) {
    hs.lim_f = task_limit(lo, hi, 0);
    pred_due = 0;
  } else {
    hs.lim_r = task_limit(hi, lo, 1);
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
// Selected steps (jobs): the dispatcher below only picks the next step of the window end, the
// formatter, the ADC mean, the command receiver and the command execution; meter_loop calls it
// in a later slot that fits its own bound (job_cost, by job id: formatter state 1..9, window-end
// stage functions 10..17, others 20..29). Cheap for the loop: the long chain of checks runs as a
// task of its own (COST_SEL), the step itself only with the call.
#define JOB_SNAP0 10
static const job_fn fmt_jobs[10] = {0, fmt_item, fmt_comma, fmt_str, fmt_num, fmt_tail, fmt_crc,
                                    fmt_digit, fmt_pow, fmt_numinit};
static_assert(FS_ITEM == 1 && FS_COMMA == 2 && FS_STR == 3 && FS_NUM == 4 && FS_TAIL == 5 &&
              FS_CRC == 6 && FS_DIGIT == 7 && FS_POW == 8 && FS_NUMINIT == 9, "fmt_jobs by state");
// window-end stage -> job id (take_snapshot's choice)
static const uint8_t snap_job[17] = {17, 10, 17, 10, 13, 13, 16, 15, 14, 17, 12, 12, 12, 12, 11, 11, 11};
static const job_fn snap_jobs[8] = {snap_fold, snap_fold_hp, snap_fold_loop, snap_copy, snap_copy_h,
                                    snap_adc, snap_meta2, snap_meta};
enum { J_DIV = 20, J_DIVINIT, J_DECIDE, J_ACT, J_ANSWER, J_TOK, J_DONE, J_START, J_RXWORD, J_RXTOK, J_RXFILT };
// Bound of each job [cycles]: meter_loop's job path beyond CALL_OVH (JOB_OVH) + the function
// (profiling build, prof_job, + the profiling read).
static const uint8_t job_cost[32] = {  // by job id
  0, JOB_B(89), JOB_B(75), JOB_B(88), JOB_B(85), JOB_B(64), JOB_B(89), JOB_B(92),
  JOB_B(49), JOB_B(43), JOB_B(130), JOB_B(56), JOB_B(101), JOB_B(74), JOB_B(56), JOB_B(73),
  JOB_B(71), JOB_B(74), 0, 0, JOB_B(81), JOB_B(100), JOB_B(80), JOB_B(99),
  JOB_B(105), JOB_B(82), JOB_B(52), JOB_B(83), JOB_B(74), JOB_B(48), JOB_B(83), 0,
};

// The formatter as a job of meter_loop: one step, then the next step is selected at once unless
// other work waits (the dispatcher's chain would pick something else first; meter_loop itself
// checks the 1 ms tick before it calls a job), so that a frame costs one slot per step.
#define FMT_CHAIN 66        // fmt_job beyond the step itself [cycles] (static count 62)
static void __attribute__((noinline)) fmt_job(void) {
  fmt_jobs[f_state]();
  uint8_t st = f_state;
  if (!st || (uint8_t)(adc_due | rx_step)) return;
  uint8_t a = UCSR0A, h = tx_head, t = tx_tail;
  if (a & _BV(RXC0)) return;
  if (h != t && ((a & _BV(UDRE0)) || (uint8_t)((h - t) & 127u) == 127u)) return;
  meter_job = fmt_job;
  meter_job_cost = (uint8_t)(job_cost[st] + FMT_CHAIN);
  meter_job_id = st;
}

// Background dispatcher: runs the first pending task whose cost bound fits `budget` cycles, or,
// for meter_loop (sel), selects the step of the long tasks as meter_job. Returns its number
// (13: a step selected), 0 if none ran.
#define SEL_JOB(fn, id)                                                           \
  do {                                                                            \
    if (sel) {                                                                    \
      meter_job = (fn); meter_job_cost = job_cost[(id)]; meter_job_id = (id);     \
      return 13;                                                                  \
    }                                                                             \
    (fn)();                                                                       \
    return 5;                                                                     \
  } while (0)
static inline __attribute__((always_inline)) uint8_t task(uint16_t budget, uint8_t sel) {
  if (TIFR2 & _BV(OCF2A)) { if (budget >= COST_TICK) { tick(); return 1; } return 0; }
  if (adc_due) {
    if (budget < COST_TICK2) return 0;
    if (adc_due == 1) adc_take(); else adc_check();
    return 11;
  }
  if (rx_step) {
    if (meter_job) return 0;  // (the selected step is this one, or runs first)
    if (rx_step == 1) SEL_JOB(rx_word, J_RXWORD);
    if (rx_step == 3) SEL_JOB(rx_filt, J_RXFILT);
    SEL_JOB(rx_tok, J_RXTOK);
  }
  if (!cmd_ready && (UCSR0A & _BV(RXC0))) { if (budget >= COST_RX) { rx_byte(UDR0); return 2; } return 0; }
  if (tx_head != tx_tail && (UCSR0A & _BV(UDRE0))) {
    if (budget < COST_TX) return 0;
    UDR0 = txbuf[tx_tail];
    tx_tail = (uint8_t)((tx_tail + 1u) & 127u);
    return 3;
  }
  if (meter_job) return 0;  // a step is selected: meter_loop runs it when it fits
  if (snap_stage && snap_state == 0 && (meter_fold_ok || (snap_stage & 0xFDu) != 1u)) {
    uint8_t j = snap_job[snap_stage < 17 ? snap_stage : 16];
    SEL_JOB(snap_jobs[j - JOB_SNAP0], j);
  }
  if (f_state != FS_IDLE) {
    if (tx_used() >= 127u) return 0;
    uint8_t st = f_state;
    if (sel) {
      meter_job = fmt_job;
      meter_job_cost = (uint8_t)(job_cost[st] + FMT_CHAIN);
      meter_job_id = st;
      return 13;
    }
    fmt_jobs[st]();
    return 5;
  }
  if (snap_state == 1) SEL_JOB(div_step, J_DIV);
  if (snap_state == 4) SEL_JOB(div_init, J_DIVINIT);
  {
    uint8_t c = cmd_ready;
    if (c == 1) SEL_JOB(cmd_decide, J_DECIDE);
    if (c == 2) SEL_JOB(cmd_act, J_ACT);
    if (c >= 5) SEL_JOB(cmd_answer, J_ANSWER);
    if (c == 3) SEL_JOB(cmd_tok, J_TOK);
    if (c == 4) SEL_JOB(cmd_done, J_DONE);
  }
  if ((rq_tail != rq_head || snap_state == 2) && tx_used() < 32u) SEL_JOB(fmt_start, J_START);
  return 0;
}

// Work that a task must do (the transmitter drains by itself, one byte per 87 us).
static uint8_t stall_waiting(void) {
  return f_state != FS_IDLE || snap_stage || snap_state == 1 || snap_state == 4 || cmd_ready || rx_step ||
         (UCSR0A & _BV(RXC0)) || ((rq_tail != rq_head || snap_state == 2) && tx_used() < 32u);
}

static uint8_t work_waiting(void) {
  return tx_head != tx_tail || f_state != FS_IDLE || snap_stage || snap_state == 1 || snap_state == 4 || cmd_ready || rx_step || adc_due ||
         (UCSR0A & _BV(RXC0)) || ((rq_tail != rq_head || snap_state == 2));
}

static inline __attribute__((always_inline)) uint8_t run_task(uint16_t budget) {
#ifdef METER_PROFILE
  uint8_t fs = f_state, ss = snap_stage;
  uint16_t t0 = TCNT1;
  uint8_t id = task(budget, 1);
  uint16_t d = TCNT1 - t0;
  if (d > prof_task[id]) prof_task[id] = d;
  if (id == 5 && d > prof_fmt[fs]) prof_fmt[fs] = d;
  if (id == 4 && ss < 16 && d > prof_snap[ss]) prof_snap[ss] = d;
#else
  uint8_t id = task(budget, 1);
#endif
  if (id == 2 || id == 12 || (id >= 4 && id < 10)) progress = 1;  // not tick, transmit, prediction
  return id;
}

// One background task for meter_loop (assembly): the first pending one if it fits `budget`.
// A step selected with budget to spare runs at once.
extern "C" ASM_VISIBLE __attribute__((noinline)) uint8_t meter_task(uint16_t budget) {
  uint8_t id = run_task(budget);
#ifndef METER_PROFILE  // (there every step runs from meter_loop: prof_job)
  if (id == 13 && budget >= (uint16_t)(COST_MIN + RUN_NOW + meter_job_cost)) {
    job_fn f = meter_job;
    meter_job = 0;
    f();
    progress = 1;
  }
#endif
  return id;
}

// ---------------------------------------------------------------------------------------------
// meter_loop(): the measuring loop, in assembly because every cycle counts at 50 kHz: wait for
// the armed edge, capture it, do the common bookkeeping with the hot state in registers, and
// between edges call the background dispatcher meter_task(budget) (C) while the prediction leaves
// room. It returns to C only for the rare cases (the hot state is then written back to meter_hs).
// Interrupts are enabled only while waiting, for one purpose: a Timer0 compare match as timeout
// (TIMER0_COMPA_vect below makes the wait return 1).
// Capture: the wait loop is `sbis; rjmp` (3 cycles); on the flag, read ICR1, write the other edge
// into TCCR1B, clear ICF1 (the datasheet's order: a change of ICES1 may set ICF1). From the flag
// to ICES1 flipped: at most 3 + 2 (sbis skip) + 4 (lds, lds) + 2 (sts) = 11 cycles; ICF1 is
// cleared one cycle later (an edge in that cycle is lost and caught by the pin check below).
// Then: pin check (the pin must still show the captured edge unless the next edge was captured
// too), latency check (only if a task ran: a capture served later than one full period may hide
// an edge pair), and for the common case (a chain of periods, the open period < 2 ms) the period
// count, high time, wrap count, the last high/low times and the task limit for the next phase.
// Returns 1 timeout, 2 missed edge (pin check), 3 slow path (C finishes, capture in
// cap_ts/cap_ms), 4 rejected (late capture), 5 tasks starve or the tick asks for C (meter_force),
// 6 phases measured again after a loss (C computes the limits).
// Registers (call-saved, so the C tasks keep them; written back to meter_hs on exit):
//   r2:r3 ts_prev, r4:r5 last_rise, r6:r7 periods_part (low half), r8..r11 sumh_part,
//   r12:r13 hp16 (= last high time), r14:r15 lim, r16 TCCR1B value for the edge after the armed
//   one, r17 ms_rise, r28 flags, r29 = 1 << ICF1.
#define ML_STR2(x) #x
#define ML_STR(x) ML_STR2(x)
#if defined(METER_PROFILE) && !defined(ML_NO_PROF_TOP)
// min cycles from one loop top to the next when the edge was already waiting and no task ran
// (prof_edge_cyc[0] after a falling edge, [1] after a rising one); adds ~30 cycles per edge
#define ML_PROF_TOP \
  "  lds r22, 0x84\n" \
  "  lds r23, 0x85\n" \
  "  lds r24, prof_prev\n" \
  "  lds r25, prof_prev+1\n" \
  "  sts prof_prev, r22\n" \
  "  sts prof_prev+1, r23\n" \
  "  sub r22, r24\n" \
  "  sbc r23, r25\n" \
  "  lds r21, prof_ok\n" \
  "  sts prof_ok, r1\n" \
  "  sbic 0x16, 5\n" \
  "  sts prof_ok, r29\n" \
  "  tst r21\n" \
  "  breq 71f\n" \
  "  ldi r30, lo8(prof_edge_cyc)\n" \
  "  ldi r31, hi8(prof_edge_cyc)\n" \
  "  sbrs r28, 0\n" \
  "  adiw r30, 2\n" \
  "  ld r24, Z\n" \
  "  ldd r25, Z+1\n" \
  "  cp r22, r24\n" \
  "  cpc r23, r25\n" \
  "  brsh 71f\n" \
  "  st Z, r22\n" \
  "  std Z+1, r23\n" \
  "71:\n"
#define ML_PROF_TASKED "  sts prof_ok, r1\n"
// longest selected step by job id (prof_job), TCNT1 around the icall
#define ML_PROF_JOB0 \
  "  lds r22, 0x84\n" \
  "  lds r23, 0x85\n" \
  "  push r22\n" \
  "  push r23\n"
#define ML_PROF_JOB1 \
  "  lds r24, 0x84\n" \
  "  lds r25, 0x85\n" \
  "  pop r23\n" \
  "  pop r22\n" \
  "  sub r24, r22\n" \
  "  sbc r25, r23\n" \
  "  lds r30, meter_job_id\n" \
  "  ldi r31, 0\n" \
  "  lsl r30\n" \
  "  subi r30, lo8(-(prof_job))\n" \
  "  sbci r31, hi8(-(prof_job))\n" \
  "  ld r22, Z\n" \
  "  ldd r23, Z+1\n" \
  "  cp r22, r24\n" \
  "  cpc r23, r25\n" \
  "  brsh 72f\n" \
  "  st Z, r24\n" \
  "  std Z+1, r25\n" \
  "72:\n"
#else
#define ML_PROF_JOB0 ""
#define ML_PROF_JOB1 
#define ML_PROF_TOP ""
#define ML_PROF_TASKED ""
#endif
asm(R"ASM(
  .section .text.meter_loop,"ax",@progbits
  .global meter_loop
  .global meter_loop_timeout
meter_loop:
  push r2
  push r3
  push r4
  push r5
  push r6
  push r7
  push r8
  push r9
  push r10
  push r11
  push r12
  push r13
  push r14
  push r15
  push r16
  push r17
  push r28
  push r29
  lds r2, meter_hs+0
  lds r3, meter_hs+1
  lds r4, meter_hs+12
  lds r5, meter_hs+13
  lds r6, meter_hs+32
  lds r7, meter_hs+33
  lds r8, meter_hs+36
  lds r9, meter_hs+37
  lds r10, meter_hs+38
  lds r11, meter_hs+39
  lds r12, meter_hs+18
  lds r13, meter_hs+19
  lds r14, meter_hs+6
  lds r15, meter_hs+7
  lds r17, meter_hs+22
  lds r28, meter_hs+20
  ldi r29, 0x20           ; 1 << ICF1
  lds r24, meter_rearm    ; after a break: arm for the edge opposite to the present level
  tst r24
  breq 1f
  sts meter_rearm, r1
  in r25, 0x03            ; PINB
  ldi r24, 0x01           ; high: falling edge next
  sbrs r25, 0
  ldi r24, 0x41           ; low: rising edge next
  sts 0x81, r24
  out 0x16, r29           ; clear ICF1
  andi r28, 0xFE
  sbrs r25, 0
  ori r28, 0x01           ; HF_ARMED_RISE
1:
  ldi r16, 0x41           ; TCCR1B for a rising edge
  sbrc r28, 0             ; armed for rising: the next one is falling
  ldi r16, 0x01
ml_top:
)ASM" ML_PROF_TOP R"ASM(
  sbic 0x17, 1            ; TIFR2.OCF2A: a tick is due
  rjmp ml_tickdue
ml_top2:
  sbic 0x16, 5            ; the edge is waiting already
  rjmp ml_cap
  movw r24, r14           ; lim: tasks must end before TCNT1 - ts_prev reaches it
  adiw r24, 1
  brne .+2            ; 0xFFFF: no limit
  rjmp ml_free
  sbiw r24, 1
  lds r22, 0x84           ; TCNT1
  lds r23, 0x85
  sub r22, r2
  sbc r23, r3             ; elapsed since the last edge
  sub r24, r22
  sbc r25, r23
  brcc .+2                ; past the limit
  rjmp ml_wait
  subi r24, lo8()ASM" ML_STR(CALL_OVH) R"ASM()
  sbci r25, hi8()ASM" ML_STR(CALL_OVH) R"ASM()
  brcc .+2                ; budget = lim - elapsed - call overhead
  rjmp ml_wait
  cpi r24, )ASM" ML_STR(COST_MIN) R"ASM(
  cpc r25, r1
  brsh .+2
  rjmp ml_wait
ml_call:
  lds r23, meter_asm_job  ; assembly jobs: window end's hand-over (bit 1), task limits (bits 0, 2)
  tst r23
  breq ml_callc
  sbrs r23, 1
  rjmp 5f
  sts meter_fold_ok, r1   ; (the dispatcher must not take stage 1/3: the sums are here)
  cpi r24, lo8()ASM" ML_STR(COST_FLUSH) R"ASM()
  ldi r22, hi8()ASM" ML_STR(COST_FLUSH) R"ASM()
  cpc r25, r22
  brlo 5f
  andi r23, 0xFD
  sts meter_asm_job, r23
  rcall ml_flush
  rjmp 6f
5:
  mov r22, r23
  andi r22, 0x05
  breq ml_callc
  cpi r24, lo8()ASM" ML_STR(COST_PRED) R"ASM()
  ldi r22, hi8()ASM" ML_STR(COST_PRED) R"ASM()
  cpc r25, r22
  brlo ml_callc
  sbrs r23, 0
  rjmp 7f
  andi r23, 0xFE          ; lim_r now, lim_f next time
  sts meter_asm_job, r23
  rcall ml_pred_r
  rjmp 6f
7:
  andi r23, 0xFB
  sts meter_asm_job, r23
  rcall ml_pred_f
6:
  ori r28, 0x80           ; HF_TASKED
  rjmp ml_top
ml_callc:
  lds r30, meter_job      ; a selected step: call it directly if it fits
  lds r31, meter_job+1
  mov r22, r30
  or r22, r31
  breq ml_disp
  lds r22, meter_job_cost
  cp r24, r22
  cpc r25, r1
  brlo ml_disp            ; too long for this slot: the dispatcher may run the tick, USART
  sbic 0x17, 1            ; the 1 ms tick first (TIFR2.OCF2A)
  rjmp ml_disp
  sts meter_job, r1
  sts meter_job+1, r1
)ASM" ML_PROF_JOB0 R"ASM(
  icall
)ASM" ML_PROF_JOB1 R"ASM(
  sts meter_progress, r29 ; (nonzero)
  ori r28, 0x80           ; HF_TASKED
)ASM" ML_PROF_TASKED R"ASM(
  rjmp ml_top
ml_disp:
  call meter_task
  tst r24
  brne .+2
  rjmp ml_none
  ori r28, 0x80           ; HF_TASKED
)ASM" ML_PROF_TASKED R"ASM(
  lds r24, meter_force    ; the tick asks for C (starvation, a long gap)
  tst r24
  brne .+2
  rjmp ml_top
  ldi r24, 5
  rjmp ml_exit
ml_tickdue:
  lds r24, 0xB2           ; TCNT2 counts 4 us since OCF2A rose: 0.5 ms late, the tasks starve
  cpi r24, 125
  brsh .+2
  rjmp ml_top2
  ldi r24, 5
  rjmp ml_exit
ml_free:
  ldi r24, 0xFF
  ldi r25, 0xFF
  rjmp ml_call
ml_none:                  ; nothing ran: far from the edge keep polling here (the tick stays on time)
  movw r24, r14
  adiw r24, 1
  brne .+2
  rjmp ml_top             ; no limit
  sbiw r24, 1
  lds r22, 0x84
  lds r23, 0x85
  sub r22, r2
  sbc r23, r3
  sub r24, r22
  sbc r25, r23
  brcc .+2
  rjmp ml_wait
  cpi r24, lo8()ASM" ML_STR(COST_MAX + CALL_OVH) R"ASM()
  ldi r22, hi8()ASM" ML_STR(COST_MAX + CALL_OVH) R"ASM()
  cpc r25, r22
  brsh .+2
  rjmp ml_wait
  rjmp ml_top
ml_wait:
  lds r24, meter_probe    ; after a loss, waiting for both phases: are they known now?
  tst r24
  breq 1f
  mov r24, r28
  andi r24, 0x0C
  cpi r24, 0x0C
  brne 1f
  rcall ml_probed
1:
  in r18, 0x26            ; timeout: OCR0A = TCNT0 + 14 (14 x 64 us = 0.9 ms)
  subi r18, 0xF2
  out 0x27, r18
  ldi r18, 0x02
  out 0x15, r18           ; TIFR0 = 1 << OCF0A
  sei
2:
  sbis 0x16, 5            ; TIFR1.ICF1
  rjmp 2b
ml_cap:
  lds r18, 0x86           ; ICR1L (latches ICR1H)
  lds r19, 0x87           ; ICR1H
  sts 0x81, r16           ; TCCR1B: arm the other edge
  out 0x16, r29           ; clear ICF1
  cli
  in r22, 0x03            ; PINB
  in r23, 0x16            ; TIFR1
  sbrc r23, 5             ; next edge already captured: nothing was lost
  rjmp 2f
  eor r22, r28            ; PB0 must equal "captured a rising edge" = armed bit
  sbrc r22, 0
  rjmp ml_miss
2:
  ldi r21, 0x40
  eor r16, r21            ; TCCR1B for the edge after the one now armed
  ldi r21, 1
  eor r28, r21            ; armed toggles; bit 0 now set <=> a falling edge was captured
  sbrc r28, 7             ; HF_TASKED: a task ran since the last capture
  rjmp ml_tasked
3:
  lds r26, meter_ms16     ; ms count, low byte
  sbrs r28, 4             ; HF_CHAIN
  rjmp ml_nochain
  mov r27, r26
  sub r27, r17            ; - ms_rise
  cpi r27, 2              ; >= 1 ms since the rising edge that opened the period: C extends it
  brlo .+2
  rjmp ml_slow
  sbrc r28, 0
  rjmp ml_fall
  ; ---- rising edge: closes the period begun at last_rise
  sbrs r28, 5             ; HF_HIGH
  rjmp ml_slow
  movw r22, r18
  sub r22, r4
  sbc r23, r5             ; period = ts - last_rise (< 2 ms)
  cp r12, r22
  cpc r13, r23
  brlo .+2            ; high >= period: C rejects the period
  rjmp ml_slow
  cp r18, r4
  cpc r19, r5
  brsh .+2            ; the 16-bit timestamp wrapped since last_rise
  rjmp ml_wrap
4:
  inc r6                  ; periods_part++
  brne 5f
  inc r7
  brne 5f
  rcall ml_pcarry
5:
  movw r4, r18            ; last_rise = ts
  mov r17, r26            ; ms_rise
  andi r28, 0xDF          ; HF_HIGH = 0
  movw r22, r18
  sub r22, r2
  sbc r23, r3             ; low time just ended
  sts meter_hs+4, r22     ; l_lo
  sts meter_hs+5, r23
  ori r28, 0x0A           ; HF_PK_LO | HF_PREV
  lds r14, meter_hs+8     ; lim = lim_r
  lds r15, meter_hs+9
  movw r2, r18            ; ts_prev
  sts meter_hs+21, r26    ; ms_prev
  rjmp ml_top
ml_fall:                  ; chained, so the previous edge was last_rise
  sbrc r28, 5             ; high time already known (cannot happen without a miss)
  rjmp ml_slow
  movw r12, r18
  sub r12, r4
  sbc r13, r5             ; high time
  sts meter_hs+2, r12     ; l_hi
  sts meter_hs+3, r13
  add r8, r12             ; sumh_part += high
  adc r9, r13
  adc r10, r1
  adc r11, r1
  ori r28, 0x26           ; HF_HIGH | HF_PK_HI | HF_PREV
  lds r14, meter_hs+10    ; lim = lim_f
  lds r15, meter_hs+11
  movw r2, r18            ; ts_prev
  sts meter_hs+21, r26    ; ms_prev
  rjmp ml_top
ml_nochain:               ; no period open (after a break): a rising edge starts the chain
  lds r24, meter_hs+21    ; ms_prev
  mov r27, r26
  sub r27, r24            ; ms since the last edge
  movw r22, r18
  sub r22, r2
  sbc r23, r3             ; the phase that just ended
  ldi r24, 0
  sbrs r28, 1             ; HF_PREV: the last edge was seen
  rjmp 51f
  cpi r27, 2
  brsh 51f
  ldi r24, 0x04           ; HF_PK_HI after a falling edge ...
  sbrs r28, 0
  ldi r24, 0x08           ; ... HF_PK_LO after a rising one
  rjmp 52f
51:
  ldi r22, 0xFF           ; unknown
  ldi r23, 0xFF
52:
  or r28, r24
  ori r28, 0x02           ; HF_PREV
  movw r2, r18            ; ts_prev
  sts meter_hs+21, r26    ; ms_prev
  sbrc r28, 0
  rjmp 53f
  sts meter_hs+4, r22     ; l_lo
  sts meter_hs+5, r23
  movw r4, r18            ; last_rise = chain_start = ts
  mov r17, r26            ; ms_rise
  sts meter_chain_start, r18
  sts meter_chain_start+1, r19
  sts meter_hs+24, r1     ; wraps = 0
  sts meter_hs+25, r1
  sts meter_hs+26, r1     ; hp_hi = 0
  sts meter_hs+27, r1
  ori r28, 0x10           ; HF_CHAIN
  andi r28, 0xDF          ; HF_HIGH = 0
  lds r14, meter_hs+8     ; lim = lim_r
  lds r15, meter_hs+9
  rjmp ml_top
53:
  sts meter_hs+2, r22     ; l_hi
  sts meter_hs+3, r23
  lds r14, meter_hs+10    ; lim = lim_f
  lds r15, meter_hs+11
  rjmp ml_top
; The task limits of task_limit() (same formula, in assembly: no C round trip blinds the
; capture). ml_probed: both phases measured again after a loss; ml_pred_r/ml_pred_f: the
; prediction task, one limit per call, every ms (pred_due 1, 2).
ml_probed:                ; only the limit of the phase now running (one fits before the next
  sts meter_probe, r1     ; edge at 50 kHz, two do not); the other is an assembly job (COST_PRED)
  lds r24, meter_asm_job
  sbrs r28, 0
  rjmp 66f
  andi r24, 0xFB          ; after a falling edge: lim_f now, lim_r due
  ori r24, 0x01
  sts meter_asm_job, r24
  rjmp ml_pred_f
66:
  andi r24, 0xFE          ; after a rising edge: lim_r now, lim_f due
  ori r24, 0x04
  sts meter_asm_job, r24
  rjmp ml_pred_r
ml_pred_f:                ; lim_f: after a falling edge (the low time begins); a long one
  rcall ml_s2             ; (>= LONG_PHASE): end before the rising edge (see task_limit)
  brcc 67f
  movw r24, r22
  cpi r23, hi8()ASM" ML_STR(LONG_PHASE) R"ASM()
  brsh 69f
  rcall ml_lim_one
  rjmp 67f
69:
  rcall ml_div16
  sub r24, r30
  sbc r25, r31
  subi r24, lo8()ASM" ML_STR(MARGIN) R"ASM()
  sbci r25, hi8()ASM" ML_STR(MARGIN) R"ASM()
67:
  sts meter_hs+10, r24
  sts meter_hs+11, r25
  sbrc r28, 0
  movw r14, r24           ; the current phase follows a falling edge
  ret
ml_pred_r:                ; lim_r: after a rising edge (the high time begins)
  rcall ml_s2
  brcc 68f
  movw r24, r20
  rcall ml_lim_one
68:
  sts meter_hs+8, r24
  sts meter_hs+9, r25
  sbrs r28, 0
  movw r14, r24
  ret
ml_s2:                    ; r20:r21 = l_hi, r22:r23 = l_lo, r26:r27 = 15/16 (l_hi + l_lo);
  lds r20, meter_hs+2     ; carry clear and r24:r25 = 0xFFFF (no limit) if a phase >= 0x3000
  lds r21, meter_hs+3
  lds r22, meter_hs+4
  lds r23, meter_hs+5
  ldi r24, 0xFF
  ldi r25, 0xFF
  cpi r21, 0x30
  brsh 69f
  cpi r23, 0x30
  brsh 69f
  movw r26, r20
  add r26, r22
  adc r27, r23
  movw r24, r26
  rcall ml_div16
  sub r26, r30
  sbc r27, r31
  sec
  ret
69:
  clc
  ret
ml_div16:                 ; r30:r31 = r24:r25 / 32 (PRED_SHIFT)
  movw r30, r24
  lsr r31
  ror r30
  lsr r31
  ror r30
  lsr r31
  ror r30
  lsr r31
  ror r30
  lsr r31
  ror r30
  ret
ml_lim_one:               ; r24:r25 = l_cur, r26:r27 = s2 -> r24:r25 = limit (see task_limit)
  rcall ml_div16
  sub r24, r30
  sbc r25, r31            ; c = 15/16 l_cur
  movw r30, r26
  add r30, r24
  adc r31, r25
  subi r30, lo8()ASM" ML_STR(HOT + 2 * SERVICE + MARGIN) R"ASM()
  sbci r31, hi8()ASM" ML_STR(HOT + 2 * SERVICE + MARGIN) R"ASM()
  brcc 61f
  clr r30
  clr r31
61:                        ; b2 = s2 + c - HOT - 2 SERVICE - MARGIN
  movw r18, r26
  subi r18, lo8()ASM" ML_STR(SERVICE + MARGIN) R"ASM()
  sbci r19, hi8()ASM" ML_STR(SERVICE + MARGIN) R"ASM()
  brcc 62f
  clr r18
  clr r19
62:                        ; b1 = s2 - SERVICE - MARGIN
  cp r30, r18
  cpc r31, r19
  brsh 63f
  movw r18, r30           ; b = min(b1, b2)
63:
  subi r24, lo8()ASM" ML_STR(MARGIN) R"ASM()
  sbci r25, hi8()ASM" ML_STR(MARGIN) R"ASM()
  brcc 64f
  clr r24
  clr r25
64:                        ; a = c - MARGIN
  cp r24, r18
  cpc r25, r19
  brsh 65f
  movw r24, r18           ; max(a, b)
65:
  ret
ml_wrap:
  lds r24, meter_hs+24
  lds r25, meter_hs+25
  adiw r24, 1
  sts meter_hs+24, r24
  sts meter_hs+25, r25
  rjmp 4b
ml_pcarry:
  lds r24, meter_hs+34
  lds r25, meter_hs+35
  adiw r24, 1
  sts meter_hs+34, r24
  sts meter_hs+35, r25
  ret
ml_tasked:
  andi r28, 0x7F
  lds r26, 0x84           ; TCNT1L
  lds r27, 0x85
  sub r26, r18
  sbc r27, r19            ; latency
  brpl .+2          ; >= 0x8000: a timestamp from the future (torn read in simulation)
  rjmp ml_reject
  mov r21, r28
  andi r21, 0x0C
  cpi r21, 0x0C
  breq .+2
  rjmp 3b
  lds r24, meter_hs+2
  lds r25, meter_hs+3
  lds r22, meter_hs+4
  lds r23, meter_hs+5
  add r24, r22
  adc r25, r23            ; l_hi + l_lo
  brcc .+2
  rjmp 3b
  cp r26, r24
  cpc r27, r25
  brsh .+2
  rjmp 3b
ml_reject:
  ldi r24, 4
  rjmp ml_exit
ml_slow:
  sts meter_hs+28, r18
  sts meter_hs+29, r19
  sts meter_hs+30, r26
  ldi r24, 3
  rjmp ml_exit
ml_miss:
  sts meter_hs+28, r18
  sts meter_hs+29, r19
  sts meter_hs+30, r22
  sts meter_hs+31, r23
  ldi r24, 2
  rjmp ml_exit
; Window end: move periods_part and sumh_part into the window sums (meter_acc) and write back
; what the C window-end task reads (flags, last_rise, hp16).
ml_flush:
  lds r22, meter_acc+0
  lds r23, meter_acc+1
  lds r24, meter_acc+2
  lds r25, meter_acc+3
  lds r18, meter_hs+34
  lds r19, meter_hs+35
  add r22, r6
  adc r23, r7
  adc r24, r18
  adc r25, r19
  sts meter_acc+0, r22
  sts meter_acc+1, r23
  sts meter_acc+2, r24
  sts meter_acc+3, r25
  lds r22, meter_acc+8
  lds r23, meter_acc+9
  lds r24, meter_acc+10
  lds r25, meter_acc+11
  add r22, r8
  adc r23, r9
  adc r24, r10
  adc r25, r11
  sts meter_acc+8, r22
  sts meter_acc+9, r23
  sts meter_acc+10, r24
  sts meter_acc+11, r25
  clr r6
  clr r7
  movw r8, r6
  movw r10, r6
  sts meter_hs+32, r1
  sts meter_hs+33, r1
  sts meter_hs+34, r1
  sts meter_hs+35, r1
  sts meter_hs+36, r1
  sts meter_hs+37, r1
  sts meter_hs+38, r1
  sts meter_hs+39, r1
  sts meter_fold_flags, r28  ; the chain at this moment, for stage 10/12
  sts meter_fold_lr, r4
  sts meter_fold_lr+1, r5
  sts meter_fold_hp, r12
  sts meter_fold_hp+1, r13
  lds r22, meter_hs+24
  lds r23, meter_hs+25
  sts meter_fold_wraps, r22
  sts meter_fold_wraps+1, r23
  sts meter_hs+24, r1     ; wraps = 0
  sts meter_hs+25, r1
  lds r22, meter_snap_stage
  subi r22, -9            ; 1 -> 10, 3 -> 12
  sts meter_snap_stage, r22
  ret
meter_loop_timeout:       ; the Timer0 compare interrupt returns here instead of into the wait
  cli
  ldi r24, 1
ml_exit:
  sts meter_job, r1       ; C may change the state: the step is selected again
  sts meter_job+1, r1
  sts meter_hs+0, r2
  sts meter_hs+1, r3
  sts meter_hs+12, r4
  sts meter_hs+13, r5
  sts meter_hs+32, r6
  sts meter_hs+33, r7
  sts meter_hs+36, r8
  sts meter_hs+37, r9
  sts meter_hs+38, r10
  sts meter_hs+39, r11
  sts meter_hs+18, r12
  sts meter_hs+19, r13
  sts meter_hs+6, r14
  sts meter_hs+7, r15
  sts meter_hs+22, r17
  sts meter_hs+20, r28
  pop r29
  pop r28
  pop r17
  pop r16
  pop r15
  pop r14
  pop r13
  pop r12
  pop r11
  pop r10
  pop r9
  pop r8
  pop r7
  pop r6
  pop r5
  pop r4
  pop r3
  pop r2
  ret
)ASM");

// Timer0 compare A: the wait timed out. Replace the interrupted address (inside meter_loop's
// loop, or in its next instructions if an edge came at the same moment: the caller resyncs) by
// meter_loop_timeout. The return address on the stack is big-endian, high byte on top.
ISR(TIMER0_COMPA_vect, ISR_NAKED) {
  asm volatile(
      "pop r0\n\t"
      "pop r0\n\t"
      "ldi r30, lo8(gs(meter_loop_timeout))\n\t"
      "ldi r31, hi8(gs(meter_loop_timeout))\n\t"
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
// through = 0 (lim_f, the phase that ends with a rising edge) and a long phase (>= LONG_PHASE, so
// that the slot before the edge is ample): the task ends before that edge, so that the rising
// edges, which delimit the period sums, are met by the wait loop (in simavr a capture is taken at
// the end of the running instruction: up to 3 ticks late during a task).
static uint16_t task_limit(uint16_t l_cur, uint16_t l_next, uint8_t through) {
  if (l_cur >= 0x3000u || l_next >= 0x3000u) return 0xFFFF;
  uint16_t a = (uint16_t)(l_cur - (l_cur >> PRED_SHIFT));
  a = a > MARGIN ? (uint16_t)(a - MARGIN) : 0;
  if (!through && (l_cur >> 8) >= (LONG_PHASE >> 8)) return a;
  uint16_t s2 = (uint16_t)(l_cur + l_next);
  s2 = (uint16_t)(s2 - (s2 >> PRED_SHIFT));
  uint16_t s3 = (uint16_t)(s2 + l_cur - (l_cur >> PRED_SHIFT));
  uint16_t b1 = s2 > SERVICE + MARGIN ? (uint16_t)(s2 - SERVICE - MARGIN) : 0;
  uint16_t b2 = s3 > HOT + 2 * SERVICE + MARGIN ? (uint16_t)(s3 - HOT - 2 * SERVICE - MARGIN) : 0;
  uint16_t b = b1 < b2 ? b1 : b2;
  return a > b ? a : b;
}

// Edges were lost: forget the phases, run no task until they are measured again.
static void lose_prediction(void) {
  hs.flags &= (uint8_t)~(HF_PK_HI | HF_PK_LO | HF_LIMS);
  hs.l_hi = hs.l_lo = 0xFFFF;
  hs.lim_r = hs.lim_f = 0;
  meter_probe = 1;
}

// Arm for the edge opposite to the present level (after a break).
// meter_loop does it on entry (meter_rearm), so that the wait begins right after the arming: an
// edge pair between arming and waiting would be one more missed edge.
static void resync(void) {
  hs.flags &= (uint8_t)~HF_PREV;
  meter_rearm = 1;
  hs.lim = meter_probe ? 0 : 0xFFFF;
}

// The rare cases of meter_loop (codes 1..4), and the slow path of the bookkeeping.
static void __attribute__((noinline)) edge_rare(uint8_t code) {
  // the slow path writes acc: finish a window end that is half taken (see take_snapshot)
  snap_settle();
  if (code == 1) {  // no edge for ~0.9 ms although one was predicted soon
#ifdef METER_PROFILE
    prof_cnt[2]++;
#endif
    hs.flags &= (uint8_t)~(HF_PK_HI | HF_PK_LO | HF_LIMS);
    hs.l_hi = hs.l_lo = 0xFFFF;
    hs.lim_r = hs.lim_f = 0xFFFF;
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
    hs.hp_hi = 0;  // the fast path of the next falling edge writes only hp16
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
  hs.lim = meter_probe ? 0 : (rise ? hs.lim_r : hs.lim_f);
}

void meter_run(void) {
  asm volatile("cli");
  hw_init();
  rx_reset();
  queue_resp(K_ID, 0, 0, 0, 0);  // boot identification, SEQ 0
  hs.flags = 0;
  hs.l_hi = hs.l_lo = hs.lim_r = hs.lim_f = 0xFFFF;
  resync();

  for (;;) {
    // ---- starvation: edges too fast for the tasks; run some blind and count what went by
    // (TCNT2 counts 4 us steps since OCF2A rose: a tick waiting for 0.5 ms forces the tasks)
    if (force == 3) {  // the tick saw no edge for MAX_PHASE_MS
      force = 0;
      chain_break();
    }
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
        if (!task(0xFFFF, 0) && !work_waiting()) break;
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

    // ---- capture, bookkeeping and background tasks until a rare case
    uint8_t code = meter_loop();
    meter_fold_ok = 1;
    if (code == 5) {  // the tasks starve
      if (!force) force = 2;
      continue;
    }
    if (code == 6) code = 0;  // phases measured again after a loss: limits below
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

// fsrlab meter, capture: setup and the rare cases of the edge handlers (capture.S calls these from
// interrupt context with every register saved): phases of 2 ms or more, missed edges, starvation.
#include <avr/io.h>
#include <stddef.h>
#include "capture.h"

static_assert(offsetof(CaptureState, prev) == CS_PREV && offsetof(CaptureState, ph_hi) == CS_PHHI &&
                  offsetof(CaptureState, ph_lo) == CS_PHLO && offsetof(CaptureState, hp32) == CS_HP32 &&
                  offsetof(CaptureState, half) == CS_HALF && offsetof(CaptureState, snap_t2) == CS_SNAPT && offsetof(CaptureState, acc) == CS_ACC && offsetof(CaptureState, snap) == CS_SNAP &&
                  sizeof(CaptureState) == CS_SIZE,
              "capture_state layout must match capture.h's offsets (used by capture.S)");
static_assert(offsetof(CaptureSums, periods) == SUM_N && offsetof(CaptureSums, sum_low) == SUM_LOW &&
                  offsetof(CaptureSums, sum_high) == SUM_HIGH && offsetof(CaptureSums, missed) == SUM_MISSED,
              "CaptureSums layout");

#define S capture_state
#define FLAGS GPIOR0  // F_* (capture.h)
#define NXT GPIOR1
// The handler's flags that describe the signal (F_REQ, F_HALF are kept by a break)
#define SIGNAL_FLAGS (_BV(F_PREV) | _BV(F_CHAIN) | _BV(F_HIGH) | _BV(F_PHI) | _BV(F_PLO))
#define KEEP extern "C" __attribute__((used, externally_visible))

static uint16_t blind_t0;   // TCNT1 when the handler stepped aside
static uint16_t blind_per;  // the last measured period then [ticks], 0 if unknown

// The open period's high time (in sum_high already), 0 if none is open.
static uint32_t open_high(void) {
  if (!(FLAGS & _BV(F_HIGH))) return 0;
  return S.ph_hi != 0xFFFFu ? S.ph_hi : S.hp32;
}

// The open period cannot be completed: take its high time back out of sum_high, forget the phases.
// (Called with interrupts disabled: from the handler, or from the background before sei.)
static void break_chain(void) {
  S.acc.sum_high -= open_high();
  FLAGS &= (uint8_t)~SIGNAL_FLAGS;
}

// Arm the capture for the edge that leaves the pin's present level; if the pin changes before the
// edge select is written (and that edge is not captured), count the edge as missed and try again.
static void resync(void) {
  for (;;) {
    uint8_t level = PINB & _BV(PB0);
    uint8_t arm = level ? TCCR_FALL : TCCR_RISE;
    TCCR1B = arm;
    TIFR1 = _BV(ICF1) | _BV(OCF1A);
    NXT = arm ^ _BV(ICES1);
    if ((PINB & _BV(PB0)) == level || (TIFR1 & _BV(ICF1))) return;
    S.acc.missed++;
  }
}

// Length of the phase that ended with the edge captured at c [ticks]: Timer1 wrapped `half` times
// by half (32768 ticks) since S.prev; one more half-wrap may be pending (compare B not yet served).
static uint32_t phase_length(uint16_t c) {
  uint8_t h = (FLAGS & _BV(F_HALF)) ? S.half : 0;
  uint16_t d = (uint16_t)(c - S.prev) - ((h & 1) ? 0x8000u : 0u);
  return ((uint32_t)h << 15) + d;
}

// The edge at c ended a phase of 2 ms or more (capture.S saw half-wraps). rising: it ended a low time.
KEEP void capture_long_phase(uint16_t c, uint8_t rising) {
  uint8_t f = FLAGS;
  uint32_t len = phase_length(c);
  S.prev = c;
  f &= (uint8_t)~_BV(F_HALF);  // from here on counted from c (capture.S moves compare B)
  if (!(f & _BV(F_PREV)) || S.half >= HALF_GAP) {
    // no measurable phase (after a break), or a gap of more than 250 ms: no period across it
    FLAGS = f;
    break_chain();
    FLAGS |= rising ? (_BV(F_PREV) | _BV(F_CHAIN)) : _BV(F_PREV);
    return;
  }
  if (rising) {
    S.ph_lo = 0xFFFF;
    if (f & _BV(F_HIGH)) {
      S.acc.periods++;
      S.acc.sum_low += len;
    }
    f = (uint8_t)((f | _BV(F_PREV) | _BV(F_CHAIN) | _BV(F_PLO)) & ~_BV(F_HIGH));
  } else {
    S.ph_hi = 0xFFFF;
    f |= _BV(F_PREV) | _BV(F_PHI);
    if (f & _BV(F_CHAIN)) {
      S.hp32 = len;
      S.acc.sum_high += len;
      f |= _BV(F_HIGH);
    }
  }
  FLAGS = f;
}

// After the edge select was flipped the pin showed that the next edge had already gone by unseen.
KEEP void capture_missed(void) {
  S.acc.missed++;
  break_chain();
  FLAGS &= (uint8_t)~_BV(F_HALF);
  resync();
}

// Edges came back to back for EDGE_LIMIT edges: faster than the handler can serve them and still
// leave time to the background. Step aside for 128 us (Timer0 compare A, capture_resume) with the
// capture interrupt off, and count what went by then. Returns TIMSK1.
KEEP uint8_t capture_blind(void) {
  blind_t0 = TCNT1;
  uint8_t f = FLAGS;
  blind_per = (f & _BV(F_PHI)) && (f & _BV(F_PLO)) ? (uint16_t)(S.ph_hi + S.ph_lo) : 0;
  break_chain();
  TCNT0 = 0;
  TIFR0 = _BV(OCF0A);
  TIMSK0 = _BV(OCIE0A);
  return _BV(OCIE1B);
}

KEEP void capture_resume(void) {
  TIMSK0 = 0;
  uint16_t gone = TCNT1 - blind_t0;
  // edges that went by: two per period (an estimate; at least one)
  uint16_t n = blind_per ? (uint16_t)(2u * (gone / blind_per)) : 0;
  S.acc.missed += n ? n : 1;
  resync();
  TIMSK1 = TIMSK_CAPT;
}

extern "C" void capture_init(void) {
  TIMSK1 = 0;
  TCCR1A = 0;
  TCCR1C = 0;
  DDRB &= (uint8_t)~_BV(PB0);   // D8 input, no pull-up
  PORTB &= (uint8_t)~_BV(PB0);
  // Timer0: the handler's wait timeout, normal mode, clk/8, OCF0A at TCNT0 = 255 (128 us)
  TIMSK0 = 0;
  TCCR0A = 0;
  TCCR0B = _BV(CS01);
  OCR0A = 255;
  FLAGS = 0;
  GPIOR2 = 0;
  S.half = 0;
  resync();
  uint16_t b = TCNT1 + 0x8000u;
  OCR1B = b < SMALL_OCR ? SMALL_OCR : b;
  TIFR1 = _BV(OCF1B);
  TIMSK1 = TIMSK_CAPT;
}

extern "C" void capture_snapshot_now(void) {
  uint8_t sreg = SREG;
  asm volatile("cli" ::: "memory");
  if (FLAGS & _BV(F_REQ)) {
    CaptureSums s;
    s.periods = S.acc.periods;
    s.sum_low = S.acc.sum_low;
    s.sum_high = S.acc.sum_high - open_high();  // it belongs to the period still open
    s.missed = S.acc.missed;
    *(CaptureSums *)&S.snap = s;
    FLAGS &= (uint8_t)~_BV(F_REQ);
  }
  SREG = sreg;
}

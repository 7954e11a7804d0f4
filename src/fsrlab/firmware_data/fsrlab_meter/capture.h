// fsrlab meter, capture of the 555 output's edges: interface between the interrupt handlers in
// capture.S (fast path, assembly), their rare cases in capture.cpp (C) and the background (meter.cpp).
//
// Design (firmware/README.md, "How it measures"): Timer1 input capture on D8 serves both edges by
// flipping the edge select ICES1 after each one. A phase can be as short as 16 CPU cycles (5 % duty
// cycle at 50 kHz), shorter than an interrupt's latency, so the handler that serves the edge which
// starts a short phase must already be polling when it comes: after each edge the handler predicts
// the next ones from the last measured high and low times and, when the phase after the next edge is
// short, arms Timer1's compare A as a wake-up a margin before that edge. Edges that start a long phase
// are served by the capture interrupt itself. Between visits the background (USART, commands,
// frames, ADC) runs as ordinary C and can be interrupted anywhere; it never disables interrupts for
// longer than a few cycles.
//
// Sums are cumulative (they wrap modulo 2^32): the background asks for a snapshot (F_REQ) at a
// window's end and reports the difference to the previous one. The handler takes it right after
// the first rising edge at or after the due time (TCNT2 = CS_SNAPT), where no period is open. sum_period = sum_low + sum_high over complete periods.
#ifndef FSRLAB_CAPTURE_H
#define FSRLAB_CAPTURE_H

// Byte offsets in capture_state (shared with the assembly).
#define CS_PREV 0    // u16 capture time of the last served edge [ticks]
#define CS_PHHI 2    // u16 last measured high time [ticks]
#define CS_PHLO 4    // u16 last measured low time
#define CS_HP32 6    // u32 the open period's high time when it was 2 ms or longer (ph_hi = 0xFFFF);
                     // else it is ph_hi (in sum_high already, its period not yet complete)
#define CS_HALF 10   // u8 half-wraps (32768 ticks) of Timer1 since CS_PREV (valid with F_HALF)
#define CS_SNAPT 11  // u8 TCNT2 at which a requested snapshot is due (taken at the first rising
                     // edge at or after it, within 127 counts of 8 us)
#define CS_ACC 12    // sums, 4 x u32: periods, sum_low, sum_high, missed
#define CS_SNAP 28   // the same, copied at a snapshot
#define CS_SIZE 44
#define SUM_N 0
#define SUM_LOW 4
#define SUM_HIGH 8
#define SUM_MISSED 12

// GPIOR0 (I/O 0x1E: sbi/cbi/sbic/sbis in one or two cycles): the handler's flags.
#define F_PREV 0   // CS_PREV is a served edge with nothing missed since (a phase can be measured)
#define F_CHAIN 1  // the last rising edge starts a measurable period
#define F_HIGH 2   // its falling edge was served: CS_HP holds the high time (implies F_CHAIN)
#define F_PHI 3    // CS_PHHI measured since the last break
#define F_PLO 4    // CS_PHLO measured since the last break
#define F_HALF 5   // Timer1 passed CS_PREV + 32768 at least once (CS_HALF counts): a long phase
#define F_REQ 6    // the background waits for a snapshot (set by it with sbi, cleared by the handler)
#define F_STARVE 7 // set by the background when it gets almost no CPU time: the handler steps aside
// GPIOR1: TCCR1B value to write when the next edge is captured (the opposite polarity).
// GPIOR2: edges served in the present visit of the handler.

// Timer1 settings: normal mode, prescaler 1 (62.5 ns ticks), no noise canceller.
#define TCCR_RISE 0x41  // CS10 | ICES1
#define TCCR_FALL 0x01  // CS10
// TIMSK1: capture interrupt and compare B (half-wrap count) always; compare A when a wake is armed.
#define TIMSK_CAPT 0x24  // ICIE1 | OCIE1B
#define TIMSK_WAKE 0x26  // ICIE1 | OCIE1B | OCIE1A

// Timing constants of the handlers [CPU cycles] (see capture.S; the supported range they give is
// measured in simavr by benchmarks/bench_firmware.py).
#define WAKE_LEAD 28     // a wake comes this long (plus 1/32 of the phase) before the predicted edge
#define CAPT_SHORT 48    // a phase shorter than this must begin while the handler polls
#define EXIT_MIN 48      // leave the handler only if the wake is at least this far ahead
#define EDGE_LIMIT 48    // edges served in one visit before the handler steps aside (starvation)
#define SMALL_OCR 16     // compare values 0..15 are avoided: simavr 1.6 loses matches just after a wrap
#define HALF_GAP 123     // half-wraps (2.048 ms each) that make a phase a gap (> 250 ms), not a phase

#ifndef __ASSEMBLER__
#include <stdint.h>

struct CaptureSums {
  uint32_t periods;   // complete periods (rising edge to rising edge, nothing missed in between)
  uint32_t sum_low;   // sum of their low times [ticks]
  uint32_t sum_high;  // sum of their high times [ticks]
  uint32_t missed;    // edges missed or rejected
};

struct CaptureState {
  uint16_t prev, ph_hi, ph_lo;
  uint32_t hp32;
  uint8_t half, snap_t2;
  CaptureSums acc, snap;
};

#ifdef __cplusplus
extern "C" {
#endif
extern volatile CaptureState capture_state;  // defined in capture.S
void capture_init(void);
// A snapshot of the sums taken now, with interrupts disabled for ~100 cycles: for the background
// when the handler has not answered a request for 2 ms (no edges, or only slow ones).
void capture_snapshot_now(void);
#ifdef __cplusplus
}
#endif
#include <avr/io.h>
// Ask for a snapshot due when TCNT2 reaches t2 (at most 127 counts ahead); the sbi is atomic
// against the handler.
static inline void capture_request(uint8_t t2) {
  capture_state.snap_t2 = t2;
  asm volatile("sbi %0, %1" ::"I"(_SFR_IO_ADDR(GPIOR0)), "I"(F_REQ) : "memory");
}
// The snapshot asked for is in capture_state.snap (the handler leaves it alone until the next request).
static inline uint8_t capture_ready(void) { return !(GPIOR0 & _BV(F_REQ)); }
// The background gets (almost) no time: the handler steps aside for 128 us at each visit until
// capture_fed() (sbi/cbi: atomic against the handler).
static inline void capture_starving(void) {
  asm volatile("sbi %0, %1" ::"I"(_SFR_IO_ADDR(GPIOR0)), "I"(F_STARVE) : "memory");
}
static inline void capture_fed(void) {
  asm volatile("cbi %0, %1" ::"I"(_SFR_IO_ADDR(GPIOR0)), "I"(F_STARVE) : "memory");
}
#endif
#endif

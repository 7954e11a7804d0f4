/*
 * fsrlab_sim: runs the fsrlab meter firmware (.elf) in simavr as an ATmega328P at 16 MHz.
 *
 * It drives D8 (PB0, ICP1) with a square wave made of segments (frequency, duty cycle, edge
 * jitter), feeds command lines into USART0 at chosen times, sets the A0 voltage, and writes every
 * byte the firmware transmits to stdout (or --out FILE). Diagnostics go to stderr, one per line,
 * starting with '#':
 *   #PD4 <cycle> <level>          each change of the C_off switch output (D4)
 *   #EDGES <rising> <falling>     edges generated on D8 (at the end)
 *   #PEEK <addr> <byte> <word>    data memory byte and little-endian 16-bit word at the end
 *   #OCR_SMALL <a> <b>            times OCR1A / OCR1B were set to a value below 16 (see main loop)
 *                                (--peek ADDR, data space address, e.g. from avr-nm minus 0x800000)
 *   #HX <cycle> <value>           an HX711 conversion read completely (24 bits and the gain pulse:
 *                                at the falling edge of the 25th SCK pulse) and its raw value
 *   #HX_POWERDOWN <cycle>         SCK stayed high for more than 60 us: the HX711 powered down
 *   #HX_POWERUP <cycle>           SCK low again: it powers up and settles before its next conversion
 *   #HX_LOST <cycle> <value>      a conversion replaced (or, during a read, dropped) before it was read
 *   #HX_SCK <max_high> <pulses> <stray>   at the end: longest SCK high time [cycles], SCK pulses,
 *                                pulses while no conversion was ready
 *   #PD2 <ddr> <port>             at the end: D2 direction and output bit (0 1 = input with pull-up)
 *   #END <cycles> <pd4>           simulated cycles and final D4 level
 *
 * Usage:
 *   fsrlab_sim FIRMWARE.elf [--time S] [--seg T0:FREQ:DUTY[:JITTER]]... [--cmd T:TEXT]...
 *              [--adc-mv MV] [--seed N] [--out FILE]
 *              [--hx SPS[:FIRST]] [--hx-values V,V,...] [--hx-stop T]
 *   --seg   from time T0 [s] on: FREQ [Hz] (0: line held low), DUTY (0..1), JITTER: each edge moves
 *           by a uniform random amount in +-JITTER periods (default 0). Segments in time order.
 *   --cmd   at time T [s] send TEXT followed by '\n' (bytes spaced 100 us, faster than 115200 baud
 *           never happens on a real line). '\\n' inside TEXT is not interpreted; use several --cmd.
 *   --time  simulated time [s] (default 1).
 *   --hx    an HX711 on D2 (DOUT) / D3 (SCK) converting SPS (10 or 80) times a second, the first
 *           conversion ready at FIRST [s] (default 1/SPS), powered up at reset. Without --hx no HX711
 *           is connected: DOUT is held high, as the firmware's pull-up does on a real board (simavr
 *           1.6 does not model pull-ups; the firmware's setting is reported by #PD2).
 *   --hx-values  raw values of the successive conversions, 24-bit two's complement
 *           (-8388608..8388607), used in turn and repeated; default: conversion k gives
 *           ((k * 2796203) mod 2^24) - 2^23, which visits the whole range.
 *   --hx-stop  from time T [s] on the HX711 is unplugged: no more conversions, DOUT pulled high.
 *
 * HX711 model: hx711_model.h (shared with fsrlab_twin.c).
 *
 * Edge timing: an edge scheduled at cycle c is seen by the simulated MCU at the end of the
 * instruction running at c (simavr processes its cycle timers between instructions), so each
 * captured timestamp lies 0..3 cycles after the ideal edge rounded to a cycle.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stdint.h>
#include <math.h>
#include <unistd.h>

#include <sim_avr.h>
#include <sim_elf.h>
#include <sim_irq.h>
#include <sim_io.h>
#include <sim_cycle_timers.h>
#include <avr_ioport.h>
#include <avr_uart.h>
#include <avr_adc.h>

#include "hx711_model.h"
#include "mcu.h"

#define F_CPU_HZ 16000000.0
#define MAX_SEG 64
#define MAX_CMD 64

typedef struct { double t0, freq, duty, jitter; } seg_t;
typedef struct { double t; char text[80]; } cmd_t;

static seg_t segs[MAX_SEG];
static int nseg;
static cmd_t cmds[MAX_CMD];
static int ncmd;
static FILE *out;
static avr_t *avr;
static avr_irq_t *pin_irq;
static avr_irq_t *uart_in;
static int pd4_level;
static unsigned peeks[64];
static int npeek;
static uint64_t n_rise, n_fall;
static uint64_t rng_state = 0x9E3779B97F4A7C15ull;

static double urand(void) { /* xorshift64*, uniform in [0, 1) */
  rng_state ^= rng_state >> 12;
  rng_state ^= rng_state << 25;
  rng_state ^= rng_state >> 27;
  return (double)((rng_state * 2685821657736338717ull) >> 11) / 9007199254740992.0;
}

/* ------------------------------------------------------------------ square-wave generator */
static double ideal_rise;   /* cycle of the current period's ideal rising edge */
static double next_edge;    /* cycle of the next scheduled edge */
static int next_level;      /* level the next edge sets */
static int cur_seg = -1;
static double cur_fall;     /* scheduled falling edge of the current period */

static int seg_at(double cycle) {
  int s = -1;
  for (int i = 0; i < nseg; i++)
    if (segs[i].t0 * F_CPU_HZ <= cycle) s = i;
  return s;
}

/* Plan the period that starts with a rising edge at ideal time ideal_rise. */
static int plan_period(void) {
  for (;;) {
    int s = seg_at(ideal_rise);
    if (s < 0) { /* before the first segment: wait for it */
      ideal_rise = segs[0].t0 * F_CPU_HZ;
      continue;
    }
    if (segs[s].freq <= 0) { /* line low: jump to the next segment */
      if (s + 1 >= nseg) return 0;
      ideal_rise = segs[s + 1].t0 * F_CPU_HZ;
      continue;
    }
    cur_seg = s;
    double p = F_CPU_HZ / segs[s].freq;
    double j = segs[s].jitter * p;
    double r = ideal_rise + (j > 0 ? (2 * urand() - 1) * j : 0);
    double f = ideal_rise + segs[s].duty * p + (j > 0 ? (2 * urand() - 1) * j : 0);
    ideal_rise += p;
    next_edge = r;
    cur_fall = f;
    return 1;
  }
}

/* Cycle for an edge at ideal time x [cycles], never before `after` + 1 (jitter may ask for the past). */
static avr_cycle_count_t to_cycle(double x, avr_cycle_count_t after) {
  double r = floor(x + 0.5);
  if (r <= (double)after) return after + 1;
  return (avr_cycle_count_t)r;
}

static avr_cycle_count_t edge_cb(struct avr_t *a, avr_cycle_count_t when, void *param) {
  (void)param; (void)when;
  avr_raise_irq(pin_irq, next_level);
  if (next_level) {
    n_rise++;
    next_level = 0;
    next_edge = cur_fall;
  } else {
    n_fall++;
    if (!plan_period()) return 0;
    next_level = 1;
  }
  return to_cycle(next_edge, a->cycle);
}

/* ------------------------------------------------------------------ HX711 on PD2 / PD3 */
/* The model itself is hx711_model.c (shared with fsrlab_twin.c); here only its values. */
#define HX_MAX_VALUES 4096
static int hx_sps;                  /* 0: no HX711 connected */
static double hx_first = -1, hx_stop = -1;
static int32_t hx_vals[HX_MAX_VALUES];
static int hx_nvals;

static int32_t hx_value(uint64_t k, avr_cycle_count_t cycle) {
  (void)cycle;
  if (hx_nvals) return hx_vals[k % (uint64_t)hx_nvals];
  return (int32_t)((k * 2796203ull) % 16777216ull) - 8388608;
}

/* ------------------------------------------------------------------ UART */
static void uart_out_cb(struct avr_irq_t *irq, uint32_t value, void *param) {
  (void)irq; (void)param;
  fputc((int)(value & 0xFF), out);
}

static int cmd_idx;
static int cmd_pos;
static avr_cycle_count_t cmd_cb(struct avr_t *a, avr_cycle_count_t when, void *param) {
  (void)param; (void)when;
  cmd_t *c = &cmds[cmd_idx];
  size_t n = strlen(c->text);
  uint8_t b = cmd_pos < (int)n ? (uint8_t)c->text[cmd_pos] : '\n';
  avr_raise_irq(uart_in, b);
  cmd_pos++;
  if (cmd_pos > (int)n) { /* line sent */
    cmd_idx++;
    cmd_pos = 0;
    if (cmd_idx >= ncmd) return 0;
    avr_cycle_count_t t = (avr_cycle_count_t)llround(cmds[cmd_idx].t * F_CPU_HZ);
    return t > a->cycle ? t : a->cycle + 1600;
  }
  return a->cycle + 1600; /* 100 us per byte */
}

/* ------------------------------------------------------------------ compare registers */
static unsigned small_a, small_b;
static void ocr_write_cb(struct avr_irq_t *irq, uint32_t value, void *param) {
  (void)irq;
  unsigned addr = param == &small_a ? 0x88 : 0x8A;
  unsigned v = (value & 0xFF) | (avr->data[addr + 1] << 8);
  if (v < 16) (*(unsigned *)param)++;
}

/* ------------------------------------------------------------------ D4 */
static void pd4_cb(struct avr_irq_t *irq, uint32_t value, void *param) {
  (void)irq; (void)param;
  int v = value ? 1 : 0;
  if (v != pd4_level) {
    pd4_level = v;
    fprintf(stderr, "#PD4 %llu %d\n", (unsigned long long)avr->cycle, v);
  }
}

static int cmp_cmd(const void *a, const void *b) {
  double d = ((const cmd_t *)a)->t - ((const cmd_t *)b)->t;
  return d < 0 ? -1 : d > 0;
}

static void usage(void) {
  fprintf(stderr, "usage: fsrlab_sim FIRMWARE.elf [--time S] [--seg T0:FREQ:DUTY[:JITTER]]... "
                  "[--cmd T:TEXT]... [--adc-mv MV] [--seed N] [--out FILE] [--hx SPS[:FIRST]] "
                  "[--hx-values V,V,...] [--hx-stop T]\n");
  exit(2);
}

int main(int argc, char **argv) {
  const char *elf = NULL, *outpath = NULL;
  double sim_time = 1.0;
  int adc_mv = 0;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (!strcmp(a, "--time") && i + 1 < argc) sim_time = atof(argv[++i]);
    else if (!strcmp(a, "--seg") && i + 1 < argc) {
      if (nseg >= MAX_SEG) usage();
      seg_t s = {0, 0, 0.5, 0};
      int n = sscanf(argv[++i], "%lf:%lf:%lf:%lf", &s.t0, &s.freq, &s.duty, &s.jitter);
      if (n < 3 || s.duty < 0 || s.duty > 1 || s.freq < 0) usage();
      if (nseg && s.t0 < segs[nseg - 1].t0) usage();
      segs[nseg++] = s;
    } else if (!strcmp(a, "--cmd") && i + 1 < argc) {
      if (ncmd >= MAX_CMD) usage();
      const char *v = argv[++i];
      const char *colon = strchr(v, ':');
      if (!colon) usage();
      cmds[ncmd].t = atof(v);
      snprintf(cmds[ncmd].text, sizeof cmds[ncmd].text, "%s", colon + 1);
      ncmd++;
    } else if (!strcmp(a, "--adc-mv") && i + 1 < argc) adc_mv = atoi(argv[++i]);
    else if (!strcmp(a, "--seed") && i + 1 < argc) rng_state ^= strtoull(argv[++i], NULL, 0) * 0x2545F4914F6CDD1Dull;
    else if (!strcmp(a, "--out") && i + 1 < argc) outpath = argv[++i];
    else if (!strcmp(a, "--peek") && i + 1 < argc) {
      unsigned a = (unsigned)strtoul(argv[++i], NULL, 0);
      if (npeek < 64) peeks[npeek++] = a;
    }
    else if (!strcmp(a, "--hx") && i + 1 < argc) {
      if (sscanf(argv[++i], "%d:%lf", &hx_sps, &hx_first) < 1 || (hx_sps != 10 && hx_sps != 80)) usage();
    } else if (!strcmp(a, "--hx-values") && i + 1 < argc) {
      char *p = argv[++i], *end;
      for (;;) {
        long v = strtol(p, &end, 0);
        if (end == p || v < -8388608L || v > 8388607L || hx_nvals >= HX_MAX_VALUES) usage();
        hx_vals[hx_nvals++] = (int32_t)v;
        if (*end == 0) break;
        if (*end != ',') usage();
        p = end + 1;
      }
    } else if (!strcmp(a, "--hx-stop") && i + 1 < argc) hx_stop = atof(argv[++i]);
    else if (a[0] != '-' && !elf) elf = a;
    else usage();
  }
  if (!elf) usage();
  /* simavr prints configuration notes with printf: keep stdout for the firmware's bytes only */
  if (outpath) out = fopen(outpath, "wb");
  else {
    int fd = dup(1);
    out = fd >= 0 ? fdopen(fd, "wb") : NULL;
  }
  dup2(2, 1);
  if (!out) { perror(outpath); return 2; }

  avr = mcu_load(elf);
  if (!avr) return 2;

  /* USART0: no stdio echo; capture output, prepare input */
  uart_in = mcu_uart(avr, uart_out_cb);

  /* D4 = PD4 watcher, D8 = PB0 driver, A0 voltage */
  avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('D'), 4), pd4_cb, NULL);
  pin_irq = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('B'), 0);
  avr_raise_irq(pin_irq, 0);
  avr_irq_t *adc0 = avr_io_getirq(avr, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_ADC0);
  if (adc0) avr_raise_irq(adc0, (uint32_t)adc_mv);

  hx_attach(avr, hx_sps, hx_first, hx_stop, hx_value);

  if (nseg) {
    ideal_rise = segs[0].t0 * F_CPU_HZ;
    if (plan_period()) {
      next_level = 1;
      avr_cycle_timer_register(avr, to_cycle(next_edge, 0), edge_cb, NULL);
    }
  }
  if (ncmd) {
    qsort(cmds, (size_t)ncmd, sizeof cmds[0], cmp_cmd);
    avr_cycle_count_t c = (avr_cycle_count_t)llround(cmds[0].t * F_CPU_HZ);
    avr_cycle_timer_register(avr, c > 0 ? c : 1, cmd_cb, NULL);
  }

  /* compare values the firmware writes below 16: simavr 1.6 loses Timer1 compare matches just
   * after the wrap, so the firmware must never arm one there (firmware/README.md). A 16-bit
   * write ends with its low byte; the high byte is in place by then. */
  avr_irq_register_notify(avr_iomem_getirq(avr, 0x88, "ocr1al", AVR_IOMEM_IRQ_ALL), ocr_write_cb, &small_a);
  avr_irq_register_notify(avr_iomem_getirq(avr, 0x8A, "ocr1bl", AVR_IOMEM_IRQ_ALL), ocr_write_cb, &small_b);

  avr_cycle_count_t end = (avr_cycle_count_t)llround(sim_time * F_CPU_HZ);
  int state = cpu_Running;
  while (avr->cycle < end) {
    state = avr_run(avr);
    if (state == cpu_Done || state == cpu_Crashed) break;
  }
  fflush(out);
  fprintf(stderr, "#EDGES %llu %llu\n", (unsigned long long)n_rise, (unsigned long long)n_fall);
  for (int i = 0; i < npeek; i++)
    fprintf(stderr, "#PEEK 0x%04x %u %u\n", peeks[i], peeks[i] < 0x8ff ? avr->data[peeks[i]] : 0u,
            peeks[i] < 0x8ff ? (unsigned)(avr->data[peeks[i]] | (avr->data[peeks[i] + 1] << 8)) : 0u);
  fprintf(stderr, "#OCR_SMALL %u %u\n", small_a, small_b);
  hx_report();
  fprintf(stderr, "#PD2 %d %d\n", (avr->data[0x2A] >> 2) & 1, (avr->data[0x2B] >> 2) & 1);
  fprintf(stderr, "#PC 0x%x state %d\n", avr->pc, avr->state);
  fprintf(stderr, "#END %llu %d\n", (unsigned long long)avr->cycle, pd4_level);
  if (state == cpu_Crashed) { fprintf(stderr, "#CRASHED\n"); return 3; }
  return 0;
}

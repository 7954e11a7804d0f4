/*
 * fsrlab_twin: the fsrlab meter firmware (.elf) in simavr as an ATmega328P at 16 MHz, driven by a
 * stream of inputs computed elsewhere (fsrlab.virtual.twin: the virtual sensor through the LM555 transient),
 * with its UART on a file descriptor (the master side of a pseudo-terminal the caller owns).
 *
 * Usage:
 *   fsrlab_twin FIRMWARE.elf --uart-fd N [--speed realtime|max] [--hx SPS[:FIRST]]
 *
 * Input, on stdin: records of 16 bytes, little endian: uint8 type, 3 bytes padding, int32 value,
 * uint64 cycle (CPU cycles since reset, 16 per microsecond).
 *   'P' value=EPOCH        the following 'E' and 'L' records belong to stream epoch EPOCH
 *   'E' value=LEVEL        D8 goes to LEVEL (0/1) at `cycle`; edges in time order
 *   'L' value=0            every edge before `cycle` has been sent: the simulation may run up to it
 *   'A' value=MV           A0 is MV millivolts from `cycle` on (time order)
 *   'H' value=RAW          HX711 conversions made from `cycle` on read RAW (24-bit two's complement)
 * Edges and the limit of an epoch other than the harness's current one are ignored: the epoch goes
 * up by one at every change of D4 (the C_off switch) or of D5..D7 (the multiplexer's select lines
 * S0..S2, written together), so edges computed for the old capacitance or channel and still in the
 * pipe never reach D8. At such a change the queued edges are dropped and the run waits until the
 * caller has sent edges for the new epoch (and a new limit).
 * End of stdin ends the run (the caller has gone).
 *
 * Output, on stderr, one line each, starting with '#':
 *   #READY                        firmware loaded, waiting for input
 *   #T <cycle>                    progress, every 5 ms of simulated time and when waiting for edges
 *   #SW <cycle> <d4> <channel> <epoch> <edges>   D4 or the channel (D5..D7) changed; <edges>: edges
 *                                 applied to D8 so far
 *   #HX..., #HX_SCK               the HX711 model (hx711_model.h)
 *   #END <cycles> <edges>         at the end
 * The firmware's bytes go to the UART fd; the bytes read from it are fed to USART0, one per 87 us
 * (115200 baud, 10 bits a byte). In real time a full pty drops bytes, as a UART with nobody
 * listening; at --speed max the simulation waits until the host has read them (the host sets the pace).
 *
 * --speed realtime holds simulated time to the wall clock (never ahead of it); max runs as fast as
 * simavr goes and the host reads. Either way the run never passes the limit the caller has confirmed.
 * The process ends when stdin closes (its caller ended or died): the pty master it holds then closes,
 * and the host sees a pulled cable.
 *
 * Edge timing as in fsrlab_sim.c: an edge scheduled at cycle c is seen by the MCU at the end of the
 * instruction running at c.
 */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stdint.h>
#include <math.h>
#include <unistd.h>
#include <fcntl.h>
#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <time.h>

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
#define TICK_CYCLES 16000u      /* I/O and pacing every 1 ms of simulated time */
#define BYTE_CYCLES 1389u       /* one UART byte at 115200 baud */
#define QCAP (1u << 16)         /* queued edges (the caller's look-ahead is far shorter) */
#define ACAP (1u << 16)         /* queued A0 / HX711 values */

typedef struct { uint64_t cycle; int32_t value; } rec_t;

static avr_t *avr;
static avr_irq_t *pin_irq, *uart_in, *adc0;
static int uart_fd = -1;
static int realtime = 1;

/* ------------------------------------------------------------------ edges on D8 */
static rec_t edges[QCAP];
static unsigned e_head, e_tail;           /* queue [head, tail) */
static int edge_armed;
static uint64_t edges_applied;
static uint32_t epoch, rx_epoch;
static uint64_t limit;                    /* confirmed: all edges before it are queued */
static int pd4_level, mux_channel, pd4_changed;

static unsigned e_count(void) { return e_tail - e_head; }

static avr_cycle_count_t at_or_after_now(uint64_t c) {
  return c > avr->cycle ? (avr_cycle_count_t)c : avr->cycle + 1;
}

static avr_cycle_count_t edge_cb(struct avr_t *a, avr_cycle_count_t when, void *param) {
  (void)param; (void)when;
  while (e_count() && edges[e_head % QCAP].cycle <= a->cycle) {
    avr_raise_irq(pin_irq, (uint32_t)edges[e_head % QCAP].value);
    e_head++;
    edges_applied++;
  }
  if (!e_count()) { edge_armed = 0; return 0; }
  return edges[e_head % QCAP].cycle;
}

static void arm_edges(void) {
  if (edge_armed || !e_count()) return;
  edge_armed = 1;
  avr_cycle_timer_register(avr, at_or_after_now(edges[e_head % QCAP].cycle) - avr->cycle, edge_cb, NULL);
}

/* ------------------------------------------------------------------ A0 and HX711 values */
static rec_t adcq[ACAP], hxq[ACAP];
static unsigned a_head, a_tail, h_head, h_tail;
static int32_t hx_current = 0;
static int adc_armed;

static avr_cycle_count_t adc_cb(struct avr_t *a, avr_cycle_count_t when, void *param) {
  (void)param; (void)when;
  while (a_tail != a_head && adcq[a_head % ACAP].cycle <= a->cycle) {
    int32_t mv = adcq[a_head % ACAP].value;
    if (adc0) avr_raise_irq(adc0, (uint32_t)(mv < 0 ? 0 : mv));
    a_head++;
  }
  if (a_tail == a_head) { adc_armed = 0; return 0; }
  return adcq[a_head % ACAP].cycle;
}

static int32_t twin_hx_value(uint64_t k, avr_cycle_count_t cycle) {
  (void)k;
  while (h_tail != h_head && hxq[h_head % ACAP].cycle <= cycle) {
    hx_current = hxq[h_head % ACAP].value;
    h_head++;
  }
  return hx_current;
}

/* ------------------------------------------------------------------ UART */
static uint8_t obuf[8192];
static size_t olen;
static uint8_t ibuf[4096];
static size_t ihead, itail;
static int feeding;
static uint64_t bytes_lost;

static void flush_out(void) {
  size_t off = 0;
  while (off < olen) {
    ssize_t n = write(uart_fd, obuf + off, olen - off);
    if (n > 0) { off += (size_t)n; continue; }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EAGAIN && !realtime) { /* max speed: the host's reading sets the pace */
      struct pollfd p = {uart_fd, POLLOUT, 0};
      if (poll(&p, 1, 1000) > 0 && !(p.revents & (POLLERR | POLLHUP | POLLNVAL))) continue;
    }
    bytes_lost += olen - off; /* EAGAIN (nobody reads) or EIO: lost, as on a UART */
    break;
  }
  olen = 0;
}

static void uart_out_cb(struct avr_irq_t *irq, uint32_t value, void *param) {
  (void)irq; (void)param;
  if (olen == sizeof obuf) flush_out();
  obuf[olen++] = (uint8_t)value;
}

static avr_cycle_count_t feed_cb(struct avr_t *a, avr_cycle_count_t when, void *param) {
  (void)param; (void)when;
  if (ihead == itail) { feeding = 0; return 0; }
  avr_raise_irq(uart_in, ibuf[ihead % sizeof ibuf]);
  ihead++;
  return a->cycle + BYTE_CYCLES;
}

static void read_uart(void) {
  while (itail - ihead < sizeof ibuf) {
    size_t room = sizeof ibuf - (itail - ihead);
    size_t pos = itail % sizeof ibuf;
    size_t n = room < sizeof ibuf - pos ? room : sizeof ibuf - pos;
    ssize_t r = read(uart_fd, ibuf + pos, n);
    if (r <= 0) break;
    itail += (size_t)r;
  }
  if (!feeding && ihead != itail) {
    feeding = 1;
    avr_cycle_timer_register(avr, 1, feed_cb, NULL);
  }
}

/* ------------------------------------------------------------------ D4, D5..D7 */
#define PORTD_DATA 0x2B /* PORTD in the data space: the whole byte is written before any pin's irq */
static void portd_cb(struct avr_irq_t *irq, uint32_t value, void *param) {
  (void)irq; (void)param; (void)value;
  uint8_t port = avr->data[PORTD_DATA];
  int v = (port >> 4) & 1, ch = (port >> 5) & 7;
  if (v == pd4_level && ch == mux_channel) return; /* (the other pins of the same write) */
  pd4_level = v;
  mux_channel = ch;
  epoch++;
  /* edges computed with the old capacitance: dropped; wait for the caller's new ones */
  avr_cycle_timer_cancel(avr, edge_cb, NULL);
  edge_armed = 0;
  e_tail = e_head;
  limit = avr->cycle;
  pd4_changed = 1;
  fprintf(stderr, "#SW %llu %d %d %u %llu\n", (unsigned long long)avr->cycle, v, ch, epoch,
          (unsigned long long)edges_applied);
}

/* ------------------------------------------------------------------ stdin records */
static uint8_t rbuf[1 << 16];
static size_t rlen;
static int stdin_eof;

static void handle(uint8_t type, int32_t value, uint64_t cycle) {
  switch (type) {
  case 'P': rx_epoch = (uint32_t)value; break;
  case 'E':
    if (rx_epoch != epoch) break;
    if (e_count() >= QCAP) { fprintf(stderr, "#ERROR edge queue full\n"); exit(3); }
    edges[e_tail % QCAP] = (rec_t){cycle, value ? 1 : 0};
    e_tail++;
    arm_edges();
    break;
  case 'L':
    if (rx_epoch == epoch && cycle > limit) limit = cycle;
    break;
  case 'A':
    if (a_tail - a_head >= ACAP) { fprintf(stderr, "#ERROR A0 queue full\n"); exit(3); }
    adcq[a_tail % ACAP] = (rec_t){cycle, value};
    a_tail++;
    if (!adc_armed) {
      adc_armed = 1;
      avr_cycle_timer_register(avr, at_or_after_now(adcq[a_head % ACAP].cycle) - avr->cycle, adc_cb, NULL);
    }
    break;
  case 'H':
    if (h_tail - h_head >= ACAP) { fprintf(stderr, "#ERROR HX711 queue full\n"); exit(3); }
    hxq[h_tail % ACAP] = (rec_t){cycle, value};
    h_tail++;
    break;
  default:
    fprintf(stderr, "#ERROR bad record type %d\n", type);
    exit(3);
  }
}

/* Read what stdin has (blocking for at most timeout_ms); returns when something was read or the
 * time is up. The queues' room decides how much is taken (back-pressure on the caller). */
static void read_stdin(int timeout_ms) {
  struct pollfd p[2] = {{0, POLLIN, 0}, {uart_fd, POLLIN, 0}};
  if (poll(p, 2, timeout_ms) <= 0) return;
  if (p[1].revents & POLLIN) read_uart();
  if (!(p[0].revents & (POLLIN | POLLHUP))) return;
  /* take no more records than every queue has room for (back-pressure on the caller) */
  size_t room = QCAP - e_count();
  if (ACAP - (a_tail - a_head) < room) room = ACAP - (a_tail - a_head);
  if (ACAP - (h_tail - h_head) < room) room = ACAP - (h_tail - h_head);
  size_t want = room * 16 > rlen ? room * 16 - rlen : 0;
  if (want > sizeof rbuf - rlen) want = sizeof rbuf - rlen;
  if (want < 16) {
    if (timeout_ms) usleep(1000); /* queues full: let the simulation drain them */
    return;
  }
  ssize_t n = read(0, rbuf + rlen, want);
  if (n == 0) { stdin_eof = 1; return; }
  if (n < 0) { if (errno != EINTR && errno != EAGAIN) stdin_eof = 1; return; }
  rlen += (size_t)n;
  size_t off = 0;
  for (; off + 16 <= rlen; off += 16) {
    const uint8_t *r = rbuf + off;
    int32_t v;
    uint64_t c;
    memcpy(&v, r + 4, 4);
    memcpy(&c, r + 8, 8);
    handle(r[0], v, c);
  }
  memmove(rbuf, rbuf + off, rlen - off);
  rlen -= off;
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static avr_cycle_count_t wake_cb(struct avr_t *a, avr_cycle_count_t when, void *param) {
  (void)a; (void)when; (void)param;
  return when + TICK_CYCLES; /* a timer every tick: a sleeping CPU never jumps past the limit */
}

static void usage(void) {
  fprintf(stderr, "usage: fsrlab_twin FIRMWARE.elf --uart-fd N [--speed realtime|max] [--hx SPS[:FIRST]]\n");
  exit(2);
}

int main(int argc, char **argv) {
  const char *elf = NULL;
  int hx_sps = 0;
  double hx_first = -1;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (!strcmp(a, "--uart-fd") && i + 1 < argc) uart_fd = atoi(argv[++i]);
    else if (!strcmp(a, "--speed") && i + 1 < argc) {
      const char *s = argv[++i];
      if (!strcmp(s, "realtime")) realtime = 1;
      else if (!strcmp(s, "max")) realtime = 0;
      else usage();
    } else if (!strcmp(a, "--hx") && i + 1 < argc) {
      if (sscanf(argv[++i], "%d:%lf", &hx_sps, &hx_first) < 1 || (hx_sps != 10 && hx_sps != 80)) usage();
    } else if (a[0] != '-' && !elf) elf = a;
    else usage();
  }
  if (!elf || uart_fd < 0) usage();
  signal(SIGPIPE, SIG_IGN);
  dup2(2, 1); /* simavr prints notes with printf */
  fcntl(uart_fd, F_SETFL, fcntl(uart_fd, F_GETFL) | O_NONBLOCK);
  setvbuf(stderr, NULL, _IOLBF, 0);

  avr = mcu_load(elf);
  if (!avr) return 2;

  uart_in = mcu_uart(avr, uart_out_cb);

  for (int pin = 4; pin <= 7; pin++)
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('D'), pin), portd_cb, NULL);
  pin_irq = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('B'), 0);
  avr_raise_irq(pin_irq, 0);
  adc0 = avr_io_getirq(avr, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_ADC0);
  if (adc0) avr_raise_irq(adc0, 0);
  hx_attach(avr, hx_sps, hx_first, -1, twin_hx_value);
  avr_cycle_timer_register(avr, TICK_CYCLES, wake_cb, NULL);

  fprintf(stderr, "#READY\n");
  double wall0 = now_s();
  uint64_t next_tick = 0, next_report = 0;
  int state = cpu_Running;
  while (!stdin_eof) {
    if (avr->cycle >= next_tick) {
      next_tick = avr->cycle + TICK_CYCLES;
      flush_out();
      read_stdin(0);
      if (avr->cycle >= next_report) {
        next_report = avr->cycle + 5 * TICK_CYCLES;
        fprintf(stderr, "#T %llu\n", (unsigned long long)avr->cycle);
      }
      if (realtime) { /* sleep until the wall clock catches up, taking input (and host bytes) meanwhile */
        double ahead;
        while (!stdin_eof && (ahead = (double)avr->cycle / F_CPU_HZ - (now_s() - wall0)) > 0.001)
          read_stdin((int)(ahead * 1000) + 1);
      }
    }
    if (avr->cycle >= limit) {
      /* no confirmed edges beyond this point: wait for the caller */
      flush_out();
      fprintf(stderr, "#T %llu\n", (unsigned long long)avr->cycle);
      while (avr->cycle >= limit && !stdin_eof) read_stdin(100);
      if (realtime) {
        double behind = (now_s() - wall0) - (double)avr->cycle / F_CPU_HZ;
        if (behind > 0.5) wall0 += behind; /* waited long for the caller: do not race to catch up */
      }
      continue;
    }
    state = avr_run(avr);
    if (state == cpu_Done || state == cpu_Crashed) break;
  }
  flush_out();
  hx_report();
  fprintf(stderr, "#END %llu %llu\n", (unsigned long long)avr->cycle, (unsigned long long)edges_applied);
  if (state == cpu_Crashed) { fprintf(stderr, "#CRASHED\n"); return 3; }
  return 0;
}
